"""Score and rank candidate effects: Bayesian information criterion with a decisive margin.

For a calibrated model with k free parameters and n data (Schwarz 1978),

    BIC = -2 ln L_max + k ln n + 2 ln V = chi2_min + k ln n + 2 ln V + const,

where V is the number of discrete variants searched (e.g. the element carrying a
stiffness loss): a uniform prior 1/V over variants adds 2 ln V, so searching more
locations must buy a proportionally better fit. The constant (from the known sigmas) is
the same for every model of one data set and is dropped.

An effect is *named* only when it is decisive (Kass & Raftery 1995: Delta BIC > 10,
"very strong" evidence) against both the current model ("no change") and the runner-up
among the other candidates; otherwise no candidate explains the gap.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import pandas as pd

from framework.diagnosis.calibrate import Fit

DECISIVE_DELTA_BIC = 10.0
#: 2 ln Bayes factor an effect must reach by the Laplace evidence against no change and the
#: runner-up (Kass & Raftery 1995: very strong; the evidence's scale is that of -Delta BIC)
DECISIVE_2LNB = 10.0
NO_CHANGE = "none"


def bic(chi2: float, k: int, n: int, n_variants: int = 1) -> float:
    """chi2 + k ln n + 2 ln(n_variants)."""
    return float(chi2 + k * math.log(n) + 2.0 * math.log(max(n_variants, 1)))


@dataclass
class Ranking:
    """Candidate table (one row per candidate, best first) and the named effect or None."""

    table: pd.DataFrame
    named: str | None
    reason: str


def rank(
    current: Fit,
    candidates: dict[str, tuple[Fit, int]],
    threshold: float = DECISIVE_DELTA_BIC,
) -> Ranking:
    """Rank ``candidates`` {effect: (best fit over its variants, number of variants)}.

    Returns the table with BIC, Delta BIC against no change (positive = candidate better)
    and the decision.
    """
    n = current.n_data
    rows = [
        {
            "effect": NO_CHANGE,
            "variant": "",
            "k": current.k,
            "k_added": 0,
            "n_variants": 1,
            "chi2": current.chi2,
            "n_unmatched": current.n_unmatched,
            "bic": bic(current.chi2, current.k, n),
        }
    ]
    for name, (fit, n_var) in candidates.items():
        rows.append(
            {
                "effect": name,
                "variant": fit.active.get(name, ""),
                "k": fit.k,
                "k_added": fit.k - current.k,
                "n_variants": n_var,
                "chi2": fit.chi2,
                "n_unmatched": fit.n_unmatched,
                "bic": bic(fit.chi2, fit.k, n, n_var),
            }
        )
    table = pd.DataFrame(rows).sort_values("bic", kind="stable").reset_index(drop=True)
    base_bic = rows[0]["bic"]
    table["delta_bic_vs_none"] = base_bic - table["bic"]
    table["rank"] = range(1, len(table) + 1)
    best = table.iloc[0]
    named: str | None = None
    if best["effect"] == NO_CHANGE:
        reason = "no candidate improves BIC over the current model"
    else:
        others = table[(table["effect"] != best["effect"]) & (table["effect"] != NO_CHANGE)]
        gap_none = base_bic - best["bic"]
        gap_next = (others["bic"].min() - best["bic"]) if len(others) else math.inf
        if gap_none > threshold and gap_next > threshold:
            named = str(best["effect"])
            reason = f"decisive: Delta BIC {gap_none:.1f} vs no change, {gap_next:.1f} vs runner-up"
        elif gap_none <= threshold:
            reason = f"not decisive: best candidate {best['effect']} gains only {gap_none:.1f} BIC over no change"
        else:
            reason = (
                f"not decisive: {best['effect']} and {others.iloc[0]['effect']} differ by {gap_next:.1f} BIC "
                "(the data cannot tell them apart)"
            )
    table["named"] = table["effect"] == (named or "")
    table["decision"] = reason
    return Ranking(table, named, reason)
