"""`jax3dc demo`: the README's main job, end to end on a CPU, with the shipped model.

Stages, each printing one line and where its outputs are:
  1. data       render procedural objects into ArrayRecord shards (split by object; the test
                split's objects were never seen by the shipped model)
  2. reference  score the train split's own targets (a sanity run that must give 100)
  3. export     one held-out object: structure, part meshes, URDF, MJCF, glTF, Blender script,
                with the MJCF and URDF loaded back in MuJoCo
  4. evaluate   `jax3dc eval run` with the shipped model (jax3dc/release) on held-out test records
  5. baselines  the no-training baselines on the same references; Table 1 of all of them
  6. predict    `jax3dc predict` on held-out test images, twice each: with their own part meshes as
                stage 1, and from the image alone (the shipped stage-1 network, jax3dc/release/stage1),
                the shipped model as stage 2, then the exports and the physics verdict; Table 1 of
                both on those images (from pixels scored by parts matched by box overlap: eval.pixels)
  7. train      only with --train-minutes > 0: `jax3dc data tokenizer` and the `tiny` preset
                trained from scratch on the train split for that many CPU minutes (a few minutes
                of CPU teach it nothing useful; GPUs train the real thing: recipes/release_model.py)
summary.json lists every stage.
"""

from __future__ import annotations

import argparse
import itertools
import json
import time
from dataclasses import dataclass
from pathlib import Path
from typing import Callable

import mujoco

from data_pipeline import tokenizer_cli
from data_pipeline.build import BuildConfig, factory_sources, run_build
from data_pipeline.shards import shard_paths
from eval import cli as eval_cli
from eval.metrics.cases import build_cases
from eval.metrics.score import evaluate
from eval.pixels import PixelsResult, predict_record, score_pixels
from eval.records import read_records, reference_of
from jax3dc.decoding import Decoding
from jax3dc.errors import Jax3dcError
from jax3dc.export.blender import export_blender
from jax3dc.export.gltf import export_gltf
from jax3dc.export.mjcf import export_mjcf
from jax3dc.export.urdf import export_urdf
from jax3dc.factories import generate_object
from jax3dc.factories.registry import SCHEMAS, run_parameters
from jax3dc.geometry.parts import part_boxes, save_parts
from jax3dc.parameters import parse_parameters
from jax3dc.predict.pipeline import Checkpoints, PredictConfig, predict
from jax3dc.predict.segmentation import camera_from_dict
from jax3dc.predict.stage1 import ReaderSettings, Stage1Config, load_reader
from jax3dc.release import default_stage1_model, default_structure_model
from jax3dc.structure import canonicalize, save_boxes, to_dict, to_json
from train import cli as train_cli


@dataclass(frozen=True)
class DemoSize:
    objects: int
    eval_records: int
    predict_images: int


SIZES = {"tiny": DemoSize(objects=120, eval_records=4, predict_images=1),
         "default": DemoSize(objects=400, eval_records=16, predict_images=2)}
IMAGE = 224  # the shipped model's training renders
COLUMNS = ("parse", "parent_acc", "edge_f1", "presence_f1", "type_acc", "axis_acc", "pos_err", "range_iou",
           "success", "sym_f1", "inst_f1")
PAPER = {"parse": 99.0, "parent_acc": 85.6, "edge_f1": 85.4, "presence_f1": 90.8, "type_acc": 96.3, "axis_acc": 89.5,
         "pos_err": 0.052, "range_iou": 71.3, "success": 82.4, "sym_f1": 54.2, "inst_f1": 19.4}
TRAIN_IMAGE = 32  # the tiny preset's 4-pixel patches: 64 per image, 16 tokens


def _command(register: Callable[[argparse._SubParsersAction], None], argv: list[str]) -> None:
    """Runs one command's function with the arguments its own parser makes of ``argv`` (its
    defaults and checks), not through ``jax3dc.cli``: the demo is one of that CLI's commands."""
    parser = argparse.ArgumentParser(prog="jax3dc")
    register(parser.add_subparsers())
    args = parser.parse_args(argv)
    code = args.func(args)
    if code:
        raise Jax3dcError(f"demo stage `jax3dc {' '.join(argv[:2])}` failed with exit code {code}")


def _stage_export(out: Path, seed: int) -> dict:
    obj = generate_object("cabinet", seed)
    structure = canonicalize(obj.structure, part_boxes(obj.parts))
    out.mkdir(parents=True, exist_ok=True)
    (out / "structure.json").write_text(to_json(structure))
    save_parts(obj.parts, out / "parts")
    save_boxes(part_boxes(obj.parts), out / "boxes.json")
    files = {
        "structure": out / "structure.json",
        "mjcf": export_mjcf(structure, obj.parts, out / "mjcf", obj.scale_m_per_nu),
        "urdf": export_urdf(structure, obj.parts, out / "urdf", obj.scale_m_per_nu),
        "gltf": export_gltf(structure, obj.parts, out / "gltf", obj.scale_m_per_nu),
        "blender": export_blender(structure, obj.parts, out / "blender", obj.scale_m_per_nu),
    }
    joints = {fmt: mujoco.MjModel.from_xml_path(str(files[fmt])).njnt for fmt in ("mjcf", "urdf")}
    return {"object": obj.object_id, "joints_in_structure": len(structure.joints()),
            "joints_loaded_in_mujoco": joints, "files": {k: str(v) for k, v in files.items()}}


