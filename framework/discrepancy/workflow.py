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
4. Show: :func:`framework.discrepancy.tables.diagnosis_tables` (rounds, candidates, modes
   before/after, parameters of every fitted model, COMAC, summary) and
   :mod:`framework.discrepancy.report` (figures drawn from those tables).

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

from framework.discrepancy import likelihood
from framework.discrepancy.calibrate import Fit, calibrate
from framework.discrepancy.detect import DEFAULT_ALPHA, Detection, detect
from framework.discrepancy.effects import Catalogue
from framework.discrepancy.score import DECISIVE_DELTA_BIC, NO_CHANGE, Ranking, rank
from framework.measurements import MeasuredModes
from framework.parameters import Parameter, ParameterSet

log = logging.getLogger(__name__)


class DiagnoseSettings(BaseModel):
    """Settings of the workflow (unknown keys rejected).

    alpha: level of the chi-square test; decisive_delta_bic: BIC margin to name an effect;
    n_starts / max_evaluations: least-squares starts and evaluations per start;
    frequency_std_rel / shape_std_rel: noise defaults when the data give no std;
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
    unmatched_window: float = Field(likelihood.DEFAULT_UNMATCHED_WINDOW, gt=0)
    use_shapes: bool = True
    frequency_std_rel: float = Field(likelihood.DEFAULT_FREQUENCY_STD_REL, gt=0)
    shape_std_rel: float = Field(likelihood.DEFAULT_SHAPE_STD_REL, gt=0)
    rank_always: bool = True
    holdout_modes: bool = False
    refine_starts: int = Field(3, ge=0)
    screen_points: int = Field(16, ge=0)
    #: seed of the calibrations' random starts and of the Sobol screening
    seed: int = Field(0, ge=0)


@dataclass
class Round:
    """One pass: the current fit, its detection, the candidate ranking, the named effect."""

    index: int
    fit: Fit
    detection: Detection
    ranking: Ranking | None = None
    named: str | None = None
    candidate_fits: dict[str, Fit] = field(default_factory=dict)


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

    from framework.problem import UpdatingProblem

    n = settings.screen_points
    pts = qmc.Sobol(d=len(new), scramble=True, seed=settings.seed).random(n)
    X = np.tile(x0, (n, 1))
    X[:, new] = pts
    obj = UpdatingProblem(model, measured, parameters=params, objective=spec_of(settings)).objective(X)
    order = np.argsort(obj)
    return [X[i] for i in order[: max(1, settings.n_starts - 1)]]


def spec_of(settings: DiagnoseSettings):
    return likelihood.objective_spec(
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
    data = likelihood.with_noise_model(measured, settings.frequency_std_rel, settings.shape_std_rel)
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
        for name, eff in catalogue.effects.items():
            if name in active:
                continue
            best = None
            for variant in eff.variants:
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
    return Diagnosis(catalogue.structure, data, rounds, conclusion, catalogue, n_evaluations=spent)


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
    from framework.discrepancy.holdout import loo_chi2

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
