"""bench.real_objects' breakdowns: reference joints right beside the paper's success, per group."""

from types import SimpleNamespace

import pytest

from bench.real_objects import _right, breakdown


def case(key: str, joints: int) -> SimpleNamespace:
    return SimpleNamespace(key=key, reference=SimpleNamespace(joints=lambda: dict.fromkeys(range(joints))))


def test_breakdown_counts_reference_joints_and_matched_ones_apart():
    cases = [case("a", 3), case("b", 2), case("c", 1)]
    rows = [{"matches": [{"gate": "success"}, {"gate": "axis"}]},  # one of three reference joints unmatched
            {"matches": [{"gate": "success"}, {"gate": "success"}]},
            {"matches": []}]
    out = breakdown(cases, rows, {"a": "door", "b": "door", "c": "laptop"})
    assert out["door"] == {"records": 2, "joints": 4, "success": 3, "ref_joints": 5,
                           "success_pct": pytest.approx(75.0), "ref_right_pct": pytest.approx(60.0)}
    assert out["laptop"]["success_pct"] is None and out["laptop"]["ref_right_pct"] == 0.0
    assert _right(out["door"]) == "3 of 5" and _right(None) == "-"
