"""Tiny datasets, model and tokenizer shared by the loader tests."""

from __future__ import annotations

import io
from pathlib import Path

import numpy as np
from PIL import Image

from data_pipeline.record import Record, encode_record
from jax3dc.factories import generate_object
from jax3dc.factories.registry import SCHEMAS
from jax3dc.geometry.parts import part_boxes
from jax3dc.processing.bpe import config_for_tokenizer
from jax3dc.model.config import Qwen3VLConfig
from jax3dc.processing.processor import ImageProcessorConfig
from jax3dc.processing.tokenizer import load_tokenizer
from jax3dc.palette import object_palette
from jax3dc.parameters import format_parameters
from jax3dc.prompt import build_prompt
from jax3dc.structure import to_json

IMAGE = 32  # side of the test images; the tiny model's patch 4 x merge 2 divides it
CATEGORIES = ("cabinet", "drawer_chest", "laptop", "door", "stapler", "faucet", "toaster", "bucket")


def tiny_config() -> Qwen3VLConfig:
    """The tiny preset with the real Qwen vocabulary and special-token ids."""
    return config_for_tokenizer(Qwen3VLConfig.tiny(), load_tokenizer())


def tiny_processor() -> ImageProcessorConfig:
    return ImageProcessorConfig(patch_size=4, min_pixels=IMAGE * IMAGE, max_pixels=IMAGE * IMAGE)


def png(rng: np.random.Generator) -> bytes:
    buf = io.BytesIO()
    Image.fromarray(rng.integers(0, 256, (IMAGE, IMAGE, 3), dtype=np.uint8)).save(buf, format="PNG")
    return buf.getvalue()


def record(category: str, seed: int, split: str = "train") -> Record:
    obj = generate_object(category, seed)
    boxes = part_boxes(obj.parts)
    prompt = build_prompt(boxes, object_palette(category, obj.object_id), len(obj.structure.joints()) or None)
    rng = np.random.default_rng(seed)
    return Record(key=f"{category}/{obj.object_id}/0", image_png=png(rng), seg_png=png(rng), prompt=prompt,
                  target=to_json(obj.structure), program=obj.program_text,
                  parameters=format_parameters(obj.parameters, SCHEMAS[category]),
                  meta={"category": category, "object_id": obj.object_id, "split": split})


def write_shard(path: Path, blobs: list[bytes]) -> None:
    from array_record.python.array_record_module import ArrayRecordWriter

    path.parent.mkdir(parents=True, exist_ok=True)
    writer = ArrayRecordWriter(str(path), "group_size:1")
    for blob in blobs:
        writer.write(blob)
    writer.close()


def write_dataset(folder: Path, records: list[Record], shards: int = 2, split: str = "train") -> Path:
    for i in range(shards):
        write_shard(folder / f"{split}-{i:05d}.array_record", [encode_record(r) for r in records[i::shards]])
    return folder
