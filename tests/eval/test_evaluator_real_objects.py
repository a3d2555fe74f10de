"""eval.evaluators.real_objects' breakdowns: reference joints right beside the paper's success, per group."""

from types import SimpleNamespace

import pytest

from eval.evaluators.real_objects import _right, breakdown


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


def test_sets_of_one_object_in_two_looks_get_keys_of_their_own(tmp_path):
    """The held-out objects in the plain and the varied look share record keys; their sets must not,
    or one `eval run` over every set refuses them."""
    from eval.evaluators.real_objects import write_sets
    from data_pipeline.build import BuildConfig, factory_sources, run_build
    from eval.records import read_records
    from data_pipeline.shards import shard_paths

    for look in ("plain", "varied"):
        run_build(tmp_path / look, factory_sources(1, 0), BuildConfig(1, 0, 32, 4, split="test", appearance=look),
                  workers=1, progress=False)
    sets = write_sets({"heldout": tmp_path / "plain", "heldout_varied": tmp_path / "varied"}, tmp_path / "out",
                      {"plain": 10, "split": 10, "merge": 10, "scene": 10})
    keys = {name: [r.key for r in read_records(shard_paths([str(f)], "test"))] for name, f in sets.items()}
    assert keys["heldout_varied_plain"] == [k + "/heldout_varied" for k in keys["heldout_plain"]]
