"""``jax3dc eval run`` end to end on tiny ArrayRecord shards of factory objects.

The scoring path runs with real structures (``--reference-as-prediction`` must score 100, a
predictions file with one broken line must show that parse failure); the generation path runs a
tiny random Qwen3-VL with the real Qwen tokenizer, whose garbage must count as parse failures with
their rule recorded, while the report still renders and a rerun resumes instead of regenerating.
"""

from __future__ import annotations

import io
import json
from pathlib import Path

import numpy as np
import pytest
from PIL import Image

from data_pipeline.record import Record, encode_record
from jax3dc.cli import main
from jax3dc.errors import InputFileError
from jax3dc.factories import generate_object
from jax3dc.geometry.parts import part_boxes
from jax3dc.palette import object_palette
from jax3dc.prompt import build_prompt
from jax3dc.structure import boxes_to_dict, to_json
from tests.tiny_checkpoint import write_tiny_checkpoint

CAMERA = {"lookat": [0.0, 0.0, 0.0], "distance": 2.4, "azimuth": 100.0, "elevation": -20.0}  # as data build writes
TEST_OBJECTS = (("cabinet", 0), ("drawer_chest", 1), ("laptop", 2))
REPORT_FILES = ("metrics.json", "per_object.jsonl", "tables.md", "per_category.md", "failure_attribution.png",
                "index.md", "references.jsonl")


def png(seed: int, size: tuple[int, int]) -> bytes:
    pixels = np.random.default_rng(seed).integers(0, 256, (size[1], size[0], 3), dtype=np.uint8)
    buf = io.BytesIO()
    Image.fromarray(pixels).save(buf, format="PNG")
    return buf.getvalue()


def factory_record(category: str, seed: int, split: str, legend_only: bool = False) -> Record:
    obj = generate_object(category, seed)
    boxes = part_boxes(obj.parts)
    prompt = build_prompt(boxes, object_palette(category, obj.object_id), len(obj.structure.joints()) or None)
    meta = {"category": category, "object_id": obj.object_id, "seed": seed, "view": 0, "split": split,
            "camera": CAMERA}
    if not legend_only:
        meta["boxes"] = boxes_to_dict(boxes)
    return Record(key=f"{category}/{obj.object_id}/0", image_png=png(seed, (48, 40)), seg_png=png(seed + 99, (48, 40)),
                  prompt=prompt, target=to_json(obj.structure), program=obj.program_text, meta=meta)


@pytest.fixture(scope="module")
def shards(tmp_path_factory) -> Path:
    from array_record.python.array_record_module import ArrayRecordWriter

    folder = tmp_path_factory.mktemp("shards")
    groups = {
        "test-00000-of-00002.array_record": [factory_record(c, s, "test", legend_only=(c == "laptop"))
                                             for c, s in TEST_OBJECTS[:2]],
        "test-00001-of-00002.array_record": [factory_record(*TEST_OBJECTS[2], "test", legend_only=True)],
        "train-00000-of-00001.array_record": [factory_record("wardrobe", 5, "train")],
    }
    for name, records in groups.items():
        writer = ArrayRecordWriter(str(folder / name), "group_size:1")
        for record in records:
            writer.write(encode_record(record))
        writer.close()
    return folder


def keys() -> list[str]:
    return [f"{c}/{c}_{s:06d}/0" for c, s in TEST_OBJECTS]


def read_jsonl(path: Path) -> list[dict]:
    return [json.loads(line) for line in path.read_text().splitlines() if line.strip()]


def test_reference_as_prediction_scores_100(shards: Path, tmp_path: Path) -> None:
    out = tmp_path / "report"
    assert main(["eval", "run", "--data", str(shards), "--reference-as-prediction", "--out", str(out),
                 "--overlays", "2"]) == 0
    for name in REPORT_FILES:
        assert (out / name).stat().st_size > 0, name
    metrics = json.loads((out / "metrics.json").read_text())
    assert metrics["counts"]["objects"] == 3  # the train shard is not read
    for key in ("parse", "parent_acc", "edge_f1", "presence_f1", "type_acc", "axis_acc", "range_iou", "success"):
        assert metrics[key] == pytest.approx(100.0), key
    assert metrics["pos_err"] == pytest.approx(0.0, abs=1e-9)
    assert metrics["counts"]["joints_matched"] == metrics["counts"]["joints_ref"] > 0
    assert sorted(r["key"] for r in read_jsonl(out / "per_object.jsonl")) == sorted(keys())
    per_category = (out / "per_category.md").read_text()
    for category, _ in TEST_OBJECTS:
        assert f"| {category} | 1 | 100.0 |" in per_category
    assert "| reference | 100.0 | 100.0 |" in (out / "tables.md").read_text()
    overlays = sorted((out / "overlays").iterdir())
    assert len(overlays) == 2
    index = (out / "index.md").read_text()
    for path in overlays:
        assert f"(overlays/{path.name})" in index
    assert Image.open(overlays[0]).size[0] >= 512


