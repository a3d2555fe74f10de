"""The stage-1 image network's recipe on CPU (issue 49): build, train, package, score on test.

    nice -n 10 python3 -m recipes.stage1_net --out runs/stage1_net

  1. data      `jax3dc data build` per --objects count (build i: OUT/data-i, build seed i), one
               view, varied appearance, no scenes, no augmentation (records carry their parameter
               text); a complete build is kept
  2. train     jax3dc.stage1_net.Stage1Net on the train split (train.stage1_net: optax AdamW,
               shifted and brightness-jittered images), bounded by --steps and --minutes
  3. package   OUT/stage1 (stage1_net.json + float16 model.safetensors), its size printed
  4. evaluate  the packaged folder through `load_reader`'s path on the test split: every text
               runs through the factory and is scored by eval.metrics.parameters (texts that run,
               category, part count exact, parts matched one-to-one by box IoU, Chamfer), over all
               test records and per build; also the reader's seconds per image. With --compare
               FOLDER, that network (e.g. the shipped one) is scored on the same records in the same
               run, each at its own image size. OUT/summary.json holds the numbers, OUT/test.jsonl
               the per-object scores, and the last lines print the table.
With --release DIR the packaged folder is also copied there (e.g. jax3dc/release/stage1).
With --box-weight W the numbers also train on their error in the parts' boxes
(train.stage1_box_metric; metrics kept by parameter text in --box-cache, which --metrics-only fills
with --box-workers processes and then stops).
With --score FOLDER... nothing is built or trained: those network folders are scored on the test
split of --data, each at its own image size, and OUT/score.json holds their rows overall and per build.
"""

from __future__ import annotations

import argparse
import io
import json
import shutil
import time
from collections import defaultdict
from collections.abc import Sequence
from pathlib import Path

import numpy as np
from PIL import Image
from flax import nnx

from data_pipeline.shards import read_dataset
from eval.metrics.parameters import score_parameters, summarise
from eval.parameters_run import table
from jax3dc.factories.registry import SCHEMAS, run_parameters
from jax3dc.stage1_net import OutputLayout, Stage1Net, Stage1NetConfig, load_network, network_image, save_network
from train.stage1_box_metric import box_metrics
from recipes.steps import call
from train.stage1_net import TrainConfig, accuracy, targets, train


def load_split_images(folders: list[Path], size: int, only: str | None = None
                       ) -> dict[str, tuple[list[str], list[np.ndarray], list[str], list[int]]]:
    """split -> (keys, network images as uint8, parameter texts, build index) of the records that
    carry parameters (of split ``only`` when given)."""
    out: dict[str, tuple[list, list, list, list]] = defaultdict(lambda: ([], [], [], []))
    for build, folder in enumerate(folders):
        for record in read_dataset(folder):
            split = record.meta.get("split", "train")
            if not record.parameters or (only is not None and split != only):
                continue
            rgb = np.asarray(Image.open(io.BytesIO(record.image_png)).convert("RGB"))
            keys, images, texts, builds = out[split]
            keys.append(record.key)
            images.append((network_image(rgb, size) * 255.0 + 0.5).astype(np.uint8))
            texts.append(record.parameters)
            builds.append(build)
    return dict(out)


def _score(network, keys: list[str], images: list[np.ndarray], texts: list[str], batch: int = 64
           ) -> tuple[list, list[str], float]:
    """Scores, predicted texts and reader seconds per image of ``network`` on the given records."""
    t = time.perf_counter()
    predicted = [text for lo in range(0, len(keys), batch)
                 for text in network.read(np.asarray(images[lo:lo + batch], np.float32) / 255.0)]
    read_s = (time.perf_counter() - t) / max(len(keys), 1)
    scores = [score_parameters(k, ref, text, SCHEMAS, run_parameters) for k, ref, text in zip(keys, texts, predicted)]
    return scores, predicted, read_s


def _per_build(scores: list, builds: list[int], folders: list[Path]) -> dict[str, dict]:
    """Table rows of ``scores`` per build folder (``builds[i]`` indexes ``folders``)."""
    return {str(folders[b]): summarise([s for s, sb in zip(scores, builds) if sb == b]) for b in sorted(set(builds))}


def _per_category(scores: list) -> dict[str, dict]:
    groups: dict[str, list] = defaultdict(list)
    for score in scores:
        groups[score.key.split("/")[0]].append(score)
    return {c: summarise(v) for c, v in sorted(groups.items())}


