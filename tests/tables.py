"""Helpers shared by the tests that compare the tables of two executions of a study."""

import pandas as pd


def assert_same_tables(a: dict, b: dict, timing: tuple[str, ...] = ("wall_s",)) -> None:
    """Every table of ``a`` equals the same table of ``b`` exactly, timing columns left out."""
    for name in a:
        x, y = (t.drop(columns=[c for c in timing if c in t]) for t in (a[name], b[name]))
        pd.testing.assert_frame_equal(x, y, check_exact=True, obj=name)
