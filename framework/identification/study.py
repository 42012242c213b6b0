"""End-to-end identification study (issue 8): simulate tests, identify, compare, update.

``run(out_dir)`` writes under ``out_dir`` (default ``results/identification``):

- ``modes.csv``: one row per structure, test, method and true mode (plus "spurious" rows
  for identified modes that match no true mode): f_true_hz, f_identified_hz, f_error_pct,
  zeta_true, zeta_identified, zeta_error_pct, mac_to_true, stable (yes/no);
- ``stability.csv``: every pole of every stability sweep (order, frequency, damping, stable);
- ``peaks.csv``: FRF peak picking candidates with coherence and phase change;
- ``updating.csv``: lab frame updated from the identified modes, one row per algorithm,
  seed and parameter (true, initial, updated, error);
- ``lab_frame_identified.yaml``, ``bridge_{vertical,lateral}_identified.yaml``: identified
  modes in the measured-modes format;
- figures ``stability_*.png``, ``frf_*.png``; lab records in ``records/`` (NPZ and CSV).
"""

from __future__ import annotations

import io
import logging
import time
from pathlib import Path

import numpy as np
import pandas as pd

from framework.identification import bridge_tests, lab_tests
from framework.identification import pipeline as pl
from framework.identification.records import save
from framework.identification.stability import plot_stability
from framework.io import atomic_write_text
from framework.measurements import save as save_modes

log = logging.getLogger(__name__)

LAB_SETTINGS = pl.IdentificationSettings(
    orders=tuple(range(6, 41, 2)), block_rows=20, decimate=4, mac_min=0.9, band_hz=(0.5, 15.0)
)
BRIDGE_SETTINGS = pl.IdentificationSettings(
    orders=tuple(range(10, 81, 2)), block_rows=30, decimate=8, mac_min=0.8, band_hz=(0.8, 10.0)
)
LAB_LABELS = ("1st y", "1st x", "1st torsion")


def _write_csv(df: pd.DataFrame, path: Path) -> None:
    buf = io.StringIO()
    df.to_csv(buf, index=False)
    atomic_write_text(path, buf.getvalue())


def _tag(table: pd.DataFrame, **cols) -> pd.DataFrame:
    table = table.copy()
    for i, (k, v) in enumerate(cols.items()):
        table.insert(i, k, v)
    return table


def _stab_rows(ident: pl.Identification, structure: str, test: str) -> pd.DataFrame:
    cols = ["order", "frequency_hz", "damping_ratio", "mac_prev", "stable"]
    return _tag(ident.stability[cols], structure=structure, test=test, method=ident.method)


