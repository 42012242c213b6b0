"""The discrepancy study: hidden effects x noise levels x seeds per structure, tidy tables.

Each case generates data from a truth with a hidden effect (or none: the null case),
runs :func:`framework.discrepancy.workflow.diagnose` with the model under test, and
returns one flat row (nevergrad-style: a failed case records its error). Rows are
stored one JSON part per case under ``_cases/`` (atomic), so a killed study resumes;
``cases.csv`` / ``rates.csv`` (+ Parquet) and ``study.png`` are rebuilt from the parts.
Detailed tables of showcase cases go to ``<root>/<case_id>/``.

Rates per (structure, hidden effect, magnitude, noise): correct = the named effects equal the
hidden ones (and, for effects with variants, the named variant is the hidden one is
reported separately as ``variant_correct``); wrong = something named that is not hidden;
partial = some but not all hidden effects named, nothing wrong; missed = nothing named
although an effect is hidden; false discovery = anything named in a null case.
"""

from __future__ import annotations

import json
import logging
import time
from collections.abc import Iterable
from pathlib import Path

import numpy as np
import pandas as pd

from framework.discrepancy.effects import get_catalogue
from framework.discrepancy.generate import NOISE_LEVELS, HiddenCase, generate
from framework.discrepancy.score import NO_CHANGE
from framework.discrepancy.workflow import DiagnoseSettings, diagnose
from framework.io import atomic_write_text, save_figure
from framework.study.store import write_table

log = logging.getLogger(__name__)

#: hidden-effect sets per structure (tuples: several effects hidden at once)
HIDDEN: dict[str, list[tuple[str, ...]]] = {
    "beam": [(), ("support_rotational_restraint",), ("localized_stiffness_loss",), ("midspan_mass",)],
    "lab_frame": [
        (),
        ("semi_rigid_joints",),
        ("sensor_mass_eccentricity",),
        ("semi_rigid_joints", "sensor_mass_eccentricity"),
    ],
    "bridge": [(), ("local_cable_vibration",), ("bearing_flexibility",)],
}
#: workflow settings per structure (budgets sized for a shared 2-core machine)
SETTINGS: dict[str, DiagnoseSettings] = {
    "beam": DiagnoseSettings(n_starts=2, max_evaluations=200, holdout_modes=True),
    "lab_frame": DiagnoseSettings(n_starts=2, max_evaluations=150),
    "bridge": DiagnoseSettings(n_starts=1, max_evaluations=60, max_rounds=2, frequency_window=0.15),
}


def case_id(structure: str, hidden: tuple[str, ...], noise: str, seed: int, magnitude: float = 1.0) -> str:
    mag = "" if magnitude == 1.0 or not hidden else f"__mag{magnitude:g}"
    return f"{structure}__{'+'.join(hidden) or 'none'}{mag}__{noise}__seed{seed}"


def plan(
    structures: Iterable[str],
    noises: Iterable[str],
    seeds: Iterable[int],
    hidden: dict | None = None,
    magnitudes: Iterable[float] = (1.0,),
) -> list[dict]:
    """One small spec per case (null and parameter-free cases once, not per magnitude)."""
    hidden = hidden or HIDDEN
    specs, seen = [], set()
    for s in structures:
        cat = get_catalogue(s)
        for h in hidden[s]:
            for mag in magnitudes:
                # magnitude is meaningless without hidden effect parameters (e.g. cable chains)
                mag = float(mag) if any(cat.effect(e).n_parameters for e in h) else 1.0
                for n in noises:
                    for seed in seeds:
                        cid = case_id(s, h, n, seed, mag)
                        if cid not in seen:
                            seen.add(cid)
                            specs.append(
                                {"structure": s, "hidden": list(h), "noise": n, "seed": int(seed), "magnitude": mag,
                                 "id": cid}
                            )  # fmt: skip
    return specs


