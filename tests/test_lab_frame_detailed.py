"""Tests of the detailed OpenSeesPy lab-frame model (SPEC 5, issue 6)."""

from __future__ import annotations

import pickle
from collections import Counter
from pathlib import Path

import numpy as np
import pandas as pd
import pytest

pytest.importorskip("openseespy")

from framework.core.correlation import mac_paired  # noqa: E402
from framework.core.errors import InputError  # noqa: E402
from framework.models.opensees import ops_module  # noqa: E402
from framework.structures.lab_frame import detailed as lfd  # noqa: E402


@pytest.fixture
def ops():
    ops = ops_module()
    ops.wipe()
    yield ops
    ops.wipe()


def test_build_has_expected_nodes_elements_and_supports(ops):
    info = lfd.build(dict(lfd.BRACKET_STIFFNESS))
    nodes = ops.getNodeTags()
    # 25 slab + 4 x 7 column + 4 base + 4 link nodes (columns inset from the corners)
    assert len(nodes) == 25 + 28 + 4 + 4
    types = Counter(ops.eleType(tag) for tag in ops.getEleTags())
    assert types == {"ShellMITC4": 16, "ElasticBeam3d": 24, "ZeroLength": 8}
    assert sorted(ops.getFixedNodes()) == [1001, 1002, 1003, 1004]
    assert info["centre_node"] == 13
    np.testing.assert_allclose(ops.nodeCoord(13), [0.0, 0.0, 0.7])
    # column axes 30 mm inside both slab edges, 700 mm tall
    np.testing.assert_allclose(ops.nodeCoord(info["column_nodes"][2][-1]), [0.295, 0.295, 0.7])
    np.testing.assert_allclose(ops.nodeCoord(info["column_nodes"][0][0]), [-0.295, -0.295, 0.0])


def test_column_option_changes_mesh_counts(ops):
    lfd.build(dict(lfd.BRACKET_STIFFNESS), mesh=8, column_elements=3, column_inset_m=0.0)
    assert len(ops.getNodeTags()) == 81 + 16 + 4  # no link nodes with columns at the corners
    assert Counter(ops.eleType(t) for t in ops.getEleTags())["ShellMITC4"] == 64
    ops.wipe()
    with pytest.raises(InputError, match="not a node of the 6 x 6 slab mesh"):
        lfd.build(dict(lfd.BRACKET_STIFFNESS), mesh=6)


def test_total_mass_centre_of_mass_and_polar_moment():
    props = lfd.mass_properties()
    assert props["total_kg"] == pytest.approx(17.5, rel=0.01)
    assert props["total_kg"] == pytest.approx(17.5, rel=1e-6)
    assert props["xcm_m"] == pytest.approx(-0.0103, abs=1e-6)
    assert props["ycm_m"] == pytest.approx(0.0062, abs=1e-6)
    assert props["polar_about_centre_kg_m2"] == pytest.approx(1.2645, rel=1e-6)


def test_added_mass_goes_to_the_slab_centre():
    from framework.structures.lab_frame.model import block_dimensions

    props = lfd.mass_properties(added_mass_kg=1.379)
    assert props["total_kg"] == pytest.approx(17.5 + 1.379, rel=1e-6)
    # a block at the origin keeps the static moments; the polar moment about the centre
    # grows by the block's own J = m d^2 / 8 (steel cylinder, h = d: 6.35e-4 kg m^2)
    assert props["xcm_m"] * props["total_kg"] == pytest.approx(-0.0103 * 17.5, rel=1e-6)
    j_block = block_dimensions(1.379)["polar_inertia_kg_m2"]
    assert j_block == pytest.approx(6.35e-4, rel=1e-3)
    assert props["polar_about_centre_kg_m2"] == pytest.approx(1.2645 + j_block, rel=1e-6)
    point = lfd.mass_properties(added_mass_kg=1.379, added_block="point")
    assert point["polar_about_centre_kg_m2"] == pytest.approx(1.2645, rel=1e-6)


def test_slab_lumping_is_exact_for_mass_and_polar_moment():
    m = lfd.slab_lumped_masses_kg(4)
    xy = lfd.slab_coordinates(4)
    mass = 7850 * 0.004 * 0.65**2
    assert m.sum() == pytest.approx(mass, rel=1e-12)
    assert (m * (xy**2).sum(axis=1)).sum() == pytest.approx(mass * 0.65**2 / 6, rel=1e-12)


def test_nonstructural_masses_reject_infeasible_positions():
    with pytest.raises(InputError, match="no non-negative masses"):
        lfd.nonstructural_masses([(0.325, 0.325), (0.325, -0.325), (-0.325, 0.325), (-0.325, -0.325)])
    with pytest.raises(InputError, match=">= 4 mass positions"):
        lfd.nonstructural_masses([(0.0, 0.0)])


