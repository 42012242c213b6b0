"""Outcomes of diagnoses of data with hidden effects: ``cases`` and ``rates`` (table -> table).

``cases``: one row per run whose data were generated (the ``summary`` table of run kind
``diagnose``), scored against the hidden effects (H: hidden set, N: named set):

- correct = H non-empty and N = H; variant_correct = correct and the named variant(s)
  (``named_location``) equal the hidden one(s) (``hidden_location``, e.g. the element of a
  stiffness loss);
- wrong = N non-empty and N not a subset of H (a named effect, full or partial, that was
  not hidden; in an out-of-candidate case any name is wrong);
- subset_named = N non-empty and N a proper subset of H;
- missed = H non-empty and N empty;
- false_discovery = H empty and N non-empty;
- partial (the verdict): effects were named but the enriched model still fails the noise
  test; full_explanation = N non-empty and not partial.

In an out-of-candidate case (the hidden effect is not a candidate) any named effect is
"wrong" by these rules; ``targets`` reports such cases apart (they must be partial).

``rates``: per structure, candidates, hidden effect, magnitude, noise level and whether the
data carry standard deviations: the number of cases, the mean of each outcome over the
completed runs, median gaps before/after, unmatched modes summed, median wall time, and the
number of runs that did not complete. ``targets``: the acceptance rates of issue 17 over
the whole study (:func:`targets`). ``agreement``: round-1 winner by BIC against the winner
by the Laplace evidence where BIC is decisive (:func:`agreement`).
"""

from __future__ import annotations

import pandas as pd

from framework.core.status import succeeded
from framework.diagnosis.score import NO_CHANGE

GROUP = ["structure", "candidates", "hidden_effect", "magnitude", "noise", "data_stds"]
CASE_COLUMNS = [
    "run_id", "id", "structure", "candidates", "noise", "data_stds", "noise_source", "seed", "magnitude",
    "hidden_effect", "hidden_location", "hidden_in_candidates", "named_effect", "named_location", "correct",
    "variant_correct", "wrong", "subset_named", "missed", "false_discovery", "partial", "full_explanation",
    "conclusion", "headline", "flags",
    "detected", "chi2_before", "p_before", "chi2_after", "p_after", "n_data", "max_freq_error_pct_before",
    "max_freq_error_pct_after", "min_mac_before", "min_mac_after", "n_unmatched_before", "n_unmatched_after",
    "bic_best_round1", "loo_best_round1", "truth", "fitted", "status", "error", "wall_s", "n_evaluations",
]  # fmt: skip
OUTCOMES = ["correct", "variant_correct", "wrong", "subset_named", "missed", "false_discovery", "full_explanation"]


def effect_set(text) -> frozenset[str]:
    """The effects of a "+"-joined name ("none" and "" are the empty set)."""
    if not isinstance(text, str) or text in ("", NO_CHANGE):
        return frozenset()
    return frozenset(text.split("+"))


def score(hidden: str, named: str, hidden_variant: str = "", named_variant: str = "") -> dict[str, bool]:
    """The outcome flags of one case (see the module docstring)."""
    h, n = effect_set(hidden), effect_set(named)
    correct = bool(h) and n == h
    return {
        "correct": correct,
        "variant_correct": correct and (named_variant or "") == (hidden_variant or ""),
        "wrong": bool(n) and not n <= h,
        "subset_named": bool(n) and n < h,
        "missed": bool(h) and not n,
        "false_discovery": not h and bool(n),
    }


def cases(summary: pd.DataFrame) -> pd.DataFrame:
    """One scored row per run with generated data, ordered by structure, hidden effect,
    magnitude, noise and seed. A run that did not complete keeps its row with its error."""
    if summary.empty or "data_source" not in summary:
        return pd.DataFrame(columns=CASE_COLUMNS)
    df = summary[summary["data_source"] == "generated"].copy()
    if df.empty:
        return pd.DataFrame(columns=CASE_COLUMNS)
    df["id"] = df["case"]
    for col in ("named_effect", "named_variant", "hidden_variant", "conclusion", "error", "headline", "flags",
                "noise_source"):
        df[col] = df[col].fillna("") if col in df else ""
    df["named_location"] = df["named_variant"]
    df["hidden_location"] = df["hidden_variant"]
    for col, default in (("partial", False), ("data_stds", True), ("hidden_in_candidates", True),
                         ("candidates", "catalogue")):
        df[col] = df[col].where(df[col].notna(), default) if col in df else default
    df["partial"] = df["partial"].astype(bool)
    done = df["status"].map(succeeded).astype(bool)
    flags = pd.DataFrame(
        [score(h, n, hv, nv) for h, n, hv, nv in df[["hidden_effect", "named_effect", "hidden_variant",
                                                       "named_variant"]].itertuples(index=False)],
        index=df.index,
    )  # fmt: skip
    flags["full_explanation"] = (df["named_effect"].map(lambda t: bool(effect_set(t))) & ~df["partial"]).to_numpy()
    for col in OUTCOMES:
        df[col] = flags[col].where(done, False).astype(bool)
    out = df[[c for c in CASE_COLUMNS if c in df]]
    return out.sort_values(["structure", "hidden_effect", "magnitude", "noise", "seed"], kind="stable").reset_index(
        drop=True
    )


