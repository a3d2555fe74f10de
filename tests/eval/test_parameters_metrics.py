"""Stage-1 parameter scores: parts matched one-to-one by box overlap whatever their ids, part-count
accuracy, Chamfer, texts that run; and ``eval run --task parameters`` end to end on shards."""

from __future__ import annotations

import dataclasses
import json
from pathlib import Path

import pytest
import trimesh

from data_pipeline.record import encode_record
from eval.metrics.parameters import score_parameters, summarise
from eval.metrics.part_matching import match_parts, matched_iou
from jax3dc.cli import main
from jax3dc.factories.registry import SCHEMAS, run_parameters
from jax3dc.parameters import format_parameters
from tests.eval.test_eval_run import factory_record
from tests.factory_samples import sample_parameters


def _box(centre, size=(0.2, 0.2, 0.2)) -> trimesh.Trimesh:
    return trimesh.creation.box(extents=size, transform=trimesh.transformations.translation_matrix(centre))


def test_a_right_part_under_another_id_still_counts():
    ref = {1: _box((0, 0, 0)), 2: _box((0.5, 0, 0))}
    swapped = {1: ref[2], 2: ref[1]}
    assert sorted(match_parts(ref, swapped)) == [(1, 2, 1.0), (2, 1, 1.0)]
    assert matched_iou(ref, swapped) == pytest.approx(1.0)


def test_parts_without_a_partner_count_zero_on_either_side():
    ref = {1: _box((0, 0, 0)), 2: _box((0.5, 0, 0))}
    extra = {**ref, 3: _box((3, 3, 3))}
    assert matched_iou(ref, extra) == pytest.approx(2 / 3)
    assert matched_iou(ref, {1: ref[1]}) == pytest.approx(1 / 2)
    assert matched_iou(ref, {}) == 0.0 and match_parts({}, ref) == []
    half = {1: _box((0.1, 0, 0))}  # overlaps part 1 by a half along x: IoU 1/3
    assert match_parts(ref, half) == [(1, 1, pytest.approx(1 / 3))]


def _text(category: str, seed: int) -> str:
    return format_parameters(sample_parameters(category, seed), SCHEMAS[category])


def test_scores_of_right_wrong_and_broken_texts():
    ref = _text("drawer_chest", 0)
    same = score_parameters("k", ref, ref, SCHEMAS, run_parameters)
    assert same.runs and same.category and same.count_exact and same.ids
    assert same.matched_iou == pytest.approx(1.0) and same.box_iou == pytest.approx(1.0) and same.chamfer < 1e-2
    other = score_parameters("k", ref, _text("laptop", 0), SCHEMAS, run_parameters)
    assert other.runs and not other.category and other.matched_iou < 0.5 and other.chamfer > 0.02
    for broken in ("", "drawer_chest(width=9)", "laptop(" + "x" * 10, "__import__('os').system('true')"):
        score = score_parameters("k", ref, broken, SCHEMAS, run_parameters)
        assert not score.runs and score.matched_iou == 0.0 and score.chamfer is None and score.error
    row = summarise([same, other, score])
    assert row["runs"] == pytest.approx(200 / 3) and row["category"] == pytest.approx(100 / 3)
    assert row["chamfer"] == pytest.approx((same.chamfer + other.chamfer) / 2)


def test_the_same_object_with_permuted_ids_matches_fully():
    """A drawer chest whose rows come in another order (a different seed with the same row count
    would not do): ids differ, the matched IoU does not."""
    params = sample_parameters("drawer_chest", 3)
    parts = run_parameters(params).parts
    ids = sorted(parts)
    permuted = {new: parts[old] for new, old in zip(ids, reversed(ids))}
    assert matched_iou(parts, permuted) == pytest.approx(1.0)


@pytest.fixture(scope="module")
def shards(tmp_path_factory) -> Path:
    from array_record.python.array_record_module import ArrayRecordWriter

    folder = tmp_path_factory.mktemp("param_shards")
    writer = ArrayRecordWriter(str(folder / "test-00000-of-00001.array_record"), "group_size:1")
    for category, seed in (("cabinet", 0), ("laptop", 2), ("stapler", 1)):
        record = factory_record(category, seed, "test")
        writer.write(encode_record(dataclasses.replace(record, parameters=_text(category, seed))))
    writer.close()
    return folder


def test_eval_run_task_parameters(shards: Path, tmp_path: Path, capsys) -> None:
    out = tmp_path / "ref"
    assert main(["eval", "run", "--task", "parameters", "--data", str(shards), "--reference-as-prediction",
                 "--out", str(out)]) == 0
    metrics = json.loads((out / "metrics.json").read_text())
    assert metrics["task"] == "parameters" and metrics["objects"] == 3
    for key in ("runs", "category", "count_exact", "matched_iou", "ids", "box_iou"):
        assert metrics[key] == pytest.approx(100.0), key
    assert "matched part-box IoU" in (out / "tables.md").read_text()
    preds = tmp_path / "preds.jsonl"
    lines = [{"key": "cabinet/cabinet_000000/0", "text": _text("cabinet", 5)},
             {"key": "laptop/laptop_000002/0", "text": "laptop(width=1)"}]  # the stapler has none
    preds.write_text("\n".join(json.dumps(line) for line in lines) + "\n")
    assert main(["eval", "run", "--task", "parameters", "--data", str(shards), "--predictions", str(preds),
                 "--out", str(tmp_path / "preds")]) == 0
    rows = [json.loads(line) for line in (tmp_path / "preds" / "parameters.jsonl").read_text().splitlines()]
    assert [r["runs"] for r in rows] == [True, False, False]
    assert rows[1]["error"].startswith("column 15")  # cut short after width: where the text stops fitting


def test_eval_run_task_parameters_refuses_records_without_them(tmp_path: Path, capsys) -> None:
    from array_record.python.array_record_module import ArrayRecordWriter

    writer = ArrayRecordWriter(str(tmp_path / "test-00000-of-00001.array_record"), "group_size:1")
    writer.write(encode_record(factory_record("cabinet", 0, "test")))
    writer.close()
    assert main(["eval", "run", "--task", "parameters", "--data", str(tmp_path), "--reference-as-prediction",
                 "--out", str(tmp_path / "out")]) == 1
    assert "no factory parameters" in capsys.readouterr().err