def run_case(spec: dict, detail_dir: Path | None = None, settings: DiagnoseSettings | None = None) -> dict:
    """Generate, diagnose, score one case; returns one flat row (errors recorded, not raised)."""
    row = {k: spec[k] for k in ("id", "structure", "noise", "seed")}
    row["magnitude"] = float(spec.get("magnitude", 1.0))
    hidden = tuple(spec["hidden"])
    row["hidden_effect"] = "+".join(hidden) or NO_CHANGE
    t0 = time.perf_counter()
    try:
        cat = get_catalogue(spec["structure"])
        measured = generate(
            cat,
            HiddenCase(
                {h: None for h in hidden},
                seed=spec["seed"],
                noise=NOISE_LEVELS[spec["noise"]],
                magnitude=row["magnitude"],
            ),
        )
        d = diagnose(cat, measured, settings or SETTINGS[spec["structure"]])
        s = d.summary()
        named = d.named_effects
        row["hidden_variant"] = "+".join(v for v in measured.meta["hidden"].values() if v)
        row["named_effect"] = "+".join(named) or NO_CHANGE
        row["named_variant"] = "+".join(d.after.active.get(n, "") for n in named if d.after.active.get(n, ""))
        row["correct"] = bool(hidden) and set(named) == set(hidden)
        row["variant_correct"] = row["correct"] and row["named_variant"] == row["hidden_variant"]
        row["wrong"] = bool(named) and not set(named) <= set(hidden)
        row["missed"] = bool(hidden) and not named
        row["false_discovery"] = (not hidden) and bool(named)
        row["partial"] = bool(named) and set(named) < set(hidden)
        row["conclusion"] = d.conclusion
        for k in ("detected", "chi2_before", "p_before", "chi2_after", "p_after", "n_data"):
            row[k] = s[k]
        for k in ("max_freq_error_pct", "min_mac", "n_unmatched"):
            row[f"{k}_before"] = s[f"{k}_before"]
            row[f"{k}_after"] = s[f"{k}_after"]
        first = d.rounds[0].ranking.table if d.rounds[0].ranking is not None else None
        row["bic_best_round1"] = str(first.iloc[0]["effect"]) if first is not None else ""
        row["loo_best_round1"] = (
            str(first.loc[first["loo_chi2"].idxmin(), "effect"]) if first is not None and "loo_chi2" in first else ""
        )
        row["truth"] = json.dumps(measured.meta["truth_parameters"])
        row["fitted"] = json.dumps(dict(zip(d.after.parameters.names, map(float, d.after.theta))))
        row["error"] = ""
        if detail_dir is not None:
            from framework.discrepancy import report

            report.write(d, detail_dir / spec["id"])
    except Exception as exc:  # a failed case is data, the sweep goes on
        log.exception("case %s failed", spec["id"])
        row["error"] = f"{type(exc).__name__}: {exc}"
    row["wall_s"] = time.perf_counter() - t0
    return row


def rates(cases: pd.DataFrame) -> pd.DataFrame:
    """Per structure, hidden effect and noise: counts, rates and median gaps."""
    ok = cases[cases["error"].fillna("") == ""]
    keys = ["structure", "hidden_effect", "magnitude", "noise"]
    g = ok.groupby(keys, sort=True)
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
    failed = cases[cases["error"] != ""].groupby(keys).size()
    out["n_failed"] = [int(failed.get(tuple(k), 0)) for k in out[keys].to_numpy()]
    return out


