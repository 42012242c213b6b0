"""The modes of an ``analysis`` study (models at given points), from its tables only.

Asked for with ``report: {modes: {references: [design_model_hz]}}``. Table:

- ``mode_summary``: variant x point x case x pairing: modes, matched modes, max
  |error_pct| over the matched modes, min MAC, the unmatched measured modes;
- ``frequencies``: the numbers of ``frequencies.png`` (base case, pairing
  ``frequency_pairing``, point ``point``): one row per measured mode with the measured
  frequency, the data's reference frequencies, and per variant the model's frequency
  ``f_<variant>_hz``, its error against the measured one ``error_<variant>_pct`` and, when
  there is a reference, its deviation from the first reference ``dev_<variant>_pct``.

Figures (base case):

- ``frequencies.png`` (pairing ``frequency_pairing``, default the first in the table, at
  point ``point``, default "initial"): measured frequency, the data's reference
  frequencies per mode (columns ``references``, default every ``*_hz`` column of the data)
  and the model's paired frequency for each variant;
- ``mode_errors.png`` (pairing ``error_pairing``, default "objective"): frequency error
  per mode, one panel per point, one line per variant, unmatched modes marked x at 0.

The figures are drawn by :mod:`framework.report.figures.modes`.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pandas as pd

MODEL_COLUMNS = ("f_measured_hz", "f_model_hz")


def summary(modes: pd.DataFrame) -> pd.DataFrame:
    rows = []
    ok = modes[modes["mode"] > 0]
    for key, g in ok.groupby(["variant", "label", "case", "pairing"], sort=False):
        matched = g["matched"].astype(bool)
        err = g.loc[matched, "error_pct"].abs()
        rows.append({**dict(zip(("variant", "label", "case", "pairing"), key)), "modes": len(g),
                     "matched": int(matched.sum()),
                     "max_abs_error_pct": float(err.max()) if len(err) else np.nan,
                     "min_mac": float(g.loc[matched, "mac"].min()) if matched.any() else np.nan,
                     "unmatched_modes": " ".join(str(m) for m in g.loc[~matched, "mode"])})
    return pd.DataFrame(rows)


def _base(modes: pd.DataFrame, pairing: str, point: str) -> pd.DataFrame:
    return modes[(modes["pairing"] == pairing) & (modes["label"] == point) & (modes["case"] == "base")
                 & (modes["mode"] > 0)]


def _references(df: pd.DataFrame, references: list[str] | None) -> list[str]:
    if references is not None:
        return list(references)
    return [c for c in df.columns if c.endswith("_hz") and c not in MODEL_COLUMNS and df[c].notna().any()]


def frequency_table(modes: pd.DataFrame, pairing: str, point: str, references: list[str] | None) -> pd.DataFrame:
    df = _base(modes, pairing, point)
    if df.empty:
        return df
    first = df[df["variant"] == df["variant"].iloc[0]]
    refs = _references(df, references)
    keep = [c for c in ("mode", "mode_label", "measured_type", "f_measured_hz") if c in first] + refs
    out = first[keep].reset_index(drop=True)
    for variant, g in df.groupby("variant", sort=False):
        f = g["f_model_hz"].to_numpy(float)
        out[f"f_{variant}_hz"] = f
        out[f"error_{variant}_pct"] = 100.0 * (f / out["f_measured_hz"].to_numpy(float) - 1.0)
        if refs:
            out[f"dev_{variant}_pct"] = 100.0 * (f / out[refs[0]].to_numpy(float) - 1.0)
    return out


def tables(tables: dict[str, pd.DataFrame], frequency_pairing: str | None = None, point: str = "initial",
           references: list[str] | None = None, **_) -> dict[str, pd.DataFrame]:
    modes = tables.get("modes")
    if modes is None or modes.empty or "pairing" not in modes:
        return {}
    out = {"mode_summary": summary(modes)}
    freq = frequency_table(modes, frequency_pairing or str(modes["pairing"].iloc[0]), point, references)
    if not freq.empty:
        out["frequencies"] = freq
    return out


def figures(tables: dict[str, pd.DataFrame], out_dir: Path, frequency_pairing: str | None = None,
            error_pairing: str = "objective", point: str = "initial", references: list[str] | None = None,
            **_) -> list[Path]:
    modes = tables.get("modes")
    if modes is None or modes.empty or "pairing" not in modes:
        return []
    from framework.report.figures.modes import errors_figure, frequencies_figure

    out_dir = Path(out_dir)
    written = []
    pairing = frequency_pairing or str(modes["pairing"].iloc[0])
    df = _base(modes, pairing, point)
    if not df.empty:
        written.append(frequencies_figure(df, _references(df, references), out_dir / "frequencies.png", pairing,
                                          point))
    df = modes[(modes["pairing"] == error_pairing) & (modes["case"] == "base") & (modes["mode"] > 0)]
    if not df.empty:
        written.append(errors_figure(df, out_dir / "mode_errors.png", error_pairing))
    return written
