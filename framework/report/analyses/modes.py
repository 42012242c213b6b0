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
"""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pandas as pd

from framework.core.io import save_figure
from framework.report.figures.updating import mode_ticks

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


def plot_frequencies(modes: pd.DataFrame, path: Path, pairing: str, point: str, references: list[str] | None) -> bool:
    import matplotlib.pyplot as plt

    df = _base(modes, pairing, point)
    if df.empty:
        return False
    first = df[df["variant"] == df["variant"].iloc[0]]
    references = _references(df, references)
    fig, ax = plt.subplots(figsize=(7.5, 4.2))
    ax.plot(first["mode"], first["f_measured_hz"], "ko", label="measured")
    for ref in references:
        ax.plot(first["mode"], first[ref], "s", mfc="none", label=ref)
    for variant, g in df.groupby("variant", sort=False):
        ax.plot(g["mode"], g["f_model_hz"], "x", ms=8, label=f"model, {variant}")
    ticks = mode_ticks(first)
    ax.set_xticks(list(ticks), list(ticks.values()), fontsize=7)
    ax.set(xlabel="measured mode", ylabel="frequency (Hz)",
           title=f"Model at the {point} point vs measured (pairing: {pairing})")
    ax.legend(fontsize=7)
    save_figure(fig, path, dpi=120)
    return True


def plot_errors(modes: pd.DataFrame, path: Path, pairing: str) -> bool:
    import matplotlib.pyplot as plt

    df = modes[(modes["pairing"] == pairing) & (modes["case"] == "base") & (modes["mode"] > 0)]
    if df.empty:
        return False
    points = list(dict.fromkeys(df["label"]))
    colors = {v: f"C{i}" for i, v in enumerate(dict.fromkeys(df["variant"]))}
    width = max(5.0, 0.95 * df["mode"].nunique() + 1.5)
    fig, axes = plt.subplots(1, len(points), figsize=(width * len(points) + 2, 4.4), sharey=True, squeeze=False)
    for ax, point in zip(axes[0], points):
        for variant, g in df[df["label"] == point].groupby("variant", sort=False):
            matched = g["matched"].astype(bool).to_numpy()
            ax.plot(g["mode"], np.where(matched, g["error_pct"], np.nan), "o-", color=colors[variant], label=variant)
            if (~matched).any():
                ax.plot(g["mode"][~matched], np.zeros((~matched).sum()), "x", color=colors[variant], ms=11, mew=2,
                        label=f"{variant}: unmatched")
        ax.axhline(0.0, color="k", lw=0.5)
        ticks = mode_ticks(df)
        ax.set_xticks(list(ticks), list(ticks.values()), fontsize=7)
        ax.set(title=f"{point} parameters", xlabel="measured mode")
    handles = {}
    for ax in axes[0]:
        for h, lab in zip(*ax.get_legend_handles_labels()):
            handles.setdefault(lab, h)
    fig.legend(list(handles.values()), list(handles), fontsize=7, loc="upper left", bbox_to_anchor=(1.0, 0.95))
    axes[0][0].set_ylabel(f"(f_model - f_measured) / f_measured [%], pairing: {pairing}")
    fig.tight_layout()
    save_figure(fig, path, dpi=120)
    return True


def figures(tables: dict[str, pd.DataFrame], out_dir: Path, frequency_pairing: str | None = None,
            error_pairing: str = "objective", point: str = "initial", references: list[str] | None = None,
            **_) -> list[Path]:
    modes = tables.get("modes")
    if modes is None or modes.empty or "pairing" not in modes:
        return []
    out_dir = Path(out_dir)
    written = []
    pairing = frequency_pairing or str(modes["pairing"].iloc[0])
    if plot_frequencies(modes, out_dir / "frequencies.png", pairing, point, references):
        written.append(out_dir / "frequencies.png")
    if plot_errors(modes, out_dir / "mode_errors.png", error_pairing):
        written.append(out_dir / "mode_errors.png")
    return written
