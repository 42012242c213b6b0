"""Figures of diagnoses, drawn from their tables only (:mod:`framework.diagnosis.tables`).

- :func:`case_figure` (``discrepancy.png``): one diagnosis: frequency error and MAC per
  mode before/after, the candidates' Delta BIC per round, COMAC per sensor and round;
- :func:`study_figure` (``study.png``): many diagnoses of data with hidden effects: the gap
  before against after per case, coloured by outcome (the ``cases`` table of
  :mod:`framework.diagnosis.outcomes`);
- :func:`power_figure` (``power.png``): rate of the correct effect named against the hidden
  effect's magnitude;
- :func:`diagnosis_figures`: those of a ``diagnose`` study (the kind's ``figures`` hook);
- :func:`write`: a diagnosis's tables (CSV + Parquet, atomic) and its figure, for the
  Python API (studies write through the engine's store instead).
"""

from __future__ import annotations

import logging
from pathlib import Path

import numpy as np
import pandas as pd

from framework.core.status import succeeded
from framework.core.tables import write_table
from framework.diagnosis.tables import diagnosis_tables
from framework.report.figures.style import save_figure, styled, subplots

log = logging.getLogger(__name__)


def write(diagnosis, output: str | Path, figure: bool = True) -> dict[str, pd.DataFrame]:
    """Write every table of ``diagnosis`` (and ``discrepancy.png``) under ``output``."""
    out = Path(output)
    tables = diagnosis_tables(diagnosis)
    for name, df in tables.items():
        write_table(df, out / name)
    if figure:
        case_figure(tables, out / "discrepancy.png")
    return tables


@styled
def case_figure(tables: dict[str, pd.DataFrame], path: Path) -> None:
    """Four panels: frequency error and MAC per mode before/after, candidate Delta BIC, COMAC
    (the tables of one diagnosis)."""
    modes = tables["modes"]
    fig, axes = subplots(2, 2, figsize=(11, 7.5))
    colors = {"before": "tab:red", "after": "tab:blue"}
    width = 0.38
    for k, stage in enumerate(("before", "after")):
        d = modes[modes["stage"] == stage]
        x = d["mode"].to_numpy() + (k - 0.5) * width
        err = d["error_pct"].to_numpy(dtype=float)
        matched = d["matched"].to_numpy(dtype=bool)
        model = d["model"].iloc[0] if len(d) else stage
        axes[0, 0].bar(x, np.where(matched, err, 0.0), width, color=colors[stage], label=f"{stage}: {model}")
        axes[0, 1].bar(x, np.where(matched, d["mac"].to_numpy(dtype=float), 0.0), width, color=colors[stage])
        for xi, ok in zip(x, matched):
            if not ok:
                for ax in (axes[0, 0], axes[0, 1]):
                    ax.text(xi, 0, "unmatched", rotation=90, ha="center", va="bottom", fontsize=7, color=colors[stage])
    ticks = sorted(modes["mode"].unique())
    for ax in (axes[0, 0], axes[0, 1]):
        ax.set_xticks(ticks)
    axes[0, 0].axhline(0, color="k", lw=0.5)
    axes[0, 0].set(xlabel="measured mode", ylabel="frequency error (%)", title="calibrated model vs measured")
    axes[0, 0].legend(fontsize=7)
    axes[0, 1].set(xlabel="measured mode", ylabel="MAC", ylim=(0, 1.05), title="MAC of paired modes")
    cands = tables.get("candidates", pd.DataFrame())
    ax = axes[1, 0]
    if len(cands):
        c = cands.copy()
        c["name"] = (
            "round " + c["round"].astype(str) + ": " + c["effect"]
            + c["effect_variant"].fillna("").map(lambda v: f" [{v}]" if v else "")
        )
        delta = c["delta_bic_vs_none"].to_numpy(dtype=float)
        # Kass & Raftery's evidence grades: 0-2 barely worth a mention, 2-6 positive, 6-10 strong,
        # > 10 very strong; the axis is linear within +-10 (where the grades are) and logarithmic beyond
        for lo, hi, shade in ((2, 6, "0.95"), (6, 10, "0.88"), (10, max(11.0, 1.5 * np.nanmax(np.abs(delta))), "0.8")):
            ax.axvspan(lo, hi, color=shade, zorder=0)
        ax.barh(c["name"], delta, color=np.where(c["named"].astype(bool), "tab:green", "0.5"), zorder=2)
        ax.axvline(10, color="k", ls="--", lw=0.8)
        ax.axvline(0, color="k", lw=0.5)
        ax.set_xscale("symlog", linthresh=10, linscale=1.0)
        ax.set(xlabel="Delta BIC vs no change (> 0: candidate better; linear to 10, log beyond)")
        ax.set_title("candidates (green: named); bands: positive 2-6, strong 6-10, very strong > 10", fontsize=9)
        ax.tick_params(axis="y", labelsize=7)
    else:
        ax.text(0.5, 0.5, "no candidates ranked", ha="center")
    com = tables.get("comac", pd.DataFrame())
    ax = axes[1, 1]
    if len(com):
        for r, d in com.groupby("round"):
            ax.plot(range(len(d)), d["comac"], "o-", label=f"round {r}: {d['model'].iloc[0]}")
        ax.set_xticks(range(len(d)), d["sensor"], rotation=90, fontsize=6)
        ax.set(ylabel="COMAC", title="COMAC by sensor", ylim=(min(0.9, float(com["comac"].min()) - 0.02), 1.005))
        ax.legend(fontsize=7)
    fig.tight_layout()
    save_figure(fig, path)


