"""The slots network's recipe (issue 64): train on record shards, score on held-out records, package.

    python3 -m recipes.stage1_slots --train DATA [DATA ...] --eval DATA --out runs/stage1_slots \
        --steps 20000 --batch 128 --workers 8

  1. load     every record of the --train folders whose meta split is --train-split (default
              train), and of the --eval folders whose split is --eval-split (default test): its
              image at the network's size and its slot targets (train.stage1_slots.slot_targets),
              decoded by --workers processes, one shard file each
  2. train    jax3dc.stage1_slots.SlotsNet with the Hungarian set loss (train.stage1_slots),
              bounded by --steps and --minutes
  3. package  OUT/slots (slots_net.json + float16 model.safetensors + MODEL_CARD.md)
  4. evaluate the packaged folder on the eval records at rest (views with no joint moved; all views
              when none is at rest): RS-dgIoU, reference parts matched (IoU >= 0.5), extra parts,
              part-kind accuracy (eval.metrics.part_boxes); OUT/summary.json holds them with the
              training log, OUT/eval.jsonl the per-object scores, and the last line printed is the
              summary as JSON.
``--tiny`` uses the CPU smoke-test size (jax3dc.stage1_slots.SlotsNetConfig.tiny).
"""

from __future__ import annotations

import argparse
import io
import json
import time
from collections.abc import Sequence
from concurrent.futures import ProcessPoolExecutor
from dataclasses import replace
from pathlib import Path

import numpy as np
from PIL import Image
from flax import nnx

from data_pipeline.shards import read_shard, shard_paths
from eval.metrics.part_boxes import score_part_boxes, summarise
from jax3dc.stage1_net import network_image
from jax3dc.stage1_slots import KINDS, SlotsNet, SlotsNetConfig, load_slots, save_slots
from jax3dc.stage1_slots.kinds import kind_of
from train.stage1_slots import SlotsTrainConfig, SlotTargets, slot_targets, stack_targets, train


def _bounds(centre: Sequence[float], extent: Sequence[float]) -> np.ndarray:
    c, e = np.asarray(centre, np.float64), np.abs(np.asarray(extent, np.float64))
    return np.stack([c - e / 2.0, c + e / 2.0])


def _load_shard(job: tuple[str, str, int, int]) -> list[tuple]:
    """(image uint8, targets row, reference boxes, reference kinds, key, at rest) of the records of
    one shard in the wanted split (one worker's job)."""
    path, split, size, slots = job
    rows = []
    for record in read_shard(Path(path)):
        if record.meta.get("split", "train") != split or not record.meta.get("boxes"):
            continue
        rgb = np.asarray(Image.open(io.BytesIO(record.image_png)).convert("RGB"))
        image = (network_image(rgb, size) * 255.0 + 0.5).astype(np.uint8)
        names = record.meta.get("part_names") or {}
        boxes = record.meta["boxes"]
        reference = [_bounds(boxes[p]["centroid"], boxes[p]["extent"]) for p in sorted(boxes, key=int)]
        kinds = [kind_of(names[p]) if p in names else None for p in sorted(boxes, key=int)]
        rows.append((image, slot_targets(record, slots), reference, kinds, record.key,
                     record.meta.get("moved_joint") is None))
    return rows


def load_records(folders: Sequence[str], split: str, size: int, slots: int, workers: int, limit: int = 0) -> list[tuple]:
    """``_load_shard`` rows of every shard of ``folders`` (in shard order), at most ``limit`` (0: all)."""
    jobs = [(str(p), split, size, slots) for p in shard_paths(list(folders), split)]
    if workers > 1:
        with ProcessPoolExecutor(workers) as pool:
            shards = list(pool.map(_load_shard, jobs))
    else:
        shards = [_load_shard(job) for job in jobs]
    rows = [row for shard in shards for row in shard]
    return rows[:limit] if limit > 0 else rows


def evaluate(folder: Path, rows: list[tuple], batch: int = 64) -> tuple[dict, list[dict]]:
    """The packaged network's part scores on ``rows`` at rest (all rows when none is at rest)."""
    network = load_slots(folder)
    rest = [r for r in rows if r[5]] or rows
    scores = []
    for lo in range(0, len(rest), batch):
        chunk = rest[lo:lo + batch]
        images = np.stack([r[0] for r in chunk]).astype(np.float32) / 255.0
        for row, slots in zip(chunk, network.read(images)):
            predicted = [_bounds(s.centre, s.extent) for s in slots]
            scores.append(score_part_boxes(row[4], row[2], row[3], predicted, [s.kind for s in slots]))
    views = "rest" if any(r[5] for r in rows) else "all"
    return {**summarise(scores), "views": views}, [s.to_dict() for s in scores]