def test_predictions_file_with_a_broken_line(shards: Path, tmp_path: Path) -> None:
    refs = {r["key"]: r for r in read_jsonl(_reference_lines(shards, tmp_path))}
    first, second, third = keys()
    preds = tmp_path / "preds.jsonl"
    preds.write_text("\n".join(json.dumps(line) for line in (
        {"key": first, "structure": refs[first]["structure"]},
        {"key": second, "text": "```json\n" + json.dumps(refs[second]["structure"]) + "\n```<|im_end|>"},
        {"key": third, "text": '{"materials": {"0": {"family": "Wood"}}, "nodes": {'},
    )) + "\n")
    out = tmp_path / "report"
    assert main(["eval", "run", "--data", str(shards), "--predictions", str(preds), "--out", str(out)]) == 0
    metrics = json.loads((out / "metrics.json").read_text())
    assert metrics["parse"] == pytest.approx(200 / 3)
    assert metrics["parent_acc"] == pytest.approx(100.0)
    assert sum(metrics["parse_failures"].values()) == 1
    rule = next(iter(metrics["parse_failures"]))
    assert f"parse failure `{rule}`" in (out / "index.md").read_text()


def _reference_lines(shards: Path, tmp_path: Path) -> Path:
    out = tmp_path / "refs"
    assert main(["eval", "run", "--data", str(shards), "--reference-as-prediction", "--out", str(out),
                 "--overlays", "0"]) == 0
    return out / "references.jsonl"


def test_bad_inputs_are_one_line_errors(shards: Path, tmp_path: Path, capsys) -> None:
    assert main(["eval", "run", "--data", str(tmp_path / "nowhere"), "--reference-as-prediction",
                 "--out", str(tmp_path / "o")]) == 1
    assert main(["eval", "run", "--data", str(shards), "--reference-as-prediction", "--predictions",
                 str(tmp_path / "p.jsonl"), "--out", str(tmp_path / "o")]) == 1  # two sources
    assert main(["eval", "run", "--data", str(shards), "--split", "val", "--reference-as-prediction",
                 "--out", str(tmp_path / "o")]) == 1
    assert main(["eval", "run", "--data", str(shards), "--reference-as-prediction", "--ground-joints",
                 "--out", str(tmp_path / "o")]) == 1  # grounding acts as a checkpoint decodes
    err = capsys.readouterr().err
    assert "nowhere" in err and "at most one of" in err and "no records of split 'val'" in err
    assert "--ground-joints grounds structures as a checkpoint decodes them" in err


def test_split_all_scores_every_record_of_every_dataset(shards: Path, tmp_path: Path) -> None:
    """--split all reads every shard (train ones too) and keeps every record whatever its meta.split,
    across several --data folders at once."""
    from array_record.python.array_record_module import ArrayRecordWriter

    other = tmp_path / "other"
    other.mkdir()
    writer = ArrayRecordWriter(str(other / "val-00000.array_record"), "group_size:1")
    writer.write(encode_record(factory_record("laptop", 7, "val")))
    writer.close()
    out = tmp_path / "report"
    assert main(["eval", "run", "--data", str(shards), str(other), "--split", "all", "--reference-as-prediction",
                 "--out", str(out), "--overlays", "0"]) == 0
    metrics = json.loads((out / "metrics.json").read_text())
    expected = sorted([*keys(), "wardrobe/wardrobe_000005/0", "laptop/laptop_000007/0"])
    assert metrics["counts"]["objects"] == len(expected) == 5
    assert sorted(r["key"] for r in read_jsonl(out / "per_object.jsonl")) == expected
    assert sorted(r["key"] for r in read_jsonl(out / "references.jsonl")) == expected
    assert metrics["parse"] == pytest.approx(100.0) and metrics["success"] == pytest.approx(100.0)
    # the default is still the test split alone
    assert main(["eval", "run", "--data", str(shards), str(other), "--reference-as-prediction",
                 "--out", str(tmp_path / "test_only"), "--overlays", "0"]) == 0
    assert json.loads((tmp_path / "test_only" / "metrics.json").read_text())["counts"]["objects"] == 3


def test_reference_run_on_a_data_build(tmp_path: Path) -> None:
    """Shards written by `jax3dc data build` (its meta camera and boxes) score 100 with overlays."""
    data, out = tmp_path / "data", tmp_path / "report"
    assert main(["data", "build", "--objects", "4", "--views", "1", "--size", "64", "--out", str(data), "--quiet"]) == 0
    split = json.loads((data / "manifest.json").read_text())["shards"]
    split = next(iter(split.values()))["split"]
    assert main(["eval", "run", "--data", str(data), "--split", split, "--reference-as-prediction",
                 "--out", str(out), "--overlays", "2"]) == 0
    metrics = json.loads((out / "metrics.json").read_text())
    assert metrics["parse"] == 100.0 and metrics["success"] == 100.0
    assert len(list((out / "overlays").glob("*.png"))) == 2


