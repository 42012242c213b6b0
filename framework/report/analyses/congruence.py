"""Torsion congruence of the lab frame: which reading reproduces the source's initial model.

For each variant (a congruence reading of :mod:`framework.structures.lab_frame.model`) the table holds
the initial model's MACs (modes table, run label ``initial_label``, case base), the lowest
objective any run found (runs table), and their misfit to the source's statements
(SPEC 5: initial MACs 0.989, 0.974, 0.999; minimum about 1.3e-6):

    mac_rms_diff    = sqrt(mean_j (MAC_j - MAC_source,j)^2)
    minimum_misfit  = |log10(min Pi / Pi_source)|
    score           = mac_rms_diff / mac_scale + minimum_misfit

(mac_scale = 0.01: a MAC difference of 0.01 weighs as much as a factor of 10 in the minimum;
our choice). ``chosen`` marks the lowest score.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pandas as pd

SOURCE_MAC = (0.989, 0.974, 0.999)
SOURCE_MINIMUM = 1.3e-6


def congruence_table(runs: pd.DataFrame, modes: pd.DataFrame, initial_label: str = "initial_model",
                     source_mac=SOURCE_MAC, source_minimum: float = SOURCE_MINIMUM,
                     mac_scale: float = 0.01) -> pd.DataFrame:
    """One row per variant: initial MACs, minimum, misfits, score, chosen."""
    rows = []
    src = np.asarray(source_mac, float)
    for variant, g in runs.groupby("variant", sort=False):
        init = modes[(modes["variant"] == variant) & (modes["label"] == initial_label) & (modes["case"] == "base")]
        init = init.sort_values("mode")
        mac = init["mac"].to_numpy(float)[: len(src)]
        initial_objective = g.loc[g["label"] == initial_label, "objective"]
        minimum = float(np.nanmin(g["objective"]))
        row = {"congruence": variant}
        for j, (m, s) in enumerate(zip(mac, src), start=1):
            row[f"mac_{j}"] = float(m)
            row[f"mac_{j}_source"] = float(s)
        rms = float(np.sqrt(np.mean((mac - src[: len(mac)]) ** 2))) if len(mac) else np.nan
        misfit = float(abs(np.log10(minimum / source_minimum)))
        row |= {
            "initial_objective": float(initial_objective.iloc[0]) if len(initial_objective) else np.nan,
            "minimum_objective": minimum, "minimum_source": source_minimum,
            "mac_rms_diff": rms, "mac_max_abs_diff": float(np.max(np.abs(mac - src[: len(mac)]))),
            "minimum_misfit_log10": misfit, "score": rms / mac_scale + misfit,
        }
        rows.append(row)
    out = pd.DataFrame(rows)
    if not out.empty:
        out["chosen"] = out["score"] == out["score"].min()
    return out


def tables(tables: dict[str, pd.DataFrame], **options) -> dict[str, pd.DataFrame]:
    if "runs" not in tables or "modes" not in tables or tables["runs"].empty:
        return {}
    return {"congruence": congruence_table(tables["runs"], tables["modes"], **options)}


def figures(tables: dict[str, pd.DataFrame], out_dir: Path, **_) -> list[Path]:
    return []
