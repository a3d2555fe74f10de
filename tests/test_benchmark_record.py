"""The benchmark record (docs/benchmarks.jsonl) stays readable by a script, scripts/benchmarks.py, and
docs/BENCHMARKS.md is exactly what that script writes from it."""

from __future__ import annotations

import importlib.util
import json
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parent.parent
_spec = importlib.util.spec_from_file_location("benchmarks", ROOT / "scripts" / "benchmarks.py")
record = importlib.util.module_from_spec(_spec)
_spec.loader.exec_module(record)

GOOD = {"name": "decode.tokens_per_s.b1", "date": "2026-11-22", "machine": "1 x NVIDIA H100 80GB HBM3",
        "commit": None, "command": "python3 bench/decode.py", "value": 245.4, "unit": "tokens/s",
        "baseline": 11.4, "ratio": 21.5, "target": 250.0, "met": False}


def _write(tmp_path: Path, entries: list[dict]) -> Path:
    path = tmp_path / "record.jsonl"
    path.write_text("".join(json.dumps(e) + "\n" for e in entries))
    return path


def test_the_real_record_passes_the_check_and_has_a_current_figure_per_name():
    entries = record.load()
    names = {e["name"] for e in entries}
    assert len(entries) >= 200
    assert set(record.latest(entries)) == names
    assert "decode.tokens_per_s.b1" in record.table(entries)


@pytest.mark.parametrize("change, words", [
    ({"value": "245.4"}, "value"),
    ({"date": "22/11/2026"}, "YYYY-MM-DD"),
    ({"date": "2026-02-30"}, "calendar date"),
    ({"met": "no"}, "met"),
    ({"baseline": float("nan")}, "baseline"),
    ({"extra": 1}, "unknown key"),
    ({"topic": ""}, "topic"),
])
def test_a_bad_line_is_refused_with_its_line_number(tmp_path, change, words):
    path = _write(tmp_path, [GOOD, GOOD, {**GOOD, **change}])
    with pytest.raises(record.RecordError, match=rf"record\.jsonl:3: .*{words}"):
        record.load(path)


def test_a_missing_key_is_named(tmp_path):
    bad = {k: v for k, v in GOOD.items() if k != "unit"}
    with pytest.raises(record.RecordError, match=r"record\.jsonl:2: missing key\(s\) unit"):
        record.load(_write(tmp_path, [GOOD, bad]))


def test_lines_out_of_date_order_are_refused(tmp_path):
    with pytest.raises(record.RecordError, match=r"record\.jsonl:2: .*date order"):
        record.load(_write(tmp_path, [GOOD, {**GOOD, "date": "2026-11-21"}]))


def test_latest_is_the_last_line_of_each_name(tmp_path):
    entries = record.load(_write(tmp_path, [
        GOOD,
        {**GOOD, "name": "other", "value": 1.0},
        {**GOOD, "value": 257.7, "date": "2026-11-23"},
        {**GOOD, "value": 249.7, "date": "2026-11-23"},
    ]))
    current = record.latest(entries)
    assert list(current) == ["decode.tokens_per_s.b1", "other"]
    assert current["decode.tokens_per_s.b1"]["value"] == 249.7
    assert current["other"]["value"] == 1.0


def test_plot_writes_a_png_and_refuses_an_unknown_name(tmp_path):
    path = _write(tmp_path, [GOOD, {**GOOD, "value": 257.7, "date": "2026-11-23"}])
    out = tmp_path / "history.png"
    assert record.main(["--record", str(path), "--plot", GOOD["name"], str(out)]) == 0
    assert out.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"
    assert record.main(["--record", str(path), "--plot", "no.such.figure", str(tmp_path / "x.png")]) == 1


def test_the_page_is_what_the_record_writes_and_fits_three_hundred_lines():
    """BENCHMARKS.md is written by `python3 scripts/benchmarks.py --page`; a hand edit or a line
    appended without re-running it shows here."""
    text = record.PAGE.read_text(encoding="utf-8")
    assert text == record.page(record.load()), f"docs/BENCHMARKS.md is stale: run {record.PAGE_COMMAND}"
    assert len(text.splitlines()) <= record.MAX_PAGE_LINES


