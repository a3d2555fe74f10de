"""Dataset card: statistics agree with the records; contact sheet written; import via CLI."""

import json

import numpy as np
from PIL import Image

from data_pipeline.build import BuildConfig, factory_sources, run_build
from data_pipeline.card import CARD_JSON, CONTACT_SHEET, dataset_card
from data_pipeline.shards import read_dataset
from jax3dc.cli import main
from tests.shared_fixtures import partnet_object



def test_card_counts_match_records(tmp_path):
    run_build(tmp_path, factory_sources(3, 2), BuildConfig(2, 2, 32, 2), workers=1, progress=False)
    stats = dataset_card(tmp_path, samples=4, progress=False)
    records = list(read_dataset(tmp_path))
    assert stats["records"] == len(records) == 6
    assert sum(c["records"] for c in stats["categories"].values()) == 6
    assert all(c["objects"] == 1 for c in stats["categories"].values())
    total_parts = sum(len(json.loads(r.target)["nodes"]) for r in records)
    assert stats["parts_per_record"]["max"] == max(len(json.loads(r.target)["nodes"]) for r in records)
    assert stats["parts_per_record"]["mean"] == round(total_parts / 6, 2)
    assert stats["target_tokens"]["max"] > 10
    assert json.loads((tmp_path / CARD_JSON).read_text()) == stats
    sheet = np.asarray(Image.open(tmp_path / CONTACT_SHEET))
    assert sheet.shape == (2 * 128, 4 * 128, 3)


def test_import_cli_writes_shards(tmp_path):
    sources = [str(partnet_object("door_8877")), str(partnet_object("microwave_7119"))]
    assert main(["data", "import", *sources, "--out", str(tmp_path), "--views", "2", "--size", "32", "--quiet"]) == 0
    records = list(read_dataset(tmp_path))
    assert sorted({r.meta["object_id"] for r in records}) == ["door_8877", "microwave_7119"]
    assert all(json.loads(r.target)["nodes"] for r in records)
