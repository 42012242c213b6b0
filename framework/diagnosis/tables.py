"""A diagnosis as tidy tables (rows of plain values), the tables of run kind ``diagnose``.

- ``summary``: one row: data, named effect(s) and variant(s), conclusion, chi2 and p of the
  model under test (before) and of the final model (after), gaps before/after (largest
  |frequency error| in %, lowest MAC, unmatched modes), the best candidate of round 1 by
  BIC and by held-out modes, the truth and the final fit as JSON text, evaluations;
- ``rounds``: per round, the chi-square test of the current model (chi2, dof, p, unmatched
  modes, z slope, sign runs, lowest COMAC), what was named and why;
- ``candidates``: per round, every candidate effect (best variant) and "none": chi2, BIC,
  Delta BIC against no change, rank, held-out-mode chi2 (``holdout_modes``), decision;
- ``modes``: per measured mode, before (model under test) and after (final model):
  frequencies, error, MAC, matched, standardized frequency residual z, shape chi2 and p;
- ``parameters``: every fitted model's parameters: the current model of every round
  (``candidate`` "none") and every candidate's fit, with the true value when the data
  were generated (an effect that was not hidden is at its null value in the truth);
- ``comac``: COMAC per sensor and round.

Column names never repeat the run key of the study tables (``label``, ``variant``, ...):
a mode's label is ``mode_label``, an effect's variant ``effect_variant``.
"""

from __future__ import annotations

import json
import math

import pandas as pd

from framework.core.parameters import Parameter
from framework.diagnosis.effects import Catalogue
from framework.diagnosis.score import NO_CHANGE
from framework.diagnosis.workflow import Diagnosis
from framework.updating.pairing import correlation_table

TABLES = ("summary", "rounds", "candidates", "modes", "parameters", "comac", "screen")


def diagnosis_rows(d: Diagnosis) -> dict[str, list[dict]]:
    """Every table of a diagnosis as lists of row dicts."""
    return {
        "summary": [summary_row(d)],
        "rounds": round_rows(d),
        "candidates": candidate_rows(d),
        "modes": mode_rows(d),
        "parameters": parameter_rows(d),
        "comac": comac_rows(d),
        "screen": [{"round": r.index + 1, **row} for r in d.rounds for row in r.screen],
    }


def diagnosis_tables(d: Diagnosis) -> dict[str, pd.DataFrame]:
    """Every table of a diagnosis as DataFrames."""
    return {name: pd.DataFrame(rows) for name, rows in diagnosis_rows(d).items()}


def summary_row(d: Diagnosis) -> dict:
    row = {k: v for k, v in d.summary().items() if k != "structure"}
    named = d.named_effects
    row["named_variant"] = "+".join(d.after.active[n] for n in named if d.after.active.get(n))
    row["n_rounds"] = len(d.rounds)
    first = d.rounds[0].ranking.table if d.rounds[0].ranking is not None else None
    row["bic_best_round1"] = str(first.iloc[0]["effect"]) if first is not None else ""
    has_loo = first is not None and "loo_chi2" in first
    row["loo_best_round1"] = str(first.loc[first["loo_chi2"].idxmin(), "effect"]) if has_loo else ""
    meta = d.measured.meta or {}
    row["hidden_variant"] = "+".join(v for v in meta.get("hidden", {}).values() if v)
    row["named_location"] = row["named_variant"]
    row["hidden_location"] = row["hidden_variant"]
    if first is not None:
        best = first.iloc[0]
        others = first[(first["effect"] != best["effect"]) & (first["effect"] != NO_CHANGE)]
        margin = float(others["bic"].min() - best["bic"]) if len(others) else math.inf
        row["bic_best_variant_round1"] = str(best["variant"])
        row["bic_decisive_round1"] = bool(best["effect"] != NO_CHANGE and best["delta_bic_vs_none"] > 10.0
                                          and margin > 10.0)  # fmt: skip
        if "log_evidence" in first and first["log_evidence"].notna().any():
            ev = first.loc[first["log_evidence"].idxmax()]
            row["evidence_best_round1"] = str(ev["effect"])
            row["evidence_best_variant_round1"] = str(ev["variant"])
            row["evidence_named_round1"] = bool(first["evidence_named"].any())
    row["truth"] = json.dumps(meta["truth_parameters"]) if "truth_parameters" in meta else ""
    row["fitted"] = json.dumps(dict(zip(d.after.parameters.names, map(float, d.after.theta))))
    row["n_evaluations"] = int(d.n_evaluations)
    return row