def _predict_one(record, joints: int, out: Path, checkpoints: Checkpoints) -> tuple[dict, dict | None]:
    """Predict one held-out test image with its own part meshes (the factory's, from the record's
    parameters) as stage 1 and the shipped model, told its ``joints`` as the record's prompt does:
    the summary entry and the structure (None when predict failed)."""
    obj = run_parameters(parse_parameters(record.parameters, SCHEMAS))
    out.mkdir(parents=True, exist_ok=True)
    (out / "input.png").write_bytes(record.image_png)
    save_parts(obj.parts, out / "input_parts")
    try:
        config = PredictConfig(Stage1Config(f"parts:{out / 'input_parts'}"), default_structure_model(),
                               decoding=Decoding(max_new_tokens=1024),
                               camera=camera_from_dict(record.meta["camera"], "record camera"),
                               num_joints=joints or None)
        result = predict(out / "input.png", config, out / "asset", checkpoints=checkpoints)
    except Jax3dcError as e:  # keep what was written, say why
        written = sorted(p.name for p in (out / "asset").iterdir()) if (out / "asset").is_dir() else []
        return {"key": record.key, "status": "partial", "out": str(out / "asset"), "reason": str(e),
                "written": written}, None
    return {"key": record.key, "status": "done", "out": str(out / "asset"), "joints": len(result.structure.joints()),
            "physics_ok": result.verdict.ok if result.verdict else None,
            "files": {k: str(v) for k, v in result.files.items()}}, to_dict(result.structure)


def _pixels_entry(result: PixelsResult, out: Path) -> dict:
    stage1 = result.stage1
    return {"key": result.key, "status": "partial" if result.failure else "done", "out": str(out),
            "reason": result.failure, "seconds": round(result.seconds, 1), "physics_ok": result.physics_ok,
            "parts_matched": result.matched, "parts_extra": result.extra, "parts_missing": result.missing,
            "category_right": stage1.category if stage1 else None,
            "matched_iou": round(100 * stage1.matched_iou, 1) if stage1 else None}


def _stage_predict(data: Path, out: Path, count: int) -> dict:
    records = list(itertools.islice(read_records(shard_paths([data], "test"), "test"), count))
    if not records:
        raise Jax3dcError(f"demo: no test records in {data} to predict")
    stage1_model = default_stage1_model()
    if stage1_model is None:
        raise Jax3dcError("demo: no stage-1 model ships with this install (jax3dc/release/stage1)")
    checkpoints = Checkpoints("float32")  # one structure model for both runs of every image
    reader = load_reader(stage1_model, ReaderSettings(checkpoints.get, 1024, True))
    references = [reference_of(r) for r in records]
    own, structures, pixels = [], {}, []
    for k, (record, reference) in enumerate(zip(records, references)):
        entry, structure = _predict_one(record, len(reference.structure.joints()), out / f"object_{k}", checkpoints)
        own.append(entry)
        if structure is not None:
            structures[record.key] = structure
        pixels.append(predict_record(record, reference, out / f"object_{k}" / "pixels",
                                     Stage1Config(read_parameters=reader), checkpoints))
    rows = {"own parts": evaluate(build_cases(references, structures)).metrics,
            "from pixels": score_pixels(references, pixels).metrics}
    status = "done" if all(e["status"] == "done" for e in own) and not any(p.failure for p in pixels) else "partial"
    return {"status": status, "out": str(out), "objects": own,
            "pixels": [_pixels_entry(p, out / f"object_{k}" / "pixels") for k, p in enumerate(pixels)],
            "metrics": {name: {c: m.get(c) for c in COLUMNS} for name, m in rows.items()}}


def _stage_train(data: Path, out: Path, minutes: float) -> dict:
    """The tiny preset from scratch on the CPU: shows the training path, teaches little."""
    train, tokenizer = out / "train", out / "tokenizer"
    # A 1k byte-level BPE of the shards: the tiny model's LM head shrinks from 151,680 rows to 1,024.
    _command(tokenizer_cli.register, ["tokenizer", "--data", str(data), "--vocab-size", "1024", "--out", str(tokenizer), "--quiet"])
    _command(train_cli.register, ["train", "--init", "tiny", "--output-dir", str(train), "--steps", "400",
          *[x for o in (f"data={data}", f"tokenizer={tokenizer}", f"image_size={TRAIN_IMAGE}", "seq_len=2048",
                        "batch_size=4", "grad_accum=1", "pack=1", "lr=3e-3", "warmup_steps=5",
                        f"time_limit_min={minutes}", "freeze=", "compute_dtype=float32", "remat=none", "log_every=5",
                        "eval_every=1000", "eval_batches=1", "save_every=1000") for x in ("--set", o)]])
    steps = [json.loads(line) for line in (train / "metrics.jsonl").read_text().splitlines()]
    last = [r for r in steps if r.get("kind") == "train"][-1]
    return {"out": str(train / "hf"), "steps": last["step"], "loss": round(last["loss"], 3),
            "first_loss": round(steps[0]["loss"], 3)}


