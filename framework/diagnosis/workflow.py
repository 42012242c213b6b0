"""The discrepancy workflow: detect -> name -> add -> repeat, and show the gap shrink.

1. Detect: calibrate the current model (maximum likelihood, :mod:`.calibrate`) and test
   the residuals against the noise model (:mod:`.detect`).
2. Name: for every candidate effect of the structure's catalogue not yet in the model
   (every variant of it), re-calibrate the enriched model - from the current estimate
   with the effect at its null value (the enriched model nests the current one), and
   from the best points of a Sobol screening of the effect's parameters - and rank by
   BIC (:mod:`.score`; optionally also by held-out-mode prediction, :mod:`.holdout`).
   An effect is named only when the discrepancy is significant and the effect is
   decisively better than no change and the runner-up.
3. Add: the named effect joins the model (re-calibrated from extra random starts);
   repeat from 1 until nothing significant remains, no candidate is decisive, or
   ``max_rounds`` effects were added.
4. Show: :func:`framework.diagnosis.tables.diagnosis_tables` (rounds, candidates, modes
   before/after, parameters of every fitted model, COMAC, summary) and
   :mod:`framework.report.figures.diagnosis` (figures drawn from those tables).

Python API: ``diagnose(catalogue, measured, settings)``; command line: ``gomu diagnose
CONFIG`` or ``gomu run CONFIG`` with a config of run kind ``diagnose``
(:mod:`framework.study.kinds.diagnose`).
"""

from __future__ import annotations

import logging
from collections.abc import Mapping
from dataclasses import dataclass, field, replace

import numpy as np
from pydantic import BaseModel, ConfigDict, Field

from framework.core.parameters import Parameter, ParameterSet
from framework.diagnosis.calibrate import Fit, calibrate, gaussian_spec
from framework.diagnosis.detect import DEFAULT_ALPHA, Detection, detect
from framework.diagnosis.effects import Catalogue
from framework.diagnosis.score import DECISIVE_DELTA_BIC, NO_CHANGE, Ranking, rank
from framework.inference.gaussian import DEFAULT_UNMATCHED_WINDOW
from framework.inference.noise import DEFAULT_FREQUENCY_STD_REL, DEFAULT_SHAPE_STD_REL, data_noise, with_stds
from framework.measured.modes import MeasuredModes

log = logging.getLogger(__name__)


class DiagnoseSettings(BaseModel):
    """Settings of the workflow (unknown keys rejected).

    alpha: level of the chi-square test; decisive_delta_bic: BIC margin to name an effect;
    n_starts / max_evaluations: least-squares starts and evaluations per start;
    frequency_std_rel / shape_std_rel: the noise assumed where the data give no standard
    deviation (default: the assumed defaults of :mod:`framework.inference.noise`, 1 % / 5 %);
    rank_always: rank the candidates in round 1 even when nothing is significant (the
    ranking is reported, nothing is named); holdout_modes: also score every candidate by
    leave-one-mode-out prediction (:mod:`.holdout`) and name an effect only when it also
    predicts held-out modes best; refine_starts: extra random starts spent on the
    enriched model once an effect is named (a poor local minimum there would make the
    next round blame a second, spurious effect); screen_points: scrambled-Sobol points
    of a new effect's parameters evaluated first (base parameters at their current
    estimate); the best of them seed the least-squares starts (effect parameters such
    as a mass position give multimodal likelihoods).
    """

    model_config = ConfigDict(extra="forbid", frozen=True, strict=True)

    alpha: float = Field(DEFAULT_ALPHA, gt=0, lt=1)
    decisive_delta_bic: float = Field(DECISIVE_DELTA_BIC, ge=0)
    n_starts: int = Field(3, ge=1)
    max_evaluations: int = Field(400, gt=0)
    max_rounds: int = Field(2, ge=1)
    mac_threshold: float = Field(0.5, ge=0, le=1)
    frequency_window: float | None = Field(None, gt=0)
    unmatched_window: float = Field(DEFAULT_UNMATCHED_WINDOW, gt=0)
    use_shapes: bool = True
    frequency_std_rel: float = Field(DEFAULT_FREQUENCY_STD_REL, gt=0)
    shape_std_rel: float = Field(DEFAULT_SHAPE_STD_REL, gt=0)
    rank_always: bool = True
    holdout_modes: bool = False
    refine_starts: int = Field(3, ge=0)
    screen_points: int = Field(16, ge=0)
    #: seed of the calibrations' random starts and of the Sobol screening
    seed: int = Field(0, ge=0)
    #: calibrate only the best ``screen_keep`` variants of an effect by the linearized
    #: screen of :mod:`.screen` (None: calibrate every variant)
    screen_keep: int | None = Field(None, ge=1)
    #: also score every candidate by its Laplace model evidence (:func:`_evidence`)
    evidence: bool = True
    #: a fitted parameter within this fraction of its range from a bound is flagged
    bound_tolerance: float = Field(0.02, ge=0, lt=0.5)