def round_rows(d: Diagnosis) -> list[dict]:
    return [
        {
            "round": r.index + 1,
            "model": r.fit.label,
            "n_parameters": r.fit.k,
            **r.detection.summary(),
            "named": r.named or NO_CHANGE,
            "decision": r.ranking.reason if r.ranking is not None else "",
            "n_evaluations": int(r.fit.n_evaluations),
        }
        for r in d.rounds
    ]


def candidate_rows(d: Diagnosis) -> list[dict]:
    rows = []
    for r in d.rounds:
        if r.ranking is None:
            continue
        fits = {NO_CHANGE: r.fit} | r.candidate_fits
        table = r.ranking.table.rename(columns={"variant": "effect_variant"})
        for rec in table.to_dict("records"):
            f = fits[rec["effect"]]
            own = {p.name: float(v) for p, v in zip(f.parameters, f.theta)
                   if rec["effect"] != NO_CHANGE and p in d.catalogue.effects[rec["effect"]].parameters}  # fmt: skip
            rec["fitted_effect"] = json.dumps(own)
            rec["fitted_all"] = json.dumps(dict(zip(f.parameters.names, map(float, f.theta))))
            rows.append({"round": r.index + 1, "model": f.label, **rec})
    return rows


def mode_rows(d: Diagnosis) -> list[dict]:
    rows = []
    last = d.rounds[-1]
    for stage, rnd in (("before", d.rounds[0]), ("after", last)):
        table = correlation_table(rnd.fit.correlation, d.measured).rename(columns={"label": "mode_label"})
        det = rnd.detection.modes
        table = table.assign(
            z_frequency=det["z_frequency"].to_numpy(),
            chi2_shape=det["chi2_shape"].to_numpy(),
            p_shape=det["p_shape"].to_numpy(),
        )
        key = {"stage": stage, "round": rnd.index + 1, "model": rnd.fit.label}
        rows += [{**key, **rec} for rec in table.to_dict("records")]
    return rows


def parameter_rows(d: Diagnosis) -> list[dict]:
    owner = {p.name: "base" for p in d.catalogue.base_parameters}
    for name, effect in d.catalogue.effects.items():
        owner |= {p.name: name for p in effect.parameters}
    truth = (d.measured.meta or {}).get("truth_parameters")
    rows = []
    for r in d.rounds:
        final = r is d.rounds[-1]
        fits = [(NO_CHANGE, r.fit)] + list(r.candidate_fits.items())
        for candidate, fit in fits:
            for p, value in zip(fit.parameters, fit.theta):
                ref = reference_parameter(d.catalogue, p.name)
                rows.append({
                    "round": r.index + 1,
                    "candidate": candidate,
                    "model": fit.label,
                    "named": candidate == r.named,
                    "final": final and candidate == NO_CHANGE,
                    "parameter": p.name,
                    "effect": owner.get(p.name, ""),
                    "effect_variant": fit.active.get(owner.get(p.name, ""), ""),
                    "value": float(value),
                    "truth": float(truth.get(p.name, ref.initial)) if truth is not None else math.nan,
                    "null_or_initial": ref.initial,
                    "lower": p.lower,
                    "upper": p.upper,
                    "unit": p.unit,
                })  # fmt: skip
    return rows


def comac_rows(d: Diagnosis) -> list[dict]:
    rows = []
    for r in d.rounds:
        for rec in r.detection.comac.to_dict("records"):
            rows.append({"round": r.index + 1, "model": r.fit.label, **rec})
    return rows


def reference_parameter(catalogue: Catalogue, name: str) -> Parameter:
    """The catalogue's definition of parameter ``name`` (its ``initial`` is the null value of an effect)."""
    for p in catalogue.base_parameters:
        if p.name == name:
            return p
    for effect in catalogue.effects.values():
        for p in effect.parameters:
            if p.name == name:
                return p
    raise KeyError(name)
