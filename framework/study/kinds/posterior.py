"""Run kind ``posterior``: the sampled posterior of an updating problem's parameters.

One run: the problem of :mod:`framework.study.kinds.updating` (structure, measured data or data
simulated from a truth drawn from the prior, parameters, objective; by default the Gaussian
formulation of :mod:`framework.diagnosis.likelihood`), its likelihood and prior
(:mod:`framework.inference.likelihood`), then

1. the MAP point by least squares on the whitened residuals (bounded, from the initial point
   and ``map_starts - 1`` prior draws) and the linearized posterior there;
2. the ensemble MCMC (``sampler``, :mod:`framework.inference.sampling`), walkers started
   around the MAP point, every population evaluated in one call through the run's
   evaluation runner (serial, processes, dask);
3. optionally nested sampling (``evidence: {name: dynesty}``) for ln Z;
4. posterior predictive frequencies of the data's modes and of the validation cases.

Every random draw comes from ``np.random.default_rng(seed)`` of the run. Tables:

- ``runs``: structure, sampler settings, n_evaluations, acceptance, min_ess, max_rhat, chi2
  and n_data at the MAP point, log_evidence_laplace, log_evidence_nested (+ _error),
  noise_assumed, simulated, wall_s, status ("ok"; "error" with the message when the MAP point,
  the sampler or the evidence raised; :class:`framework.core.status.Status`), error;
- ``parameters``: run x parameter: unit, lower, upper, truth (simulated data), map, lin_std,
  lin_ci90_lower/upper, mean, std, median, ci90_lower/upper (5 % / 95 % quantiles), ess,
  rhat, mean_shift_std = (mean - map) / std, std_ratio = lin_std / std, covered_sampled,
  covered_linearized (truth inside the 90 % interval);
- ``predictive``: run x case x measured mode: f_measured_hz, f_map_hz, mean_hz,
  ci90_lower_hz, ci90_upper_hz (model frequency), pi90_lower_hz, pi90_upper_hz (with the
  measurement noise), inside_pi90;
- ``identifiability``: singular directions of the whitened Jacobian at the MAP point;
- ``draws``: up to ``store_draws`` posterior draws per run (physical units), for corner plots.
"""

from __future__ import annotations

import logging
import time
from dataclasses import replace
from pathlib import Path
from typing import Literal

import numpy as np
from pydantic import Field, StrictInt

from framework.core.errors import InputError
from framework.core.status import Status
from framework.study.kinds import updating
from framework.study.kinds.base import Kind, failure
from framework.study.schema import Strict, StudyHeader
from framework.updating.objectives import ObjectiveSpec

log = logging.getLogger(__name__)

TABLES = ("runs", "parameters", "predictive", "identifiability", "draws")


# ---- schema ------------------------------------------------------------------------------
class NoiseConfig(Strict):
    """Standard deviations assumed where the data give none (and named in ``noise_assumed``)."""

    frequency_std_rel: float = Field(0.005, gt=0, lt=1, strict=False)
    shape_std_rel: float = Field(0.02, gt=0, lt=10, strict=False)


class SimulateConfig(NoiseConfig):
    """Simulated data: truth from the prior, noise of these relative standard deviations."""


class PriorConfig(Strict):
    kind: Literal["uniform", "normal"] = "uniform"
    width: float = Field(0.25, gt=0, le=100, strict=False)


class SamplerConfig(Strict):
    name: Literal["emcee"] = "emcee"
    walkers: StrictInt = Field(32, ge=4, le=10_000)
    steps: StrictInt = Field(2000, ge=10, le=1_000_000)
    burn: StrictInt = Field(500, ge=0)
    thin: StrictInt = Field(1, ge=1)


class EvidenceConfig(Strict):
    name: Literal["none", "dynesty"] = "none"
    live_points: StrictInt = Field(200, ge=10, le=100_000)
    dlogz: float = Field(0.5, gt=0, strict=False)
    max_evaluations: StrictInt | None = Field(None, ge=100)


