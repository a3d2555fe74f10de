"""Re-render the image I of built records with Blender Cycles: an appearance-shifted test set.

Training images come from MuJoCo's rasteriser; a model that only works on that look is not
worth shipping. Here the records of a built split get a new I from a path tracer, from the same
camera and the same posed parts, with looks MuJoCo never drew: sun and area lights of other
colours, a lit world, Principled-BSDF materials (metal, coat, transmission, wood grain and
speckle textures), other background kinds and tone mapping. S, the prompt, the target and the
rest of the record are kept, so ``jax3dc eval run`` scores the new shards unchanged and the
score difference is the appearance shift alone.

bpy needs numpy < 2 and cannot share the project's environment: every random choice is made
here, and ``cycles_scene.py`` (beside this file) builds and renders the scenes in the Python
that has bpy (``JAX3DC_BLENDER_PYTHON``, else the repository's ``.venv-blender``). Cycles' alpha
is the object's coverage: the record's meta keeps its IoU with S's parts, a check that the two
renderers saw the object from the same camera.
"""

from __future__ import annotations

import colorsys
import json
import os
import subprocess
import tempfile
import time
from dataclasses import dataclass, replace
from pathlib import Path
from typing import Callable, Iterable, Mapping

import numpy as np
import trimesh
from PIL import Image

from data_pipeline.record import Record
from data_pipeline.record_parts import record_parts
from data_pipeline.samples import derived_rng
from data_pipeline.shards import finished, load_manifest, read_shard, save_manifest, shard_paths, write_shard
from jax3dc.errors import InputFileError, Jax3dcError, SetupError
from jax3dc.materials import MATERIALS
from jax3dc.palette import BACKGROUND_RGB
from jax3dc.render import png_array, png_bytes
from jax3dc.structure import Structure, parse_structure

RENDERER = "cycles"
SCENE_SCRIPT = Path(__file__).with_name("cycles_scene.py")
MIN_MASK_IOU = 0.8  # below this Cycles and S disagree about where the object is: a camera bug, not a look
BACKGROUNDS = ("studio", "stripes", "tiles", "blotches")


@dataclass(frozen=True)
class CyclesSettings:
    """Render cost: path-traced samples per pixel, OIDN denoising, CPU threads."""

    samples: int = 24
    denoise: bool = True
    threads: int = 2


def blender_python() -> str:
    """The Python with bpy: ``JAX3DC_BLENDER_PYTHON``, else ``.venv-blender`` of the checkout."""
    path = os.environ.get("JAX3DC_BLENDER_PYTHON", "")
    if not path:
        local = Path(__file__).resolve().parent.parent / ".venv-blender" / "bin" / "python"
        path = str(local) if local.is_file() else ""
    if not path or not os.path.isfile(path):
        raise SetupError(f"no Python with bpy (JAX3DC_BLENDER_PYTHON={path!r}): create one with "
                         "`python3 -m venv .venv-blender && .venv-blender/bin/pip install bpy==5.0.1` "
                         "in the repository, or export JAX3DC_BLENDER_PYTHON=/path/to/bin/python")
    return path


def camera_frame(camera: Mapping) -> dict:
    """Blender camera of a record's ``meta["camera"]`` (MuJoCo free camera: look-at point,
    distance, azimuth and elevation in degrees, vertical field of view, default 45).

    MuJoCo looks along f = (cos e cos a, cos e sin a, sin e) from ``lookat - distance * f`` with
    up (-sin e cos a, -sin e sin a, cos e); a Blender camera looks along its local -Z with +Y up,
    so its rotation's columns are right = f x up, up, -f."""
    a, e = np.deg2rad(float(camera["azimuth"])), np.deg2rad(float(camera["elevation"]))
    forward = np.array([np.cos(e) * np.cos(a), np.cos(e) * np.sin(a), np.sin(e)])
    up = np.array([-np.sin(e) * np.cos(a), -np.sin(e) * np.sin(a), np.cos(e)])
    location = np.asarray(camera["lookat"], dtype=np.float64) - float(camera["distance"]) * forward
    rotation = np.stack([np.cross(forward, up), up, -forward], axis=1)
    return {"location": location.tolist(), "rotation": rotation.tolist(), "fovy": float(camera.get("fovy", 45.0))}


