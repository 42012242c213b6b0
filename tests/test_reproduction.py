"""The reproduction report (docs/reproduction.md) is what the committed tables give."""

from __future__ import annotations

from pathlib import Path

from framework.cli import main
from framework.report import reproduction
from framework.structures.registry import reproduction_providers

ROOT = Path(__file__).resolve().parents[1]
PROVIDERS = reproduction_providers()


def test_docs_reproduction_is_up_to_date_with_the_committed_tables():
    expected = reproduction.render(reproduction.collect(ROOT / "results", PROVIDERS))
    text = (ROOT / "docs" / "reproduction.md").read_text(encoding="utf-8")
    assert text == expected, "docs/reproduction.md is stale: gomu report --reproduction results --output docs/reproduction.md"


def test_every_row_has_the_report_columns_and_lab_and_bridge_are_there():
    rows = reproduction.collect(ROOT / "results", PROVIDERS)
    assert all(tuple(r) == reproduction.COLUMNS for r in rows)
    studies = {r["study"] for r in rows}
    assert any("Laboratory frame" in s for s in studies) and any("footbridge" in s for s in studies)
    # the congruence rows: exactly one reading is the default
    cong = [r for r in rows if r["item"].startswith("torsion congruence")]
    assert len(cong) == 4 and sum("the default" in r["choice"] for r in cong) == 1


def test_providers_come_from_the_structure_descriptors_in_registry_order():
    from framework.structures.beam.reproduction import rows as beam
    from framework.structures.bridge.reproduction import rows as bridge
    from framework.structures.lab_frame.reproduction import rows as lab_frame
    from framework.structures.smu.reproduction import rows as smu

    assert PROVIDERS == [lab_frame, bridge, beam, smu]


def test_missing_tables_give_not_run_rows(tmp_path):
    rows = reproduction.collect(tmp_path, PROVIDERS)
    assert rows and all(r["verdict"] == "not run" for r in rows if r["ours"].startswith("(no table"))
    assert any(r["ours"] == "(no table results/lab_frame_timing/timing.csv)" for r in rows)


def test_cli_writes_the_report_and_refuses_a_missing_folder(tmp_path, capsys):
    out = tmp_path / "r.md"
    assert main(["report", "--reproduction", str(ROOT / "results"), "--output", str(out)]) == 0
    assert out.read_text(encoding="utf-8") == (ROOT / "docs" / "reproduction.md").read_text(encoding="utf-8")
    assert main(["report", "--reproduction", str(tmp_path / "nowhere")]) == 2
    err = capsys.readouterr().err
    assert "results folder" in err and "nowhere" in err and "Traceback" not in err