def _gaussian_objective() -> ObjectiveSpec:
    return ObjectiveSpec(formulation="gaussian", failure_penalty=1e12)


class Config(StudyHeader):
    kind: Literal["posterior"] = "posterior"
    runs: StrictInt = Field(1, ge=1, le=100_000)
    structure: updating.StructureConfig
    measured: updating.MeasuredConfig
    validation: list[updating.ValidationCase] = Field(default_factory=list)
    parameters: updating.ParametersConfig = Field(default_factory=updating.ParametersConfig)
    objective: ObjectiveSpec = Field(default_factory=_gaussian_objective)
    prior: PriorConfig = Field(default_factory=PriorConfig)
    noise: NoiseConfig = Field(default_factory=NoiseConfig)
    simulate: SimulateConfig | None = None
    sampler: SamplerConfig = Field(default_factory=SamplerConfig)
    evidence: EvidenceConfig = Field(default_factory=EvidenceConfig)
    map_starts: StrictInt = Field(4, ge=1, le=1000)
    predictive_draws: StrictInt = Field(200, ge=0, le=100_000)
    store_draws: StrictInt = Field(0, ge=0, le=100_000)


# ---- plan --------------------------------------------------------------------------------
def plan_runs(cfg: Config, sweep_values: dict) -> list[dict]:
    if cfg.sampler.burn >= cfg.sampler.steps:
        raise InputError(f"study {cfg.study!r}: sampler.burn ({cfg.sampler.burn}) must be below sampler.steps "
                         f"({cfg.sampler.steps})")
    data = cfg.model_dump(mode="json")
    keys = ("structure", "measured", "validation", "parameters", "objective", "prior", "noise", "simulate",
            "sampler", "evidence", "map_starts", "predictive_draws", "store_draws")
    task = {k: data[k] for k in keys}
    columns = {"structure": cfg.structure.name, "sampler": cfg.sampler.name}
    return [{"label": "posterior", "seed": cfg.seed + i, "task": task, "columns": columns,
             "relevant": list(sweep_values)} for i in range(cfg.runs)]


# ---- problem -----------------------------------------------------------------------------
def _with_noise(measured, task: dict):
    """The data with standard deviations filled where absent (gaussian formulation), and the
    text naming what was assumed."""
    from framework.diagnosis.likelihood import with_noise_model

    noise = task["noise"]
    assumed = []
    if measured.frequency_std_hz is None:
        assumed.append(f"frequency std {100 * noise['frequency_std_rel']:g} % of f")
    if measured.has_shapes and measured.shape_std is None and task["objective"].get("use_shapes", True):
        assumed.append(f"shape std {100 * noise['shape_std_rel']:g} % of the peak")
    if task["objective"]["formulation"] != "gaussian":
        return measured, None
    return with_noise_model(measured, noise["frequency_std_rel"], noise["shape_std_rel"]), "; ".join(assumed)


def build(task: dict, rng: np.random.Generator, structure_options=None, measured_cfg=None, simulated=None):
    """(problem, noise model, prior, truth or None) of the task (or of a validation case)."""
    from framework.inference.likelihood import Prior, noise_model
    from framework.inference.simulate import simulate
    from framework.structures.registry import make_structure
    from framework.updating.problem import UpdatingProblem

    options = {**task["structure"]["options"], **(structure_options or {})}
    model = make_structure(task["structure"]["name"], **options)
    params = updating.parameters_from(model, task["parameters"])
    prior = Prior(params, task["prior"]["kind"], task["prior"]["width"])
    measured = updating.measured_from(measured_cfg or task["measured"])
    truth = None
    if simulated is not None:
        truth, measured = simulated
    elif task.get("simulate") and measured_cfg is None:
        sim = task["simulate"]
        truth, measured = simulate(model, params, measured, prior, rng, sim["frequency_std_rel"],
                                   sim["shape_std_rel"])
    measured, assumed = _with_noise(measured, task)
    problem = UpdatingProblem(model, measured, params, updating.objective_from(task["objective"]))
    noise = noise_model(problem, task["noise"]["frequency_std_rel"], task["noise"]["shape_std_rel"])
    if assumed is not None:
        noise = replace(noise, assumed=assumed)
    return problem, noise, prior, truth