@dataclass
class Round:
    """One pass: the current fit, its detection, the candidate ranking, the named effect."""

    index: int
    fit: Fit
    detection: Detection
    ranking: Ranking | None = None
    named: str | None = None
    candidate_fits: dict[str, Fit] = field(default_factory=dict)
    #: screening rows (effect, variant, chi2_lin, calibrated) when variants were screened
    screen: list[dict] = field(default_factory=list)


@dataclass
class Diagnosis:
    """Outcome of :func:`diagnose`."""

    structure: str
    measured: MeasuredModes
    rounds: list[Round]
    conclusion: str
    catalogue: Catalogue
    #: model evaluations of every calibration and screening (held-out-mode refits not counted)
    n_evaluations: int = 0
    #: "data" when the data give both standard deviations, else the assumption used
    noise_source: str = "data"
    #: the enriched model still fails the noise test: the named effects explain part of the gap
    partial: bool = False
    #: every round in one line
    headline: str = ""
    #: named effect -> flags of its fit (parameter at a bound, sign against the physics)
    flags: dict[str, list[str]] = field(default_factory=dict)

    @property
    def before(self) -> Fit:
        return self.rounds[0].fit

    @property
    def after(self) -> Fit:
        return self.rounds[-1].fit

    @property
    def named_effects(self) -> list[str]:
        return [r.named for r in self.rounds if r.named]

    def summary(self) -> dict:
        """One flat row: named effects, gap before/after, chi2 and p before/after."""
        b, a = self.before.gap(), self.after.gap()
        d0, d1 = self.rounds[0].detection, self.rounds[-1].detection
        row = {
            "structure": self.structure,
            "data": self.measured.name,
            "named_effect": "+".join(self.named_effects) or NO_CHANGE,
            "detected": d0.significant,
            "conclusion": self.conclusion,
            "partial": self.partial,
            "headline": self.headline,
            "noise_source": self.noise_source,
            "noise_warning": noise_warning(self.noise_source),
            "flags": "; ".join(f"{k}: {', '.join(v)}" for k, v in self.flags.items() if v),
            "chi2_before": d0.chi2,
            "p_before": d0.p_value,
            "chi2_after": d1.chi2,
            "p_after": d1.p_value,
            "n_data": self.before.n_data,
        }
        row |= {f"{k}_before": v for k, v in b.items()} | {f"{k}_after": v for k, v in a.items()}
        return row


def _label(active: Mapping[str, str]) -> str:
    return "+".join(f"{k}[{v}]" if v else k for k, v in active.items()) or "model under test"


def _warm_parameters(catalogue: Catalogue, active: Mapping[str, str], warm: Fit | None) -> ParameterSet:
    """The model's parameters with initial values moved to the current estimate (nesting)."""
    params = catalogue.parameters(active)
    if warm is None:
        return params
    values = dict(zip(warm.parameters.names, warm.theta))
    out = []
    for p in params:
        init = float(np.clip(values.get(p.name, p.initial), p.lower, p.upper))
        out.append(Parameter(p.name, init, p.lower, p.upper, p.unit, p.description))
    return ParameterSet(out)


