"""Bring your own OpenSeesPy model: a two-storey shear frame updated to 'measured' modes."""

import openseespy.opensees as ops

from framework.core.parameters import Parameter, ParameterSet
from framework.measured.modes import MeasuredModes
from framework.models.opensees import OpenSeesModel
from framework.optimizers import Budget, run_optimizer
from framework.updating.problem import UpdatingProblem


def build(v):  # v: {parameter name: value}; creates the model in the OpenSees domain
    ops.model("basic", "-ndm", 1, "-ndf", 1)
    for tag in (0, 1, 2):
        ops.node(tag, 0.0)
    ops.fix(0, 1)
    ops.uniaxialMaterial("Elastic", 1, v["k1_n_per_m"])
    ops.uniaxialMaterial("Elastic", 2, v["k2_n_per_m"])
    ops.element("zeroLength", 1, 0, 1, "-mat", 1, "-dir", 1)
    ops.element("zeroLength", 2, 1, 2, "-mat", 2, "-dir", 1)
    ops.mass(1, 1000.0)
    ops.mass(2, 800.0)


params = ParameterSet([
    Parameter("k1_n_per_m", 2.0e6, 1.0e6, 4.0e6, "N/m", "storey 1 stiffness"),
    Parameter("k2_n_per_m", 1.5e6, 0.5e6, 3.0e6, "N/m", "storey 2 stiffness"),
])
model = OpenSeesModel(build, params, measured_dofs={"floor1": (1, 1), "floor2": (2, 1)},
                      n_modes=2)

if __name__ == "__main__":
    truth = model.modal({"k1_n_per_m": 2.6e6, "k2_n_per_m": 1.2e6})  # stands in for a test
    measured = MeasuredModes(truth.frequencies_hz, ("floor1", "floor2"), truth.shapes)
    problem = UpdatingProblem(model, measured)
    result = run_optimizer("pso", problem, seed=1, budget=Budget(max_evaluations=2000))
    print(dict(zip(params.names, result.theta_best.round(-3))), f"objective {result.objective:.2e}")
    print(problem.mode_table(result.theta_best))
