"""The report of ``jax3dc physics sweep`` (eval.physics_report) from typed verdicts: the summary
counts the joints' findings by check, the verdict lines and the index hold their reason strings."""

from __future__ import annotations

import json
from pathlib import Path

from eval.physics_report import write_report
from jax3dc.physics.findings import WARNING, Finding, Verdict, describe

PENETRATES = Finding("penetration", joints=(2,), parts=(1,), depth=0.04, state=((2, 1.2),))
PAST = Finding("limit", WARNING, joints=(3,), reachable=2.7721, limit="hi")
PIVOT = Finding("pivot", joints=(3,), parts=(1,))


def test_the_summary_counts_findings_by_check_and_the_files_hold_their_reasons(tmp_path: Path) -> None:
    results = [
        {"object": "a", "category": "cabinet", "verdict": Verdict((2, 3), (PENETRATES, PAST)), "plot": "plots/a.png",
         "cost": {"seconds": 1.0}},
        {"object": "b", "category": "cabinet", "verdict": Verdict((2, 3), (PIVOT,)), "plot": None},
        {"object": "c", "category": None, "verdict": Verdict((), ()), "plot": None},
    ]
    summary = write_report(results, [{"object": "d", "why": "no part program in the record"}], tmp_path)
    assert summary == {"objects": 3, "objects_ok": 1, "joints": 4, "joints_ok": 2,
                       "reasons": {"penetration": 1, "pivot": 1}, "warnings": {"limit": 1}, "skipped": 1}
    assert json.loads((tmp_path / "summary.json").read_text()) == summary
    lines = [json.loads(line) for line in (tmp_path / "verdicts.jsonl").read_text().splitlines()]
    assert lines[0] == {"object": "a", "category": "cabinet", **results[0]["verdict"].to_json()}
    assert lines[3] == {"object": "d", "skipped": "no part program in the record"}
    assert [json.loads(line)["object"] for line in (tmp_path / "costs.jsonl").read_text().splitlines()] == ["a"]
    index = (tmp_path / "index.md").read_text().splitlines()
    assert f"| a | 2 | no | {describe(PENETRATES)} |  |" in index
    assert f"| a | 3 | yes |  | {describe(PAST)} |" in index
    assert "| b | 3 | no | pivot detached |  |" in index and "![a](plots/a.png)" in index