def _hsv(rgb: Iterable[float], dh: float, s_scale: float, v_scale: float) -> list[float]:
    h, s, v = colorsys.rgb_to_hsv(*(min(max(float(c), 0.0), 1.0) for c in rgb))
    return list(colorsys.hsv_to_rgb((h + dh) % 1.0, min(s * s_scale, 1.0), min(v * v_scale, 1.0)))


def _srgb_to_linear(rgb: Iterable[float]) -> list[float]:
    """Blender colours are linear; the family colours are meant as display (sRGB) colours."""
    c = np.clip(np.asarray(list(rgb), dtype=np.float64), 0.0, 1.0)
    return np.where(c <= 0.04045, c / 12.92, ((c + 0.055) / 1.055) ** 2.4).tolist()


def _light_colour(rng: np.random.Generator) -> list[float]:
    """Warm to cool white, or one time in three a clearly coloured light."""
    if rng.uniform() < 0.33:
        return list(colorsys.hsv_to_rgb(rng.uniform(), rng.uniform(0.25, 0.6), 1.0))
    t = rng.uniform(-1.0, 1.0)
    c = np.array([1.0 + 0.25 * t, 1.0 + 0.05 * t, 1.0 - 0.3 * t])
    return (c / c.max()).tolist()


def sample_material(family: str, rng: np.random.Generator) -> dict:
    """A Principled-BSDF material for a material family: the family colour moved in hue, saturation
    and value (one material in five painted an unrelated colour), and the family's kind of
    roughness, metal, coat, transmission and texture."""
    if rng.uniform() < 0.2 and family not in ("Glass", "Metal"):
        colour = list(colorsys.hsv_to_rgb(rng.uniform(), rng.uniform(0.2, 0.8), rng.uniform(0.3, 0.9)))
    else:
        colour = _hsv(MATERIALS[family].rgba[:3], rng.uniform(-0.06, 0.06), rng.uniform(0.5, 1.6), rng.uniform(0.6, 1.2))
    spec = {"roughness": float(rng.uniform(0.3, 0.8)), "metallic": 0.0, "transmission": 0.0, "coat": 0.0}
    texture = None
    if family == "Metal":
        spec.update(roughness=float(rng.uniform(0.1, 0.5)), metallic=float(rng.uniform(0.7, 1.0)))
    elif family == "Wood":
        texture = "grain" if rng.uniform() < 0.7 else None
    elif family == "Glass":
        spec.update(roughness=float(rng.uniform(0.0, 0.15)), transmission=float(rng.uniform(0.6, 0.95)))
    elif family in ("Fabric", "Stone"):
        spec.update(roughness=float(rng.uniform(0.7, 1.0)))
        texture = "speckle" if rng.uniform() < 0.6 else None
    elif family in ("Plastic", "Ceramic"):
        spec.update(roughness=float(rng.uniform(0.05, 0.5)), coat=float(rng.uniform(0.0, 0.8)))
    elif family == "Rubber":
        spec.update(roughness=float(rng.uniform(0.7, 1.0)))
    else:
        spec.update(metallic=float(rng.uniform(0.0, 0.4)))
    spec["colour"] = _srgb_to_linear(colour)
    if texture:
        spec.update(texture=texture, scale=float(rng.uniform(3.0, 12.0)),
                    colour2=_srgb_to_linear(_hsv(colour, rng.uniform(-0.03, 0.03), 1.1, rng.uniform(0.45, 0.8))))
    return spec


