"""Likelihood, linearized posterior and Laplace evidence (framework.inference), and the
linearized columns of the updating run kind."""

from dataclasses import replace

import numpy as np
import pandas as pd
import pytest

from framework.core.parameters import Parameter, ParameterSet
from framework.inference.evidence import laplace_log_evidence
from framework.inference.likelihood import Prior, noise_model
from framework.inference.linearized import linearized_posterior
from framework.inference.tables import linearized_columns
from framework.structures.registry import builtin_measured, make_structure
from framework.updating.objectives import ObjectiveSpec
from framework.updating.problem import UpdatingProblem


def _lab_problem(std_hz=(0.02, 0.03, 0.04), use_shapes=False):
    model = make_structure("lab_frame_3dof")
    measured = replace(builtin_measured("lab_frame", "base"), frequency_std_hz=np.array(std_hz))
    return UpdatingProblem(model, measured, objective=ObjectiveSpec(use_shapes=use_shapes, pairing="frequency"))


def test_likelihood_equals_hand_computed_value():
    problem = _lab_problem()
    theta = problem.parameters.initial
    f_model = np.sort(problem.model.modal(problem.parameters.as_dict(theta)).frequencies_hz)[:3]
    fe, sd = np.array([3.58, 5.01, 7.28]), np.array([0.02, 0.03, 0.04])
    hand = np.sum(-0.5 * ((f_model - fe) / sd) ** 2 - np.log(sd) - 0.5 * np.log(2 * np.pi))
    noise = noise_model(problem)
    assert noise.assumed == ""
    ev = problem.evaluate(problem.x_initial[None, :])
    assert noise.log_likelihood(ev.residuals, ev.ok)[0] == pytest.approx(hand, rel=1e-10)
    assert noise.n_data == 3


def test_missing_standard_deviations_are_a_visible_assumption():
    model = make_structure("lab_frame_3dof")
    problem = UpdatingProblem(model, builtin_measured("lab_frame", "base"))
    noise = noise_model(problem)
    assert noise.assumed == ("frequency std 1 % of f; shape std 5 % of the peak; "
                             "MAC residual Gaussian with std (n_dof-1) s^2/2")
    assert noise.sources == {"frequency": "assumed", "shape": "assumed"}
    assert noise.scales[:3] == pytest.approx(np.full(3, 0.01))  # sqrt(alpha w) sigma_f / f
    # the MAC rows: (n_dof - 1) s_rel^2 / 2 with s_rel = 5 % of the peak (3 DOFs)
    assert noise.scales[3:] == pytest.approx(np.full(3, 2 * 0.05**2 / 2))


def test_failed_evaluation_has_zero_likelihood():
    problem = _lab_problem()
    noise = noise_model(problem)
    assert noise.log_likelihood(np.zeros((1, 3)), np.array([False]))[0] == -np.inf


def test_prior_densities_and_draws():
    params = ParameterSet([Parameter("a", 1.0, 0.0, 2.0), Parameter("b", 5.0, 0.0, 10.0)])
    uniform = Prior(params)
    assert uniform.log_pdf(np.array([[1.0, 5.0]]))[0] == pytest.approx(-np.log(20.0))
    assert uniform.log_pdf(np.array([[3.0, 5.0]]))[0] == -np.inf
    normal = Prior(params, "normal", width=0.1)
    draws = normal.sample(np.random.default_rng(0), 20000)
    assert draws.mean(axis=0) == pytest.approx([1.0, 5.0], abs=0.01)
    assert draws.std(axis=0) == pytest.approx([0.2, 1.0], rel=0.03)
    with pytest.raises(Exception, match="uniform' or 'normal"):
        Prior(params, "cauchy")


def _linear_toy(rng, k=3, n=8):
    A = rng.normal(size=(n, k))
    sd = rng.uniform(0.5, 2.0, n)
    params = ParameterSet([Parameter(f"t{i}", 0.0, -100.0, 100.0) for i in range(k)])
    return A, sd, params


def test_linearized_intervals_cover_a_linear_gaussian_toy():
    """y = A theta + e, e ~ N(0, diag sd^2), flat prior: the 90 % interval is exact; coverage
    over 4000 noise draws is 0.90 +- 0.015 (3 binomial sd)."""
    rng = np.random.default_rng(1)
    A, sd, params = _linear_toy(rng)
    span = params.upper - params.lower
    truth = np.array([1.0, -2.0, 0.5])
    hits = np.zeros(3)
    n = 4000
    Aw = A / sd[:, None]
    for _ in range(n):
        y = A @ truth + sd * rng.normal(size=sd.size)
        theta_hat = np.linalg.lstsq(Aw, y / sd, rcond=None)[0]
        lin = linearized_posterior(A * span[None, :], sd, params, theta_hat)
        lo, hi = lin.interval(0.9)
        hits += (lo <= truth) & (truth <= hi)
    assert hits / n == pytest.approx(np.full(3, 0.9), abs=0.015)
    exact_cov = np.linalg.inv(Aw.T @ Aw)
    assert lin.covariance == pytest.approx(exact_cov, rel=1e-8)


