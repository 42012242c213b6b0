"""Update the 3-DOF laboratory frame to its measured modes with the sensitivity method.

Builds the problem from the built-in model and data, runs SM from the initial point and
prints the updated parameters (physical values and ratios to initial) and the mode table.
Run: ``python examples/gallery/lab_frame_update.py``
"""

from framework.optimizers import Budget, run_optimizer
from framework.structures.lab_frame.model import make_model, measured
from framework.updating.problem import UpdatingProblem


def main() -> dict:
    problem = UpdatingProblem(make_model(), measured("base"))
    result = run_optimizer("sm", problem, seed=0, budget=Budget(max_evaluations=1000), start="initial")
    ratios = problem.parameters.to_ratio(result.theta_best)
    for p, value, ratio in zip(problem.parameters, result.theta_best, ratios):
        relative = f"({ratio:.3f} x initial)" if ratio == ratio else "(initial 0)"  # NaN: no ratio to 0
        print(f"{p.name:4s} {value:10.4g} {p.unit:4s} {relative}")
    print(problem.mode_table(result.theta_best).round(4).to_string(index=False))
    print(f"objective {result.objective:.3e} after {result.n_evaluations} model evaluations")
    return {"objective": result.objective, "theta": result.theta_best}


if __name__ == "__main__":
    main()