def map_point(problem, noise, prior, rng: np.random.Generator, starts: int, runner=None) -> np.ndarray:
    """MAP point in x: bounded least squares of the whitened residuals (and, for a normal prior,
    its whitened deviations) from the initial point and ``starts - 1`` prior draws."""
    from scipy.optimize import least_squares

    m = noise.scales.size
    span = prior.span
    P = np.sqrt(np.diag(prior.hessian()))

    def fun(x):
        r = problem.residuals(x, runner)[:m] / noise.scales
        if prior.kind == "normal":
            r = np.r_[r, P * (problem.parameters.to_physical(x) - problem.parameters.initial)]
        return r

    def jac(x):
        J = problem.jacobian(x, runner).J[:m] / noise.scales[:, None]
        if prior.kind == "normal":
            J = np.vstack([J, np.diag(P * span)])
        return J

    x_starts = [problem.x_initial] + list(problem.parameters.to_normalized(prior.sample(rng, starts - 1)))
    best, best_cost = None, np.inf
    for x0 in x_starts:
        try:
            res = least_squares(fun, np.clip(x0, 1e-6, 1 - 1e-6), jac=jac, bounds=(0.0, 1.0), x_scale="jac",
                                max_nfev=200)
        except (ValueError, np.linalg.LinAlgError, RuntimeError) as exc:
            log.debug("MAP start failed: %s", exc)
            continue
        if res.cost < best_cost:
            best, best_cost = res.x, res.cost
    if best is None:
        raise RuntimeError("every MAP start failed")
    return best


def walker_start(x_map: np.ndarray, hessian_x: np.ndarray, n: int, rng: np.random.Generator) -> np.ndarray:
    """n walker positions around x_map: draws of N(x_map, H_x^-1) with every direction's std
    capped at 0.05 (of the span), kept inside (0, 1)."""
    w, V = np.linalg.eigh(hessian_x)
    sd = np.minimum(1.0 / np.sqrt(np.maximum(w, 1e-300)), 0.05)
    X = x_map + (rng.standard_normal((n, x_map.size)) * sd) @ V.T
    return np.clip(X, 1e-6, 1 - 1e-6)


def paired_frequencies(problem, X: np.ndarray, runner=None) -> np.ndarray:
    """Model frequency (Hz) paired with each measured mode at points X (n, k) -> (n, m); NaN
    where unmatched or failed."""
    ev = problem.evaluate(X, runner)
    corr = ev.correlations
    f = getattr(corr, "f_model_hz", None)
    if f is None:
        m = problem.measured.n_modes
        f = np.vstack([c.f_model_hz if c is not None else np.full(m, np.nan) for c in corr])
    f = np.array(f, float)
    f[~ev.ok] = np.nan
    return f


