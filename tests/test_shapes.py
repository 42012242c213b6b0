"""Mode-shape and correlation tables (framework.report.shape_tables) and their figures (framework.report.figures)."""

import runpy
from pathlib import Path

import numpy as np
import pandas as pd
import pytest

from framework.measured.modes import MeasuredModes
from framework.models.geometry import model_shapes
from framework.report.figures import draw_problem_shapes
from framework.report.figures.shapes import paired_figure
from framework.report.shape_tables import shape_tables
from framework.structures.lab_frame.model import make_model, measured
from framework.study.config import validate
from framework.study.runner import report, run_study
from framework.updating.problem import UpdatingProblem

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
    assert np.nanmax(np.hypot(modes["ux"], modes["uy"])) == pytest.approx(1.0, abs=1e-5)  # 5 decimals
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
    pytest.importorskip("plotly")
    from framework.report.figures.interactive import all_html

    pages = all_html(tmp_path)
    assert [p.name for p in pages] == ["shapes_initial.html", "shapes_updated.html"]
    assert "10.7" in pages[0].read_text()  # the slider names mode 2 by its frequency (10.74 Hz)


def test_study_writes_shape_tables_on_resume_and_report_needs_no_model(tmp_path, monkeypatch):
    cfg = validate({"study": "lab_small", "structure": {"name": "lab_frame_3dof"},
                    "measured": {"builtin": "lab_frame"}, "budget": {"max_evaluations": 300},
                    "algorithms": {"sm": {"algorithm": "sm", "settings": {"start": "initial"}}},
                    "runs": 1, "output": str(tmp_path / "lab")})
    run_study(cfg, progress=False, figures=False, shapes=True)
    out = tmp_path / "lab"
    for name in ("geometry", "mode_shapes", "sensor_shapes", "mac_matrix", "comac"):
        (out / f"{name}.csv").unlink()
    run_study(cfg, resume=True, progress=False, figures=False, shapes=True)  # nothing left to run
    assert (out / "mac_matrix.csv").exists()
    states = set(pd.read_csv(out / "mode_shapes.csv")["state"])
    assert states == {"initial", "updated"}

    import framework.structures.registry as registry

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
    t = shape_tables(UpdatingProblem(model, data), {"initial": model.parameters.initial})
    assert t["geometry"].empty and t["mode_shapes"].empty
    assert set(t["sensor_shapes"]["layout"]) == {"channels"}
    np.testing.assert_allclose(t["sensor_shapes"]["measured_ux"], t["sensor_shapes"]["model_ux"], atol=1e-5)
    path = paired_figure(None, t["mode_shapes"], t["sensor_shapes"], tmp_path / "p.png", "initial")
    assert path.stat().st_size > 5000
