"""Mode-shape and correlation tables (framework.shapes) and their figures (framework.figures)."""

import runpy
from pathlib import Path

import numpy as np
import pandas as pd
import pytest

from framework.figures import draw_problem_shapes, shape_figures
from framework.measurements import MeasuredModes
from framework.models.lab_frame import make_model, measured
from framework.problem import UpdatingProblem
from framework.shapes.geometry import model_shapes
from framework.shapes.tables import shape_tables
from framework.study.config import validate
from framework.study.runner import report, run_study

ROOT = Path(__file__).resolve().parents[1]


def _lab_problem(data=None):
    model = make_model()
    return UpdatingProblem(model, data or measured("base"))


def test_lab_frame_tables_pair_measured_with_model_and_move_the_slab_rigidly():
    problem = _lab_problem()
    theta0 = problem.parameters.initial
    t = shape_tables(problem, {"initial": theta0})
    geo = t["geometry"]
    assert (geo["kind"] == "node").sum() == 8 and (geo["kind"] == "element").sum() == 8
    mac = t["mac_matrix"]
    mvm = mac[mac["kind"] == "measured_vs_model"].pivot(index="i", columns="j", values="mac").to_numpy()
    assert mvm.shape == (3, 3)
    assert np.all(np.diag(mvm) > 0.97)  # SPEC 5: the initial model's modes are in the measured order
    auto = mac[mac["kind"] == "auto_measured"].pivot(index="i", columns="j", values="mac").to_numpy()
    np.testing.assert_allclose(np.diag(auto), 1.0)
    # the slab is rigid: the four corners' x displacement differs only through the torsion
    modes = t["mode_shapes"]
    slab = modes[(modes["node"] > 4) & (modes["mode"] == 1)]
    assert np.nanmax(np.hypot(modes["ux"], modes["uy"])) == pytest.approx(1.0)
    assert slab["uz"].abs().max() == 0.0
    comac = t["comac"]
    assert set(comac["dof"]) == {"y", "x", "torsion"} and comac["comac"].between(0.9, 1.0).all()


def test_measured_equal_to_model_modes_lies_on_the_model_shape():
    problem = _lab_problem()
    theta = problem.parameters.initial
    r = problem.model.modal(problem.parameters.as_dict(theta))
    data = MeasuredModes(r.frequencies_hz, r.dofs, -2.5 * r.shapes)  # any scale and sign
    t = shape_tables(UpdatingProblem(problem.model, data), {"initial": theta})
    s = t["sensor_shapes"]
    for c in "xyz":
        np.testing.assert_allclose(s[f"measured_u{c}"], s[f"model_u{c}"], atol=1e-12)
    np.testing.assert_allclose(s["mac"], 1.0)


def test_opensees_user_model_from_examples_renders_a_mode_shape_figure(tmp_path):
    pytest.importorskip("openseespy.opensees")
    ns = runpy.run_path(str(ROOT / "examples" / "own_model.py"))
    model = ns["model"]
    truth = model.modal({"k1_n_per_m": 2.6e6, "k2_n_per_m": 1.2e6})
    data = MeasuredModes(truth.frequencies_hz, ("floor1", "floor2"), truth.shapes)
    problem = UpdatingProblem(model, data)
    shapes = model_shapes(model, {})
    assert shapes.has_geometry and shapes.node_shapes.shape == (3, 3, 2)
    # node shapes agree with the model's shapes at the measured DOFs (mass-normalized)
    np.testing.assert_allclose(shapes.node_shapes[1:, 0, :], shapes.dof_shapes, rtol=1e-9, atol=1e-12)
    files = draw_problem_shapes(problem, {"initial": problem.parameters.initial,
                                          "updated": np.array([2.6e6, 1.2e6])}, tmp_path)
    names = {f.name for f in files}
    assert {"shapes_model.png", "shapes_paired_initial.png", "shapes_paired_updated.png", "mac_matrix.png"} <= names
    assert all(f.stat().st_size > 5000 for f in files)
    upd = pd.read_csv(tmp_path / "sensor_shapes.csv").query("state == 'updated'")
    np.testing.assert_allclose(upd["mac"], 1.0, atol=1e-9)


def test_study_writes_shape_tables_on_resume_and_report_needs_no_model(tmp_path, monkeypatch):
    cfg = validate({"study": "lab_small", "structure": {"name": "lab_frame_3dof"},
                    "measured": {"builtin": "lab_frame"}, "budget": {"max_evaluations": 300},
                    "algorithms": {"sm": {"algorithm": "sm", "settings": {"start": "initial"}}},
                    "runs": 1, "output": str(tmp_path / "lab")})
    run_study(cfg, progress=False, figures=False)
    out = tmp_path / "lab"
    for name in ("geometry", "mode_shapes", "sensor_shapes", "mac_matrix", "comac"):
        (out / f"{name}.csv").unlink()
    run_study(cfg, resume=True, progress=False, figures=False)  # nothing left to run
    assert (out / "mac_matrix.csv").exists()
    states = set(pd.read_csv(out / "mode_shapes.csv")["state"])
    assert states == {"initial", "updated"}

    import framework.models.registry as registry

    def broken(*args, **kwargs):
        raise RuntimeError("model cannot be built here")

    monkeypatch.setattr(registry, "make_structure", broken)
    written = {p.name for p in report(out)}
    assert {"shapes_paired_updated.png", "mac_matrix.png", "comac.png"} <= written


def test_model_without_geometry_is_drawn_by_channel(tmp_path):
    class Chain:
        """A 2-DOF model without geometry (as a matrix model without coordinates)."""

        def __init__(self):
            self.inner = make_model()

        parameters = property(lambda self: self.inner.parameters)
        dofs = ("a", "b", "c")

        def modal(self, theta):
            from framework.models.base import ModalResult

            r = self.inner.modal(theta)
            return ModalResult(r.frequencies_hz, r.shapes, ("a", "b", "c"))

    model = Chain()
    r = model.modal({})
    data = MeasuredModes(r.frequencies_hz, ("a", "b", "c"), r.shapes)
    files = draw_problem_shapes(UpdatingProblem(model, data), {"initial": model.parameters.initial}, tmp_path)
    assert (tmp_path / "shapes_paired_initial.png") in files
    assert set(pd.read_csv(tmp_path / "sensor_shapes.csv")["layout"]) == {"channels"}
    assert pd.read_csv(tmp_path / "geometry.csv").empty if (tmp_path / "geometry.csv").stat().st_size > 1 else True
    assert shape_figures(tmp_path)
