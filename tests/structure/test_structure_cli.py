"""`jax3dc validate` and `jax3dc canonicalize` through jax3dc.cli.main, bad input included."""

import json

import pytest

from jax3dc.cli import main
from jax3dc.structure import MAX_DOCUMENT_BYTES, Box, parse_structure, save_boxes


def document():
    return {
        "materials": {"0": {"family": "Wood", "desc": "oak"}, "1": {"family": "Metal", "desc": "steel"}},
        "nodes": {
            "1": {"parent": None, "material": 0, "name": "handle"},
            "2": {"parent": 1, "material": 0,
                  "joint": {"type": "hinge", "axis": [0, 0, -1], "pivot": [0.45, -0.3, 0], "range": [0, 1.571]}},
            "3": {"parent": 2, "material": 1},
        },
        "relations": [{"type": "instance", "a": 3, "b": 1}],
    }


@pytest.fixture
def files(tmp_path):
    path = tmp_path / "structure.json"
    path.write_text(json.dumps(document(), indent=2))
    boxes = tmp_path / "boxes.json"
    save_boxes({1: Box((0, 0, 0), (0.1, 0.1, 0.1)), 2: Box((0, 0, 0), (1, 0.5, 0.5)), 3: Box((0, 0, 0), (0.2, 0.2, 0.2))},
               boxes)
    return path, boxes


def test_validate_ok(files, capsys):
    path, _ = files
    assert main(["validate", str(path)]) == 0
    assert capsys.readouterr().out.strip() == "valid: 3 parts, 1 joints, 1 relations"
    assert main(["validate", str(path), "--parts", "3"]) == 0
    assert main(["validate", str(path), "--part-ids", "3,1,2"]) == 0


def test_validate_lists_every_problem_one_per_line(files, capsys):
    path, _ = files
    doc = document()
    doc["materials"]["1"]["family"] = "Steel"
    doc["nodes"]["2"]["joint"]["axis"] = [0, 0, 0]
    doc["relations"][0]["b"] = 3
    path.write_text(json.dumps(doc))
    assert main(["validate", str(path), "--parts", "4"]) == 1
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 4
    assert all(line.startswith(f"{path}: ") for line in err)
    assert [line.rsplit("[", 1)[1] for line in err] == ["family]", "axis_zero]", "part_ids]", "relation_self]"]


def _edited(path, value):
    def make():
        doc = document()
        obj = doc
        for k in path[:-1]:
            obj = obj[k]
        obj[path[-1]] = value
        return json.dumps(doc, indent=2)  # NaN is written as Python's json writes it
    return make


@pytest.mark.parametrize("text,rule,fragment", [
    (lambda: json.dumps(document(), indent=2)[:200], "json", "line "),
    (_edited(["nodes", "2", "joint", "axis"], [0, float("nan"), -1]), "axis_finite", "node 2 joint.axis"),
    (_edited(["nodes", "1", "parent"], 3), "cycle", "1 -> 3 -> 2 -> 1"),
    (_edited(["nodes", "3", "material"], 5), "material_exists", "node 3 material"),
])
def test_bad_documents_one_clear_line_and_exit_1(files, capsys, text, rule, fragment):
    path, boxes = files
    path.write_text(text())
    if rule == "axis_finite":
        assert "NaN" in path.read_text()
    assert main(["validate", str(path)]) == 1
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and f"[{rule}]" in err[0] and fragment in err[0]
    assert main(["canonicalize", str(path), "--boxes", str(boxes)]) == 1
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and err[0].startswith("jax3dc canonicalize: error: ") and f"[{rule}]" in err[0]


def test_missing_file_and_huge_file(tmp_path, capsys):
    assert main(["validate", str(tmp_path / "nope.json")]) == 1
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and "nope.json: no such file" in err[0]
    big = tmp_path / "big.json"
    big.write_text('{"materials": {}, "nodes": {}, "pad": "' + "x" * (10 * 1024 * 1024) + '"}')
    assert main(["validate", str(big)]) == 1
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and "[document_size]" in err[0] and str(MAX_DOCUMENT_BYTES) in err[0]
    assert main(["validate", str(tmp_path)]) == 1
    assert "is a directory" in capsys.readouterr().err


def test_bad_part_ids_argument(files, capsys):
    path, _ = files
    with pytest.raises(SystemExit) as info:
        main(["validate", str(path), "--part-ids", "1,x"])
    assert info.value.code == 2
    assert "comma-separated integers" in capsys.readouterr().err


def test_canonicalize_prints_and_writes(files, capsys, tmp_path):
    path, boxes = files
    assert main(["canonicalize", str(path), "--boxes", str(boxes)]) == 0
    printed = capsys.readouterr().out.strip()
    c = json.loads(printed)
    assert c["nodes"]["2"]["parent"] is None  # largest box
    assert c["nodes"]["1"] == {"parent": 2, "material": 0,
                               "joint": {"type": "hinge", "axis": [0.0, 0.0, 1.0], "pivot": [0.45, -0.3, 0.0],
                                         "range": [0.0, 1.571]}}
    assert c["relations"] == [{"type": "instance", "a": 1, "b": 3}]
    assert " " not in printed and "handle" not in printed
    out = tmp_path / "canonical.json"
    assert main(["canonicalize", str(path), "--boxes", str(boxes), "--out", str(out), "--names"]) == 0
    assert capsys.readouterr().out == ""
    written = out.read_text().strip()
    assert parse_structure(written).nodes[1].name == "handle"
    # canonical input is a fixed point
    out.write_text(printed)
    assert main(["canonicalize", str(out), "--boxes", str(boxes)]) == 0
    assert capsys.readouterr().out.strip() == printed


def test_canonicalize_bad_boxes(files, capsys, tmp_path):
    path, boxes = files
    assert main(["canonicalize", str(path), "--boxes", str(tmp_path / "none.json")]) == 1
    assert "none.json: no such file" in capsys.readouterr().err
    boxes.write_text('{"1": {"centroid": [0, 0, 0], "extent": [1, 1]}}')
    assert main(["canonicalize", str(path), "--boxes", str(boxes)]) == 1
    assert "box 1 extent" in capsys.readouterr().err
    boxes.write_text('{"1": {"centroid": [0, 0, 0], "extent": [1, 1, 1]}}')
    assert main(["canonicalize", str(path), "--boxes", str(boxes)]) == 1
    assert "[box_missing]" in capsys.readouterr().err