def sample_lights(rng: np.random.Generator) -> list[dict]:
    """A sun from above at any azimuth and one or two area lights around the object, each with its
    own colour and strength."""
    az, el = rng.uniform(0.0, 2 * np.pi), rng.uniform(np.deg2rad(20.0), np.deg2rad(75.0))
    sun_dir = -np.array([np.cos(el) * np.cos(az), np.cos(el) * np.sin(az), np.sin(el)])
    lights = [{"type": "sun", "direction": sun_dir.tolist(), "colour": _light_colour(rng),
               "energy": float(rng.uniform(1.5, 5.0)), "angle": float(rng.uniform(0.5, 15.0))}]
    for _ in range(int(rng.integers(1, 3))):
        az, el = rng.uniform(0.0, 2 * np.pi), rng.uniform(np.deg2rad(-10.0), np.deg2rad(70.0))
        r = rng.uniform(2.0, 4.0)
        location = r * np.array([np.cos(el) * np.cos(az), np.cos(el) * np.sin(az), np.sin(el)])
        lights.append({"type": "area", "location": location.tolist(), "colour": _light_colour(rng),
                       "energy": float(rng.uniform(40.0, 250.0) * r * r / 9.0), "size": float(rng.uniform(0.5, 2.0))})
    return lights


def sample_look(structure: Structure, rng: np.random.Generator) -> dict:
    """Everything random about one Cycles view: per-material looks (each part a little off its
    material's), lights, world, tone mapping, exposure and the background."""
    by_material = {mid: sample_material(structure.materials[mid].family, rng) for mid in sorted(structure.materials)}
    parts = {}
    for pid, node in sorted(structure.nodes.items()):
        spec = dict(by_material[node.material])
        spec["colour"] = (np.clip(np.asarray(spec["colour"]) * rng.uniform(0.9, 1.1), 0.0, 1.0)).tolist()
        parts[pid] = spec
    world = {"colour": _srgb_to_linear(_hsv(_light_colour(rng), 0.0, 1.0, rng.uniform(0.6, 1.0))),
             "strength": float(rng.uniform(0.15, 0.7))}
    background = {"kind": str(rng.choice(BACKGROUNDS)), "seed": int(rng.integers(1 << 62))}
    return {"parts": parts, "lights": sample_lights(rng), "world": world,
            "view_transform": "AgX" if rng.uniform() < 0.4 else "Standard",
            "exposure": float(rng.uniform(-0.4, 0.4)), "background": background}


def _random_rgb(rng: np.random.Generator, value: tuple[float, float]) -> np.ndarray:
    return np.array(colorsys.hsv_to_rgb(rng.uniform(), rng.uniform(0.05, 0.6), rng.uniform(*value)))


def background_image(kind: str, seed: int, size: int) -> np.ndarray:
    """A float RGB [size, size, 3] backdrop of a kind MuJoCo's renders never have: ``studio`` (a
    wall above a floor at a random horizon), ``stripes`` (two colours at a random angle),
    ``tiles`` (a grid with grout lines) or ``blotches`` (smooth noise between three colours)."""
    rng = np.random.default_rng(seed)
    y, x = np.mgrid[0:size, 0:size] / float(size)
    a, b = _random_rgb(rng, (0.3, 0.95)), _random_rgb(rng, (0.15, 0.8))
    if kind == "studio":
        horizon = rng.uniform(0.45, 0.8)
        wall = a * (1.0 - 0.3 * y[..., None])
        floor = b * (0.7 + 0.3 * ((y - horizon) / (1.0 - horizon))[..., None])
        soft = np.clip((y - horizon) / 0.02, 0.0, 1.0)[..., None]
        return wall * (1 - soft) + floor * soft
    if kind == "stripes":
        angle, period = rng.uniform(0.0, np.pi), rng.uniform(0.05, 0.25)
        t = (x * np.cos(angle) + y * np.sin(angle)) / period
        return np.where((np.floor(t) % 2 == 0)[..., None], a, b)
    if kind == "tiles":
        cells = int(rng.integers(4, 12))
        u, v = (x * cells) % 1.0, (y * cells) % 1.0
        grout = ((u < 0.06) | (v < 0.06))[..., None]
        shade = rng.uniform(0.85, 1.15, size=(cells + 1, cells + 1))[(y * cells).astype(int), (x * cells).astype(int)]
        return np.where(grout, b, a * shade[..., None])
    if kind == "blotches":
        coarse = rng.uniform(size=(5, 5))
        grid = np.linspace(0, 4, size)
        i = np.clip(grid.astype(int), 0, 3)
        f = grid - i
        rows = coarse[i] * (1 - f)[:, None] + coarse[i + 1] * f[:, None]
        noise = rows[:, i] * (1 - f)[None, :] + rows[:, i + 1] * f[None, :]
        c = _random_rgb(rng, (0.2, 0.9))
        t = noise[..., None]
        return np.where(t < 0.5, a * (1 - 2 * t) + b * 2 * t, b * (2 - 2 * t) + c * (2 * t - 1))
    raise ValueError(f"background kind must be one of {', '.join(BACKGROUNDS)}, not {kind!r}")


