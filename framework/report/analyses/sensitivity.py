"""Sensitivities and identifiability of an ``analysis`` study, from its tables only.

Asked for with ``report: {sensitivity: {variants: [...]}}`` (``variants``: the variants to
draw, default all). Table:

- ``sensitivity_summary``: variant x point x parameter: the largest |S_f| = |(df/f)/(dp/p)|
  over the modes and the mode it belongs to, the largest |S_MAC|, and the parameter's rank
  (1 = largest |S_f|) at that point; a parameter whose largest |S_f| is far below the
  others' is not identifiable from the frequencies.

Figures: ``sensitivity.png`` (one row per variant and point: frequency and MAC
sensitivities per parameter and mode), ``parameter_correlation.png`` (correlation of the
linearized fit, one heat map per variant and point), ``singular_values.png``.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pandas as pd


def _select(df: pd.DataFrame | None, variants: list[str] | None) -> pd.DataFrame | None:
    if df is not None and variants:
        df = df[df["variant"].isin(variants)]
    return None if df is None or df.empty else df


def summary(sens: pd.DataFrame) -> pd.DataFrame:
    """Largest relative sensitivities per variant, point and parameter."""
    rows = []
    for (variant, point, parameter), g in sens.groupby(["variant", "label", "parameter"], sort=False):
        f = g["rel_sensitivity_frequency"].abs().to_numpy()
        i = int(np.nanargmax(f)) if np.isfinite(f).any() else 0
        rows.append({"variant": variant, "label": point, "parameter": parameter,
                     "max_abs_frequency_sensitivity": float(np.nanmax(f)) if np.isfinite(f).any() else np.nan,
                     "mode_of_max": g["mode_label"].iloc[i],
                     "max_abs_mac_sensitivity": float(g["rel_sensitivity_mac"].abs().max())})
    out = pd.DataFrame(rows)
    out["rank"] = out.groupby(["variant", "label"])["max_abs_frequency_sensitivity"].rank(
        ascending=False, method="min").astype(int)
    return out


def tables(tables: dict[str, pd.DataFrame], variants: list[str] | None = None) -> dict[str, pd.DataFrame]:
    sens = _select(tables.get("sensitivity"), variants)
    return {} if sens is None else {"sensitivity_summary": summary(sens)}


def figures(tables: dict[str, pd.DataFrame], out_dir: Path, variants: list[str] | None = None, **_) -> list[Path]:
    """sensitivity.png, parameter_correlation.png, singular_values.png of the tables there are
    (:mod:`framework.report.figures.sensitivity`)."""
    from framework.report.figures import sensitivity as draw

    out_dir = Path(out_dir)
    written = []
    sens = _select(tables.get("sensitivity"), variants)
    if sens is not None:
        written.append(draw.sensitivity_figure(sens, out_dir / "sensitivity.png"))
    corr = _select(tables.get("parameter_correlation"), variants)
    if corr is not None:
        written.append(draw.correlation_figure(corr, out_dir / "parameter_correlation.png"))
    ident = _select(tables.get("identifiability"), variants)
    if ident is not None:
        written.append(draw.singular_values_figure(ident, out_dir / "singular_values.png"))
    return written
