"""Tidy result store: one atomic part file per finished run, consolidated tables.

Layout of ``results/<study>/``:
- ``_runs/<run_id>.json``: every row of one run, written atomically when the run ends;
  a run is "stored" exactly when its part exists, so a killed study loses at most the
  runs in progress and ``--resume`` skips the stored ones (no duplicate, no lost rows);
- ``<table>.csv`` and ``<table>.parquet`` for runs, parameters, modes, history, extra:
  rebuilt from the parts (atomically) after runs finish, sorted by label, variant, seed;
- ``config.yaml``: the resolved config.
"""

from __future__ import annotations

import io
import json
import re
from pathlib import Path

import pandas as pd

from framework.io import atomic_write_bytes, atomic_write_text
from framework.study.execute import TABLES

SORT_KEYS = ["label", "variant", "seed"]


class ResultStore:
    def __init__(self, root: str | Path):
        self.root = Path(root)
        self.parts = self.root / "_runs"

    def clean_temp(self) -> int:
        """Remove temporary files left by a process killed in the middle of a write."""
        n = 0
        for folder in (self.root, self.parts):
            if folder.exists():
                for tmp in folder.glob(".*.tmp"):
                    tmp.unlink(missing_ok=True)
                    n += 1
        return n

    def stored_ids(self) -> set[str]:
        if not self.parts.exists():
            return set()
        return {p.stem for p in self.parts.glob("*.json")}

    def write_run(self, run_id: str, tables: dict[str, list[dict]]) -> None:
        payload = json.dumps(tables, default=_json_default)
        atomic_write_text(self.parts / f"{run_id}.json", payload)

    def read_parts(self, run_ids: set[str] | None = None) -> dict[str, pd.DataFrame]:
        rows: dict[str, list[dict]] = {t: [] for t in TABLES}
        files = sorted(self.parts.glob("*.json")) if self.parts.exists() else []
        for path in files:
            if run_ids is not None and path.stem not in run_ids:
                continue
            data = json.loads(path.read_text())
            for table in TABLES:
                rows[table].extend(data.get(table, []))
        return {t: _sorted(pd.DataFrame(r)) for t, r in rows.items()}

    def consolidate(self, run_ids: set[str] | None = None) -> dict[str, pd.DataFrame]:
        """Rewrite every table (CSV + Parquet) from the stored parts."""
        frames = self.read_parts(run_ids)
        for name, df in frames.items():
            write_table(df, self.root / name)
        return frames

    def write_config(self, text: str) -> None:
        atomic_write_text(self.root / "config.yaml", text)


def natural_key(text: str) -> str:
    """Sort key that orders numbers inside text by value ('swarm_size=5' < 'swarm_size=40')."""
    return re.sub(r"-?\d+(?:\.\d+)?(?:e-?\d+)?", lambda m: f"{float(m.group()) + 1e12:030.9f}", str(text))


def _sorted(df: pd.DataFrame) -> pd.DataFrame:
    if df.empty:
        return df
    keys = [k for k in SORT_KEYS if k in df.columns]
    extra = [k for k in ("case", "mode", "parameter", "evaluation", "key") if k in df.columns]
    order = keys + extra
    if not order:
        return df
    key = lambda col: col.map(natural_key) if col.name in ("label", "variant") else col  # noqa: E731
    return df.sort_values(order, kind="stable", key=key).reset_index(drop=True)


def write_table(df: pd.DataFrame, stem: Path) -> None:
    """Write ``stem.csv`` and ``stem.parquet`` atomically."""
    stem.parent.mkdir(parents=True, exist_ok=True)
    atomic_write_text(stem.with_suffix(".csv"), df.to_csv(index=False))
    buf = io.BytesIO()
    df.to_parquet(buf, index=False)
    atomic_write_bytes(stem.with_suffix(".parquet"), buf.getvalue())


def read_table(root: str | Path, name: str) -> pd.DataFrame:
    root = Path(root)
    for suffix in (".parquet", ".csv"):
        path = (root / name).with_suffix(suffix)
        if path.exists():
            return pd.read_parquet(path) if suffix == ".parquet" else pd.read_csv(path)
    raise FileNotFoundError(f"no table {name!r} in {root}")


def _json_default(obj):
    import numpy as np

    if isinstance(obj, np.integer):
        return int(obj)
    if isinstance(obj, np.floating):
        return float(obj)
    if isinstance(obj, np.ndarray):
        return obj.tolist()
    if isinstance(obj, np.bool_):
        return bool(obj)
    return str(obj)
