"""Result store of a study: one atomic part file per finished run, consolidated tables.

Layout of ``results/<study>/``:
- ``_runs/<run_id>.json``: ``{"run_id", "study", "kind", "tables": {table: [rows]}}``,
  written atomically when the run ends. A run is stored exactly when a valid part exists,
  so a killed study loses at most the runs in progress and ``--resume`` skips the stored ones.
- A part that cannot be read (empty, cut, not JSON, not this layout, or holding another
  run's rows) is moved to ``_runs/_damaged/`` with a warning and its run is computed again;
  it never stops the study and never counts as stored.
- ``<table>.csv`` / ``.parquet``: rebuilt from the parts (atomically) after runs finish.
- ``config.yaml``: the resolved config; ``study.json``: which study owns the folder, so a run
  of another study into the same folder is refused instead of deleting its runs.
"""

from __future__ import annotations

import json
import logging
import time
from pathlib import Path

import numpy as np
import pandas as pd

from framework.core.errors import InputError
from framework.core.io import atomic_write_text
from framework.core.tables import frame_from_rows, read_table, sort_rows, write_table

log = logging.getLogger(__name__)

__all__ = ["ResultStore", "read_table", "write_table"]


class ResultStore:
    def __init__(self, root: str | Path):
        self.root = Path(root)
        self.parts = self.root / "_runs"
        self.damaged = self.parts / "_damaged"

    # ---- ownership ------------------------------------------------------------------
    def claim(self, study: str) -> None:
        """Make sure the folder is usable and belongs to ``study`` (or to nobody yet)."""
        if self.root.exists() and not self.root.is_dir():
            raise InputError(f"output {self.root}: exists and is not a folder")
        try:
            self.parts.mkdir(parents=True, exist_ok=True)
        except OSError as exc:
            raise InputError(f"output {self.root}: cannot create the results folder ({exc.strerror})") from None
        owner = self.owner()
        if owner is not None and owner != study:
            raise InputError(
                f"output {self.root}: holds the results of study {owner!r}; "
                f"give study {study!r} its own output folder"
            )
        for folder in (self.root, self.parts):  # before any run is computed, not after
            probe = folder / ".write_test.tmp"
            try:
                probe.write_text("ok")
                probe.unlink()
            except OSError as exc:
                raise InputError(f"output {folder}: not writable ({exc.strerror})") from None
        if owner is None:
            atomic_write_text(self.root / "study.json", json.dumps({"study": study}))

    def owner(self) -> str | None:
        path = self.root / "study.json"
        if path.exists():
            try:
                return str(json.loads(path.read_text())["study"])
            except (ValueError, KeyError, TypeError, UnicodeDecodeError):
                return None
        config = self.root / "config.yaml"  # folders written before study.json existed
        if config.exists():
            import yaml

            try:
                data = yaml.safe_load(config.read_text())
                if isinstance(data, dict) and data.get("study"):
                    return str(data["study"])
            except (yaml.YAMLError, UnicodeDecodeError, ValueError):
                pass
        for part in self._part_files():  # else the study its stored parts name
            try:
                data = json.loads(part.read_text(encoding="utf-8"))
            except (ValueError, UnicodeDecodeError, OSError):
                continue
            if isinstance(data, dict) and isinstance(data.get("study"), str) and data["study"]:
                return data["study"]
        return None

    # ---- parts ----------------------------------------------------------------------
    def clean_temp(self) -> int:
        """Remove temporary files left by a process killed in the middle of a write."""
        n = 0
        for folder in (self.root, self.parts):
            if folder.exists():
                for tmp in folder.glob(".*.tmp"):
                    tmp.unlink(missing_ok=True)
                    n += 1
        return n

    def discard(self, run_ids: set[str] | None = None) -> int:
        """Delete the stored parts of ``run_ids`` (all parts if None)."""
        n = 0
        for path in self._part_files():
            if run_ids is None or path.stem in run_ids:
                path.unlink(missing_ok=True)
                n += 1
        return n

    def _part_files(self) -> list[Path]:
        return sorted(self.parts.glob("*.json")) if self.parts.exists() else []

    def stored_ids(self) -> set[str]:
        """Run ids with a valid part; damaged parts are quarantined on the way."""
        return {path.stem for path in self._part_files() if self._read_part(path) is not None}

    def write_run(self, run_id: str, tables: dict[str, list[dict]], study: str = "", kind: str = "") -> None:
        payload = {"run_id": run_id, "study": study, "kind": kind, "tables": tables}
        atomic_write_text(self.parts / f"{run_id}.json", json.dumps(payload, default=_json_default))

    def _read_part(self, path: Path) -> dict[str, list[dict]] | None:
        """The tables of a part, or None after quarantining a damaged one."""
        try:
            data = json.loads(path.read_text(encoding="utf-8"))
            tables = _part_tables(data, path.stem)
        except (ValueError, UnicodeDecodeError, OSError) as exc:
            self._quarantine(path, f"{type(exc).__name__}: {exc}")
            return None
        return tables

    def _quarantine(self, path: Path, why: str) -> None:
        self.damaged.mkdir(parents=True, exist_ok=True)
        target = self.damaged / f"{path.stem}.{time.strftime('%Y%m%dT%H%M%S')}.json"
        path.replace(target)
        log.warning("damaged result part %s moved to %s (%s); its run will be computed again", path, target, why)

    def damaged_parts(self) -> list[Path]:
        return sorted(self.damaged.glob("*.json")) if self.damaged.exists() else []

    def read_parts(self, run_ids: set[str] | None = None, tables: tuple[str, ...] = ()) -> dict[str, pd.DataFrame]:
        """Every table of the stored parts (only ``run_ids`` if given), sorted."""
        rows: dict[str, list[dict]] = {t: [] for t in tables}
        for path in self._part_files():
            if run_ids is not None and path.stem not in run_ids:
                continue
            part = self._read_part(path)
            if part is None:
                continue
            for table, table_rows in part.items():
                rows.setdefault(table, []).extend(table_rows)
        return {t: sort_rows(frame_from_rows(r)) for t, r in rows.items()}

    def consolidate(self, run_ids: set[str] | None = None, tables: tuple[str, ...] = ()) -> dict[str, pd.DataFrame]:
        """Rewrite every table (CSV + Parquet) from the stored parts."""
        frames = self.read_parts(run_ids, tables)
        for name, df in frames.items():
            write_table(df, self.root / name)
        return frames

    def write_config(self, text: str) -> None:
        atomic_write_text(self.root / "config.yaml", text)


