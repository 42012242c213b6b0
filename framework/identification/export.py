"""Identified modes as measured-modes files, from the ``identified`` and ``shapes`` tables.

``export_files(tables, out_dir, export)`` writes one ``<name>.yaml`` per entry of the
study's ``report.export`` (format of :mod:`framework.measured.modes`): the modes identified by
``method`` for test ``label`` (the mean over its records when it has several, else its one
record, or the ``record`` named), of the run with the lowest seed; with variants, one file
per variant (``<name>_<variant>.yaml``). ``true_labels`` names each mode after the true mode
it was paired with (else "mode k"). These files are what an ``updating`` study reads as
``measured: {file: ...}``.
"""

from __future__ import annotations

import logging
import re
from pathlib import Path

import numpy as np
import pandas as pd

from framework.core.errors import InputError
from framework.identification.pipeline import to_measured_modes
from framework.identification.stability import SelectedModes
from framework.measured.modes import MeasuredModes
from framework.measured.modes import save as save_modes

log = logging.getLogger(__name__)


def measured_from_tables(
    identified: pd.DataFrame, shapes: pd.DataFrame, name: str, true_labels: bool = False, source: str = ""
) -> MeasuredModes:
    """Measured modes of one run and record (rows of ``identified`` and ``shapes`` of it)."""
    if identified.empty:
        raise InputError(f"export {name!r}: no identified modes")
    identified = identified.sort_values("mode", kind="stable")
    modes = identified["mode"].astype(int).tolist()
    channels = list(dict.fromkeys(shapes["channel"]))
    values = np.zeros((len(channels), len(modes)))
    for j, mode in enumerate(modes):
        rows = shapes[shapes["mode"] == mode]
        values[[channels.index(c) for c in rows["channel"]], j] = rows["value"].to_numpy(float)
    table = identified.reset_index(drop=True)
    labels = None
    if true_labels:
        labels = [lab if isinstance(lab, str) and lab else f"mode {k}" for k, lab in zip(modes, table["true_label"])]
    return to_measured_modes(SelectedModes(table, values, tuple(channels)), name, labels, source=source)


def export_files(tables: dict[str, pd.DataFrame], out_dir: Path, export: dict) -> list[Path]:
    """Write the measured-modes files asked for in ``report.export``; returns their paths."""
    runs, identified, shapes = (tables.get(t) for t in ("runs", "identified", "shapes"))
    if runs is None or identified is None or shapes is None or runs.empty:
        return []
    written = []
    for name, options in export.items():
        sel = runs[(runs["label"] == options["label"]) & (runs["method"] == options.get("method", "n4sid"))]
        sel = sel[sel["status"] == "ok"].sort_values("seed", kind="stable").drop_duplicates("variant")
        if sel.empty:
            log.warning("export %s: no successful %s run of test %r", name, options.get("method"), options["label"])
            continue
        several = sel["variant"].nunique() > 1
        for _, run in sel.iterrows():
            record = options.get("record") or ("mean" if int(run["records"]) > 1 else None)
            ident = identified[identified["run_id"] == run["run_id"]]
            if ident.empty:
                log.warning("export %s: run %s identified no mode", name, run["run_id"])
                continue
            record = record or ident["record"].iloc[0]
            ident = ident[ident["record"] == record]
            shp = shapes[(shapes["run_id"] == run["run_id"]) & (shapes["record"] == record)]
            stem = f"{name}_{run['variant']}" if several else name
            stem = re.sub(r"[^A-Za-z0-9_.=+-]", "_", stem)
            source = f"{run['method']} of simulated {run['test']} of {run['structure']}, {record} (test {run['label']})"
            try:
                modes = measured_from_tables(ident, shp, stem, bool(options.get("true_labels")), source)
            except InputError as exc:
                log.warning("export %s: %s", name, exc)
                continue
            written.append(save_modes(modes, out_dir / f"{stem}.yaml"))
    return written
