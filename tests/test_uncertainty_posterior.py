"""Sampled posterior: samplers against closed forms on linear-Gaussian toys, reproducibility
from the seed on every evaluation backend, the posterior run kind's tables."""

import numpy as np
import pandas as pd
import pytest

pytest.importorskip("emcee")

from framework.inference.sampling import run_dynesty, run_emcee, split_rhat  # noqa: E402


def _toy(rng, k=2, n=6):
    """Linear-Gaussian toy in x: y = A x + e, e ~ N(0, sd^2), flat prior on [0, 1]^k with the
    posterior far inside the box (so it is N(mu, (A'WA)^-1) in closed form)."""
    A = rng.normal(size=(n, k)) * 20.0
    sd = np.full(n, 1.0)
    x_true = np.full(k, 0.5)
    y = A @ x_true + sd * rng.normal(size=n)
    W = np.diag(1 / sd**2)
    cov = np.linalg.inv(A.T @ W @ A)
    mu = cov @ A.T @ W @ y

    def log_like(X):
        X = np.atleast_2d(X)
        r = (X @ A.T - y) / sd
        out = -0.5 * np.sum(r**2, axis=1) - np.sum(np.log(sd)) - 0.5 * n * np.log(2 * np.pi)
        return np.where(np.all((X >= 0) & (X <= 1), axis=1), out, -np.inf)

    exact_log_z = float(_log_gauss_integral(A, y, sd))
    return log_like, mu, cov, exact_log_z


def _log_gauss_integral(A, y, sd):
    """ln of the integral of L(x) dx over R^k (the box holds all of it): Gaussian integral."""
    W = np.diag(1 / sd**2)
    H = A.T @ W @ A
    mu = np.linalg.solve(H, A.T @ W @ y)
    r = (A @ mu - y) / sd
    k, n = A.shape[1], A.shape[0]
    ln_lmax = -0.5 * r @ r - np.sum(np.log(sd)) - 0.5 * n * np.log(2 * np.pi)
    return ln_lmax + 0.5 * k * np.log(2 * np.pi) - 0.5 * np.linalg.slogdet(H)[1]


def test_emcee_posterior_matches_closed_form_on_linear_gaussian():
    rng = np.random.default_rng(3)
    log_like, mu, cov, _ = _toy(rng)
    x0 = mu + 0.01 * rng.normal(size=(16, 2))
    res = run_emcee(log_like, x0, np.random.default_rng(0), n_walkers=16, n_steps=1500, burn=300)
    sd = np.sqrt(np.diag(cov))
    assert res.draws.mean(axis=0) == pytest.approx(mu, abs=0.1 * sd.max())
    assert res.draws.std(axis=0) == pytest.approx(sd, rel=0.1)
    assert np.corrcoef(res.draws.T)[0, 1] == pytest.approx(cov[0, 1] / sd.prod(), abs=0.1)
    assert res.ess.min() > 300 and res.rhat.max() < 1.2


def test_nested_evidence_matches_closed_form():
    pytest.importorskip("dynesty")
    rng = np.random.default_rng(4)
    log_like, mu, cov, exact = _toy(rng)
    res = run_dynesty(log_like, 2, np.random.default_rng(1), n_live=150, dlogz=0.1)
    assert res.log_evidence == pytest.approx(exact, abs=max(3 * res.log_evidence_error, 0.3))
    assert res.draws.mean(axis=0) == pytest.approx(mu, abs=0.2 * np.sqrt(cov.max()))


def test_split_rhat_flags_chains_that_disagree():
    rng = np.random.default_rng(5)
    good = rng.normal(size=(1000, 8, 1))
    bad = good + np.arange(8)[None, :, None]
    assert split_rhat(good)[0] < 1.01
    assert split_rhat(bad)[0] > 1.5


def _config(tmp_path, name, backend="serial", **extra):
    from framework.study.config import validate

    data = {"study": name, "kind": "posterior", "structure": {"name": "lab_frame_3dof"},
            "measured": {"builtin": "lab_frame", "case": "base"},
            "validation": [{"case": "mass_0.654kg", "structure_options": {"case": "mass_0.654kg"},
                            "measured": {"builtin": "lab_frame", "case": "mass_0.654kg"}}],
            "sampler": {"walkers": 16, "steps": 120, "burn": 40}, "map_starts": 1, "predictive_draws": 30,
            "store_draws": 50, "runs": 1, "output": str(tmp_path / name),
            "execution": {"evaluation_backend": backend, "workers": 2,
                          "backend": "dask" if backend == "dask" else "serial"}, **extra}
    return validate(data)


