"""Figures of ``posterior`` studies, drawn from their tables only.

- ``corner_<run>.png`` (``draws``): histograms and pairwise scatter of the posterior draws
  of the first run;
- ``predictive.png`` (``predictive``): per case and mode of the first run, the 90 % credible
  (model) and predictive (with noise) intervals of the frequency, relative to the measured one;
- ``coverage.png`` (``coverage``, :mod:`framework.report.analyses.posterior`): coverage of
  the 90 % intervals per structure and parameter, sampled and linearized.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pandas as pd

from framework.report.figures.style import save_figure, styled, subplots


def posterior_figures(tables: dict, out_dir: Path) -> list[Path]:
    """Corner plot (draws), predictive bands (predictive) and coverage (coverage); returns the files."""
    out_dir = Path(out_dir)
    written: list[Path] = []
    draws = tables.get("draws")
    if draws is not None and len(draws):
        for run_id, d in draws.groupby("run_id") if "run_id" in draws else [("", draws)]:
            names = [c for c in tables["parameters"]["parameter"].unique() if c in d]
            path = out_dir / (f"corner_{str(run_id)[:8]}.png" if run_id else "corner.png")
            written.append(corner_figure(d, names, path))
            break  # one corner plot (the first run) per study
    pred = tables.get("predictive")
    if pred is not None and len(pred) and "ci90_lower_hz" in pred:
        first = pred[pred["run_id"] == pred["run_id"].iloc[0]] if "run_id" in pred else pred
        written.append(predictive_figure(first.dropna(subset=["ci90_lower_hz"]), out_dir / "predictive.png"))
    cov = tables.get("coverage")
    if cov is not None and len(cov):
        written.append(coverage_figure(cov, out_dir / "coverage.png"))
    return written


@styled
def corner_figure(draws: pd.DataFrame, names: list[str], path: Path) -> Path:
    """Histogram of each parameter's draws on the diagonal, pairwise scatter below."""
    k = len(names)
    fig, axes = subplots(k, k, figsize=(1.9 * k, 1.9 * k), squeeze=False)
    for i in range(k):
        for j in range(k):
            ax = axes[i, j]
            if j > i:
                ax.axis("off")
                continue
            if i == j:
                ax.hist(draws[names[i]], bins=30, color="0.4")
            else:
                ax.plot(draws[names[j]], draws[names[i]], ".", ms=1.5, alpha=0.4, color="C0")
            if i == k - 1:
                ax.set_xlabel(names[j], fontsize=7)
            if j == 0 and i > 0:
                ax.set_ylabel(names[i], fontsize=7)
            ax.tick_params(labelsize=5)
    fig.tight_layout()
    return save_figure(fig, path)


@styled
def predictive_figure(first: pd.DataFrame, path: Path) -> Path:
    """90 % credible and predictive intervals of each frequency, relative to the measured one."""
    fig, ax = subplots(figsize=(7, 3.5))
    labels = [f"{c}\n{m}" for c, m in zip(first["case"], first["mode"])]
    x = np.arange(len(first))
    fe = first["f_measured_hz"].to_numpy()
    rel = lambda col: 100.0 * (first[col].to_numpy() - fe) / fe  # noqa: E731
    mean = rel("mean_hz")
    ax.errorbar(x, mean, yerr=[mean - rel("pi90_lower_hz"), rel("pi90_upper_hz") - mean],
                fmt="none", ecolor="0.75", elinewidth=6, label="90 % predictive (with noise)")
    ax.errorbar(x, mean, yerr=[mean - rel("ci90_lower_hz"), rel("ci90_upper_hz") - mean],
                fmt="o", color="C0", ms=3, capsize=3, label="90 % credible (model)")
    ax.axhline(0.0, color="C3", lw=1, label="measured")
    ax.set_ylabel("(f_model - f_measured) / f_measured [%]")
    ax.set_xticks(x, labels, fontsize=6)
    ax.legend(fontsize=7)
    fig.tight_layout()
    return save_figure(fig, path)


@styled
def coverage_figure(cov: pd.DataFrame, path: Path) -> Path:
    """Coverage of the intervals per structure and parameter, one marker per method; the
    nominal value (the table's ``nominal``) as a line in a +-0.05 band."""
    fig, ax = subplots(figsize=(8, 3.5))
    cov = cov.reset_index(drop=True)
    for i, (method, g) in enumerate(cov.groupby("method")):
        ax.plot(np.arange(len(g)) + 0.15 * i, g["coverage"], "o", label=method)
    g0 = cov[cov["method"] == cov["method"].iloc[0]]
    ax.set_xticks(np.arange(len(g0)), [f"{s}\n{p}" for s, p in zip(g0.get("structure", ""), g0["parameter"])],
                  fontsize=5, rotation=90)
    nominal = float(cov["nominal"].iloc[0])
    ax.axhspan(nominal - 0.05, nominal + 0.05, color="0.9")
    ax.axhline(nominal, color="k", lw=0.8)
    ax.set_ylabel("coverage of 90 % intervals")
    ax.legend(fontsize=7)
    fig.tight_layout()
    return save_figure(fig, path)
