"""Tidy tables on disk: CSV for people, Parquet for pandas, both written atomically.

Every table the framework writes goes through :func:`write_table`, so every table has the
same guarantees: a reader sees the old or the new file, never a part; columns that mix
types (a mode label ``1`` next to ``1st x``, a mapping) are stored as text instead of making
pyarrow fail after a study has computed everything; rows are in a stable, natural order.
"""

from __future__ import annotations

import io
import math
import re
from pathlib import Path

import pandas as pd

from framework.core.errors import InputError
from framework.core.io import atomic_write_bytes, atomic_write_text

#: columns that order the rows of every table (those present), in this order
SORT_KEYS = ("label", "variant", "seed", "case", "mode", "parameter", "evaluation", "key")
NATURAL = ("label", "variant", "case")


def natural_key(text) -> str:
    """Sort key that orders numbers inside text by value ('swarm_size=5' < 'swarm_size=40')."""
    return re.sub(r"-?\d+(?:\.\d+)?(?:e-?\d+)?", lambda m: f"{float(m.group()) + 1e12:030.9f}", str(text))


def sort_rows(df: pd.DataFrame) -> pd.DataFrame:
    """Rows ordered by the sort keys present (natural order for text keys)."""
    if df.empty:
        return df
    order = [k for k in SORT_KEYS if k in df.columns]
    if not order:
        return df.reset_index(drop=True)

    def key(col: pd.Series) -> pd.Series:
        if col.name in NATURAL or col.dtype == object:
            return col.map(natural_key)
        return col

    return df.sort_values(order, kind="stable", key=key).reset_index(drop=True)


def frame_from_rows(rows: list[dict]) -> pd.DataFrame:
    """A DataFrame of row dicts whose integer columns stay integers where rows lack them
    (nullable Int64, not float64) and booleans stay booleans."""
    df = pd.DataFrame(rows)
    for name in df.columns:
        values = [r[name] for r in rows if name in r and r[name] is not None]
        if not values or len(values) == len(rows):
            continue
        if all(isinstance(v, bool) for v in values):
            df[name] = pd.array([r.get(name) for r in rows], dtype="boolean")
        elif all(isinstance(v, int) and not isinstance(v, bool) and -(2**63) <= v < 2**63 for v in values):
            df[name] = pd.array([r.get(name) for r in rows], dtype="Int64")
    return df


def _uniform(col: pd.Series) -> pd.Series:
    """A column pyarrow can store: mixed Python types (or containers) become text.

    Numbers that do not fit an int64 or are not finite floats stay numbers where pyarrow can
    hold them (float64), else become text; None/NaN stay missing.
    """
    if col.dtype != object:
        return col
    values = col.dropna()
    kinds = {type(v) for v in values}
    if not kinds:
        return col
    if kinds <= {str}:
        return col
    if kinds <= {bool}:
        return col.astype("boolean")
    if kinds <= {int} and all(-(2**63) <= v < 2**63 for v in values):
        return col.astype("Int64")
    if kinds <= {int, float} and all(isinstance(v, float) or abs(v) < 2**53 for v in values):
        return col.astype(float)
    return col.map(lambda v: v if v is None or (isinstance(v, float) and math.isnan(v)) else _text(v))


def _text(value) -> str:
    if isinstance(value, dict | list | tuple):
        import json

        return json.dumps(value, sort_keys=True, default=str)
    return str(value)


def storable(df: pd.DataFrame) -> pd.DataFrame:
    """``df`` with every column of one storable type (see :func:`_uniform`)."""
    return df.apply(_uniform) if not df.empty else df


def write_table(df: pd.DataFrame, stem: Path) -> None:
    """Write ``stem.csv`` and ``stem.parquet`` atomically (Parquet first: it fails loudest)."""
    stem = Path(stem)
    df = storable(df)
    buf = io.BytesIO()
    df.to_parquet(buf, index=False)
    atomic_write_bytes(stem.with_suffix(".parquet"), buf.getvalue())
    atomic_write_text(stem.with_suffix(".csv"), df.to_csv(index=False))


def read_table(root: str | Path, name: str) -> pd.DataFrame:
    """Table ``name`` of a results folder (Parquet, else CSV); InputError naming a damaged file."""
    root = Path(root)
    for suffix in (".parquet", ".csv"):
        path = (root / name).with_suffix(suffix)
        if not path.exists():
            continue
        try:
            return pd.read_parquet(path) if suffix == ".parquet" else pd.read_csv(path)
        except Exception as exc:  # pyarrow and pandas raise many kinds for a damaged file
            raise InputError(f"{path}: damaged table, cannot be read ({type(exc).__name__}: {exc})") from None
    raise FileNotFoundError(f"no table {name!r} in {root}")


def read_tables(root: str | Path, names) -> dict[str, pd.DataFrame]:
    """The tables of ``names`` that exist in ``root``."""
    out = {}
    for name in names:
        try:
            out[name] = read_table(root, name)
        except FileNotFoundError:
            continue
    return out