def fit_model(
    catalogue: Catalogue,
    active: Mapping[str, str],
    measured: MeasuredModes,
    settings: DiagnoseSettings,
    warm: Fit | None = None,
) -> Fit:
    """Calibrate the catalogue's model with ``active`` effects to ``measured``.

    The fit's ``n_evaluations`` includes the screening points evaluated to pick its starts.
    """
    model = catalogue.model(active)
    params = _warm_parameters(catalogue, active, warm)
    x0 = params.x_initial
    starts = [x0]
    screened = 0
    new = [i for i, n in enumerate(params.names) if warm is not None and n not in warm.parameters.names]
    if new and settings.screen_points > 0:  # screen the new parameters, start from the best points
        starts += _screened_starts(model, measured, params, x0, new, settings)
        screened = settings.screen_points
    elif new:  # second start: the new effect's parameters a third into their range
        x1 = x0.copy()
        x1[new] = np.where(x0[new] < 0.5, x0[new] + 1 / 3, x0[new] - 1 / 3)
        starts.append(x1)
    fit = calibrate(
        model,
        measured,
        parameters=catalogue.parameters(active),
        x_starts=starts,
        spec=spec_of(settings),
        n_starts=settings.n_starts,
        seed=settings.seed,
        max_evaluations=settings.max_evaluations,
        label=_label(active),
        active=dict(active),
    )
    return replace(fit, n_evaluations=fit.n_evaluations + screened)


def _screened_starts(model, measured, params, x0, new, settings: DiagnoseSettings) -> list[np.ndarray]:
    """The best ``n_starts - 1`` (at least 1) of ``screen_points`` Sobol points in the new parameters."""
    from scipy.stats import qmc

    from framework.updating.problem import UpdatingProblem

    n = settings.screen_points
    pts = qmc.Sobol(d=len(new), scramble=True, seed=settings.seed).random(n)
    X = np.tile(x0, (n, 1))
    X[:, new] = pts
    obj = UpdatingProblem(model, measured, parameters=params, objective=spec_of(settings)).objective(X)
    order = np.argsort(obj)
    return [X[i] for i in order[: max(1, settings.n_starts - 1)]]


def spec_of(settings: DiagnoseSettings):
    return gaussian_spec(
        mac_threshold=settings.mac_threshold,
        frequency_window=settings.frequency_window,
        unmatched_window=settings.unmatched_window,
        use_shapes=settings.use_shapes,
    )


def diagnose(
    catalogue: Catalogue,
    measured: MeasuredModes,
    settings: DiagnoseSettings | None = None,
    start: Mapping[str, str] | None = None,
) -> Diagnosis:
    """Run detect -> name -> add until nothing significant remains (see module docstring)."""
    settings = settings or DiagnoseSettings()
    noise_source = noise_source_of(measured, settings)
    if noise_source != "data":
        log.warning("%s: %s", measured.name, noise_warning(noise_source))
    # the noise is fixed once: every calibration and test of this diagnosis whitens with it
    data = with_stds(measured, data_noise(measured, settings.frequency_std_rel, settings.shape_std_rel))
    if not settings.use_shapes or not data.has_shapes:
        settings = settings.model_copy(update={"use_shapes": False})
    spec = spec_of(settings)
    active = catalogue.check_active(start or {})
    fit = fit_model(catalogue, active, data, settings)
    spent = fit.n_evaluations
    rounds: list[Round] = []
    conclusion = ""
    for r in range(settings.max_rounds + 1):
        det = detect(fit, data, spec, settings.alpha)
        rnd = Round(r, fit, det)
        rounds.append(rnd)
        if not det.significant and not (settings.rank_always and r == 0):
            conclusion = "no significant discrepancy remains" if r else "no significant discrepancy"
            break
        if r == settings.max_rounds:
            conclusion = f"stopped after {settings.max_rounds} added effects; discrepancy still significant"
            break
        candidates: dict[str, tuple[Fit, int]] = {}
        projector = None
        for name, eff in catalogue.candidate_effects().items():
            if name in active:
                continue
            variants = list(eff.variants)
            if settings.screen_keep is not None and len(variants) > settings.screen_keep:
                if projector is None:
                    projector, used = _projector(catalogue, active, fit, data, settings)
                    spent += used
                variants, rows, used = _screen(catalogue, active, name, eff, fit, data, settings, projector)
                spent += used
                rnd.screen.extend(rows)
            best = None
            for variant in variants:
                f = fit_model(catalogue, {**active, name: variant}, data, settings, warm=fit)
                spent += f.n_evaluations
                if best is None or f.chi2 < best.chi2:
                    best = f
            candidates[name] = (best, len(eff.variants))
        if not candidates:
            conclusion = "every candidate effect is already in the model"
            break
        rnd.ranking = rank(fit, candidates, settings.decisive_delta_bic)
        rnd.candidate_fits = {k: v[0] for k, v in candidates.items()}
        if settings.evidence:
            spent += _evidence(rnd, catalogue, fit, candidates, data, settings)
        _flag_table(rnd, catalogue, settings)
        if settings.holdout_modes and data.n_modes >= 2:
            _holdout(rnd, catalogue, data, spec, settings)
        if not det.significant:
            conclusion = "no significant discrepancy"
            break
        if rnd.ranking.named is None:
            conclusion = "no candidate explains the gap: " + rnd.ranking.reason
            break
        rnd.named = rnd.ranking.named
        log.info("round %d: named %s (%s)", r + 1, rnd.named, rnd.ranking.reason)
        fit = candidates[rnd.named][0]
        active = dict(fit.active)
        if settings.refine_starts:
            refined = _refine(catalogue, fit, data, settings)
            spent += refined.n_evaluations
            fit = refined if refined.chi2 < fit.chi2 else fit
    d = Diagnosis(catalogue.structure, data, rounds, conclusion, catalogue, n_evaluations=spent,
                  noise_source=noise_source)  # fmt: skip
    _verdict(d, settings)
    return d


