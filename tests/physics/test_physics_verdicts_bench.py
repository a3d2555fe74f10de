"""The ground-truth evaluator's per-object verdict lines (written as each object finishes) and the
comparison of two such files (C against MJX, scripts/compare_verdicts.py)."""

from __future__ import annotations

import importlib.util
import json
import subprocess
import sys
from pathlib import Path

from jax3dc.factories import FACTORIES, generate_object
from jax3dc.physics.verdict import check_object

SCRIPTS = Path(__file__).resolve().parents[2] / "scripts"


def _compare_module():
    spec = importlib.util.spec_from_file_location("compare_verdicts", SCRIPTS / "compare_verdicts.py")
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


def test_verdict_lines_hold_each_objects_check(tmp_path):
    out = tmp_path / "verdicts.jsonl"
    subprocess.run([sys.executable, "-m", "eval.evaluate", "physics_ground_truth", "--categories", "toilet,desk_fan",
                    "--fixtures", "", "--no-mutations", "--workers", "2", "--verdicts", str(out)],
                   check=True, capture_output=True, text=True)
    records = {r["object"]: r for r in map(json.loads, out.read_text().splitlines())}
    assert sorted(records) == ["desk_fan_000000", "toilet_000000"]
    for category in ("toilet", "desk_fan"):
        obj = generate_object(category, 0)
        record = records[obj.object_id]
        assert record["backend"] == "c" and record["seconds"] > 0
        expected = check_object(obj.structure, obj.parts, obj.scale_m_per_nu, mounted=FACTORIES[category].mounted)
        assert record["verdict"] == json.loads(json.dumps(expected))
    assert records["toilet_000000"]["verdict"]["ok"]  # a toilet is bolted down: checked mounted, it passes


def _record(name: str, joints: dict[str, list[str]]) -> dict:
    verdict = {"ok": not any(joints.values()), "checks": {},
               "joints": {p: {"ok": not r, "reasons": r} for p, r in joints.items()}}
    return {"object": name, "backend": "c", "verdict": verdict, "seconds": 1.0}


def test_comparison_counts_agreement_over_shared_objects(tmp_path):
    compare_verdicts = _compare_module()
    a = tmp_path / "a.jsonl"
    b = tmp_path / "b.jsonl"
    a.write_text("\n".join(json.dumps(r) for r in (
        _record("door", {"2": ["penetrates part 1 at q=0.300"], "3": []}),
        _record("lamp", {"2": []}),
        _record("only_in_a", {"2": []}))) + "\n")
    # the same reason found at another joint value agrees; a missing reason and a cut-off line do not count
    b.write_text("\n".join(json.dumps(r) for r in (
        _record("door", {"2": ["penetrates part 1 at q=0.400"], "3": ["limit unreachable: hi (stops at q=1.0)"]}),
        _record("lamp", {"2": ["detached from parent at q=0.100"]}))) + '\n{"object": "cut')
    r = compare_verdicts.compare(compare_verdicts.load(a), compare_verdicts.load(b))
    assert (r["objects"], r["same object verdict"]) == (2, 1)
    assert (r["joints"], r["same ok"], r["same reasons"]) == (3, 1, 1)
    assert [d.split(":")[0] for d in r["differences"]] == ["door joint 3", "lamp joint 2"]