OUTCOME_COLORS = {
    "correct": "tab:green",
    "wrong": "tab:red",
    "false discovery": "tab:purple",
    "missed": "tab:orange",
    "none (null case)": "0.5",
    "partial (subset named)": "tab:olive",
}


@styled
def study_figure(cases: pd.DataFrame, path: Path) -> None:
    """Gap before/after per case (max frequency error, log scale), coloured by naming outcome;
    one panel per structure (the ``cases`` table)."""
    ok = cases[cases["status"].map(succeeded).astype(bool)].copy()
    ok["outcome"] = np.select(
        [ok[c].astype(bool) for c in ("correct", "wrong", "false_discovery", "missed", "subset_named")],
        ["correct", "wrong", "false discovery", "missed", "partial (subset named)"],
        "none (null case)",
    )
    structures = sorted(ok["structure"].unique())
    n = max(len(structures), 1)
    fig, axes = subplots(1, n, figsize=(5.5 * n, 4.5), squeeze=False)
    gaps = ["max_freq_error_pct_before", "max_freq_error_pct_after"]
    for ax, structure in zip(axes[0], structures):
        d = ok[ok["structure"] == structure]
        for outcome, dd in d.groupby("outcome"):
            ax.scatter(dd[gaps[0]], dd[gaps[1]], s=18, color=OUTCOME_COLORS[outcome], label=f"{outcome} ({len(dd)})",
                       alpha=0.8)  # fmt: skip
        values = d[gaps].to_numpy(dtype=float)
        lim = [max(1e-3, float(np.nanmin(values)) / 2), float(np.nanmax(values)) * 2]
        ax.plot(lim, lim, "k--", lw=0.7)
        ax.set(xscale="log", yscale="log", xlabel="max |freq error| before (%)", ylabel="after (%)", title=structure)
        ax.legend(fontsize=7)
    fig.tight_layout()
    save_figure(fig, path)


@styled
def power_figure(cases: pd.DataFrame, path: Path) -> None:
    """Power curve: rate of the correct effect and location named against the hidden effect's
    magnitude, one line per noise level, one panel per structure (cases with the hidden
    effect among the candidates)."""
    ok = cases[cases["status"].map(succeeded).astype(bool) & (cases["hidden_effect"] != "none")]
    if "hidden_in_candidates" in ok:
        ok = ok[ok["hidden_in_candidates"].astype(bool)]
    structures = sorted(ok["structure"].unique())
    n = max(len(structures), 1)
    fig, axes = subplots(1, n, figsize=(4.2 * n, 3.6), squeeze=False)
    for ax, structure in zip(axes[0], structures):
        d = ok[ok["structure"] == structure]
        for noise, dd in d.groupby("noise"):
            g = dd.groupby("magnitude")
            ax.plot(g["variant_correct"].mean().index, g["variant_correct"].mean().to_numpy(), "o-",
                    label=f"{noise} (effect+location)")  # fmt: skip
            ax.plot(g["correct"].mean().index, g["correct"].mean().to_numpy(), "x--", alpha=0.6,
                    label=f"{noise} (effect)")  # fmt: skip
        ax.set(xlabel="magnitude of the hidden effect (1 = full)", ylabel="rate named correctly", title=structure,
               ylim=(-0.03, 1.03))  # fmt: skip
        ax.legend(fontsize=6)
    fig.tight_layout()
    save_figure(fig, path)


def diagnosis_figures(tables: dict[str, pd.DataFrame], out_dir: Path, showcase_seeds=(),
                      outcomes: bool = False) -> list[Path]:
    """The figures of a ``diagnose`` study: ``discrepancy.png`` (a study of one run),
    ``showcase/<case>.png`` (every run of the seeds ``showcase_seeds``; figures of runs no
    longer shown are removed), ``study.png`` and ``power.png`` (``outcomes``: the ``cases`` table)."""
    out_dir = Path(out_dir)
    summary = tables.get("summary")
    written: list[Path] = []
    if summary is None or summary.empty:
        return written
    done = summary[summary["status"].map(succeeded)]
    if len(summary) == 1 and len(done) == 1:
        case_figure(_run_tables(tables, done["run_id"].iloc[0]), out_dir / "discrepancy.png")
        written.append(out_dir / "discrepancy.png")
    showcase = done[done["seed"].isin(list(showcase_seeds))]
    folder = out_dir / "showcase"
    names = showcase["case"].where(~showcase["case"].duplicated(keep=False),
                                   showcase["case"] + "__" + showcase["run_id"].str[:8])  # fmt: skip
    for run_id, name in zip(showcase["run_id"], names):
        path = folder / f"{name}.png"
        case_figure(_run_tables(tables, run_id), path)
        written.append(path)
    if folder.exists():  # figures of runs no longer shown
        for stale in set(folder.glob("*.png")) - set(written):
            stale.unlink()
    if outcomes and tables.get("cases") is not None and not tables["cases"].empty:
        study_figure(tables["cases"], out_dir / "study.png")
        written.append(out_dir / "study.png")
        power_figure(tables["cases"], out_dir / "power.png")
        written.append(out_dir / "power.png")
    return written


def _run_tables(tables: dict, run_id: str) -> dict:
    return {name: df[df["run_id"] == run_id] for name, df in tables.items() if "run_id" in df}
