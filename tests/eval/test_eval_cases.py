"""Reading predictions: parse failures carry their rule; equivalent spellings score the same."""

import json
import random

import pytest

from eval.metrics.cases import (MAX_LINE_BYTES, MISSING_RULE, Reference, build_cases, json_text, load_predictions,
                                load_references)
from eval.metrics.score import evaluate
from jax3dc.errors import InputFileError
from jax3dc.structure import boxes_from_dict, canonicalize, parse_structure

# A cabinet: body 1 (largest), shelf 2, two doors 3 and 4 (symmetric), handles 5, 6, 7 (instances).
BOXES = {
    "1": {"centroid": [0, 0, 0], "extent": [0.8, 0.4, 1.0]},
    "2": {"centroid": [0, 0, 0], "extent": [0.7, 0.35, 0.02]},
    "3": {"centroid": [-0.2, -0.21, 0], "extent": [0.39, 0.02, 0.95]},
    "4": {"centroid": [0.2, -0.21, 0], "extent": [0.39, 0.02, 0.95]},
    "5": {"centroid": [-0.05, -0.24, 0], "extent": [0.01, 0.03, 0.2]},
    "6": {"centroid": [0.05, -0.24, 0], "extent": [0.01, 0.03, 0.2]},
    "7": {"centroid": [0.0, -0.24, 0.4], "extent": [0.01, 0.03, 0.2]},
}


def door(x, axis_z=1.0, rng=(0.0, 1.5)):
    return {"type": "hinge", "axis": [0.0, 0.0, axis_z], "pivot": [x, -0.2, 0.0], "range": list(rng)}


REFERENCE = {
    "materials": {"0": {"family": "Wood", "desc": "oak"}, "1": {"family": "Metal"}},
    "nodes": {
        "1": {"parent": None, "material": 0},
        "2": {"parent": 1, "material": 0},
        "3": {"parent": 1, "material": 0, "joint": door(-0.39, rng=(-1.5, 0.0))},
        "4": {"parent": 1, "material": 0, "joint": door(0.39)},
        "5": {"parent": 3, "material": 1},
        "6": {"parent": 4, "material": 1},
        "7": {"parent": 1, "material": 1},
    },
    "relations": [{"type": "symmetric", "a": 3, "b": 4, "plane": "yz"},
                  {"type": "instance", "a": 5, "b": 6}, {"type": "instance", "a": 5, "b": 7}],
}


def _reference() -> Reference:
    boxes = boxes_from_dict(BOXES)
    return Reference("cab", canonicalize(parse_structure(REFERENCE), boxes), boxes)


def _imperfect() -> dict:
    """A prediction with a wrong parent, a tilted, shifted door and a missing relation."""
    doc = json.loads(json.dumps(REFERENCE))
    doc["nodes"]["6"]["parent"] = 1
    doc["nodes"]["4"]["joint"] = {"type": "hinge", "axis": [0.1, 0.0, 1.0], "pivot": [0.36, -0.2, 0.0], "range": [0.2, 1.2]}
    doc["relations"] = doc["relations"][1:]
    return doc


def _score(doc):
    e = evaluate(build_cases([_reference()], {"cab": doc}))
    return e.metrics, e.rows


def _shuffled(obj, rnd):
    if isinstance(obj, dict):
        items = list(obj.items())
        rnd.shuffle(items)
        return {k: _shuffled(v, rnd) for k, v in items}
    if isinstance(obj, list) and obj and isinstance(obj[0], dict):
        return [_shuffled(v, rnd) for v in rnd.sample(obj, len(obj))]
    return obj


def _rerooted_at_door(doc):
    """The same structure rooted at door 3: edge 1-3 reversed, its joint moved to 1 with [-hi, -lo]."""
    doc = json.loads(json.dumps(doc))
    j = doc["nodes"]["3"].pop("joint")
    j["range"] = [-j["range"][1], -j["range"][0]]
    doc["nodes"]["3"]["parent"] = None
    doc["nodes"]["1"]["parent"] = 3
    doc["nodes"]["1"]["joint"] = j
    return doc


def _flipped_axes(doc):
    doc = json.loads(json.dumps(doc))
    for node in doc["nodes"].values():
        if "joint" in node:
            j = node["joint"]
            j["axis"] = [-a for a in j["axis"]]
            j["range"] = [-j["range"][1], -j["range"][0]]
    return doc


def _other_star_anchor(doc):
    doc = json.loads(json.dumps(doc))
    keep = [r for r in doc["relations"] if r["type"] != "instance"]
    doc["relations"] = keep + [{"type": "instance", "a": 7, "b": 5}, {"type": "instance", "a": 7, "b": 6}]
    return doc


@pytest.mark.parametrize("base", [REFERENCE, _imperfect()], ids=["perfect", "imperfect"])
@pytest.mark.parametrize("variant", ["key_order", "reroot", "flip_axis", "star_anchor", "all"])
def test_canonically_equivalent_predictions_score_the_same(base, variant):
    rnd = random.Random(5)
    change = {
        "key_order": lambda d: _shuffled(d, rnd),
        "reroot": _rerooted_at_door,
        "flip_axis": _flipped_axes,
        "star_anchor": _other_star_anchor,
        "all": lambda d: _shuffled(_other_star_anchor(_flipped_axes(_rerooted_at_door(d))), rnd),
    }[variant]
    changed = change(base)
    assert json.dumps(changed) != json.dumps(base)
    want = _score(base)
    assert _score(changed) == want
    assert _score(json.dumps(changed)) == want  # as raw text, too
    if base is REFERENCE:
        assert want[0]["parent_acc"] == want[0]["success"] == want[0]["inst_f1"] == 100.0


