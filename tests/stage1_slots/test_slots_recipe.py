"""recipes/stage1_slots.py on CPU at the tiny size: a handful of records, a few steps; the loss
falls, the folder is written and loads, and the last line printed is the summary as JSON."""

from __future__ import annotations

import json

from data_pipeline.samples import factory_source, object_records
from data_pipeline.shards import write_dataset
from jax3dc.stage1_slots import load_slots
from recipes.stage1_slots import main


def test_the_tiny_recipe_trains_evaluates_and_packages(tmp_path, capsys):
    records = [r for category in ("cabinet", "laptop", "bucket", "drawer_chest")
               for r in object_records(factory_source(category, 0), 1, 0, 32, split="train")]
    write_dataset(tmp_path / "data", records)
    out = tmp_path / "run"
    summary = main(["--train", str(tmp_path / "data"), "--eval", str(tmp_path / "data"), "--eval-split", "train",
                    "--tiny", "--slots", "8", "--steps", "30", "--batch", "4", "--lr", "3e-3", "--log-every", "10",
                    "--out", str(out)])
    assert summary["steps"] == 30 and summary["train_records"] == 4 and summary["eval_records"] == 4
    assert summary["last_loss"] < 0.8 * summary["first_loss"], summary
    assert set(summary["eval"]) >= {"rs_dgiou", "matched_share", "extra_share", "kind_accuracy"}
    assert 0.0 <= summary["eval"]["rs_dgiou"] <= 2.0
    assert json.loads(capsys.readouterr().out.strip().splitlines()[-1]) == summary
    assert load_slots(out / "slots").model.config.slots == 8
    assert (out / "summary.json").is_file() and len((out / "eval.jsonl").read_text().splitlines()) == 4