def main(argv: Sequence[str] | None = None) -> dict:
    p = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    p.add_argument("--train", nargs="+", required=True, help="record shard folders (or files) to train on")
    p.add_argument("--eval", nargs="+", required=True, help="record shard folders (or files) to score on")
    p.add_argument("--train-split", default="train", help="meta split of the training records")
    p.add_argument("--eval-split", default="test", help="meta split of the scored records (val or test)")
    p.add_argument("--out", default="runs/stage1_slots")
    p.add_argument("--steps", type=int, default=20000)
    p.add_argument("--batch", type=int, default=128)
    p.add_argument("--minutes", type=float, default=60.0, help="training stops after this many minutes")
    p.add_argument("--workers", type=int, default=1, help="processes decoding the records")
    p.add_argument("--lr", type=float, default=5e-4)
    p.add_argument("--slots", type=int, default=24, help="part slots K")
    p.add_argument("--image-size", type=int, default=128, help="image side the network reads")
    p.add_argument("--tiny", action="store_true", help="the CPU smoke-test network size")
    p.add_argument("--limit", type=int, default=0, help="records of each side to use (0: all)")
    p.add_argument("--log-every", type=int, default=100)
    p.add_argument("--seed", type=int, default=0)
    a = p.parse_args(argv)
    out = Path(a.out)
    out.mkdir(parents=True, exist_ok=True)
    config = (SlotsNetConfig.tiny(a.slots) if a.tiny else SlotsNetConfig(slots=a.slots, image_size=a.image_size))
    t = time.perf_counter()
    train_rows = load_records(a.train, a.train_split, config.image_size, config.slots, a.workers, a.limit)
    eval_rows = load_records(a.eval, a.eval_split, config.image_size, config.slots, a.workers, a.limit)
    if not train_rows or not eval_rows:
        raise SystemExit(f"no records: {len(train_rows)} of split {a.train_split!r} in --train, "
                         f"{len(eval_rows)} of split {a.eval_split!r} in --eval")
    data: SlotTargets = stack_targets([r[0] for r in train_rows], [r[1][:4] for r in train_rows])
    dropped = sum(r[1][4] for r in train_rows)
    print(f"[stage1_slots] {len(train_rows)} train and {len(eval_rows)} eval records loaded in "
          f"{time.perf_counter() - t:.0f} s ({dropped} train parts past {config.slots} slots dropped)", flush=True)

    model = SlotsNet(config, nnx.Rngs(a.seed))
    train_config = SlotsTrainConfig(steps=a.steps, batch=a.batch, lr=a.lr, time_limit_s=a.minutes * 60,
                                    log_every=a.log_every, seed=a.seed)
    if a.tiny:
        train_config = replace(train_config, warmup=min(train_config.warmup, max(a.steps // 10, 1)), shift=1)
    t = time.perf_counter()
    log = train(model, data, train_config, on_log=lambda row: print(f"[stage1_slots] {row}", flush=True))
    train_s = time.perf_counter() - t
    steps = log[-1]["step"]
    recipe = (f"python3 -m recipes.stage1_slots --train {' '.join(a.train)} --eval {' '.join(a.eval)} "
              f"--steps {a.steps} --batch {a.batch} --lr {a.lr} --slots {a.slots} --image-size {config.image_size}"
              f"{' --tiny' if a.tiny else ''} --seed {a.seed}")
    package = save_slots(out / "slots", model, notes={"recipe": recipe, "train_records": len(train_rows),
                                                      "steps": steps})
    metrics, rows = evaluate(package, eval_rows)
    with (out / "eval.jsonl").open("w", encoding="utf-8") as f:
        f.writelines(json.dumps(r, separators=(",", ":")) + "\n" for r in rows)
    summary = {"steps": steps, "train_seconds": round(train_s, 1), "steps_per_s": round(steps / max(train_s, 1e-9), 2),
               "train_records": len(train_rows), "eval_records": len(eval_rows), "kinds": list(KINDS),
               "first_loss": log[0]["loss"], "last_loss": log[-1]["loss"], "eval": metrics,
               "weights_bytes": (package / "model.safetensors").stat().st_size, "package": str(package)}
    (out / "summary.json").write_text(json.dumps({**summary, "args": vars(a), "train_log": log}, indent=1),
                                      encoding="utf-8")
    print(json.dumps(summary), flush=True)
    return summary


if __name__ == "__main__":
    main()