def lab_study(
    out_dir: Path,
    sweep_seeds=(1, 2, 3),
    snap_seeds=(4, 5),
    sweep_s: float = 150.0,
    save_records: bool = True,
    update: bool = True,
) -> dict[str, pd.DataFrame]:
    """Lab frame: 3 sweeps (N4SID, FRF peak picking on their average), 2 snap-backs (SSI-cov),
    export of the mean of the sweeps, updating of the 3-DOF model from it."""
    f_true, z_true, phi_true = lab_tests.true_modes()
    modes, stab = [], []
    sweeps = [lab_tests.sweep(s, duration_s=sweep_s) for s in sweep_seeds]
    idents = []
    for rec in sweeps:
        ident = pl.identify(rec, LAB_SETTINGS)
        idents.append(ident)
        cmp = pl.compare_to_truth(ident.selected, f_true, z_true, phi_true, LAB_LABELS)
        modes.append(_tag(cmp, structure="lab_frame", test=rec.name, method="n4sid"))
        stab.append(_stab_rows(ident, "lab_frame", rec.name))
    for seed in snap_seeds:
        rec = lab_tests.snap_back(seed)
        ident = pl.identify(rec, LAB_SETTINGS, free_decay=True)
        cmp = pl.compare_to_truth(ident.selected, f_true, z_true, phi_true, LAB_LABELS)
        modes.append(_tag(cmp, structure="lab_frame", test=rec.name, method="ssi_cov"))
        stab.append(_stab_rows(ident, "lab_frame", rec.name))
        if seed == snap_seeds[0]:
            plot_stability(
                ident.stability,
                out_dir / "stability_lab_frame_snapback.png",
                ident.selected,
                title=f"lab frame, {rec.name}, SSI-cov (output only)",
                f_max_hz=15.0,
            )
            if save_records:
                save(rec, out_dir / "records" / f"{rec.name}.npz")
    frf, peaks, pp = pl.peak_picking(sweeps, band_hz=(1.0, 15.0))
    cmp = pl.compare_to_truth(pp, f_true, z_true, phi_true, LAB_LABELS)
    modes.append(_tag(cmp, structure="lab_frame", test="sweeps_average", method="peak_picking"))
    from framework.identification.frf import plot_frf

    plot_frf(
        frf, out_dir / "frf_lab_frame.png", peaks, f"lab frame: H1 averaged over {len(sweeps)} sweeps", f_max_hz=15.0
    )
    indicator = (frf.frequency_hz, np.abs(frf.h[:, :, 0]).sum(axis=1))
    plot_stability(
        idents[0].stability,
        out_dir / "stability_lab_frame.png",
        idents[0].selected,
        indicator,
        title=f"lab frame, {sweeps[0].name}, N4SID (orders 6-40, 1 %, MAC 0.9)",
        f_max_hz=15.0,
    )
    avg = pl.average_identifications([i.selected for i in idents])
    cmp = pl.compare_to_truth(avg, f_true, z_true, phi_true, LAB_LABELS)
    modes.append(_tag(cmp, structure="lab_frame", test="sweeps_mean", method="n4sid"))
    measured = pl.to_measured_modes(
        avg, "lab_frame_identified", LAB_LABELS, source="N4SID, mean of 3 simulated sweeps (framework.identification)"
    )
    save_modes(measured, out_dir / "lab_frame_identified.yaml")
    if save_records:
        save(sweeps[0], out_dir / "records" / f"{sweeps[0].name}.npz")
        save(sweeps[0], out_dir / "records" / f"{sweeps[0].name}.csv")
    peaks = _tag(peaks, structure="lab_frame", test="sweeps_average")
    out = {
        "modes": pd.concat(modes, ignore_index=True),
        "stability": pd.concat(stab, ignore_index=True),
        "peaks": peaks,
    }
    if update:
        out["updating"] = update_lab(measured)
    return out


def update_lab(measured, algorithms=(("sm", (1,)), ("pso", (1, 2, 3))), max_evaluations: int = 20000):
    """Update the 3-DOF model from identified modes; error of each parameter vs the truth."""
    from framework.models import lab_frame
    from framework.optimizers import Budget, run_optimizer
    from framework.problem import UpdatingProblem

    rows = []
    for name, seeds in algorithms:
        for seed in seeds:
            problem = UpdatingProblem(lab_frame.make_model(), measured)
            budget = Budget(max_evaluations=max_evaluations, stall_iterations=50, target_objective=1e-12)
            t0 = time.perf_counter()
            res = run_optimizer(name, problem, seed=seed, budget=budget)
            wall = time.perf_counter() - t0
            for p, value in zip(problem.parameters, res.theta_best):
                true = lab_tests.TRUE_THETA[p.name]
                rows.append(
                    {
                        "structure": "lab_frame",
                        "algorithm": name,
                        "seed": seed,
                        "parameter": p.name,
                        "unit": p.unit,
                        "true": true,
                        "initial": p.initial,
                        "updated": float(value),
                        "error": float(value) - true,
                        "error_pct_of_range": 100 * (float(value) - true) / (p.upper - p.lower),
                        "objective": res.objective,
                        "n_evaluations": res.n_evaluations,
                        "wall_s": wall,
                        "status": res.status,
                    }
                )
    return pd.DataFrame(rows)


