"""Reproduction-report rows of the beam study, read from the committed tables."""

from pathlib import Path

import pytest

from framework.structures.beam.reproduction import rows

RESULTS = Path(__file__).resolve().parents[1] / "results"
KEYS = {"study", "item", "source", "ours", "choice", "verdict"}
ITEMS = {"frequencies (truth)", "SOO (baseline difference)", "SOO independent updates (ours)", "MOO (NSGA-II)",
         "regularized (PSO + Tikhonov)", "L-curve", "damage indices"}


@pytest.mark.skipif(not (RESULTS / "beam_damage" / "comparison.csv").exists(), reason="beam tables not committed")
def test_rows_cover_every_item_from_the_committed_tables():
    out = rows(RESULTS)
    assert {r["item"] for r in out} == ITEMS
    for r in out:
        assert set(r) == KEYS and all(isinstance(v, str) and v for v in r.values())
        assert r["choice"] == "source-given" or r["choice"].startswith(("source-given", "our assumption: "))
    truth = next(r for r in out if r["item"] == "frequencies (truth)")
    assert truth["verdict"] == "reproduced within 0.05 %"
    assert "12.83, 51.78" in truth["source"]
    soo = next(r for r in out if r["item"] == "SOO (baseline difference)")
    assert "3 % noise (20 seeds)" in soo["ours"]
    assert rows(RESULTS) == out  # a pure function of the tables


def test_missing_tables_give_not_run_rows_naming_the_table(tmp_path):
    out = rows(tmp_path)
    assert len(out) == 7 and all(r["verdict"] == "not run" for r in out)
    assert all(r["ours"] == "(no table results/beam_truth/modes.csv)" for r in out)