# ---- one run -----------------------------------------------------------------------------
def run(spec: dict, runner) -> dict[str, list[dict]]:
    """One posterior run; ``runner`` evaluates the model, isolated for user code as in an
    updating run (:func:`framework.study.kinds.base.evaluation_runner`)."""
    from framework.inference.evidence import laplace_log_evidence
    from framework.inference.likelihood import log_posterior_x
    from framework.inference.linearized import at_optimum
    from framework.inference.sampling import EVIDENCE_SAMPLERS, SAMPLERS

    t0 = time.perf_counter()
    task = spec["task"]
    tables: dict[str, list[dict]] = {t: [] for t in TABLES}
    rng = np.random.default_rng(spec["seed"])
    problem, noise, prior, truth = build(task, rng)
    params = problem.parameters
    log_prob = log_posterior_x(problem, noise, prior, runner)
    s, e = task["sampler"], task["evidence"]
    row = {"n_walkers": s["walkers"], "n_steps": s["steps"], "burn": s["burn"], "evidence_sampler": e["name"],
           "noise_assumed": noise.assumed, "simulated": truth is not None, "n_data": noise.n_data,
           "status": Status.OK, "error": ""}
    try:
        x_map = map_point(problem, noise, prior, rng, task["map_starts"], runner)
        lin = at_optimum(problem, x_map, noise, prior, runner)
        ev = problem.evaluate(x_map[None, :], runner)
        theta_map = params.to_physical(x_map)
        ln_l = float(noise.log_likelihood(ev.residuals, ev.ok)[0])
        row.update(chi2=float(noise.chi2(ev.residuals)[0]),
                   log_evidence_laplace=laplace_log_evidence(ln_l, float(prior.log_pdf(theta_map)[0]),
                                                             lin.hessian_x, prior.span))
        x0 = walker_start(x_map, lin.hessian_x, s["walkers"], rng)
        result = SAMPLERS[s["name"]](log_prob, x0, rng, n_walkers=s["walkers"], n_steps=s["steps"], burn=s["burn"],
                                     thin=s["thin"])
        n_eval = result.n_evaluations
        if e["name"] != "none":
            ev_res = EVIDENCE_SAMPLERS[e["name"]](_log_likelihood_x(problem, noise, runner), params.__len__(), rng,
                                                  _prior_transform(prior), n_live=e["live_points"], dlogz=e["dlogz"],
                                                  max_evaluations=e["max_evaluations"])
            n_eval += ev_res.n_evaluations
            row.update(log_evidence_nested=ev_res.log_evidence, log_evidence_nested_error=ev_res.log_evidence_error)
    except Exception as exc:  # a failed run is a row, never the end of the study
        log.debug("posterior run failed", exc_info=True)
        row.update(**failure(exc, Status.ERROR), wall_s=time.perf_counter() - t0)
        tables["runs"].append(row)
        return tables
    row.update(n_evaluations=n_eval, acceptance=result.acceptance, min_ess=float(np.min(result.ess)),
               max_rhat=float(np.max(result.rhat)))
    draws = params.to_physical(result.draws)
    lo_lin, hi_lin = lin.interval(0.9)
    q05, q50, q95 = np.quantile(draws, [0.05, 0.5, 0.95], axis=0)
    mean, std = draws.mean(axis=0), draws.std(axis=0, ddof=1)
    for j, p in enumerate(params):
        prow = {"parameter": p.name, "unit": p.unit, "lower": p.lower, "upper": p.upper,
                "truth": float(truth[j]) if truth is not None else np.nan, "map": float(theta_map[j]),
                "lin_std": float(lin.std[j]), "lin_ci90_lower": float(lo_lin[j]), "lin_ci90_upper": float(hi_lin[j]),
                "mean": float(mean[j]), "std": float(std[j]), "median": float(q50[j]),
                "ci90_lower": float(q05[j]), "ci90_upper": float(q95[j]), "ess": float(result.ess[j]),
                "rhat": float(result.rhat[j]), "mean_shift_std": float((mean[j] - theta_map[j]) / std[j]),
                "std_ratio": float(lin.std[j] / std[j])}
        if truth is not None:
            prow["covered_sampled"] = bool(q05[j] <= truth[j] <= q95[j])
            prow["covered_linearized"] = bool(lo_lin[j] <= truth[j] <= hi_lin[j])
        tables["parameters"].append(prow)
    tables["identifiability"] = lin.identifiability_rows()
    tables["predictive"] = _predictive(task, problem, noise, draws, theta_map, rng, runner)
    if task["store_draws"]:
        pick = rng.choice(len(draws), size=min(task["store_draws"], len(draws)), replace=False)
        tables["draws"] = [{"draw": int(i), **params.as_dict(draws[i])} for i in np.sort(pick)]
    row["wall_s"] = time.perf_counter() - t0
    tables["runs"].append(row)
    return tables


def _log_likelihood_x(problem, noise, runner):
    from framework.inference.batch import log_likelihood_batch

    def log_like(X):
        return log_likelihood_batch(problem, noise, np.atleast_2d(X), runner)

    return log_like