def composite(rgba: np.ndarray, background: np.ndarray) -> np.ndarray:
    """uint8 RGB of a straight-alpha RGBA render over a float background."""
    alpha = rgba[..., 3:4].astype(np.float64) / 255.0
    out = rgba[..., :3].astype(np.float64) / 255.0 * alpha + background * (1.0 - alpha)
    return np.round(np.clip(out, 0.0, 1.0) * 255.0).astype(np.uint8)


def mask_iou(alpha: np.ndarray, seg_rgb: np.ndarray) -> float:
    """IoU of Cycles' object coverage (alpha ≥ 0.5) with S's part pixels (not the background)."""
    rendered = alpha >= 128
    parts = np.any(seg_rgb != np.asarray(BACKGROUND_RGB, dtype=seg_rgb.dtype), axis=-1)
    union = np.logical_or(rendered, parts).sum()
    return float(np.logical_and(rendered, parts).sum() / union) if union else 1.0


def _record_parts(record: Record, sources: Mapping[str, Path] | None) -> dict[int, trimesh.Trimesh]:
    """The record's part meshes posed as in its view, rebuilt by the code that built the record."""
    return record_parts(record, sources)[0]


def restyle_records(records: list[Record], settings: CyclesSettings = CyclesSettings(),
                    sources: Mapping[str, Path] | None = None) -> tuple[list[Record], list[float]]:
    """``records`` with I rendered by Cycles (one Blender process for the batch); returns the new
    records and the seconds each Cycles render took. The look of a record is drawn from its key
    and build seed only, so restyling the same records twice gives the same looks."""
    if not records:
        return [], []

    with tempfile.TemporaryDirectory(prefix="jax3dc_cycles_") as tmp:
        views, looks = [], []
        for i, record in enumerate(records):
            parts = _record_parts(record, sources)
            arrays = {}
            for pid, mesh in parts.items():
                arrays[f"v{pid}"] = np.asarray(mesh.vertices, dtype=np.float32)
                arrays[f"f{pid}"] = np.asarray(mesh.faces, dtype=np.int32)
            np.savez(Path(tmp) / f"{i}.npz", **arrays)
            look = sample_look(parse_structure(record.target),
                               derived_rng(record.meta.get("seed", 0), record.key, RENDERER))
            looks.append(look)
            views.append({"meshes": str(Path(tmp) / f"{i}.npz"), "png": str(Path(tmp) / f"{i}.png"),
                          "camera": camera_frame(record.meta["camera"]),
                          "parts": [{"id": pid, "material": look["parts"][pid]} for pid in sorted(parts)],
                          "lights": look["lights"], "world": look["world"],
                          "view_transform": look["view_transform"], "exposure": look["exposure"]})
        size = _record_size(records[0])
        job = {"samples": settings.samples, "denoise": settings.denoise, "threads": settings.threads,
               "size": size, "views": views, "timings": str(Path(tmp) / "timings.json")}
        (Path(tmp) / "job.json").write_text(json.dumps(job))
        run = subprocess.run([blender_python(), "-I", str(SCENE_SCRIPT), str(Path(tmp) / "job.json")],
                             capture_output=True, text=True)
        if run.returncode != 0:
            tail = " ".join((run.stderr or run.stdout).strip().splitlines()[-3:])
            raise Jax3dcError(f"Cycles render of {len(records)} records (first {records[0].key}) failed: {tail}")
        seconds = json.loads((Path(tmp) / "timings.json").read_text())
        out = []
        for i, (record, look) in enumerate(zip(records, looks)):
            rgba = _read_rgba(Path(tmp) / f"{i}.png")
            if rgba.shape[:2] != (size, size) or _record_size(record) != size:
                raise Jax3dcError(f"record {record.key}: Cycles image is {rgba.shape[1]}x{rgba.shape[0]}, "
                                  f"the batch renders {size} px: restyle records of one size together")
            seg = png_array(record.seg_png)
            iou = mask_iou(rgba[..., 3], seg)
            if iou < MIN_MASK_IOU:
                raise Jax3dcError(f"record {record.key}: the Cycles object mask overlaps S's parts with IoU "
                                  f"{iou:.3f} < {MIN_MASK_IOU}: camera or pose differs from the record's")
            background = background_image(look["background"]["kind"], look["background"]["seed"], size)
            meta = dict(record.meta, renderer=RENDERER, appearance=RENDERER,
                        cycles={"samples": settings.samples, "denoise": settings.denoise,
                                "background": look["background"]["kind"],
                                "view_transform": look["view_transform"], "mask_iou": round(iou, 4)})
            out.append(replace(record, image_png=png_bytes(composite(rgba, background)), meta=meta))
        return out, seconds