def _tables(tmp_path, name):
    return {t: pd.read_csv(tmp_path / name / f"{t}.csv") for t in ("runs", "parameters", "predictive", "draws")}


@pytest.mark.parametrize("backend", ["processes", pytest.param("dask", marks=pytest.mark.slow)])
def test_posterior_run_is_reproducible_from_the_seed_on_every_backend(tmp_path, backend):
    from framework.study.runner import run_study

    if backend == "dask":
        pytest.importorskip("distributed")
    run_study(_config(tmp_path, "serial"), figures=False)
    run_study(_config(tmp_path, backend, backend=backend), figures=False)
    a, b = _tables(tmp_path, "serial"), _tables(tmp_path, backend)
    for t in ("parameters", "predictive", "draws"):
        cols = [c for c in a[t] if c not in ("study", "run_id", "wall_s")]
        pd.testing.assert_frame_equal(a[t][cols], b[t][cols])
    assert a["runs"]["n_evaluations"].iloc[0] == b["runs"]["n_evaluations"].iloc[0]


def test_posterior_run_tables_on_the_lab_frame(tmp_path):
    from framework.study.runner import run_study

    run_study(_config(tmp_path, "lab"), figures=False)
    t = _tables(tmp_path, "lab")
    run = t["runs"].iloc[0]
    assert run["status"] == "ok" and run["n_data"] == 9
    assert "frequency std 0.5 % of f" in run["noise_assumed"]
    p = t["parameters"].set_index("parameter")
    assert (p["ci90_lower"] < p["mean"]).all() and (p["mean"] < p["ci90_upper"]).all()
    assert (p["std_ratio"] > 0.3).all() and (p["std_ratio"] < 3).all()
    pred = t["predictive"]
    assert set(pred["case"]) == {"base", "mass_0.654kg"}
    assert ((pred["ci90_lower_hz"] <= pred["mean_hz"]) & (pred["mean_hz"] <= pred["ci90_upper_hz"])).all()
    assert len(t["draws"]) == 50


def test_simulated_runs_report_coverage(tmp_path):
    from framework.study.runner import run_study

    cfg = _config(tmp_path, "sim", simulate={"frequency_std_rel": 0.005, "shape_std_rel": 0.02}, runs=2,
                  validation=[], predictive_draws=0, store_draws=0)
    run_study(cfg, figures=False)
    cov = pd.read_csv(tmp_path / "sim" / "coverage.csv")
    assert list(cov.columns[:6]) == ["structure", "method", "parameter", "nominal", "coverage", "n_seeds"]
    assert len(cov) == 12 and (cov["n_seeds"] == 2).all()
    truth = pd.read_csv(tmp_path / "sim" / "parameters.csv").groupby("seed")["truth"].first()
    assert truth.iloc[0] != truth.iloc[1]  # each seed draws its own truth


def test_bad_sampler_settings_are_input_errors(tmp_path):
    from framework.core.errors import InputError
    from framework.study.plan import plan

    with pytest.raises(InputError, match="burn"):
        plan(_config(tmp_path, "bad", sampler={"walkers": 8, "steps": 100, "burn": 100}))


@pytest.mark.parametrize("structure, measured, options", [("lab_frame_3dof", "lab_frame", {}),
                                                          ("beam", "beam", {"n_modes": 5})])
def test_population_likelihood_equals_the_problems_residuals(structure, measured, options):
    """The one-call Gaussian residuals of a population equal UpdatingProblem.evaluate's, point
    by point, on measured and on simulated data, in process and through a process runner."""
    from framework.execution.parallel import make_evaluation_runner
    from framework.inference.batch import gaussian_residuals_batch
    from framework.study.kinds.posterior import build

    for simulate in (None, {"frequency_std_rel": 0.005, "shape_std_rel": 0.02}):
        task = {"structure": {"name": structure, "options": options}, "measured": {"builtin": measured, "case": "base"},
                "parameters": {}, "objective": {"formulation": "gaussian", "failure_penalty": 1e12},
                "prior": {"kind": "uniform", "width": 0.25}, "noise": {"frequency_std_rel": 0.005, "shape_std_rel": 0.02},
                "simulate": simulate}
        problem, noise, _, _ = build(task, np.random.default_rng(0))
        X = np.random.default_rng(1).random((12, problem.n_params))
        expected = problem.evaluate(X).residuals
        np.testing.assert_allclose(gaussian_residuals_batch(problem, X), expected, rtol=1e-10, atol=1e-12)
    runner, close = make_evaluation_runner("processes", workers=2)
    try:
        np.testing.assert_allclose(gaussian_residuals_batch(problem, X, runner), expected, rtol=1e-10, atol=1e-12)
    finally:
        close()
