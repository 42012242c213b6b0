"""Derived tables and figures of ``posterior`` studies, from the tables only."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pandas as pd

from framework.report.figures.style import save_figure, styled, subplots

NOMINAL = 0.9


def coverage_table(parameters: pd.DataFrame | None) -> pd.DataFrame | None:
    """structure, method, parameter, nominal, coverage, n_seeds from runs with a known truth."""
    if parameters is None or "covered_sampled" not in parameters or parameters["truth"].isna().all():
        return None
    df = parameters[parameters["truth"].notna()]
    keys = [c for c in ("structure", "variant") if c in df] + ["parameter"]
    rows = []
    for method, col in (("sampled", "covered_sampled"), ("linearized", "covered_linearized")):
        g = df.groupby(keys, sort=True)[col].agg(["mean", "count"]).reset_index()
        g = g.rename(columns={"mean": "coverage", "count": "n_seeds"})
        g.insert(len(keys) - 1, "method", method)
        g["nominal"] = NOMINAL
        rows.append(g)
    out = pd.concat(rows, ignore_index=True)
    first = ["structure", "method", "parameter", "nominal", "coverage", "n_seeds"]
    return out[[c for c in first if c in out] + [c for c in out if c not in first]]


def agreement_table(parameters: pd.DataFrame | None) -> pd.DataFrame | None:
    """Per run on measured data and parameter: sampled mean - MAP in sampled std, lin_std / std,
    and whether the sampled and linearized posteriors agree (|shift| <= 0.1, |ratio - 1| <= 0.2)."""
    if parameters is None or "mean_shift_std" not in parameters:
        return None
    if "truth" in parameters:  # runs on simulated data are summarized by the coverage table
        parameters = parameters[parameters["truth"].isna()]
        if parameters.empty:
            return None
    cols = [c for c in ("structure", "variant", "run_id", "seed", "parameter", "map", "mean", "lin_std", "std",
                        "mean_shift_std", "std_ratio") if c in parameters]
    out = parameters[cols].copy()
    out["agree"] = (out["mean_shift_std"].abs() <= 0.1) & ((out["std_ratio"] - 1).abs() <= 0.2)
    return out


@styled
def posterior_figures(tables: dict, out_dir: Path) -> list[Path]:
    """Corner plot (draws), predictive bands (predictive) and coverage bars (coverage)."""
    out_dir = Path(out_dir)
    written: list[Path] = []
    draws = tables.get("draws")
    if draws is not None and len(draws):
        for run_id, d in draws.groupby("run_id") if "run_id" in draws else [("", draws)]:
            names = [c for c in tables["parameters"]["parameter"].unique() if c in d]
            k = len(names)
            fig, axes = subplots(k, k, figsize=(1.9 * k, 1.9 * k), squeeze=False)
            for i in range(k):
                for j in range(k):
                    ax = axes[i, j]
                    if j > i:
                        ax.axis("off")
                        continue
                    if i == j:
                        ax.hist(d[names[i]], bins=30, color="0.4")
                    else:
                        ax.plot(d[names[j]], d[names[i]], ".", ms=1.5, alpha=0.4, color="C0")
                    if i == k - 1:
                        ax.set_xlabel(names[j], fontsize=7)
                    if j == 0 and i > 0:
                        ax.set_ylabel(names[i], fontsize=7)
                    ax.tick_params(labelsize=5)
            fig.tight_layout()
            path = out_dir / (f"corner_{str(run_id)[:8]}.png" if run_id else "corner.png")
            save_figure(fig, path)
            written.append(path)
            break  # one corner plot (the first run) per study
    pred = tables.get("predictive")
    if pred is not None and len(pred) and "ci90_lower_hz" in pred:
        first = pred[pred["run_id"] == pred["run_id"].iloc[0]] if "run_id" in pred else pred
        first = first.dropna(subset=["ci90_lower_hz"])
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
        path = out_dir / "predictive.png"
        save_figure(fig, path)
        written.append(path)
    cov = tables.get("coverage")
    if cov is not None and len(cov):
        fig, ax = subplots(figsize=(8, 3.5))
        cov = cov.reset_index(drop=True)
        for i, (method, g) in enumerate(cov.groupby("method")):
            ax.plot(np.arange(len(g)) + 0.15 * i, g["coverage"], "o", label=method)
        g0 = cov[cov["method"] == cov["method"].iloc[0]]
        ax.set_xticks(np.arange(len(g0)), [f"{s}\n{p}" for s, p in zip(g0.get("structure", ""), g0["parameter"])],
                      fontsize=5, rotation=90)
        ax.axhspan(0.85, 0.95, color="0.9")
        ax.axhline(NOMINAL, color="k", lw=0.8)
        ax.set_ylabel("coverage of 90 % intervals")
        ax.legend(fontsize=7)
        fig.tight_layout()
        path = out_dir / "coverage.png"
        save_figure(fig, path)
        written.append(path)
    return written