def _record_size(record: Record) -> int:
    return int(record.meta.get("size") or png_array(record.seg_png).shape[0])


def _read_rgba(path: Path) -> np.ndarray:
    with Image.open(path) as image:
        return np.asarray(image.convert("RGBA"))


def restyle_dataset(source: Path, out: Path, split: str = "test", limit: int = 0,
                    settings: CyclesSettings = CyclesSettings(), sources: Mapping[str, Path] | None = None,
                    on_batch: Callable[[int], None] | None = None) -> dict:
    """Write ``out``: the first ``limit`` (0: all) records of ``split`` in ``source``'s shards,
    each shard's records restyled into a shard of the same name. A finished shard of an earlier
    run with the same settings is kept (resume); returns the manifest, whose ``restyle`` entry
    holds the settings and the seconds per image."""
    if limit < 0:
        raise Jax3dcError(f"--limit must be >= 0, not {limit}")
    if load_manifest(source) is None:
        raise InputFileError(source, "no manifest.json: not a dataset written by `jax3dc data build`")
    if out.resolve() == source.resolve():
        raise InputFileError(out, "is the source dataset: write the restyled records to another folder")
    blender_python()  # no Blender, no work: say so before rebuilding any parts
    out.mkdir(parents=True, exist_ok=True)
    wanted = {"renderer": RENDERER, "source": str(source.resolve()), "split": split, "limit": limit,
              "samples": settings.samples, "denoise": settings.denoise}
    manifest = load_manifest(out) or {"shards": {}, "restyle": dict(wanted, seconds={}), "complete": False}
    if {k: manifest.get("restyle", {}).get(k) for k in wanted} != wanted:
        raise InputFileError(out, "holds a restyle with other settings or source; use a new --out directory")
    remaining = limit or None
    for path in shard_paths([source], split):
        if remaining is not None and remaining <= 0:
            break
        records = [r for r in read_shard(path) if split == "all" or r.meta.get("split") == split]
        if remaining is not None:
            records = records[:remaining]
            remaining -= len(records)
        if not records:
            continue
        name = path.name
        if not finished(out, manifest, name):
            start = time.perf_counter()
            restyled, seconds = restyle_records(records, settings, sources)
            count, sha = write_shard(out / name, restyled)
            manifest["shards"][name] = {"records": count, "sha256": sha, "split": split}
            manifest["restyle"]["seconds"][name] = {"render": round(sum(seconds), 3),
                                                    "wall": round(time.perf_counter() - start, 3)}
            save_manifest(out, manifest)
        if on_batch is not None:
            on_batch(len(records))
    manifest["complete"] = True
    save_manifest(out, manifest)
    return manifest


def seconds_per_image(manifest: dict) -> tuple[float, float]:
    """(Cycles render seconds, wall seconds including part rebuild and Blender start) per image."""
    records = sum(s["records"] for s in manifest["shards"].values())
    times = manifest["restyle"]["seconds"].values()
    if not records:
        return 0.0, 0.0
    return sum(t["render"] for t in times) / records, sum(t["wall"] for t in times) / records