# --------------------------------------------------------------------------- generation
@pytest.fixture(scope="module")
def checkpoint(tmp_path_factory) -> Path:
    """A tiny random Qwen3-VL whose vocabulary covers the real Qwen special ids, saved with the
    real tokenizer and an image processor sized for it."""
    return write_tiny_checkpoint(tmp_path_factory.mktemp("tiny_checkpoint"))


@pytest.mark.slow
def test_generation_garbage_is_parse_failures_and_resumes(shards: Path, checkpoint: Path, tmp_path: Path,
                                                         monkeypatch, capsys) -> None:
    from jax3dc.sampler import Sampler

    out = tmp_path / "report"
    argv = ["eval", "run", "--checkpoint", str(checkpoint), "--data", str(shards), "--out", str(out),
            "--batch-size", "2", "--max-new-tokens", "5", "--bucket", "256", "--dtype", "float32", "--overlays", "3",
            "--unconstrained"]  # the grammar refuses a budget below the shortest document: garbage needs it off
    batches: list[int] = []
    real = Sampler.generate_batch

    def counted(self, prompts, *args):
        batches.append(len(prompts))
        return real(self, prompts, *args)

    monkeypatch.setattr(Sampler, "generate_batch", counted)
    assert main(argv) == 0
    assert batches == [2, 1]
    assert "generated 3 objects" in capsys.readouterr().out
    assert "generated 3 objects" in (out / "index.md").read_text()
    lines = read_jsonl(out / "predictions.jsonl")
    assert sorted(line["key"] for line in lines) == sorted(keys())
    assert all(1 <= line["new_tokens"] <= 5 and (line["new_tokens"] == 5 or line["stopped"]) for line in lines)
    metrics = json.loads((out / "metrics.json").read_text())
    assert metrics["parse"] == 0.0
    assert sum(metrics["parse_failures"].values()) == 3 and "missing" not in metrics["parse_failures"]
    rows = read_jsonl(out / "per_object.jsonl")
    assert all(not row["parsed"] and row["failure_rule"] for row in rows)
    for name in REPORT_FILES:
        assert (out / name).stat().st_size > 0, name
    assert len(list((out / "overlays").iterdir())) == 3

    # Resume: a killed run left two lines and a torn third; only the missing key is generated.
    text = (out / "predictions.jsonl").read_text().splitlines()
    (out / "predictions.jsonl").write_text("\n".join(text[:2]) + "\n" + text[2][:7])
    batches.clear()
    assert main(argv) == 0
    assert batches == [1]
    again = read_jsonl(out / "predictions.jsonl")
    assert again[:2] == lines[:2] and sorted(line["key"] for line in again) == sorted(keys())


@pytest.mark.slow
def test_batched_windowed_generation_equals_plain_generate_per_row(shards: Path, checkpoint: Path) -> None:
    """Batch rows (left padding, vision_window, the topped-up row) decode as each prompt alone
    through jax3dc.generate.generate with full vision attention."""
    import jax

    from data_pipeline.shards import shard_paths
    from eval.records import read_records
    from jax3dc.sampler import DecodeOptions, Sampler
    from jax3dc.generate import GenerationConfig
    from tests.generation import generate
    from jax3dc.processing.processor import preprocess_images

    generator = Sampler.load(checkpoint, dtype="float32")
    records = list(read_records(shard_paths([shards], "test"), "test"))
    prompts = [generator.prompt(r) for r in records]
    with jax.default_matmul_precision("highest"):
        batched = generator.generate_batch(prompts[:2], 3, max_new_tokens=4, bucket=32,
                                           options=DecodeOptions(constrained=False))
        special = generator.tokenizer.special
        config = GenerationConfig(max_new_tokens=4, stop_ids=special.stop_ids, pad_id=special.endoftext)
        for prompt, (sample,) in zip(prompts[:2], batched):
            text, n = sample.text, sample.new_tokens
            images = preprocess_images(generator.images(prompt.record), generator.processor)
            alone = generate(generator.model, prompt.input_ids[None], None, images.pixel_values, images.image_grid_thw,
                             config=config)
            length = int(alone.lengths[0])
            assert n == length
            assert text == generator.tokenizer.decode(np.asarray(alone.tokens)[0, :length].tolist())


def test_weights_only_export_falls_back_to_packaged_tokenizer(checkpoint: Path, tmp_path: Path, capsys) -> None:
    import shutil

    from jax3dc.sampler import Sampler
    from jax3dc.processing.processor import ImageProcessorConfig

    for path in checkpoint.iterdir():
        if path.name == "config.json" or path.suffix == ".safetensors" or path.name.endswith(".index.json"):
            shutil.copy(path, tmp_path / path.name)
    generator = Sampler.load(tmp_path, dtype="float32")
    assert generator.tokenizer.special.im_end == 151645
    assert generator.processor == ImageProcessorConfig.qwen3_vl()
    err = capsys.readouterr().err
    assert "no tokenizer.json" in err and "no preprocessor_config.json" in err
    with pytest.raises(InputFileError, match="no config.json"):
        Sampler.load(tmp_path / "missing")
