"""`jax3dc eval metrics` and `jax3dc eval baselines` end to end on small JSONL files."""

import json

import pytest

from eval.metrics.score import TABLE1_KEYS, TABLE2_KEYS
from jax3dc.cli import main
from test_eval_cases import BOXES, REFERENCE

SCENE_BOXES = {
    "1": {"centroid": [-0.3, 0, 0], "extent": [0.4, 0.4, 0.4]},
    "2": {"centroid": [-0.3, 0, 0.25], "extent": [0.3, 0.3, 0.1]},
    "3": {"centroid": [0.3, 0, 0], "extent": [0.3, 0.3, 0.3]},
    "4": {"centroid": [0.3, 0, 0.2], "extent": [0.1, 0.1, 0.1]},
}
SCENE = {
    "materials": {"0": {"family": "Wood"}},
    "nodes": {"1": {"parent": None, "material": 0}, "2": {"parent": 1, "material": 0},
              "3": {"parent": None, "material": 0}, "4": {"parent": 3, "material": 0}},
}


@pytest.fixture
def ref_file(tmp_path):
    path = tmp_path / "ref.jsonl"
    lines = [{"key": "cab", "structure": REFERENCE, "boxes": BOXES},
             {"key": "scene", "structure": SCENE, "boxes": SCENE_BOXES},
             {"key": "lost", "structure": SCENE, "boxes": SCENE_BOXES}]
    path.write_text("".join(json.dumps(x) + "\n" for x in lines))
    return path


def test_eval_metrics_writes_metrics_and_rows(tmp_path, ref_file, capsys):
    pred = tmp_path / "pred.jsonl"
    wired = json.loads(json.dumps(SCENE))
    wired["nodes"]["3"]["parent"] = 1  # the two objects wired into one
    pred.write_text(
        json.dumps({"key": "cab", "text": "```json\n" + json.dumps(REFERENCE) + "\n```<|im_end|>"}) + "\n"
        + json.dumps({"key": "scene", "structure": wired}) + "\n"
        + json.dumps({"key": "extra", "text": "{}"}) + "\n"
    )
    out = tmp_path / "out"
    assert main(["eval", "metrics", "--pred", str(pred), "--ref", str(ref_file), "--out", str(out)]) == 0
    text = capsys.readouterr().out
    assert "Table 1a" in text and "Table 2" in text and "missing 1" in text and "ignored 1" in text
    m = json.loads((out / "metrics.json").read_text())
    assert set(TABLE1_KEYS + TABLE2_KEYS) <= set(m)
    # 2 of 3 parsed; over scenes: 1 of 2 scene references parsed, it predicts 1 object of 2
    assert m["parse"] == pytest.approx(200 / 3)
    assert m["scene_parse"] == 50.0 and m["objects_per_scene"] == 1.0 and m["count_match"] == 0.0
    # scene partition: nodes {1,2,3,4} all in one object vs {1,2},{3,4}: pairs 6 predicted, 2 reference,
    # 2 in both -> precision 2/6, recall 1; Rand (2 + 0) / 6; Hungarian keeps one object: 2 of 4 nodes
    assert m["pair_precision"] == pytest.approx(100 / 3) and m["pair_recall"] == 100.0
    assert m["rand_index"] == pytest.approx(100 / 3) and m["cluster_acc"] == 50.0
    rows = [json.loads(line) for line in (out / "per_object.jsonl").read_text().splitlines()]
    assert [r["key"] for r in rows] == ["cab", "scene", "lost"]
    assert rows[0]["parent_acc"] == 100.0 and rows[2]["failure_rule"] == "missing"


def test_eval_metrics_default_out_is_beside_the_predictions(tmp_path, ref_file):
    pred = tmp_path / "run7.jsonl"
    pred.write_text(json.dumps({"key": "cab", "structure": REFERENCE}) + "\n")
    assert main(["eval", "metrics", "--pred", str(pred), "--ref", str(ref_file)]) == 0
    assert (tmp_path / "run7.metrics" / "metrics.json").is_file()


def test_eval_metrics_bad_file_is_one_line_and_exit_1(tmp_path, ref_file, capsys):
    pred = tmp_path / "pred.jsonl"
    pred.write_text("not json\n")
    assert main(["eval", "metrics", "--pred", str(pred), "--ref", str(ref_file)]) == 1
    err = capsys.readouterr().err.strip()
    assert err.count("\n") == 0 and "pred.jsonl: line 1: not JSON" in err


def test_eval_baselines_scores_every_baseline_and_reference_is_perfect(tmp_path, ref_file, capsys):
    out = tmp_path / "base"
    assert main(["eval", "baselines", "--ref", str(ref_file), "--out", str(out)]) == 0
    text = capsys.readouterr().out
    for name in ("star", "heuristic", "reference"):
        assert any(line.startswith(name) for line in text.splitlines()), name
        assert (out / name / "predictions.jsonl").is_file() and (out / name / "per_object.jsonl").is_file()
    ref = json.loads((out / "reference" / "metrics.json").read_text())
    for key in ("parse", "parent_acc", "edge_f1", "presence_f1", "success", "sym_f1", "inst_f1", "full_partition"):
        assert ref[key] == 100.0, key
    star = json.loads((out / "star" / "metrics.json").read_text())
    assert star["presence_f1"] == 0.0 and star["count_match"] == 0.0  # star wires every scene into one object
    # the written predictions score the same through `eval metrics`
    again = tmp_path / "again"
    assert main(["eval", "metrics", "--pred", str(out / "star" / "predictions.jsonl"), "--ref", str(ref_file),
                 "--out", str(again)]) == 0
    assert json.loads((again / "metrics.json").read_text()) == star
    assert (out / "tables.txt").read_text().startswith("Table 1a")


def test_eval_without_subcommand_prints_help(capsys):
    assert main(["eval"]) == 2
    out = capsys.readouterr().out
    assert "metrics" in out and "baselines" in out
