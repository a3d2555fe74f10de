"""The benchmark record (docs/benchmarks.jsonl) stays readable by a script: bench/record.py checks it."""

from __future__ import annotations

import importlib.util
import json
import re
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parent.parent
_spec = importlib.util.spec_from_file_location("bench_record", ROOT / "bench" / "record.py")
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



def _cited_figures(text: str) -> list[tuple[str, str, str, str | None]]:
    """(name, date, commit, value cell) of every table row of docs/BENCHMARKS.md that names figures.

    A cell may name several figures of one family ("`release.fixtures_parent`, `_edge_f1`"); their
    values stand in a table of their own, so the value cell is given only for a single name."""
    cited = []
    for line in text.splitlines():
        if not line.startswith("| `"):
            continue
        cells = [c.strip() for c in line.strip().strip("|").split("|")]
        names = re.findall(r"`([^`]+)`", cells[0])
        base = names[0].rsplit("_", 1)[0]
        for name in names:
            cited.append((base + name if name.startswith("_") else name, cells[5], cells[7],
                          cells[1] if len(names) == 1 else None))
    return cited


def _numbers(cell: str) -> list[float]:
    """The numbers a cell shows; "a/b" also counts as the percentage 100 a / b."""
    numbers = [float(x.replace(",", "")) for x in re.findall(r"\d[\d,]*(?:\.\d+)?(?:e-?\d+)?", cell)]
    numbers += [100 * int(a) / int(b) for a, b in re.findall(r"(\d+) ?/ ?(\d+)", cell) if int(b)]
    return numbers


def test_every_figure_in_benchmarks_md_is_the_current_line_of_the_record():
    """The page shows current figures only: value, date and commit of the name's latest line."""
    current = record.latest(record.load())
    cited = _cited_figures((ROOT / "docs" / "BENCHMARKS.md").read_text())
    assert len(cited) >= 100
    for name, date, commit, shown in cited:
        assert name in current, f"BENCHMARKS.md cites {name}, which docs/benchmarks.jsonl lacks"
        line = current[name]
        assert date == line["date"], f"{name}: BENCHMARKS.md says {date}, the record {line['date']}"
        assert commit == (line["commit"] or "—"), f"{name}: BENCHMARKS.md says {commit}, the record {line['commit']}"
        if shown is not None:
            value = line["value"]
            assert any(abs(n - value) <= max(0.051, abs(value) * 1e-3) for n in _numbers(shown)), (
                f"{name}: BENCHMARKS.md shows {shown!r}, the record's value is {value}")