# ---- noise, screening, evidence, flags, verdict ------------------------------------------
def noise_source_of(measured: MeasuredModes, settings: DiagnoseSettings) -> str:
    """"data" when the data carry the standard deviations the test needs, else the assumption."""
    noise = data_noise(measured, settings.frequency_std_rel, settings.shape_std_rel, use_shapes=settings.use_shapes)
    missing = []
    if noise.frequency_source == "assumed":
        missing.append(f"frequency std = {settings.frequency_std_rel:.2%} of f")
    if noise.shape_source == "assumed":
        missing.append(f"shape std = {settings.shape_std_rel:.1%} of the largest component")
    return "data" if not missing else "assumed: " + ", ".join(missing)


def noise_warning(noise_source: str) -> str:
    """The warning printed in the summary when the noise test runs under an assumption."""
    if noise_source == "data":
        return ""
    return (f"WARNING: the data give no standard deviations; the noise test assumes {noise_source[9:]} "
            "(settings frequency_std_rel / shape_std_rel); if the real noise is larger, a 'significant "
            "discrepancy' may be noise")  # fmt: skip


def _projector(catalogue, active, fit: Fit, data, settings) -> tuple[np.ndarray, int]:
    from framework.diagnosis.screen import base_projector
    from framework.updating.problem import UpdatingProblem

    problem = UpdatingProblem(catalogue.model(active), data, parameters=fit.parameters, objective=spec_of(settings))
    x0 = fit.parameters.to_normalized(fit.theta)
    return base_projector(problem, x0), 1 + len(x0)


def _screen(catalogue, active, name, eff, fit: Fit, data, settings, projector):
    """The ``screen_keep`` best variants by the linearized screen, the screening rows, evaluations."""
    from framework.diagnosis.screen import screen_scores

    x_base = dict(zip(fit.parameters.names, map(float, fit.theta)))
    scores, used = {}, 0
    for variant in eff.variants:
        act = {**active, name: variant}
        params = catalogue.parameters(act)
        base = {p.name: x_base.get(p.name, p.initial) for p in params}
        scores[variant], n = screen_scores(catalogue.model(act), data, params, base, eff, projector, spec_of(settings),
                                           fit.residuals)
        used += n
    order = sorted(eff.variants, key=lambda v: scores[v])
    keep = order[: settings.screen_keep]
    rows = [{"effect": name, "effect_variant": v, "chi2_linearized": scores[v], "screen_rank": i + 1,
             "calibrated": v in keep} for i, v in enumerate(order)]  # fmt: skip
    return keep, rows, used


#: step in x of the central differences of the evidence's Jacobian
EVIDENCE_FD_STEP = 1e-3


