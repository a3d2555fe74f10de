"""Dataset card: statistics of a built dataset and a contact sheet of sample records.

Statistics per split and category: records, objects, parts, joints by type, relations by type,
and token counts of the prompt and target text under the Qwen3 tokenizer (the lengths training
pays for).
"""

from __future__ import annotations

import json
from collections import Counter, defaultdict
from pathlib import Path

import numpy as np
from PIL import Image
from tqdm import tqdm

from jax3dc.render import png_array
from data_pipeline.shards import load_manifest, read_dataset
from jax3dc.errors import InputFileError
from jax3dc.processing.tokenizer import load_tokenizer

CARD_JSON = "card.json"
CONTACT_SHEET = "contact_sheet.png"


def _summary(values: list[int]) -> dict:
    if not values:
        return {"mean": 0.0, "max": 0, "p95": 0}
    a = np.asarray(values)
    return {"mean": round(float(a.mean()), 2), "max": int(a.max()), "p95": int(np.percentile(a, 95))}


def dataset_card(directory: Path, samples: int = 16, thumb: int = 128, progress: bool = True) -> dict:
    """Write ``card.json`` and ``contact_sheet.png`` (I above S for ``samples`` records) into
    ``directory``; returns the statistics."""
    manifest = load_manifest(directory)
    if manifest is None:
        raise InputFileError(directory, "no manifest.json: not a dataset written by `jax3dc data build`")
    tokenizer = load_tokenizer()
    total = sum(s["records"] for s in manifest["shards"].values())
    records_per = Counter()
    objects_per: dict[str, set] = defaultdict(set)
    splits = Counter()
    joints, relations = Counter(), Counter()
    parts, prompt_tokens, target_tokens = [], [], []
    tiles = []
    for record in tqdm(read_dataset(directory), total=total, unit="record", disable=not progress):
        category = record.meta.get("category", "?")
        records_per[category] += 1
        objects_per[category].add(record.meta.get("object_id"))
        splits[record.meta.get("split", "?")] += 1
        doc = json.loads(record.target)
        parts.append(len(doc["nodes"]))
        joints.update(n["joint"]["type"] for n in doc["nodes"].values() if "joint" in n)
        relations.update(r["type"] for r in doc["relations"])
        prompt_tokens.append(len(tokenizer.encode(record.prompt)))
        target_tokens.append(len(tokenizer.encode(record.target)))
        if len(tiles) < samples:
            tiles.append((png_array(record.image_png), png_array(record.seg_png)))
    stats = {
        "records": sum(records_per.values()),
        "splits": dict(sorted(splits.items())),
        "categories": {c: {"records": records_per[c], "objects": len(objects_per[c])} for c in sorted(records_per)},
        "joints": dict(sorted(joints.items())),
        "relations": dict(sorted(relations.items())),
        "parts_per_record": _summary(parts),
        "prompt_tokens": _summary(prompt_tokens),
        "target_tokens": _summary(target_tokens),
    }
    (directory / CARD_JSON).write_text(json.dumps(stats, indent=1))
    if tiles:
        write_contact_sheet(tiles, thumb, directory / CONTACT_SHEET)
    return stats


def write_contact_sheet(tiles: list[tuple[np.ndarray, np.ndarray]], thumb: int, path: Path) -> None:
    columns = min(8, len(tiles))
    rows = -(-len(tiles) // columns)
    sheet = Image.new("RGB", (columns * thumb, rows * 2 * thumb), (255, 255, 255))
    for k, (image, seg) in enumerate(tiles):
        x, y = (k % columns) * thumb, (k // columns) * 2 * thumb
        sheet.paste(Image.fromarray(image).resize((thumb, thumb), Image.BILINEAR), (x, y))
        sheet.paste(Image.fromarray(seg).resize((thumb, thumb), Image.NEAREST), (x, y + thumb))
    sheet.save(path, format="PNG", compress_level=6)