def score_folders(networks: list[str], folders: list[Path], out: Path) -> dict:
    """Each network folder scored on the test records of ``folders`` (overall and per build)."""
    rows, cache = {}, {}
    for folder in networks:
        network = load_network(folder)
        size = network.model.config.image_size
        if size not in cache:
            cache[size] = load_split_images(folders, size, only="test")["test"]
        keys, images, texts, builds = cache[size]
        scores, _, read_s = _score(network, keys, images, texts)
        rows[folder] = {"test": summarise(scores), "reader_seconds_per_image": round(read_s, 4),
                        "per_build": _per_build(scores, builds, folders), "per_category": _per_category(scores)}
        print(table(folder, rows[folder]["test"]).splitlines()[-1], flush=True)
    (out / "score.json").write_text(json.dumps(rows, indent=1), encoding="utf-8")
    return rows


def main(argv: Sequence[str] | None = None) -> None:
    p = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    p.add_argument("--out", default="runs/stage1_net")
    p.add_argument("--data", nargs="+", default=[], help="built datasets to use instead of building OUT/data")
    p.add_argument("--objects", type=int, nargs="+", default=[4000, 7000],
                   help="objects per build; build i (OUT/data-i) uses build seed i, so builds share no object")
    p.add_argument("--render-size", type=int, default=128, help="image side of the build")
    p.add_argument("--workers", type=int, default=1)
    p.add_argument("--image-size", type=int, default=96, help="image side the network reads")
    p.add_argument("--widths", type=int, nargs="+", default=[32, 48, 96, 128], help="channels of the residual blocks")
    p.add_argument("--hidden", type=int, default=192, help="width of the layer the heads read")
    p.add_argument("--blocks", type=int, default=1, help="residual blocks per width")
    p.add_argument("--compare", default="", help="a network folder to score on the same test records")
    p.add_argument("--score", nargs="+", default=[], help="only score these network folders on --data's test split")
    p.add_argument("--init", default="", help="start from this network folder's weights (fine-tuning); its "
                   "config replaces --image-size, --widths, --blocks and --hidden")
    p.add_argument("--steps", type=int, default=3000)
    p.add_argument("--minutes", type=float, default=10.0, help="training stops after this many minutes")
    p.add_argument("--batch", type=int, default=64)
    p.add_argument("--lr", type=float, default=2e-3)
    p.add_argument("--number-weight", type=float, default=4.0, help="weight of the numbers' smooth-L1 loss")
    p.add_argument("--discrete-weight", type=float, default=1.0, help="weight of the discrete values' cross-entropy")
    p.add_argument("--box-weight", type=float, default=0.0, help="weight of the numbers' box-metric loss "
                   "(train.stage1_box_metric; 0: off)")
    p.add_argument("--box-cache", default="", help="JSON-lines cache of box metrics by parameter text")
    p.add_argument("--box-workers", type=int, default=1, help="processes computing box metrics")
    p.add_argument("--metrics-only", action="store_true", help="only fill --box-cache with the train split's "
                   "box metrics (no images decoded, nothing trained)")
    p.add_argument("--eval-limit", type=int, default=0, help="test objects to score (0: all)")
    p.add_argument("--seed", type=int, default=0)
    p.add_argument("--release", default="", help="also copy the packaged folder here")
    a = p.parse_args(argv)
    out = Path(a.out)
    out.mkdir(parents=True, exist_ok=True)
    folders = [Path(d) for d in a.data] or [out / f"data-{seed}" for seed in range(len(a.objects))]
    if a.score:
        score_folders(a.score, folders, out)
        return
    for seed, (folder, objects) in enumerate(zip(folders, a.objects if not a.data else [])):
        manifest = folder / "manifest.json"
        if not (manifest.exists() and json.loads(manifest.read_text()).get("complete")):
            call(["data", "build", "--out", str(folder), "--objects", str(objects), "--seed", str(seed), "--scenes", "0",
                   "--views", "1", "--size", str(a.render_size), "--workers", str(a.workers), "--appearance", "varied",
                   "--quiet"])

    layout = OutputLayout.of(SCHEMAS)
    width = max(sum(1 for s in layout.numbers if s.category == c) for c in layout.categories)
    if a.metrics_only:
        if not a.box_cache:
            raise SystemExit("--metrics-only needs --box-cache")
        t = time.perf_counter()
        texts = [r.parameters for f in folders for r in read_dataset(f)
                 if r.parameters and r.meta.get("split", "train") == "train"]
        box_metrics(texts, layout, SCHEMAS, width, workers=a.box_workers, cache=Path(a.box_cache))
        print(f"[stage1_net] box metrics of {len(set(texts))} train objects in {time.perf_counter() - t:.0f} s")
        return
    start = load_network(a.init) if a.init else None
    if start is not None:
        if start.schemas != SCHEMAS:
            raise SystemExit(f"--init {a.init}: its schemas are not the factories' (a network of another version)")
        c = start.model.config
        a.image_size, a.widths, a.blocks, a.hidden = c.image_size, list(c.widths), c.blocks, c.hidden
    t = time.perf_counter()
    splits = load_split_images(folders, a.image_size)
    box = {}
    if a.box_weight > 0:  # the loss reads metrics of the train split only
        texts = splits["train"][2]
        box["train"] = box_metrics(texts, layout, SCHEMAS, width, workers=a.box_workers,
                                   cache=Path(a.box_cache) if a.box_cache else None)
        print(f"[stage1_net] box metrics of {len(set(texts))} train objects in {time.perf_counter() - t:.0f} s", flush=True)
    sets = {name: targets(images, texts, layout, SCHEMAS, box.get(name))
            for name, (_, images, texts, _) in splits.items()}
    print(f"[stage1_net] records: {({k: len(v) for k, v in sets.items()})} loaded in {time.perf_counter() - t:.0f} s",
          flush=True)

    model = start.model if start is not None else Stage1Net(
        Stage1NetConfig.for_layout(layout, image_size=a.image_size, widths=tuple(a.widths), hidden=a.hidden,
                                   blocks=a.blocks), nnx.Rngs(a.seed))
    config = TrainConfig(steps=a.steps, batch=a.batch, lr=a.lr, time_limit_s=a.minutes * 60, seed=a.seed,
                         number_weight=a.number_weight, box_weight=a.box_weight,
                         discrete_weight=a.discrete_weight)
    t = time.perf_counter()
    log = train(model, sets["train"], layout, config, on_log=lambda row: print(f"[stage1_net] {row}", flush=True))
    train_s = time.perf_counter() - t
    held_out = {name: accuracy(model, sets[name], layout) for name in ("val", "test") if name in sets}
    print(f"[stage1_net] trained {log[-1]['step']} steps in {train_s:.0f} s; held out: {held_out}", flush=True)

    package = out / "stage1"
    source = f"--data {' '.join(a.data)}" if a.data else f"--objects {' '.join(map(str, a.objects))}"
    recipe = (f"python3 -m recipes.stage1_net {source}{f' --init {a.init}' if a.init else ''} --image-size {a.image_size} "
              f"--widths {' '.join(map(str, a.widths))} --blocks {a.blocks} --hidden {a.hidden} --batch {a.batch} "
              f"--lr {a.lr} --steps {a.steps} --minutes {a.minutes} --seed {a.seed} --number-weight {a.number_weight} "
              f"--box-weight {a.box_weight} --discrete-weight {a.discrete_weight}")
    save_network(package, model, SCHEMAS, notes={"recipe": recipe, "train_records": len(sets["train"]),
                                                 "steps": log[-1]["step"]})
    weights = (package / "model.safetensors").stat().st_size
    print(f"[stage1_net] packaged {package}: weights {weights / 2**20:.2f} MiB", flush=True)

    network = load_network(package)  # score what ships (float16 weights), not the training copy
    keys, images, texts, builds = splits["test"]
    n = len(keys) if a.eval_limit <= 0 else min(a.eval_limit, len(keys))
    t = time.perf_counter()
    scores, predicted, read_s = _score(network, keys[:n], images[:n], texts[:n])
    score_s = time.perf_counter() - t
    metrics = summarise(scores)
    per_build = _per_build(scores, builds[:n], folders)
    compared = {}
    if a.compare:
        other = load_network(a.compare)
        size = other.model.config.image_size
        own = load_split_images(folders, size, only="test")["test"] if size != a.image_size else splits["test"]
        index = {k: i for i, k in enumerate(own[0])}
        chosen = [index[k] for k in keys[:n]]
        other_scores, _, _ = _score(other, keys[:n], [own[1][i] for i in chosen], texts[:n])
        compared = {"folder": a.compare, "test": summarise(other_scores),
                    "per_build": _per_build(other_scores, builds[:n], folders)}
    with (out / "test.jsonl").open("w", encoding="utf-8") as f:
        for s, text, ref in zip(scores, predicted, texts):
            f.write(json.dumps({**s.to_dict(), "predicted": text, "reference": ref}, separators=(",", ":")) + "\n")
    summary = {"args": vars(a), "records": {k: len(v) for k, v in sets.items()}, "train_seconds": round(train_s, 1),
               "train_log": log, "held_out": held_out, "weights_bytes": weights,
               "reader_seconds_per_image": round(read_s, 4), "scoring_seconds": round(score_s, 1), "test": metrics,
               "test_per_build": per_build, "compared": compared,
               "test_per_category": _per_category(scores)}
    (out / "summary.json").write_text(json.dumps(summary, indent=1), encoding="utf-8")
    if a.release:
        shutil.copytree(package, a.release, dirs_exist_ok=True)
        print(f"[stage1_net] copied to {a.release}", flush=True)
    print(f"[stage1_net] reader {read_s * 1000:.1f} ms/image; wrote {out / 'summary.json'}")
    print("\n## stage-1 image network, procedural test split\n" + table("stage1_net", metrics), flush=True)
    if compared:
        print(table(Path(a.compare).name, compared["test"]).splitlines()[-1], flush=True)


if __name__ == "__main__":
    main()