def _evidence(rnd: Round, catalogue: Catalogue, fit: Fit, candidates, data, settings) -> int:
    """Laplace ln Z (:func:`framework.inference.evidence.laplace_log_evidence_chi2`, uniform prior
    on the box and over the V variants searched) of no change and of every candidate's best fit
    into the ranking table; the Jacobian of the whitened residuals at each fit from
    ``UpdatingProblem.jacobian`` (central differences: the Gaussian formulation has no exact
    Jacobian). 2 (ln Z_1 - ln Z_0) is on the scale of -Delta BIC; an effect is decisive by the
    evidence when it beats no change and the runner-up by ``DECISIVE_2LNB`` (Kass & Raftery:
    very strong). A parameter at its bound (flagged) makes the approximation rough."""
    from framework.diagnosis.score import DECISIVE_2LNB
    from framework.inference.evidence import laplace_log_evidence_chi2
    from framework.updating.problem import UpdatingProblem

    fits = {NO_CHANGE: (fit, 1)} | candidates
    log_z, used = {}, 0
    for name, (f, n_var) in fits.items():
        model = catalogue.model(f.active)
        problem = UpdatingProblem(model, data, parameters=f.parameters, objective=spec_of(settings))
        x = f.parameters.to_normalized(f.theta)
        jac = problem.jacobian(x, result=f.modal, fd_step=EVIDENCE_FD_STEP, scheme="central")
        used += jac.cost
        spans = np.array([p.span for p in f.parameters])
        log_z[name] = laplace_log_evidence_chi2(f.chi2, jac.J[: len(f.residuals)], spans, n_var)
    table = rnd.ranking.table
    table["log_evidence"] = table["effect"].map(log_z)
    table["two_ln_bayes_vs_none"] = 2 * (table["log_evidence"] - log_z[NO_CHANGE])
    ordered = table.sort_values("log_evidence", ascending=False, na_position="last")
    best = ordered.iloc[0]
    named = ""
    if best["effect"] != NO_CHANGE and best["two_ln_bayes_vs_none"] > DECISIVE_2LNB:
        others = ordered[(ordered["effect"] != best["effect"]) & (ordered["effect"] != NO_CHANGE)]
        margin = 2 * (best["log_evidence"] - others["log_evidence"].max()) if len(others) else np.inf
        if margin > DECISIVE_2LNB:
            named = str(best["effect"])
    table["evidence_best"] = table["effect"] == best["effect"]
    table["evidence_named"] = table["effect"] == named if named else False
    return used


def _fit_flags(f: Fit, catalogue: Catalogue, tol: float) -> list[str]:
    """A parameter within ``tol`` of its range from a bound (not at its null value there), a sign
    against the effect's ``expected_sign``."""
    out = []
    signs = {}
    nulls = {}
    for eff in catalogue.effects.values():
        for p in eff.parameters:
            signs[p.name] = eff.expected_sign.get(p.name, 0)
            nulls[p.name] = p.initial
    for p, v in zip(f.parameters, f.theta):
        x = (v - p.lower) / p.span if p.span > 0 else 0.5
        null = nulls.get(p.name)
        at_null = null is not None and abs(v - null) <= tol * p.span
        if (x <= tol or x >= 1 - tol) and not at_null:
            out.append(f"{p.name} = {v:.4g} at its {'lower' if x <= tol else 'upper'} bound")
        s = signs.get(p.name, 0)
        if s and (v - nulls[p.name]) * s < 0 and not at_null:
            out.append(f"{p.name} = {v:.4g} has the sign against the effect's physics")
    return out


def _flag_table(rnd: Round, catalogue: Catalogue, settings: DiagnoseSettings) -> None:
    table = rnd.ranking.table
    fits = {NO_CHANGE: rnd.fit} | rnd.candidate_fits
    table["flags"] = table["effect"].map(lambda e: "; ".join(_fit_flags(fits[e], catalogue, settings.bound_tolerance)))


