"""Outcomes of diagnoses of data with hidden effects: ``cases`` and ``rates`` (table -> table).

``cases``: one row per run whose data were generated (the ``summary`` table of run kind
``diagnose``), scored against the hidden effects (H: hidden set, N: named set):

- correct = H non-empty and N = H; variant_correct = correct and the named variant(s)
  equal the hidden one(s) (e.g. the element of a stiffness loss);
- wrong = N non-empty and N not a subset of H;
- partial = N non-empty and N a proper subset of H;
- missed = H non-empty and N empty;
- false_discovery = H empty and N non-empty.

``rates``: per structure, hidden effect, magnitude and noise level: the number of cases,
the mean of each outcome over the completed runs, median gaps before/after, unmatched modes
summed, median wall time, and the number of runs that did not complete.
"""

from __future__ import annotations

import pandas as pd

from framework.discrepancy.score import NO_CHANGE

GROUP = ["structure", "hidden_effect", "magnitude", "noise"]
CASE_COLUMNS = [
    "run_id", "id", "structure", "noise", "seed", "magnitude", "hidden_effect", "hidden_variant", "named_effect",
    "named_variant", "correct", "variant_correct", "wrong", "partial", "missed", "false_discovery", "conclusion",
    "detected", "chi2_before", "p_before", "chi2_after", "p_after", "n_data", "max_freq_error_pct_before",
    "max_freq_error_pct_after", "min_mac_before", "min_mac_after", "n_unmatched_before", "n_unmatched_after",
    "bic_best_round1", "loo_best_round1", "truth", "fitted", "status", "error", "wall_s", "n_evaluations",
]  # fmt: skip
OUTCOMES = ["correct", "variant_correct", "wrong", "partial", "missed", "false_discovery"]


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
        "partial": bool(n) and n < h,
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
    for col in ("named_effect", "named_variant", "hidden_variant", "conclusion", "error"):
        df[col] = df[col].fillna("") if col in df else ""
    done = df["status"] == "completed"
    flags = pd.DataFrame(
        [score(h, n, hv, nv) for h, n, hv, nv in df[["hidden_effect", "named_effect", "hidden_variant",
                                                       "named_variant"]].itertuples(index=False)],
        index=df.index,
    )  # fmt: skip
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
    ok = cases[cases["status"] == "completed"]
    g = ok.groupby(GROUP, sort=True)
    out = g.agg(
        n_cases=("seed", "size"),
        detected_rate=("detected", "mean"),
        correct_rate=("correct", "mean"),
        variant_correct_rate=("variant_correct", "mean"),
        wrong_rate=("wrong", "mean"),
        partial_rate=("partial", "mean"),
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
    failed = cases[cases["status"] != "completed"].groupby(GROUP).size()
    out["n_failed"] = [int(failed.get(tuple(k), 0)) for k in out[GROUP].to_numpy()]
    return out