def consolidate(root: Path) -> tuple[pd.DataFrame, pd.DataFrame]:
    parts = sorted((root / "_cases").glob("*.json"))
    cases = pd.DataFrame([json.loads(p.read_text()) for p in parts])
    if cases.empty:
        return cases, cases
    if "magnitude" not in cases:  # parts written before the column existed
        cases["magnitude"] = 1.0
    cases["magnitude"] = cases["magnitude"].fillna(1.0)
    cases["error"] = cases["error"].astype(object).where(cases["error"].notna(), "").astype(str)
    derived = ~cases[["correct", "wrong", "missed"]].fillna(False).astype(bool).any(axis=1) & (
        cases["hidden_effect"] != NO_CHANGE
    )
    if "partial" not in cases:  # parts written before the column existed
        cases["partial"] = derived
    cases["partial"] = cases["partial"].astype(object).where(cases["partial"].notna(), derived).astype(bool)
    cases = cases.sort_values(["structure", "hidden_effect", "magnitude", "noise", "seed"], kind="stable").reset_index(
        drop=True
    )
    r = rates(cases)
    write_table(cases, root / "cases")
    write_table(r, root / "rates")
    plot(cases, root / "study.png")
    return cases, r


def run(specs: list[dict], root: str | Path, resume: bool = True, showcase_seeds: Iterable[int] = ()) -> pd.DataFrame:
    """Run every case not stored yet; consolidate the tables."""
    root = Path(root)
    parts = root / "_cases"
    done = {p.stem for p in parts.glob("*.json")} if resume and parts.exists() else set()
    showcase = set(showcase_seeds)
    for i, spec in enumerate(specs):
        if spec["id"] in done:
            continue
        row = run_case(spec, detail_dir=root if spec["seed"] in showcase else None)
        atomic_write_text(parts / f"{spec['id']}.json", json.dumps(row, default=_json))
        log.warning(
            "[%d/%d] %s -> %s (%.1f s)",
            i + 1,
            len(specs),
            spec["id"],
            row.get("named_effect", row["error"]),
            row["wall_s"],
        )
    return consolidate(root)[0]


def _json(obj):
    if isinstance(obj, (np.integer,)):
        return int(obj)
    if isinstance(obj, (np.floating,)):
        return float(obj)
    if isinstance(obj, np.bool_):
        return bool(obj)
    return str(obj)


def plot(cases: pd.DataFrame, path: Path) -> None:
    """Gap before/after per case (max frequency error, log scale) and naming outcome."""

    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    ok = cases[cases["error"] == ""].copy()
    ok["outcome"] = np.select(
        [
            ok["correct"].astype(bool),
            ok["wrong"].astype(bool),
            ok["false_discovery"].astype(bool),
            ok["missed"].astype(bool),
            ok["partial"].astype(bool),
        ],
        ["correct", "wrong", "false discovery", "missed", "partial (subset named)"],
        "none (null case)",
    )
    structures = sorted(ok["structure"].unique())
    fig, axes = plt.subplots(1, max(len(structures), 1), figsize=(5.5 * max(len(structures), 1), 4.5), squeeze=False)
    colors = {
        "correct": "tab:green",
        "wrong": "tab:red",
        "false discovery": "tab:purple",
        "missed": "tab:orange",
        "none (null case)": "0.5",
        "partial (subset named)": "tab:olive",
    }
    for ax, s in zip(axes[0], structures):
        d = ok[ok["structure"] == s]
        for outcome, dd in d.groupby("outcome"):
            ax.scatter(
                dd["max_freq_error_pct_before"],
                dd["max_freq_error_pct_after"],
                s=18,
                color=colors[outcome],
                label=f"{outcome} ({len(dd)})",
                alpha=0.8,
            )
        lim = [
            max(1e-3, float(np.nanmin(d[["max_freq_error_pct_before", "max_freq_error_pct_after"]].to_numpy())) / 2),
            float(np.nanmax(d[["max_freq_error_pct_before", "max_freq_error_pct_after"]].to_numpy())) * 2,
        ]
        ax.plot(lim, lim, "k--", lw=0.7)
        ax.set(xscale="log", yscale="log", xlabel="max |freq error| before (%)", ylabel="after (%)", title=s)
        ax.legend(fontsize=7)
    fig.tight_layout()
    save_figure(fig, path, dpi=110, tight=False)