def _verdict(d: Diagnosis, settings: DiagnoseSettings) -> None:
    """conclusion (never more than the noise test supports), partial, headline, flags."""
    parts = []
    for r in d.rounds:
        det = r.detection
        txt = f"round {r.index + 1}: {r.fit.label} chi2 {det.chi2:.1f} (p {det.p_value:.2g}"
        txt += f", {det.n_unmatched} unmatched)" if det.n_unmatched else ")"
        if r.named:
            where = r.candidate_fits[r.named].active.get(r.named, "")
            txt += f" -> named {r.named}" + (f"[{where}]" if where else "")
        elif r.ranking is not None and det.significant:
            txt += f" -> nothing named ({r.ranking.reason})"
        elif not det.significant:
            txt += " -> consistent with the noise"
        parts.append(txt)
    d.headline = "; ".join(parts)
    named = d.named_effects
    last = d.rounds[-1].detection
    for r in d.rounds:
        if r.named:
            d.flags[r.named] = _fit_flags(r.candidate_fits[r.named], d.catalogue, settings.bound_tolerance)
    if not named:
        rk = d.rounds[-1].ranking
        if d.rounds[-1].detection.significant and rk is not None and len(rk.table) > 1:
            top = rk.table[rk.table["effect"] != NO_CHANGE].head(2)
            gains = rk.table.set_index("effect")["delta_bic_vs_none"]
            if len(top) == 2 and gains[top.iloc[0]["effect"]] > settings.decisive_delta_bic:
                a, b = (f"{r['effect']}[{r['variant']}]" if r["variant"] else r["effect"] for _, r in top.iterrows())
                d.conclusion = (f"ambiguous: {a} and {b} both reduce the gap (Delta BIC vs no change "
                                f"{gains[top.iloc[0]['effect']]:.1f} and {gains[top.iloc[1]['effect']]:.1f}) and the "
                                "data cannot tell them apart; nothing named (more or other sensors needed, or the "
                                "missing physics lies outside the candidates)")  # fmt: skip
                return
        if d.rounds[0].detection.significant:
            d.conclusion = ("unexplained: significant discrepancy and no candidate explains it "
                            f"({d.rounds[-1].ranking.reason if d.rounds[-1].ranking else d.conclusion}); "
                            "the missing physics may lie outside the candidates")  # fmt: skip
        return
    where = " + ".join(f"{n}[{d.after.active.get(n, '')}]" if d.after.active.get(n) else n for n in named)
    if not last.significant:
        d.conclusion = f"explained by {where}: the enriched model passes the noise test (p {last.p_value:.2g})"
        return
    d.partial = True
    gap = d.after.gap()
    d.conclusion = (f"partial: {where} reduce chi2 from {d.before.chi2:.1f} to {last.chi2:.1f}, but the remaining "
                    f"discrepancy is significant (p {last.p_value:.2g}, max |frequency error| "
                    f"{gap['max_freq_error_pct']:.2f} %, {gap['n_unmatched']} unmatched); the missing physics may "
                    "lie outside the candidates")  # fmt: skip


def _refine(catalogue: Catalogue, fit: Fit, data: MeasuredModes, settings: DiagnoseSettings) -> Fit:
    """The enriched model re-calibrated from its estimate plus ``refine_starts`` random starts."""
    x0 = fit.parameters.to_normalized(fit.theta)
    return calibrate(
        catalogue.model(fit.active),
        data,
        parameters=catalogue.parameters(fit.active),
        spec=spec_of(settings),
        n_starts=1 + settings.refine_starts,
        seed=settings.seed + 1000,
        max_evaluations=settings.max_evaluations,
        label=fit.label,
        active=dict(fit.active),
        x_starts=[x0],
    )


def _holdout(rnd: Round, catalogue: Catalogue, data: MeasuredModes, spec, settings: DiagnoseSettings) -> None:
    """Add leave-one-mode-out predictive chi2 to the ranking; veto a name it contradicts."""
    from framework.diagnosis.holdout import loo_chi2

    fits = {NO_CHANGE: rnd.fit} | rnd.candidate_fits
    loo = {k: loo_chi2(catalogue, f, data, spec, settings.max_evaluations)[0] for k, f in fits.items()}
    table = rnd.ranking.table
    table["loo_chi2"] = table["effect"].map(loo)
    table["delta_loo_vs_none"] = loo[NO_CHANGE] - table["loo_chi2"]
    best_loo = min(loo, key=loo.get)
    named = rnd.ranking.named
    if named is not None and best_loo != named:
        rnd.ranking.named = None
        rnd.ranking.reason = (
            f"not named: {named} is best by BIC but {best_loo} predicts held-out modes best "
            f"(LOO chi2 {loo[best_loo]:.1f} vs {loo[named]:.1f})"
        )
        table["named"] = False
        table["decision"] = rnd.ranking.reason