def test_imperfect_prediction_hand_worked():
    m, rows = _score(_imperfect())
    # parents: node 6 wrong of 7 nodes
    assert m["parent_acc"] == pytest.approx(600 / 7)
    # door 4: axis angle atan(0.1) = 0.0997 rad passes; lines: the predicted axis through (0.36, -0.2, 0)
    # tilted in x-z, the reference vertical through (0.39, -0.2, 0); they are skew with the common
    # normal along y, and both pivots share y = -0.2, so the distance is 0 -> success.
    # ranges [0.2, 1.2] vs [0, 1.5]: IoU 1.0 / 1.5.
    match4 = next(x for x in rows[0]["matches"] if x["ref_child"] == 4)
    assert match4["gate"] == "success" and match4["line_distance"] == pytest.approx(0.0, abs=1e-9)
    assert match4["range_iou"] == pytest.approx(1 / 1.5)
    assert m["sym_f1"] == 0.0 and m["inst_f1"] == 100.0


def test_parse_failures_carry_the_rule():
    ref = _reference()
    bad_ids = json.loads(json.dumps(REFERENCE))
    del bad_ids["nodes"]["7"]
    cases = build_cases([ref, Reference("b", ref.structure, ref.boxes), Reference("c", ref.structure, ref.boxes)],
                        {"cab": "{not json", "b": bad_ids})
    assert [c.failure_rule for c in cases] == ["json", "part_ids", MISSING_RULE]
    assert all(c.prediction is None and c.failure for c in cases)
    m = evaluate(cases).metrics
    assert m["parse"] == 0.0 and m["parse_failures"] == {"json": 1, "missing": 1, "part_ids": 1}


def test_json_text_strips_end_marker_and_code_fence():
    doc = json.dumps(REFERENCE)
    assert json_text(f"```json\n{doc}\n```<|im_end|>\n") == doc
    assert json_text(f"  {doc}<|endoftext|>") == doc
    assert json_text("Sure! " + doc) == "Sure! " + doc  # prose around the JSON is a format failure


def test_file_errors_name_file_and_line(tmp_path):
    ref = tmp_path / "ref.jsonl"
    ref.write_text(json.dumps({"key": "a", "structure": REFERENCE, "boxes": BOXES}) + "\n\n{oops\n")
    with pytest.raises(InputFileError, match="line 3: not JSON"):
        load_references(ref)
    ref.write_text(json.dumps({"key": "a", "structure": REFERENCE, "boxes": {"1": BOXES["1"]}}) + "\n")
    with pytest.raises(InputFileError, match=r"no box for parts \[2, 3, 4, 5, 6, 7\]"):
        load_references(ref)
    bad = json.loads(json.dumps(REFERENCE))
    bad["nodes"]["2"]["parent"] = 2
    ref.write_text(json.dumps({"key": "a", "structure": bad, "boxes": BOXES}) + "\n")
    with pytest.raises(InputFileError, match="invalid reference.*self_parent"):
        load_references(ref)
    ref.write_text("\n")
    with pytest.raises(InputFileError, match="no reference lines"):
        load_references(ref)
    pred = tmp_path / "pred.jsonl"
    pred.write_text('{"key": "a", "text": "x"}\n{"key": "a", "text": "y"}\n')
    with pytest.raises(InputFileError, match="line 2 .*duplicate key"):
        load_predictions(pred)
    pred.write_text('{"key": "a"}\n')
    with pytest.raises(InputFileError, match='needs "text" or "structure"'):
        load_predictions(pred)
    with pytest.raises(InputFileError, match="cannot read"):
        load_predictions(tmp_path / "absent.jsonl")


@pytest.mark.parametrize("line, message", [
    (b'{"key": "a", "text": NaN}', r"line 2: not JSON \(NaN is not a JSON number\)"),
    (b'{"key": "a", "text": "x", "text": "y"}', r"line 2: not JSON \(key 'text' appears twice"),
    (b'{"key": "a", "n": ' + b"9" * 5000 + b"}", r"line 2: not JSON \(Exceeds the limit"),
    (b'{"key": ' + b"[" * 100_000 + b"]" * 100_000 + b"}", r"line 2: not JSON \(nested too deeply\)"),
    (b'{"key": "\xff"}', r"line 2: not UTF-8 text \(byte 9\)"),
    (b'{"key": "\\ud800", "text": "x"}', "line 2: \"key\" is not valid Unicode text \\(a lone surrogate"),
    (b'{"key": "a", "text": "' + b"x" * MAX_LINE_BYTES + b'"}', f"line 2 is over {MAX_LINE_BYTES} bytes"),
])
def test_hostile_lines_name_the_problem(tmp_path, line, message):
    pred = tmp_path / "pred.jsonl"
    pred.write_bytes(b'{"key": "b", "text": "x"}\n' + line + b"\n")
    with pytest.raises(InputFileError, match=message):
        load_predictions(pred)