def bridge_study(
    out_dir: Path, seed: int = 1, sweep_s: float = bridge_tests.SWEEP_DURATION_S, jump_s: float = 300.0
) -> dict[str, pd.DataFrame]:
    """Bridge: vertical and lateral shaker sweeps (N4SID, peak picking), jumping (SSI-cov)."""
    truth = bridge_tests.true_modes()
    modes, stab, peaks_all = [], [], []
    tests = [
        ("vertical", "uz", bridge_tests.sweep(seed, "vertical", duration_s=sweep_s)),
        ("lateral", "uy", bridge_tests.sweep(seed + 1, "lateral", duration_s=sweep_s)),
        ("jumping", "uz", bridge_tests.jumping(seed + 2, duration_s=jump_s)),
    ]
    from framework.identification.frf import plot_frf

    for kind, comp, full in tests:
        channels = tuple(d for d in full.output_labels if d.endswith(comp))
        rec = full.select(channels)
        rows = [truth["dofs"].index(d) for d in channels]
        types = bridge_tests.TEST_MODE_TYPES.get(kind, ("vertical", "torsional"))
        keep = np.flatnonzero(np.isin(truth["mode_type"], types) & (truth["f_hz"] <= BRIDGE_SETTINGS.band_hz[1]))
        true_args = (
            truth["f_hz"][keep],
            truth["zeta"][keep],
            truth["shapes"][np.ix_(rows, keep)],
            [truth["labels"][k] for k in keep],
        )
        energy = truth["deck_energy"][keep]
        ident = pl.identify(rec, BRIDGE_SETTINGS)
        modes.append(
            _tag(
                _with_energy(pl.compare_to_truth(ident.selected, *true_args), energy),
                structure="bridge",
                test=rec.name,
                method=ident.method,
            )
        )
        stab.append(_stab_rows(ident, "bridge", rec.name))
        indicator = None
        if rec.has_inputs:
            frf, peaks, pp = pl.peak_picking(rec, band_hz=(1.0, 10.0))
            modes.append(
                _tag(
                    _with_energy(pl.compare_to_truth(pp, *true_args), energy),
                    structure="bridge",
                    test=rec.name,
                    method="peak_picking",
                )
            )
            peaks_all.append(_tag(peaks, structure="bridge", test=rec.name))
            plot_frf(
                frf,
                out_dir / f"frf_bridge_{kind}.png",
                peaks,
                f"bridge, {kind} shaker sweep: H1 ({comp} channels)",
                f_max_hz=12.0,
            )
            indicator = (frf.frequency_hz, np.abs(frf.h[:, :, 0]).sum(axis=1))
        plot_stability(
            ident.stability,
            out_dir / f"stability_bridge_{kind}.png",
            ident.selected,
            indicator,
            title=f"bridge, {rec.name}, {ident.method} (orders 10-80, 1 %, MAC 0.8)",
            f_max_hz=10.0,
        )
        if kind in ("vertical", "lateral"):
            measured = pl.to_measured_modes(
                ident.selected, f"bridge_{kind}_identified", source=f"{ident.method} of a simulated {kind} sweep"
            )
            save_modes(measured, out_dir / f"bridge_{kind}_identified.yaml")
    return {
        "modes": pd.concat(modes, ignore_index=True),
        "stability": pd.concat(stab, ignore_index=True),
        "peaks": pd.concat(peaks_all, ignore_index=True),
    }


def _with_energy(cmp: pd.DataFrame, energy: np.ndarray) -> pd.DataFrame:
    """Add the true modes' deck kinetic-energy share (NaN for spurious rows)."""
    cmp = cmp.copy()
    cmp.insert(2, "deck_energy", np.concatenate([energy, np.full(len(cmp) - energy.size, np.nan)]))
    return cmp


def run(out_dir: str | Path = "results/identification", bridge: bool = True, quick: bool = False) -> dict:
    """Run the lab and bridge studies and write the tables and figures (``quick``: short records)."""
    out = Path(out_dir)
    out.mkdir(parents=True, exist_ok=True)
    t0 = time.perf_counter()
    lab = lab_study(out, sweep_s=60.0 if quick else 150.0, update=not quick)
    tables = {k: [v] for k, v in lab.items()}
    if bridge:
        br = bridge_study(
            out, sweep_s=120.0 if quick else bridge_tests.SWEEP_DURATION_S, jump_s=120.0 if quick else 300.0
        )
        for k, v in br.items():
            tables.setdefault(k, []).append(v)
    result = {k: pd.concat(v, ignore_index=True) for k, v in tables.items()}
    for k, v in result.items():
        _write_csv(v, out / f"{k}.csv")
    log.info("identification study written to %s in %.1f s", out, time.perf_counter() - t0)
    return result
