"""`jax3dc demo`: the README's main job, end to end on the embedded default, on a CPU.

Stages, each printing one line and where its outputs are:
  1. data       render procedural objects into ArrayRecord shards (split by object)
  2. reference  score the train split's own targets (a sanity run that must give 100)
  3. baselines  the no-training baselines on that split, scored with the paper's metrics
  4. export     one held-out object: structure, part meshes, URDF, MJCF, glTF, Blender script,
                with the MJCF and URDF loaded back in MuJoCo
  5. train      stage-2 fine-tuning: skipped until the grain loader turns shards into training
                batches (issue 5); the trainer itself runs today on synthetic batches only
  6. predict    image in, asset out: skipped until `jax3dc predict` exists (issue 9)
A skipped stage says so and why; nothing is faked. summary.json lists every stage.
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


SIZES = {"tiny": DemoSize(objects=40, image=48), "default": DemoSize(objects=160, image=224)}


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
    record("train", t, "skipped", reason="needs the grain loader from shards to training batches (issue 5)")
    record("predict", t, "skipped", reason="needs `jax3dc predict` (issue 9)")

    summary = {"size": size, "seed": seed, "stages": stages}
    (out / "summary.json").write_text(json.dumps(summary, indent=1))
    print(f"[demo] summary: {out / 'summary.json'}", flush=True)
    return summary