def test_laplace_evidence_equals_closed_form_on_linear_gaussian():
    """Gaussian prior N(mu0, P0) (bounds at +-50 prior sd: truncation negligible) and linear
    model: ln Z = ln N(y; A mu0, S + A P0 A') exactly; Laplace at the posterior mode equals it."""
    from scipy.stats import multivariate_normal

    rng = np.random.default_rng(2)
    A, sd, _ = _linear_toy(rng)
    width = 0.01  # prior sd = width * span
    params = ParameterSet([Parameter(f"t{i}", 0.3 * i, 0.3 * i - 50.0, 0.3 * i + 50.0) for i in range(3)])
    prior = Prior(params, "normal", width=width)
    mu0, P0 = params.initial, np.diag((width * prior.span) ** 2)
    y = A @ np.array([0.5, 0.1, -0.4]) + sd * rng.normal(size=sd.size)
    S = np.diag(sd**2)
    exact = multivariate_normal(A @ mu0, S + A @ P0 @ A.T).logpdf(y)
    Si = np.diag(1 / sd**2)
    H = A.T @ Si @ A + np.linalg.inv(P0)
    mode = np.linalg.solve(H, A.T @ Si @ y + np.linalg.inv(P0) @ mu0)
    r = (A @ mode - y) / sd
    ln_l = -0.5 * r @ r - np.sum(np.log(sd)) - 0.5 * sd.size * np.log(2 * np.pi)
    lin = linearized_posterior(A * prior.span[None, :], sd, params, mode, prior.hessian())
    ln_z = laplace_log_evidence(ln_l, prior.log_pdf(mode)[0], lin.hessian_x, prior.span)
    assert ln_z == pytest.approx(exact, abs=1e-6)


def test_identifiability_names_the_undetermined_combination():
    params = ParameterSet([Parameter(n, 0.0, -1.0, 1.0) for n in "abc"])
    J = np.array([[1.0, 0.0, 0.0], [0.0, 1.0, 1.0], [0.0, 2.0, 2.0]])  # b - c undetermined
    lin = linearized_posterior(J, np.ones(3), params, np.zeros(3))
    rows = lin.identifiability_rows()
    assert rows[-1]["singular_value"] == pytest.approx(0.0, abs=1e-12)
    assert rows[-1]["information_ratio"] > 1e6
    assert set(rows[-1]["combination"].split()[1::2]) == {"b", "c"}


def test_linearized_failure_is_recorded_not_raised(monkeypatch):
    problem = _lab_problem()

    def broken(*args, **kwargs):
        raise np.linalg.LinAlgError("boom")

    monkeypatch.setattr(UpdatingProblem, "jacobian", broken)
    out = linearized_columns(problem, problem.x_initial)
    assert "LinAlgError: boom" in out["run"]["uq_error"]
    assert all(np.isnan(p["std"]) for p in out["parameters"])


def test_updating_run_reports_linearized_columns(tmp_path):
    from framework.study.config import validate
    from framework.study.runner import run_study

    # torsion in sensor units (congruence "model"), the reading this test was written for
    cfg = validate({"study": "uq", "structure": {"name": "lab_frame_3dof", "options": {"congruence": "model"}},
                    "measured": {"builtin": "lab_frame", "case": "base", "options": {"congruence": "model"}},
                    "budget": {"max_evaluations": 2000},
                    "algorithms": {"sm": {"algorithm": "sm", "settings": {"start": "initial"}}},
                    "runs": 1, "output": str(tmp_path / "uq")})
    run_study(cfg, figures=False)
    runs = pd.read_csv(tmp_path / "uq" / "runs.csv")
    params = pd.read_csv(tmp_path / "uq" / "parameters.csv").set_index("parameter")
    ident = pd.read_csv(tmp_path / "uq" / "identifiability.csv")
    assert runs["n_data"].iloc[0] == 6 and runs["chi2"].iloc[0] > 0
    assert np.isfinite(runs["log_evidence_laplace"].iloc[0])
    assert (params["ci90_lower"] < params["value"]).all() and (params["value"] < params["ci90_upper"]).all()
    assert params.loc["kyy", "std"] == pytest.approx((params.loc["kyy", "ci90_upper"] - params.loc["kyy", "ci90_lower"])
                                                     / (2 * 1.6448536), rel=1e-6)
    assert params["noise_assumed"].str.contains("frequency std 1 % of f; shape std 5 % of the peak").all()
    assert runs["noise_frequency_source"].iloc[0] == "assumed" and runs["noise_shape_source"].iloc[0] == "assumed"
    assert len(ident) == 6
    worst = ident.sort_values("singular_value").iloc[0]
    assert worst["dominant_parameter"] == "kxy" and worst["information_ratio"] > 1


@pytest.mark.smu
def test_four_story_singular_values_name_alpha_4_least_determined():
    """SMU four-storey frame (skipped without the data): at the MAP point of the Gaussian
    likelihood the least-determined direction is alpha_4, with a std several times the others'."""
    from framework.inference.linearized import at_optimum
    from framework.structures.smu import model as smu
    from framework.study.kinds.posterior import map_point

    if not smu.available():
        pytest.skip(f"SMU data not found in {smu.smu_dir()}")
    model = smu.make_four_story(measured_floors=[1, 2, 3, 4], n_modes=4)
    problem = UpdatingProblem(model, smu.four_story_measured("base"),
                              objective=ObjectiveSpec(formulation="gaussian", failure_penalty=1e12))
    noise, prior = noise_model(problem), Prior(problem.parameters)
    x = map_point(problem, noise, prior, np.random.default_rng(0), 2)
    lin = at_optimum(problem, x, noise, prior)
    last = lin.identifiability_rows()[-1]
    assert last["dominant_parameter"] == "alpha_4"
    std = dict(zip(lin.names, lin.std))
    assert std["alpha_4"] > 2.5 * max(std["alpha_1"], std["alpha_2"], std["alpha_3"])