def test_bad_inputs_name_the_field(ops):
    values = dict(lfd.BRACKET_STIFFNESS, k_r2=-1.0)
    with pytest.raises(InputError, match="k_r2 must be > 0"):
        lfd.build(values)
    with pytest.raises(InputError, match="missing for \\['k_u1'\\]"):
        lfd.build({k: v for k, v in lfd.BRACKET_STIFFNESS.items() if k != "k_u1"})
    with pytest.raises(InputError, match="mesh must be an even number"):
        lfd.build(dict(lfd.BRACKET_STIFFNESS), mesh=3)
    with pytest.raises(InputError, match="unknown case 'heavy'"):
        lfd.make_model(case="heavy")


def test_each_bracket_component_gets_its_own_stiffness(ops):
    values = {name: 1000.0 * (i + 1) for i, name in enumerate(lfd.BRACKET_STIFFNESS)}
    info = lfd.build(values)
    assert len(info["bracket_elements"]) == 8
    for ele in info["bracket_elements"]:
        tangents = [ops.eleResponse(ele, "material", k, "tangent")[0] for k in range(1, 7)]
        np.testing.assert_allclose(tangents, list(values.values()))


def test_bracket_axes_map_kr2_to_y_sway_and_kr3_to_x_sway():
    model = lfd.make_model()
    f0 = model.modal({}).frequencies_hz[:3]
    f_r2 = model.modal({"k_r2": 0.5 * 797.3}).frequencies_hz[:3]
    f_r3 = model.modal({"k_r3": 0.1 * 35455.0}).frequencies_hz[:3]
    # mode 1 is the y sway, mode 2 the x sway
    assert f_r2[0] < 0.9 * f0[0] and f_r2[1] == pytest.approx(f0[1], rel=0.005)
    assert f_r3[1] < 0.8 * f0[1] and f_r3[0] == pytest.approx(f0[0], rel=0.005)
    # k_u3 (through the strip thickness) acts in y: a very soft value lowers the y sway only
    f_u3 = model.modal({"k_u3": 0.05 * 2.4e7}).frequencies_hz[:3]
    assert f_u3[0] < f0[0] and f_u3[1] == pytest.approx(f0[1], rel=1e-3)


def test_initial_frequencies_and_mode_order():
    model = lfd.make_model()
    result = model.modal({})
    # documented initial values (source's detailed model: about 3.58, 7.97, 10.29 Hz)
    np.testing.assert_allclose(result.frequencies_hz[:3], [3.7206, 8.2192, 10.5077], rtol=2e-3)
    assert result.dofs == ("y", "x", "torsion")
    measured = lfd.measured("base")
    macs = mac_paired(result.at(measured.dofs)[:, :3], measured.shapes)
    assert np.all(macs > 0.95), macs


def test_model_is_picklable_and_pure():
    model = lfd.make_model(added_mass_kg=0.654)
    clone = pickle.loads(pickle.dumps(model))
    a = model.modal({"k_r2": 700.0}).frequencies_hz
    b = clone.modal({"k_r2": 700.0}).frequencies_hz
    np.testing.assert_allclose(a, b, rtol=1e-10)
    np.testing.assert_allclose(model.modal({"k_r2": 700.0}).frequencies_hz, a, rtol=1e-10)


def test_short_sensitivity_method_update_reaches_measured_frequencies():
    from framework.optimizers import Budget, run_optimizer
    from framework.updating.problem import UpdatingProblem

    model = lfd.make_model()
    params = model.parameters.subset(lfd.UPDATED_PARAMETERS)
    problem = UpdatingProblem(model, lfd.measured("base"), parameters=params)
    pi0 = problem.objective1(problem.x_initial)
    result = run_optimizer("sm", problem, seed=0, budget=Budget(max_evaluations=120))
    assert result.objective < 1e-3 < pi0
    table = problem.mode_table(result.theta_best)
    assert np.all(np.abs(table["error_pct"]) < 1.0), table
    assert table["matched"].all()
    k_r2, k_r3 = result.theta_best
    assert 650 < k_r2 < 800 and 1500 < k_r3 < 2400


def test_short_pso_run_improves_on_the_initial_model():
    from framework.optimizers import Budget, run_optimizer
    from framework.updating.problem import UpdatingProblem

    model = lfd.make_model()
    params = model.parameters.subset(lfd.UPDATED_PARAMETERS)
    problem = UpdatingProblem(model, lfd.measured("base"), parameters=params)
    pi0 = problem.objective1(problem.x_initial)
    result = run_optimizer(
        "pso", problem, seed=3, budget=Budget(max_evaluations=200, target_objective=None), swarm_size=10
    )
    assert result.n_evaluations <= 200
    assert result.objective < 0.01 * pi0


