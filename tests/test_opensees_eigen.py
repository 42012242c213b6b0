"""OpenSeesModel's default solver (K and M extracted from OpenSees, modes from scipy): agreement with
OpenSees' own eigen solvers on every built-in OpenSees structure, multi-point constraints, and results
that do not depend on what the process evaluated before."""

import dataclasses
import functools
import logging
import pickle
import runpy
import subprocess
import sys
from pathlib import Path

import numpy as np
import pandas as pd
import pytest

from framework.core.errors import ModelEvaluationError
from framework.core.parameters import Parameter, ParameterSet
from framework.models.opensees import OpenSeesModel

ops = pytest.importorskip("openseespy.opensees")
from openseespy.opensees import equalDOF as _unrecorded_equal_dof  # noqa: E402 - bypasses the record

ROOT = Path(__file__).resolve().parents[1]
RTOL_FREQUENCY = 1e-9
MAC_TOL = 1e-9


def _mac_diagonal(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    return (np.sum(a * b, axis=0) ** 2) / (np.sum(a * a, axis=0) * np.sum(b * b, axis=0))


def _assert_agree(new, ref) -> None:
    assert new.n_modes == ref.n_modes
    np.testing.assert_allclose(new.frequencies_hz, ref.frequencies_hz, rtol=RTOL_FREQUENCY, atol=0)
    assert np.all(np.abs(_mac_diagonal(new.shapes, ref.shapes) - 1.0) <= MAC_TOL)


def _lab_frame():
    from framework.structures.lab_frame import detailed as lab_frame_detailed

    return lab_frame_detailed.make_model(), {"k_r2": 600.0, "k_r3": 20000.0}


def _lab_frame_effects():
    from framework.structures.lab_frame import effects as lab_effects

    model = lab_effects.make_model({"semi_rigid_joints": "", "sensor_mass_eccentricity": ""})
    return model, {"flex_r2": 1.5, "flex_r3": 0.5, "sensor_x_m": 0.2, "sensor_y_m": -0.22}


def _beam():
    from framework.structures.beam import model as beam

    model = beam.make_opensees_model()
    return model, {model.parameters.names[2]: 0.6, model.parameters.names[7]: 0.8}


def _bridge():
    from framework.structures import bridge

    return bridge.make_model(fast=False), dict(zip(bridge.PARAMETER_NAMES, [0.8, 1.1, 0.9, 1.2, 0.7, 1.05]))


def _own_model():
    return runpy.run_path(str(ROOT / "examples" / "own_model.py"))["model"], {"k1_n_per_m": 2.6e6}


def _faulty_build():
    from tests import faulty_build

    return faulty_build.make_model(), dict(faulty_build.TRUTH)


STRUCTURES = {
    "lab_frame_detailed": (_lab_frame, ("-genBandArpack", "-fullGenLapack")),
    "lab_frame_effects": (_lab_frame_effects, ("-genBandArpack",)),
    "beam": (_beam, ("-fullGenLapack",)),
    "bridge_plain": (_bridge, ("",)),
    "own_model": (_own_model, ("-fullGenLapack",)),
    "faulty_build": (_faulty_build, ("-fullGenLapack",)),
}


@pytest.mark.parametrize("name", list(STRUCTURES))
def test_scipy_solver_agrees_with_opensees_solvers(name):
    make, references = STRUCTURES[name]
    model, theta = make()
    new = dataclasses.replace(model, solver="scipy").modal(theta)
    for flag in references:  # OpenSees' own solvers rebuild the model at every evaluation
        ref = dataclasses.replace(model, solver=flag, linear_parameters=()).modal(theta)
        _assert_agree(new, ref)
        for key, values in ref.mode_info.items():  # the bridge's postprocess: energy shares, mode types
            if np.asarray(values).dtype.kind == "f":
                np.testing.assert_allclose(new.mode_info[key], values, rtol=1e-9, atol=1e-12)
            else:
                assert list(new.mode_info[key]) == list(values)


def test_default_solver_is_scipy_and_bad_flags_are_rejected():
    model, _ = _own_model()
    assert dataclasses.replace(model, solver=OpenSeesModel.solver).solver == "scipy"
    with pytest.raises(ValueError, match="solver must be 'scipy' or an OpenSees eigen flag"):
        dataclasses.replace(model, solver="lapack")


# ---- multi-point constraints ---------------------------------------------------------------
PARAMS = ParameterSet([Parameter("E", 2.0e11, 1.0e11, 3.0e11, "Pa", "Young's modulus")])


def _frame_3d(v, equal_dof=None):
    """A 3D portal: floor on a rigid diaphragm, roof node with an arm on a rigid beam link, a
    point on a rigid bar and a node tied by an equalDOF in x and z."""
    equal_dof = equal_dof or ops.equalDOF
    ops.model("basic", "-ndm", 3, "-ndf", 6)
    for i, (x, y) in enumerate([(0.0, 0.0), (4.0, 0.0), (4.0, 3.0), (0.0, 3.0)]):
        ops.node(1 + i, x, y, 0.0)
        ops.node(11 + i, x, y, 3.0)
        ops.fix(1 + i, 1, 1, 1, 1, 1, 1)
    ops.node(20, 2.2, 1.4, 3.0)  # diaphragm master, off the centre
    ops.fix(20, 0, 0, 1, 1, 1, 0)
    ops.rigidDiaphragm(3, 20, 11, 12, 13, 14)
    ops.node(40, 4.0, 3.0, 4.0)  # roof node above 13
    ops.node(30, 5.0, 3.5, 4.4)  # arm end: rigid beam link from 40
    ops.rigidLink("beam", 40, 30)
    ops.node(31, 4.5, 3.0, 4.0)  # rigid bar from 40: same translations
    ops.rigidLink("bar", 40, 31)
    ops.node(41, 3.0, 3.0, 4.0)  # equal x and z displacement as 40
    equal_dof(40, 41, 1, 3)
    ops.geomTransf("Linear", 1, 0.0, 1.0, 0.0)  # vertical members
    ops.geomTransf("Linear", 2, 0.0, 0.0, 1.0)  # horizontal members
    section = (0.01, v["E"], 0.4 * v["E"], 2e-5, 1e-5, 1.2e-5)
    for i in range(4):
        ops.element("elasticBeamColumn", 1 + i, 1 + i, 11 + i, *section, 1)
    ops.element("elasticBeamColumn", 10, 13, 40, *section, 1)
    ops.element("elasticBeamColumn", 11, 40, 41, *section, 2)
    ops.element("elasticBeamColumn", 12, 31, 41, *section, 2)
    for node in (11, 12, 13, 14):
        ops.mass(node, 500.0, 500.0, 500.0, 0.0, 0.0, 0.0)
    ops.mass(30, 100.0, 100.0, 100.0, 0.0, 0.0, 0.0)
    ops.mass(31, 200.0, 200.0, 200.0, 0.0, 0.0, 0.0)
    ops.mass(40, 50.0, 50.0, 50.0, 0.0, 0.0, 0.0)
    ops.mass(41, 80.0, 80.0, 80.0, 0.0, 0.0, 0.0)


def _frame_3d_unrecorded(v):
    return _frame_3d(v, equal_dof=_unrecorded_equal_dof)


def _frame_2d(v):
    ops.model("basic", "-ndm", 2, "-ndf", 3)
    ops.node(1, 0.0, 0.0)
    ops.node(2, 0.0, 3.0)
    ops.node(3, 1.5, 3.5)  # on a rigid beam link from 2
    ops.fix(1, 1, 1, 1)
    ops.geomTransf("Linear", 1)
    ops.element("elasticBeamColumn", 1, 1, 2, 0.01, v["E"], 2e-5, 1)
    ops.rigidLink("beam", 2, 3)
    ops.mass(2, 300.0, 300.0, 0.0)
    ops.mass(3, 100.0, 100.0, 2.0)


CONSTRAINED_3D = {f"n{n}_{d}": (n, d) for n in (11, 13, 30, 31, 41) for d in range(1, 7)}
CONSTRAINED_2D = {f"n3_{d}": (3, d) for d in (1, 2, 3)}


def _eigenvectors(result, info, ops_view, nodes):
    """Postprocess recording every DOF of ``nodes`` as the ops it receives reports them."""
    vectors = np.array([[v for n in nodes for v in ops_view.nodeEigenvector(n, j + 1)] for j in range(result.n_modes)])
    return dataclasses.replace(result, meta={**result.meta, "vectors": vectors.T})


@pytest.mark.parametrize("build, dofs", [(_frame_3d, CONSTRAINED_3D), (_frame_2d, CONSTRAINED_2D)])
def test_constrained_nodes_are_recovered_from_their_retained_nodes(build, dofs):
    nodes = sorted({n for n, _ in dofs.values()})
    post = functools.partial(_eigenvectors, nodes=nodes)
    n_modes = 3 if build is _frame_2d else 6
    new = OpenSeesModel(build, PARAMS, dofs, n_modes=n_modes, postprocess=post).modal({})
    ref = OpenSeesModel(build, PARAMS, dofs, n_modes=n_modes, postprocess=post, solver="-fullGenLapack").modal({})
    _assert_agree(new, ref)
    mac = _mac_diagonal(new.meta["vectors"], ref.meta["vectors"])
    assert np.all(np.abs(mac - 1.0) <= MAC_TOL)
    assert np.abs(new.shapes).max() > 0.0


def test_unrecorded_constraint_falls_back_to_opensees_full_lapack(caplog):
    dofs = {"n41_x": (41, 1), "n41_y": (41, 2), "n11_x": (11, 1)}
    with caplog.at_level(logging.WARNING, logger="framework.models.opensees"):
        new = OpenSeesModel(_frame_3d_unrecorded, PARAMS, dofs, n_modes=4).modal({})
    assert "not known" in caplog.text and "-fullGenLapack" in caplog.text
    ref = OpenSeesModel(_frame_3d_unrecorded, PARAMS, dofs, n_modes=4, solver="-fullGenLapack").modal({})
    _assert_agree(new, ref)
    # the recorded build gives the same modes through scipy
    _assert_agree(OpenSeesModel(_frame_3d, PARAMS, dofs, n_modes=4).modal({}), ref)


# ---- normalization and failures ------------------------------------------------------------
def test_shapes_are_mass_normalized_with_the_largest_measured_component_positive():
    model, _ = _own_model()  # two floors, both measured: M = diag(1000, 800) kg
    result = dataclasses.replace(model, solver="scipy").modal({"k1_n_per_m": 2.6e6, "k2_n_per_m": 1.2e6})
    s = result.shapes
    np.testing.assert_allclose(s.T @ np.diag([1000.0, 800.0]) @ s, np.eye(2), atol=1e-12)
    for j in range(2):
        assert s[np.argmax(np.abs(s[:, j])), j] > 0.0


@pytest.mark.parametrize("dofs, message", [({"a": (7, 1)}, "bad_dof: the model has no node 7"),
                                           ({"a": (2, 2)}, "bad_dof: node 2 has DOFs 1..1, not 2")])
def test_a_measured_dof_the_model_lacks_is_a_failure_with_a_reason(dofs, message):
    model, _ = _own_model()
    with pytest.raises(ModelEvaluationError, match=message):
        dataclasses.replace(model, measured_dofs=dofs, solver="scipy").modal({})


def test_too_many_modes_is_a_failure_with_a_reason():
    model, _ = _own_model()
    with pytest.raises(ModelEvaluationError, match="too_few_modes: n_modes=3 > 2 DOFs with mass"):
        dataclasses.replace(model, n_modes=3, solver="scipy").modal({})


def test_sparse_shift_invert_path_agrees_with_the_dense_path(monkeypatch):
    from framework.models import eigen_solve

    model, theta = _lab_frame()
    model = dataclasses.replace(model, solver="scipy")
    dense = model.modal(theta)
    monkeypatch.setattr(eigen_solve, "DENSE_LIMIT", 10)  # 318 equations, 3 of 159 massive modes: shift-invert
    sparse = model.modal(theta)
    _assert_agree(sparse, dense)
    again = model.modal(theta)
    assert np.array_equal(sparse.frequencies_hz, again.frequencies_hz) and np.array_equal(sparse.shapes, again.shapes)


# ---- history independence ------------------------------------------------------------------
_HISTORY_SCRIPT = """
import sys
import numpy as np
from framework.structures.lab_frame import detailed as lab_frame_detailed
model = lab_frame_detailed.make_model(solver=sys.argv[1])
point = {"k_r2": 700.0, "k_r3": 15000.0}
others = [{"k_r2": 100.0 + 150.0 * i, "k_r3": 1000.0 + 4000.0 * i} for i in range(8)]
def digest(r):
    return (r.frequencies_hz.tobytes() + r.shapes.tobytes()).hex()
out = [digest(model.modal(point))]          # after 0 other evaluations
model.modal(others[0])
out.append(digest(model.modal(point)))      # after 1
for theta in others[1:]:
    model.modal(theta)
out.append(digest(model.modal(point)))      # after 7 more
print(" ".join(out))
"""


def test_same_point_gives_bit_identical_modes_whatever_ran_before_in_the_process():
    proc = subprocess.run([sys.executable, "-c", _HISTORY_SCRIPT, "scipy"], capture_output=True, text=True,
                          cwd=ROOT, timeout=300, check=True)
    digests = proc.stdout.split()
    assert len(digests) == 3 and len(set(digests)) == 1
    # and the same bits in this process, after everything the test session ran before
    from framework.structures.lab_frame import detailed as lab_frame_detailed

    r = lab_frame_detailed.make_model(solver="scipy").modal({"k_r2": 700.0, "k_r3": 15000.0})
    assert (r.frequencies_hz.tobytes() + r.shapes.tobytes()).hex() == digests[0]


def _study(tmp_path: Path, name: str, execution: dict) -> Path:
    from framework.study.config import validate
    from framework.study.runner import run_study

    data = {
        "study": "lab_frame_detailed_small",
        "structure": {"name": "lab_frame_detailed", "options": {"solver": "scipy"}},
        "measured": {"builtin": "lab_frame", "case": "base"},
        "validation": [{"case": "mass_0.654kg", "structure_options": {"case": "mass_0.654kg"},
                        "measured": {"builtin": "lab_frame", "case": "mass_0.654kg"}}],
        "parameters": {"names": ["k_r2", "k_r3"], "bounds": {"k_r2": [79.73, 1594.6], "k_r3": [354.55, 35455.0]}},
        "objective": {"alpha": 1.0, "beta": 1.0, "pairing": "mac", "mac_threshold": 0.5},
        "budget": {"max_evaluations": 24, "target_objective": None},
        "algorithms": {"pso": {"algorithm": "pso", "settings": {"swarm_size": 6}},
                       "sm": {"algorithm": "sm", "settings": {"start": "initial"}, "runs": 1}},
        "runs": 2,
        "seed": 0,
        "execution": {"progress": False, **execution},
        "output": str(tmp_path / name),
    }
    run_study(validate(data), figures=False)
    return tmp_path / name


def test_lab_frame_detailed_study_gives_identical_tables_serially_and_on_processes(tmp_path):
    serial = _study(tmp_path, "serial", {"backend": "serial"})
    procs = _study(tmp_path, "procs", {"backend": "processes", "workers": 2})
    for table in ("runs", "parameters", "modes", "history"):
        a, b = pd.read_parquet(serial / f"{table}.parquet"), pd.read_parquet(procs / f"{table}.parquet")
        a, b = a.drop(columns=["wall_s"], errors="ignore"), b.drop(columns=["wall_s"], errors="ignore")
        pd.testing.assert_frame_equal(a, b, check_exact=True, obj=table)
    runs = pd.read_parquet(serial / "runs.parquet")
    assert len(runs) == 3 and (runs["n_failed_evaluations"] == 0).all() and (runs["status"] != "failed").all()


# ---- stiffness linear in declared parameters -------------------------------------------------
CHAIN = ParameterSet([
    Parameter("k1_n_per_m", 2.0e6, 1.0e6, 4.0e6, "N/m", "storey 1 stiffness"),
    Parameter("k2_n_per_m", 1.5e6, 0.5e6, 3.0e6, "N/m", "storey 2 stiffness"),
    Parameter("m2_kg", 800.0, 600.0, 1000.0, "kg", "floor 2 mass"),
])


def _chain(v, square_k2=False):
    ops.model("basic", "-ndm", 1, "-ndf", 1)
    for tag in (0, 1, 2):
        ops.node(tag, 0.0)
    ops.fix(0, 1)
    ops.uniaxialMaterial("Elastic", 1, v["k1_n_per_m"])
    ops.uniaxialMaterial("Elastic", 2, v["k2_n_per_m"] ** 2 / 1.5e6 if square_k2 else v["k2_n_per_m"])
    ops.element("zeroLength", 1, 0, 1, "-mat", 1, "-dir", 1)
    ops.element("zeroLength", 2, 1, 2, "-mat", 2, "-dir", 1)
    ops.mass(1, 1000.0)
    ops.mass(2, v["m2_kg"])


def _chain_square(v):
    return _chain(v, square_k2=True)


def _chain_model(build=_chain, linear=("k1_n_per_m", "k2_n_per_m")):
    return OpenSeesModel(build, CHAIN, {"floor1": (1, 1), "floor2": (2, 1)}, n_modes=2, linear_parameters=linear)


def test_linear_parameters_give_the_modes_of_a_build_per_evaluation():
    model, theta = _lab_frame()
    names = tuple(model.parameters.names)  # the six bracket springs: zeroLength elastic stiffnesses
    direct = dataclasses.replace(model, solver="scipy")
    linear = dataclasses.replace(model, solver="scipy", linear_parameters=names)
    _assert_agree(linear.modal(theta), direct.modal(theta))
    _assert_agree(linear.modal({"k_u3": 1.0e7, "k_r1": 500.0}), direct.modal({"k_u3": 1.0e7, "k_r1": 500.0}))
    assert "_linear" in linear.__dict__
    fresh = pickle.loads(pickle.dumps(linear))  # operators are not shipped to workers ...
    assert "_linear" not in fresh.__dict__
    a, b = fresh.modal(theta), linear.modal(theta)  # ... and extracted again to the same bits
    assert a.frequencies_hz.tobytes() == b.frequencies_hz.tobytes() and a.shapes.tobytes() == b.shapes.tobytes()


def test_linear_parameters_fall_back_to_a_build_when_another_parameter_changes():
    linear, direct = _chain_model(), OpenSeesModel(_chain, CHAIN, {"floor1": (1, 1), "floor2": (2, 1)}, n_modes=2)
    theta = {"k1_n_per_m": 2.5e6, "m2_kg": 900.0}
    a, b = linear.modal(theta), direct.modal(theta)
    assert a.frequencies_hz.tobytes() == b.frequencies_hz.tobytes()  # built: the same computation
    np.testing.assert_allclose(linear.modal({"k2_n_per_m": 1.0e6}).frequencies_hz,
                               direct.modal({"k2_n_per_m": 1.0e6}).frequencies_hz, rtol=1e-12)


@pytest.mark.parametrize("build, linear, message", [
    (_chain, ("k2_n_per_m", "m2_kg"), "nonlinear_parameter: m2_kg changes the mass matrix"),
    (_chain_square, ("k1_n_per_m", "k2_n_per_m"), r"nonlinear_parameter: the stiffness is not linear in"),
])
def test_a_wrong_linear_declaration_fails_every_evaluation_relying_on_it(build, linear, message):
    model = _chain_model(build, linear)
    for _ in range(2):
        with pytest.raises(ModelEvaluationError, match=message):
            model.modal({"k2_n_per_m": 1.0e6})


def test_linear_parameters_are_checked_at_construction():
    with pytest.raises(ValueError, match=r"linear_parameters: unknown parameter\(s\) \['k3'\]"):
        _chain_model(linear=("k3",))
    with pytest.raises(ValueError, match="linear_parameters needs solver 'scipy'"):
        dataclasses.replace(_chain_model(), solver="-fullGenLapack")
