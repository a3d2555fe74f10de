"""`jax3dc demo`: the README's main job, end to end on the embedded default, on a CPU.

Stages, each printing one line and where its outputs are:
  1. data       render procedural objects into ArrayRecord shards (split by object)
  2. reference  score the train split's own targets (a sanity run that must give 100)
  3. baselines  the no-training baselines on that split, scored with the paper's metrics
  4. export     one held-out object: structure, part meshes, URDF, MJCF, glTF, Blender script,
                with the MJCF and URDF loaded back in MuJoCo
  5. train      `jax3dc data tokenizer` (a 1k BPE of the shards), then `jax3dc train`: the `tiny`
                preset trained from scratch on the train split for a few minutes of CPU time,
                exported as an HF folder
  6. evaluate   `jax3dc eval run` of that model on held-out test records, next to the baselines
  7. predict    `jax3dc predict` on one held-out test image: its part meshes as stage 1, the
                trained model as stage 2, every output written that can be
A CPU run this short does not teach a model to write valid structures: the evaluate and predict
stages report what the model produced (usually parse 0 and a predict that stops at the
structure with its raw text kept), and the README says how to run the real fine-tune on GPUs.
Nothing is faked. summary.json lists every stage.
"""

from __future__ import annotations

import json
import time
from dataclasses import dataclass
from pathlib import Path

from jax3dc.errors import Jax3dcError


@dataclass(frozen=True)
class DemoSize:
    objects: int
    image: int


    train_minutes: float
    eval_records: int


SIZES = {"tiny": DemoSize(objects=40, image=48, train_minutes=0.2, eval_records=2),
         "default": DemoSize(objects=160, image=224, train_minutes=5.0, eval_records=8)}
TRAIN_IMAGE = 32  # the tiny preset's 4-pixel patches: 64 per image, 16 tokens


def _cli(argv: list[str]) -> None:
    from jax3dc.cli import main

    code = main(argv)
    if code != 0:
        raise Jax3dcError(f"demo stage `jax3dc {' '.join(argv[:2])}` failed with exit code {code}")


def _stage_export(out: Path, seed: int) -> dict:
    import mujoco

    from data_pipeline.factories import generate_object
    from jax3dc.export.blender import export_blender
    from jax3dc.export.gltf import export_gltf
    from jax3dc.export.mjcf import export_mjcf
    from jax3dc.export.urdf import export_urdf
    from jax3dc.geometry.parts import part_boxes, save_parts
    from jax3dc.structure import canonicalize, save_boxes, to_json

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


def _stage_predict(data: Path, out: Path, model: Path) -> dict:
    """Predict one held-out test image with its own part meshes as stage 1 and the trained model."""
    from data_pipeline.factories import generate_object
    from data_pipeline.shards import shard_paths
    from eval.generation import read_records
    from eval.predict.pipeline import predict
    from eval.predict.segmentation import camera_from_dict
    from jax3dc.geometry.parts import save_parts

    record = next(read_records(shard_paths([data], "test"), "test"))
    obj = generate_object(record.meta["category"], int(record.meta["seed"]))
    out.mkdir(parents=True, exist_ok=True)
    (out / "input.png").write_bytes(record.image_png)
    save_parts(obj.parts, out / "input_parts")
    try:
        result = predict(out / "input.png", f"parts:{out / 'input_parts'}", model, out=out / "asset",
                         camera=camera_from_dict(record.meta["camera"], "record camera"), max_new_tokens=512,
                         dtype="float32")
    except Jax3dcError as e:  # the short-trained model's output: keep what was written, say why
        written = sorted(p.name for p in (out / "asset").iterdir()) if (out / "asset").is_dir() else []
        return {"status": "partial", "out": str(out / "asset"), "reason": str(e), "key": record.key,
                "written": written}
    return {"status": "done", "out": str(out / "asset"), "key": record.key,
            "files": {k: str(v) for k, v in result.files.items()}}


def run_demo(out: Path, size: str = "default", seed: int = 0) -> dict:
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
    _cli(["data", "build", "--out", str(data), "--objects", str(spec.objects), "--views", "1",
          "--size", str(spec.image), "--seed", str(seed), "--quiet"])
    record("data", t, "done", out=str(data))

    t = time.perf_counter()
    reference = out / "reference"
    # The baselines need no training, so they are scored on the larger train split.
    _cli(["eval", "run", "--data", str(data), "--out", str(reference), "--reference-as-prediction",
          "--split", "train", "--overlays", "4"])
    ref_metrics = json.loads((reference / "metrics.json").read_text())
    record("reference", t, "done", out=str(reference), objects=ref_metrics["counts"]["objects"],
           metrics={k: ref_metrics.get(k) for k in ("parse", "parent_acc", "edge_f1", "presence_f1", "success")})

    t = time.perf_counter()
    baselines = out / "baselines"
    _cli(["eval", "baselines", "--ref", str(reference / "references.jsonl"), "--out", str(baselines)])
    table = {}
    for name in ("star", "heuristic"):
        m = json.loads((baselines / name / "metrics.json").read_text())
        table[name] = {k: m.get(k) for k in ("parse", "parent_acc", "edge_f1", "presence_f1", "success")}
    record("baselines", t, "done", out=str(baselines), metrics=table)

    t = time.perf_counter()
    record("export", t, "done", out=str(out / "asset"), **_stage_export(out / "asset", seed))

    t = time.perf_counter()
    train, tokenizer = out / "train", out / "tokenizer"
    # A 1k byte-level BPE of the shards: the tiny model's LM head shrinks from 151,680 rows to
    # 1,024, which is what makes CPU steps affordable (bench/tokenizer.py: 0.35x the FLOPs).
    _cli(["data", "tokenizer", "--data", str(data), "--vocab-size", "1024", "--out", str(tokenizer), "--quiet"])
    _cli(["train", "--init", "tiny", "--output-dir", str(train), "--steps", "400",
          *[x for o in (f"data={data}", f"tokenizer={tokenizer}", f"image_size={TRAIN_IMAGE}", "seq_len=2048", "batch_size=4", "grad_accum=1",
                        "pack=1", "lr=3e-3", "warmup_steps=5", f"time_limit_min={spec.train_minutes}", "freeze=",
                        "compute_dtype=float32", "remat=none", "log_every=5", "eval_every=1000", "eval_batches=1",
                        "save_every=1000") for x in ("--set", o)]])
    steps = [json.loads(line) for line in (train / "metrics.jsonl").read_text().splitlines()]
    last = [r for r in steps if r.get("kind") == "train"][-1]
    record("train", t, "done", out=str(train / "hf"), steps=last["step"], loss=round(last["loss"], 3),
           first_loss=round(steps[0]["loss"], 3))

    t = time.perf_counter()
    evaluation = out / "evaluate"
    _cli(["eval", "run", "--checkpoint", str(train / "hf"), "--data", str(data), "--split", "test", "--limit",
          str(spec.eval_records), "--batch-size", str(spec.eval_records), "--max-new-tokens", "256",
          "--dtype", "float32", "--out", str(evaluation), "--overlays", "0"])
    m = json.loads((evaluation / "metrics.json").read_text())
    record("evaluate", t, "done", out=str(evaluation),
           metrics={k: m.get(k) for k in ("parse", "parent_acc", "edge_f1", "presence_f1", "success")})

    t = time.perf_counter()
    record("predict", t, **_stage_predict(data, out / "predict", train / "hf"))

    summary = {"size": size, "seed": seed, "stages": stages}
    (out / "summary.json").write_text(json.dumps(summary, indent=1))
    print(f"[demo] summary: {out / 'summary.json'}", flush=True)
    return summary