def test_only_global_modes_are_paired_with_the_three_measured_dofs():
    """Local slab modes (> 20 Hz) look like pure x at the centre node (MAC ~0.99 on three
    DOFs); the model returns the three global modes only, so pairing cannot pick them."""
    from framework.updating.problem import UpdatingProblem

    model = lfd.make_model(column_inset_m=0.04)
    assert model.n_modes == 3
    problem = UpdatingProblem(model, lfd.measured("base"), parameters=model.parameters.subset(["k_r2", "k_r3"]))
    table = problem.mode_table(problem.parameters.initial)
    np.testing.assert_allclose(table["f_model_hz"], [3.698, 8.148, 10.088], rtol=2e-3)
    assert table["matched"].all()


ROOT = Path(__file__).resolve().parents[1]


def _study(name, tmp_path, **changes):
    """A committed study config with changes, run into tmp_path; its tables."""
    from framework.study.config import load, validate
    from framework.study.runner import run_study

    data = load(ROOT / "studies" / f"{name}.yaml").model_dump(mode="json")
    data.update(output=str(tmp_path / name), **changes)
    data["execution"]["progress"] = False
    tables = run_study(validate(data), figures=False)
    return {k: v for k, v in tables.items()} | {
        p.stem: pd.read_csv(p) for p in (tmp_path / name).glob("*.csv") if p.stem not in tables}


def test_sensitivity_study_finds_only_the_bending_brackets_sensitive(tmp_path):
    """studies/lab_frame_detailed_sensitivity.yaml (run kind analysis), initial detailed model."""
    t = _study("lab_frame_detailed_sensitivity", tmp_path, variants={}, points={"initial": {}},
               report={"sensitivity": {}})
    sens = t["sensitivity"].set_index(["parameter", "mode"])["rel_sensitivity_frequency"]
    assert sens[("k_r2", 1)] > 0.3 and sens[("k_r3", 2)] > 0.03 and abs(sens[("k_u1", 1)]) < 1e-3
    summary = t["sensitivity_summary"].set_index("parameter")
    assert set(summary.index[summary["rank"] <= 2]) == {"k_r2", "k_r3"}
    modes = t["modes"]
    base = modes[modes["case"] == "base"].sort_values("mode")
    np.testing.assert_allclose(base["f_model_hz"], [3.7206, 8.2192, 10.5077], rtol=2e-3)
    assert set(modes["case"]) == {"base", "mass_0.654kg", "mass_1.379kg"}
    assert t["points"]["condition_number"].iloc[0] > 1e6  # six stiffnesses, three frequencies and MACs


def test_committed_updated_point_is_the_best_detailed_run():
    """The sensitivity study's updated point = the best detailed run of studies/lab_frame_detailed.yaml."""
    from framework.study.config import load

    point = load(ROOT / "studies" / "lab_frame_detailed_sensitivity.yaml").points["updated"].values
    best = pd.read_csv(ROOT / "results" / "lab_frame_detailed" / "updating" / "comparison_runs.csv")
    best = best[best["variant"] == "detailed"].iloc[0]
    assert point == {"k_r2": pytest.approx(best["k_r2"], rel=1e-12), "k_r3": pytest.approx(best["k_r3"], rel=1e-12)}


def test_updating_study_meets_acceptance_and_compares_with_the_3dof_model(tmp_path):
    """studies/lab_frame_detailed.yaml with one run per algorithm (~10 s)."""
    t = _study("lab_frame_detailed", tmp_path, runs=1,
               report={"comparison": {"by": "variant"}})
    modes = t["modes"]
    det = modes[modes["variant"] == "detailed"]
    assert set(det["case"]) == {"base", "mass_0.654kg", "mass_1.379kg"}
    assert det[det["case"] == "base"]["error_pct"].abs().max() < 1.0
    assert det["error_pct"].abs().max() < 2.5
    summary = t["comparison_summary"].set_index(["model", "case"])
    assert set(summary.index.get_level_values("model")) == {"detailed", "3dof"}
    assert summary.loc[("detailed", "mass_1.379kg"), "max_abs_error_pct"] < summary.loc[
        ("3dof", "mass_1.379kg"), "max_abs_error_pct"]
    runs = t["comparison_runs"].set_index("model")
    assert 650 < runs.loc["detailed", "k_r2"] < 800 and np.isnan(runs.loc["3dof", "k_r2"])