def rates(cases: pd.DataFrame) -> pd.DataFrame:
    """Per structure, hidden effect, magnitude and noise: counts, outcome rates, median gaps."""
    if cases.empty:
        return pd.DataFrame()
    ok = cases[cases["status"].map(succeeded).astype(bool)]
    g = ok.groupby(GROUP, sort=True)
    out = g.agg(
        n_cases=("seed", "size"),
        detected_rate=("detected", "mean"),
        correct_rate=("correct", "mean"),
        variant_correct_rate=("variant_correct", "mean"),
        wrong_rate=("wrong", "mean"),
        subset_named_rate=("subset_named", "mean"),
        partial_rate=("partial", "mean"),
        full_explanation_rate=("full_explanation", "mean"),
        missed_rate=("missed", "mean"),
        false_discovery_rate=("false_discovery", "mean"),
        max_freq_error_pct_before=("max_freq_error_pct_before", "median"),
        max_freq_error_pct_after=("max_freq_error_pct_after", "median"),
        min_mac_before=("min_mac_before", "median"),
        min_mac_after=("min_mac_after", "median"),
        n_unmatched_before=("n_unmatched_before", "sum"),
        n_unmatched_after=("n_unmatched_after", "sum"),
        wall_s=("wall_s", "median"),
    ).reset_index()
    failed = cases[~cases["status"].map(succeeded).astype(bool)].groupby(GROUP).size()
    out["n_failed"] = [int(failed.get(tuple(k), 0)) for k in out[GROUP].to_numpy()]
    return out


def targets(cases: pd.DataFrame) -> pd.DataFrame:
    """The acceptance rates of issue 17 over the completed cases (one row per target)."""
    ok = cases[cases["status"].map(succeeded).astype(bool)]
    hidden = ok[ok["hidden_effect"] != NO_CHANGE]
    inside = hidden[hidden["hidden_in_candidates"].astype(bool)]
    outside = hidden[~hidden["hidden_in_candidates"].astype(bool)]
    null = ok[ok["hidden_effect"] == NO_CHANGE]
    full = inside[inside["magnitude"] == 1.0]
    rows = [
        ("correct effect and location at full magnitude", ">= 0.90", full["variant_correct"], len(full)),
        ("correct effect at full magnitude", "", full["correct"], len(full)),
        ("wrong names (cases with a hidden effect)", "<= 0.02", hidden["wrong"], len(hidden)),
        ("wrong names, hidden effect among the candidates", "<= 0.02", inside["wrong"], len(inside)),
        ("named effects in out-of-candidate cases (any name is wrong there)", "", outside["wrong"],
         len(outside)),
        ("wrong full explanations (named as full, not hidden)", "",
         ok["wrong"] & ok["full_explanation"], len(ok)),
        ("wrong names (every case)", "", ok["wrong"], len(ok)),
        ("false discoveries, null cases with stds", "<= 0.05",
         null[null["data_stds"].astype(bool)]["false_discovery"], int(null["data_stds"].astype(bool).sum())),
        ("false discoveries, null cases without stds", "<= 0.05",
         null[~null["data_stds"].astype(bool)]["false_discovery"], int((~null["data_stds"].astype(bool)).sum())),
        ("out-of-candidate cases named as a full explanation", "0", outside["full_explanation"], len(outside)),
        ("out-of-candidate cases named as partial", "", outside["partial"], len(outside)),
    ]  # fmt: skip
    return pd.DataFrame([
        {"target": name, "required": req, "rate": float(v.mean()) if n else float("nan"), "count": int(v.sum()),
         "n_cases": n}
        for name, req, v, n in rows
    ])  # fmt: skip


def agreement(summary: pd.DataFrame) -> pd.DataFrame:
    """Per completed run where round-1 BIC is decisive: BIC's and the evidence's winner (effect, location)."""
    need = {"bic_decisive_round1", "evidence_best_round1"}
    if summary.empty or not need <= set(summary):
        return pd.DataFrame()
    done = summary["status"].map(succeeded).astype(bool)
    d = summary[done & summary["bic_decisive_round1"].fillna(False).astype(bool)]
    out = d[["run_id", "case", "structure", "bic_best_round1", "bic_best_variant_round1", "evidence_best_round1",
             "evidence_best_variant_round1", "evidence_named_round1"]].copy()  # fmt: skip
    out["same_effect"] = out["bic_best_round1"] == out["evidence_best_round1"]
    out["same_location"] = out["same_effect"] & (
        out["bic_best_variant_round1"].fillna("") == out["evidence_best_variant_round1"].fillna(""))
    return out.reset_index(drop=True)