def _part_tables(data, run_id: str) -> dict[str, list[dict]]:
    """Check a part's layout; ValueError if it is not one run's rows."""
    if not isinstance(data, dict):
        raise ValueError(f"a part must be a JSON object, got {type(data).__name__}")
    tables = data.get("tables") if "tables" in data else data  # parts written before the layout had "tables"
    if not isinstance(tables, dict):
        raise ValueError("'tables' must be an object")
    if "run_id" in data and data["run_id"] != run_id:
        raise ValueError(f"the part holds run {data['run_id']!r}, not {run_id!r}")
    for name, rows in tables.items():
        if not isinstance(name, str) or not isinstance(rows, list) or not all(isinstance(r, dict) for r in rows):
            raise ValueError(f"table {name!r} is not a list of rows")
        ids = {r.get("run_id") for r in rows}
        if ids - {run_id}:
            raise ValueError(f"table {name!r} holds rows of run(s) {sorted(map(str, ids - {run_id}))}")
    return tables


def _json_default(obj):
    if isinstance(obj, np.integer):
        return int(obj)
    if isinstance(obj, np.floating):
        return float(obj)
    if isinstance(obj, np.ndarray):
        return obj.tolist()
    if isinstance(obj, np.bool_):
        return bool(obj)
    return str(obj)