def table_1(rows: dict[str, dict]) -> str:
    """Table 1 as text: one line per system, the paper's row last."""
    head = f"{'system':<12}" + "".join(f"{c:>12}" for c in COLUMNS)
    lines = [head]
    for name, m in {**rows, "paper (Ours)": PAPER}.items():
        cells = []
        for c in COLUMNS:
            v = m.get(c)
            cells.append(f"{'-':>12}" if v is None else f"{v:>12.3f}" if c == "pos_err" else f"{v:>12.1f}")
        lines.append(f"{name:<12}" + "".join(cells))
    return "\n".join(lines)


def run_demo(out: Path, size: str = "default", seed: int = 0, train_minutes: float = 0.0) -> dict:
    """Runs every stage into ``out`` and returns (and writes) the summary."""
    spec = SIZES[size]
    out.mkdir(parents=True, exist_ok=True)
    stages: list[dict] = []

    def record(name: str, started: float, status: str, **info) -> None:
        entry = {"stage": name, "status": status, "seconds": round(time.perf_counter() - started, 1), **info}
        stages.append(entry)
        where = info.get("out") or info.get("reason") or ""
        print(f"[demo] {name:<9} {status:<8} {entry['seconds']:>6.1f} s  {where}", flush=True)

    t = time.perf_counter()
    data = out / "data"
    config = BuildConfig(views=1, seed=seed, size=IMAGE, objects_per_shard=8, appearance="varied")
    run_build(data, factory_sources(spec.objects, seed), config, workers=2, progress=False)
    record("data", t, "done", out=str(data))

    t = time.perf_counter()
    reference = out / "reference"
    _command(eval_cli.register, ["eval", "run", "--data", str(data), "--out", str(reference), "--reference-as-prediction",
          "--split", "train", "--overlays", "4"])
    ref_metrics = json.loads((reference / "metrics.json").read_text())
    record("reference", t, "done", out=str(reference), objects=ref_metrics["counts"]["objects"],
           metrics={k: ref_metrics.get(k) for k in ("parse", "parent_acc", "edge_f1", "presence_f1", "success")})

    t = time.perf_counter()
    record("export", t, "done", out=str(out / "asset"), **_stage_export(out / "asset", seed))

    t = time.perf_counter()
    evaluation = out / "evaluate"
    _command(eval_cli.register, ["eval", "run", "--data", str(data), "--split", "test", "--limit", str(spec.eval_records),
          "--batch-size", "8", "--max-new-tokens", "1024", "--dtype", "float32", "--out", str(evaluation),
          "--overlays", "4"])
    m = json.loads((evaluation / "metrics.json").read_text())
    record("evaluate", t, "done", out=str(evaluation), objects=m["counts"]["objects"],
           metrics={k: m.get(k) for k in COLUMNS})

    t = time.perf_counter()
    baselines = out / "baselines"
    _command(eval_cli.register, ["eval", "baselines", "--ref", str(evaluation / "references.jsonl"), "--out", str(baselines)])
    rows = {"shipped": m}
    for name in ("heuristic", "star"):
        rows[name] = json.loads((baselines / name / "metrics.json").read_text())
    record("baselines", t, "done", out=str(baselines),
           metrics={name: {k: rows[name].get(k) for k in COLUMNS} for name in ("heuristic", "star")})

    t = time.perf_counter()
    predicted = _stage_predict(data, out / "predict", spec.predict_images)
    record("predict", t, **predicted)

    if train_minutes > 0:
        t = time.perf_counter()
        record("train", t, "done", **_stage_train(data, out, train_minutes))

    summary = {"size": size, "seed": seed, "stages": stages}
    (out / "summary.json").write_text(json.dumps(summary, indent=1))
    print(f"\nTable 1 on {m['counts']['objects']} held-out test records (%; pos_err in nu):\n" + table_1(rows),
          flush=True)
    print(f"\nTable 1 on the {len(predicted['objects'])} held-out images predicted end to end, stage 1 from the "
          f"image's own parts and from the image alone (%; pos_err in nu):\n" + table_1(predicted["metrics"]),
          flush=True)
    print(f"[demo] summary: {out / 'summary.json'}", flush=True)
    return summary
