"""Records carry the factory's parameter text (the stage-1 target) and the parameters task reads it."""

import dataclasses

import numpy as np
import pytest

from data_pipeline.build import BuildConfig, factory_sources, run_build
from data_pipeline.examples import ExampleEncoder, MissingParameters
from data_pipeline.record import decode_record, encode_record
from data_pipeline.shards import read_dataset
from jax3dc.factories.registry import SCHEMAS, run_parameters
from jax3dc.parameters import parse_parameters
from jax3dc.processing.tokenizer import load_tokenizer
from jax3dc.structure import boxes_to_dict
from jax3dc.geometry.parts import part_boxes
from tests.loader.loader_fixtures import record, tiny_config, tiny_processor


def test_build_writes_parameters_that_rebuild_the_record(tmp_path):
    """A handful of objects, with split/merge variants: the factory's own records carry the text,
    which runs into the record's parts (the same boxes, the same canonical target); variants whose
    parts are no longer the factory's carry none."""
    config = BuildConfig(views=1, seed=3, size=32, objects_per_shard=4, augment=True)
    run_build(tmp_path, factory_sources(4, config.seed), config, workers=1, progress=False)
    records = list(read_dataset(tmp_path))
    own = [r for r in records if r.meta["augmentation"] is None]
    assert len(own) == 4 and all(r.parameters for r in own)
    assert all(r.parameters is None for r in records if r.meta["augmentation"] is not None)
    for r in own:
        params = parse_parameters(r.parameters, SCHEMAS)
        assert params.category == r.meta["category"]
        obj = run_parameters(params)
        assert obj.program_text == r.program
        assert boxes_to_dict(part_boxes(obj.parts)) == r.meta["boxes"]  # view 0 is the rest pose


def test_record_without_parameters_keeps_its_bytes():
    r = dataclasses.replace(record("stapler", 0), parameters=None)
    blob = encode_record(r)
    assert b'"parameters"' not in blob and decode_record(blob) == r
    full = record("stapler", 0)
    assert decode_record(encode_record(full)).parameters == full.parameters


def test_parameters_task_is_image_alone_to_the_text():
    tok = load_tokenizer()
    enc = ExampleEncoder(tok, tiny_processor(), tiny_config().vision.spatial_merge_size, task="parameters", image_size=32)
    r = record("laptop", 1)
    ex = enc.encode(r)
    assert enc.images_per_example == 1 and len(ex.image_grid_thw) == 1
    answer = tok.decode([int(t) for t, keep in zip(ex.input_ids, np.asarray(ex.labels) >= 0) if keep])
    assert answer.startswith(r.parameters) and r.parameters.startswith("laptop(")
    with pytest.raises(MissingParameters, match="no factory parameters"):
        enc.encode(dataclasses.replace(r, parameters=None))


def test_loader_mixes_the_parameters_task_with_structure(tmp_path):
    """One folder under two tasks (as `train data_tasks=structure,parameters` reads it): rows hold
    structure examples (I and S) and parameter examples (I alone)."""
    from data_pipeline.loader import LoaderConfig, ShardLoader
    from tests.loader.loader_fixtures import CATEGORIES, IMAGE, write_dataset

    data = write_dataset(tmp_path, [record(c, 0) for c in CATEGORIES], shards=2)
    cfg = LoaderConfig(sources=(str(data), str(data)), seq_len=2400, rows=2, pack=2, image_size=IMAGE,
                       tasks=("structure", "parameters"), weights=(0.5, 0.5))
    it = ShardLoader.create(cfg, tiny_config(), load_tokenizer(), tiny_processor())
    merged = 64 // 4
    images = []
    for _ in range(6):
        batch = next(it)
        for row in range(2):
            ids, seg = batch["input_ids"][row], batch["segment_ids"][row]
            for s in range(1, int(seg.max()) + 1):
                images.append(int((ids[seg == s] == tiny_config().image_token_id).sum()) // merged)
    assert set(images) == {1, 2}, images
