"""The one noise model (framework.inference.noise): assumed defaults defined once, sources of the
standard deviations, each formulation's residual scales, the simulator of noisy modes, and the
``gaussian`` formulation through ``gomu run`` with and without standard deviations in the data."""

from __future__ import annotations

import os
import subprocess
import sys
from dataclasses import replace
from pathlib import Path

import numpy as np
import pandas as pd
import pytest
import yaml

from framework.inference.likelihood import noise_model
from framework.inference.noise import DEFAULT_FREQUENCY_STD_REL, DEFAULT_SHAPE_STD_REL, data_noise
from framework.inference.simulate import NOISE_LEVELS, Noise, UniformShapeNoise, noisy_measurement
from framework.measured.modes import save
from framework.structures.registry import builtin_measured, make_structure
from framework.updating.objectives import ObjectiveSpec
from framework.updating.problem import UpdatingProblem

ROOT = Path(__file__).resolve().parents[1]


def test_the_assumed_defaults_are_defined_once_and_used_everywhere():
    from framework.diagnosis.workflow import DiagnoseSettings
    from framework.study.kinds.posterior import NoiseConfig

    assert (DEFAULT_FREQUENCY_STD_REL, DEFAULT_SHAPE_STD_REL) == (0.01, 0.05)
    s = DiagnoseSettings()
    assert (s.frequency_std_rel, s.shape_std_rel) == (DEFAULT_FREQUENCY_STD_REL, DEFAULT_SHAPE_STD_REL)
    n = NoiseConfig()
    assert (n.frequency_std_rel, n.shape_std_rel) == (DEFAULT_FREQUENCY_STD_REL, DEFAULT_SHAPE_STD_REL)
    top = NOISE_LEVELS["very_high"]
    assert (top.frequency_std_rel, top.shape_std_rel) == (DEFAULT_FREQUENCY_STD_REL, DEFAULT_SHAPE_STD_REL)
    m = builtin_measured("lab_frame", "base")
    noise = data_noise(m)
    np.testing.assert_allclose(noise.frequency_std_hz, 0.01 * m.frequencies_hz)
    np.testing.assert_allclose(noise.shape_std, 0.05 * np.max(np.abs(m.shapes), axis=0)[None, :] * np.ones((3, 3)))
    given = data_noise(replace(m, frequency_std_hz=np.array([0.02, 0.03, 0.04])))
    assert (given.frequency_source, given.shape_source) == ("data", "assumed")
    assert given.assumed == "shape std 5 % of the peak"
    assert data_noise(m, use_shapes=False).shape_source == ""


def _draws(formulation: str, n: int, noise: Noise, options=None):
    """Residuals (n, r) at the truth of ``n`` noisy measurements of the 3-DOF lab frame, and the
    noise model of the first (the data carry the noise's standard deviations)."""
    model = make_structure("lab_frame_3dof")
    truth = model.modal({p.name: p.initial for p in model.parameters})
    dofs = builtin_measured("lab_frame", "base").dofs
    rng = np.random.default_rng(5)
    spec = ObjectiveSpec(formulation=formulation, options=options or {})
    rows, first = [], None
    for _ in range(n):
        m = noisy_measurement(truth.frequencies_hz[:3], truth.at(dofs)[:, :3], dofs, noise, rng)
        problem = UpdatingProblem(model, m, objective=spec)
        rows.append(problem.residuals(problem.x_initial)[: problem.n_modal_residuals])
        first = first or noise_model(problem)
    return np.array(rows), first


@pytest.mark.parametrize("formulation, options", [("spec", None), ("reference", None),
                                                  ("reference", {"shape_term": "eigenvector"})])
def test_residual_scales_are_the_residuals_standard_deviations(formulation, options):
    """Monte Carlo (600 noisy data sets at the true parameters): each Gaussian residual row's
    standard deviation equals the formulation's scale (within 10 %: first order in the noise,
    sampling error 3 %); the MAC rows are an approximation and are not checked."""
    R, nm = _draws(formulation, 600, Noise(0.01, 0.02), options)
    gaussian_rows = slice(None) if options else slice(0, 3)
    np.testing.assert_allclose(R[:, gaussian_rows].std(axis=0) / nm.scales[gaussian_rows], 1.0, atol=0.1)
    assert nm.sources == {"frequency": "data", "shape": "data"}


def test_gaussian_residuals_are_standard_normal_and_chi2_has_n_data_degrees():
    R, nm = _draws("gaussian", 600, Noise(0.01, 0.05))
    assert nm.scales == pytest.approx(np.ones(R.shape[1])) and nm.n_data == 3 + 3 * 2
    np.testing.assert_allclose(R[:, :3].std(axis=0), 1.0, atol=0.1)
    assert np.mean(np.sum(R**2, axis=1)) == pytest.approx(nm.n_data, rel=0.1)