def test_each_figure_on_the_page_once_with_its_current_line():
    entries = record.load()
    shown = [e for lines in record.on_page(entries).values() for e in lines]
    names = [e["name"] for e in shown]
    assert len(names) == len(set(names)) >= 100
    text = record.PAGE.read_text(encoding="utf-8")
    for e in shown:
        rows = [line for line in text.splitlines() if line.startswith(f"| `{e['name']}` |")]
        assert len(rows) == 1, e["name"]
        assert f" {e['date']} " in rows[0] and f" {e['commit'] or '—'} " in rows[0]


def test_the_page_groups_current_lines_by_topic_and_numbers_long_commands(tmp_path):
    long_command = "python3 bench/train_step.py" + " --flag value" * 10
    entries = record.load(_write(tmp_path, [
        {**GOOD, "topic": "Speed of predict, demo and decoding"},
        {**GOOD, "name": "new.figure", "command": long_command, "topic": "A topic of its own", "unit": "s (cold)"},
        {**GOOD, "name": "history.only"},
        {**GOOD, "name": "release4.heldout_success", "value": 33.9, "met": None, "target": None,
         "topic": "Release models: real objects", "machine": "developer CPU machine (2 cores), shared"},
        {**GOOD, "name": "new.figure", "command": long_command, "value": 2.5, "date": "2026-11-23",
         "topic": "A topic of its own", "unit": "s (cold)"},
    ]))
    text = record.page(entries)
    headings = [line for line in text.splitlines() if line.startswith("## ")]
    assert headings == ["## Release models: real objects", "## Speed of predict, demo and decoding",
                        "## A topic of its own", "## Commands"]
    assert "history.only" not in text
    assert "| `release4.heldout_success` | 33.9 | tokens/s | 11.4 | 21.5× | — | 2026-11-22 | CPU-2 (shared) |" in text
    assert "| `decode.tokens_per_s.b1` | 245.4 | tokens/s | 11.4 | 21.5× | 250.0: **missed** |" in text
    assert "| `new.figure` | 2.5 | s |" in text and text.count(long_command) == 1
    assert text.rstrip().endswith(f"1. `{long_command}`")


def test_a_figure_whose_new_line_names_no_topic_is_reported(tmp_path):
    entries = record.load(_write(tmp_path, [{**GOOD, "topic": "Decoding"}, {**GOOD, "date": "2026-11-23"}]))
    assert record.left_page(entries) == [GOOD["name"]]
    assert GOOD["name"] not in record.page(entries)


@pytest.mark.parametrize("machine, short", [
    ("1 x NVIDIA H100 80GB HBM3 + 16 CPU cores", "H100"),
    ("one NVIDIA H200 (16 host cores)", "H200"),
    ("4 x H100 80GB HBM3 (one host), jax 0.11.2", "4×H100"),
    ("16 CPU cores of the H100 machine, shared with MJX runs", "H100 CPUs (shared)"),
    ("16 cores of a 4 x NVIDIA H200 host", "4×H200 CPUs"),
    ("developer CPU machine (2 shared cores); trained on 1 x NVIDIA H200", "CPU-2 (shared)"),
    ("developer CPU machine, one core", "CPU-2, one core"),
    ("a TPU v5e", "a TPU v5e"),
])
def test_machines_get_one_short_name_each(machine, short):
    assert record.short_machine(machine) == short


@pytest.mark.parametrize("unit, head", [
    ("tokens/s decode, batch 1", "tokens/s decode, batch 1"),
    ("s cold compile (trace+lower 2.2, XLA 27.7); 17,004 tokens/s", "s cold compile"),
    ("% success of matched joints, the real pool's held-out fifth", "% success of matched joints"),
    ("objects of 200 with the same winners and repairs as C", "objects of 200 with the same winners and…"),
])
def test_a_unit_is_cut_to_its_head(unit, head):
    assert record.short_unit(unit) == head