def _prior_transform(prior):
    """Unit cube -> x of the prior (identity for uniform; truncated normal quantiles)."""
    if prior.kind == "uniform":
        return None
    from scipy.special import ndtr, ndtri

    p = prior.parameters
    mu, sd, _ = prior._normal()
    lo, hi = ndtr((p.lower - mu) / sd), ndtr((p.upper - mu) / sd)
    return lambda u: p.to_normalized(np.clip(mu + sd * ndtri(lo + u * (hi - lo)), p.lower, p.upper))


def _predictive(task, problem, noise, draws, theta_map, rng, runner) -> list[dict]:
    """Posterior predictive frequencies of the data's modes and of every validation case."""
    n = min(task["predictive_draws"], len(draws))
    if n == 0:
        return []
    thetas = draws[rng.choice(len(draws), size=n, replace=False)]
    names = problem.parameters.names
    cases = [("base", problem)]
    for case in task.get("validation", []):
        try:
            vp, _, _, _ = build(task, rng, case["structure_options"], case["measured"])
            cases.append((case["case"], vp))
        except Exception as exc:  # a failed prediction is a row
            log.debug("validation case %s failed: %s", case["case"], exc)
    rows = []
    for name, prob in cases:
        if prob.parameters.names != names:
            raise InputError(f"validation case {name!r}: its parameters differ from the problem's")
        X = prob.parameters.to_normalized(np.vstack([theta_map, thetas]))
        f = paired_frequencies(prob, X, runner)
        f_map, f = f[0], f[1:]
        m = prob.measured
        sigma = m.frequency_std_hz if m.frequency_std_hz is not None else \
            task["noise"]["frequency_std_rel"] * m.frequencies_hz
        noisy = f + sigma * rng.standard_normal(f.shape)
        for j in range(m.n_modes):
            ok = np.isfinite(f[:, j])
            if not ok.any():
                rows.append({"case": name, "mode": j + 1, "mode_label": m.labels[j],
                             "f_measured_hz": float(m.frequencies_hz[j]), "n_draws": 0})
                continue
            lo, hi = np.quantile(f[ok, j], [0.05, 0.95])
            plo, phi = np.quantile(noisy[ok, j], [0.05, 0.95])
            fe = float(m.frequencies_hz[j])
            rows.append({"case": name, "mode": j + 1, "mode_label": m.labels[j], "f_measured_hz": fe,
                         "f_map_hz": float(f_map[j]), "mean_hz": float(np.mean(f[ok, j])), "ci90_lower_hz": float(lo),
                         "ci90_upper_hz": float(hi), "pi90_lower_hz": float(plo), "pi90_upper_hz": float(phi),
                         "inside_pi90": bool(plo <= fe <= phi), "n_draws": int(ok.sum())})
    return rows


# ---- analyses and figures ----------------------------------------------------------------
def analyses(tables: dict, report: dict) -> dict:
    """``coverage`` (runs with simulated data): per structure, method and parameter, the
    fraction of seeds whose 90 % interval holds the truth; ``agreement``: sampled vs linearized
    per run and parameter."""
    from framework.report.analyses.posterior import agreement_table, coverage_table

    out = {}
    cov = coverage_table(tables.get("parameters"))
    if cov is not None:
        out["coverage"] = cov
    agree = agreement_table(tables.get("parameters"))
    if agree is not None:
        out["agreement"] = agree
    return out


def figures(tables: dict, out_dir: Path, report: dict) -> list[Path]:
    from framework.report.figures.posterior import posterior_figures

    return posterior_figures(tables, out_dir)


KIND = Kind(
    name="posterior", config=Config, tables=TABLES, plan_runs=plan_runs, run=run, check=updating.check,
    identity=updating.identity, preflight=updating.preflight, preflight_key=updating.problem_key,
    evaluates_model=True, user_code=updating.user_model, analyses=analyses, figures=figures,
)
