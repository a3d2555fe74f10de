"""A perfect prediction scores 100 everywhere (0 for the error and failure shares)."""

import math

import pytest

from eval.metrics.score import TABLE1_KEYS, TABLE2_KEYS, Case, evaluate
from eval.metrics.tables import format_tables
from eval_structures import hinge, slide, structure
from jax3dc.structure.schema import Relation

CEN = {i: (0.1 * (i % 4), 0.2 * (i // 4), 0.0) for i in range(1, 12)}


def _split():
    cabinet = structure(
        {1: None, 2: 1, 3: 1, 4: 1, 5: 1, 6: 1, 7: 1, 8: 2},
        {2: hinge(pivot=(0.4, -0.3, 0.0), rng=(0.0, math.pi / 2)), 3: hinge(pivot=(-0.4, -0.3, 0.0), rng=(-1.5, 0.0)),
         4: slide(rng=(0.0, 0.35))},
        (Relation("symmetric", 2, 3, "yz"), Relation("instance", 5, 6), Relation("instance", 5, 7)),
    )
    scene = structure({1: None, 2: 1, 3: None, 4: 3, 5: None, 6: 5, 7: 5}, {4: hinge(axis=(1, 0, 0))},
                      (Relation("instance", 2, 6),))
    return [Case("cabinet", cabinet, CEN, cabinet), Case("scene", scene, CEN, scene)]


def test_perfect_prediction_scores_100_everywhere():
    m = evaluate(_split()).metrics
    zero = {"pos_err", "fail_type", "fail_axis", "fail_origin", "fail_limit"}
    for key in TABLE1_KEYS + TABLE2_KEYS:
        if key == "objects_per_scene":
            assert m[key] == m["objects_per_scene_ref"] == 3
        elif key in zero:
            assert m[key] == 0.0, key
        else:
            assert m[key] == pytest.approx(100.0), key
    assert m["counts"] == {"objects": 2, "parsed": 2, "joints_pred": 4, "joints_ref": 4, "joints_matched": 4,
                           "scenes": 1, "scenes_parsed": 1}


def test_parse_is_over_all_references_and_the_rest_over_the_parsed_subset():
    cases = _split() + [Case("bad", structure({1: None}), CEN, None, "json", "not JSON")]
    e = evaluate(cases)
    assert e.metrics["parse"] == pytest.approx(200 / 3)
    assert e.metrics["parent_acc"] == pytest.approx(100.0)
    assert e.metrics["parse_failures"] == {"json": 1}
    assert e.rows[-1] == {"key": "bad", "parsed": False, "scene": False, "failure_rule": "json", "failure": "not JSON"}


def test_tables_show_every_column_and_dashes_for_unmeasured():
    m = evaluate(_split()).metrics
    text = format_tables([("perfect", m), ("empty", evaluate([]).metrics)])
    assert "Table 2" in text and "Sym F1" in text and "Range IoU" in text
    # 100.0 cells: Table 1a 7 (all but Pos.), 1b 4 (Success and relations), Table 2 8 (all but Obj./scene)
    assert text.count("100.0") == 7 + 4 + 8
    empty_lines = [line for line in text.splitlines() if line.startswith("empty")]
    assert len(empty_lines) == 3 and all(set(line.split()[1:]) == {"-"} for line in empty_lines)