def test_simulator_kinds_normalise_shapes_and_draw_from_the_generator():
    f, phi = np.array([2.0, 5.0]), np.array([[1.0, -4.0], [-2.0, 1.0], [0.5, 2.0]])
    m = noisy_measurement(f, phi, ("a", "b", "c"), Noise(0.01, 0.02), np.random.default_rng(3))
    clean = phi / np.array([-2.0, -4.0])  # largest-magnitude component +1
    rng = np.random.default_rng(3)
    eps_f, eps_s = rng.standard_normal(2), rng.standard_normal((3, 2))
    np.testing.assert_allclose(m.frequencies_hz, f * (1 + 0.01 * eps_f))
    np.testing.assert_allclose(m.shapes, clean + 0.02 * eps_s)
    np.testing.assert_allclose(m.frequency_std_hz, 0.01 * m.frequencies_hz)
    assert np.all(m.shape_std == 0.02)
    u = noisy_measurement(f, phi, ("a", "b", "c"), UniformShapeNoise(0.03), np.random.default_rng(3))
    np.testing.assert_array_equal(u.frequencies_hz, f)
    np.testing.assert_allclose(u.shapes, clean * (1 + 0.03 * np.random.default_rng(3).uniform(-1, 1, (3, 2))))
    assert u.frequency_std_hz is None and u.shape_std is None


def test_central_jacobian_is_second_order_and_one_sided_at_a_bound():
    model = make_structure("lab_frame_3dof")
    problem = UpdatingProblem(model, builtin_measured("lab_frame", "base"), objective=ObjectiveSpec(formulation="gaussian"))
    x = np.full(problem.n_params, 0.5)
    x[0] = 0.0
    jac = problem.jacobian(x, scheme="central", fd_step=1e-3)
    assert jac.method == "fd" and jac.cost == 2 * problem.n_params
    i = 1
    lo, hi = x.copy(), x.copy()
    lo[i], hi[i] = x[i] - 1e-3, x[i] + 1e-3
    expected = (problem.residuals(hi) - problem.residuals(lo)) / 2e-3
    np.testing.assert_allclose(jac.J[:, i], expected, rtol=1e-9, atol=1e-9)
    at_bound = (problem.residuals(np.r_[1e-3, x[1:]]) - problem.residuals(x)) / 1e-3
    np.testing.assert_allclose(jac.J[:, 0], at_bound, rtol=1e-9, atol=1e-9)
    with pytest.raises(ValueError, match="scheme"):
        problem.jacobian(x, scheme="backward")


def _gomu_run(tmp_path: Path, name: str, measured: dict) -> tuple[pd.DataFrame, pd.DataFrame]:
    cfg = yaml.safe_load((ROOT / "studies" / "lab_frame.yaml").read_text())
    cfg.update(study=f"gaussian_{name}", measured=measured, validation=[], runs=1,
               algorithms={"sm_initial": cfg["algorithms"]["sm_initial"]}, output=str(tmp_path / name))
    path = tmp_path / f"study_{name}.yaml"
    path.write_text(yaml.safe_dump(cfg))
    out = subprocess.run([sys.executable, "-m", "framework.cli", "run", str(path), "--set",
                          "objective.formulation=gaussian", "--set", "budget.max_evaluations=300", "--quiet",
                          "--no-figures"], cwd=ROOT, capture_output=True, text=True, timeout=300,
                         env={**os.environ, "PYTHONPATH": str(ROOT)})
    assert out.returncode == 0, out.stderr
    return pd.read_csv(tmp_path / name / "runs.csv"), pd.read_csv(tmp_path / name / "parameters.csv")


def test_gaussian_formulation_runs_through_gomu_run_with_and_without_stds(tmp_path):
    """Issue 24: ``gomu run studies/lab_frame.yaml --set objective.formulation=gaussian`` ended every
    run in a TypeError (a missing shape std); it runs, and reports the noise it whitened with."""
    base = builtin_measured("lab_frame", "base")
    save(base, tmp_path / "modes_no_stds.yaml")
    runs, params = _gomu_run(tmp_path, "no_stds", {"file": str(tmp_path / "modes_no_stds.yaml")})
    run = runs.iloc[0]
    assert run["status"] == "converged" and run["uq_error"] != run["uq_error"]  # NaN: no error
    assert (run["noise_frequency_source"], run["noise_shape_source"]) == ("assumed", "assumed")
    assert (params["noise_assumed"] == "frequency std 1 % of f; shape std 5 % of the peak").all()
    assert run["chi2"] == pytest.approx(run["objective"], rel=1e-9)  # whitened at the noise it reports
    assert run["n_data"] == 9

    with_stds = replace(base, frequency_std_hz=0.005 * base.frequencies_hz, shape_std=np.full((3, 3), 0.02))
    save(with_stds, tmp_path / "modes_with_stds.yaml")
    runs2, params2 = _gomu_run(tmp_path, "with_stds", {"file": str(tmp_path / "modes_with_stds.yaml")})
    run2 = runs2.iloc[0]
    assert run2["status"] == "converged"
    assert (run2["noise_frequency_source"], run2["noise_shape_source"]) == ("data", "data")
    assert params2["noise_assumed"].isna().all()  # "" in the table: nothing assumed
    assert run2["chi2"] == pytest.approx(run2["objective"], rel=1e-9)
    assert run2["chi2"] > 3 * run["chi2"]  # the data's smaller standard deviations weigh the same misfit more
