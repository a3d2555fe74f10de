"""A factory object, its rendered image and its parts written as a GLB and as an OBJ with groups."""

from __future__ import annotations

import os
from functools import lru_cache
from pathlib import Path

os.environ.setdefault("MUJOCO_GL", "egl")

import numpy as np  # noqa: E402
import trimesh  # noqa: E402

from jax3dc.factories import generate_object  # noqa: E402
from jax3dc.render import Camera, Lighting, PartRenderer, paint_segmentation, png_bytes  # noqa: E402
from jax3dc.geometry.parts import part_boxes  # noqa: E402
from jax3dc.structure import canonicalize, to_json  # noqa: E402

SIZE = 96
CAMERA = Camera(lookat=(0.0, 0.0, 0.0), distance=2.4, azimuth=100.0, elevation=-20.0)
CATEGORY, SEED = "cabinet", 0


@lru_cache(maxsize=None)
def factory_object():
    return generate_object(CATEGORY, SEED)


def target_json() -> str:
    """The object's own canonical target, standing in for a perfect structure model."""
    obj = factory_object()
    return to_json(canonicalize(obj.structure, part_boxes(obj.parts)))


def direct_render(palette: np.ndarray, size: int = SIZE) -> tuple[np.ndarray, np.ndarray]:
    """(RGB, S) of the factory parts rendered straight from the dataset renderer."""
    obj = factory_object()
    light = Lighting(ambient=0.3, headlight=0.5, key_dir=(0.3, 0.4, -0.8), key_strength=0.4)
    renderer = PartRenderer(obj.parts, {pid: (0.6, 0.5, 0.4, 1.0) for pid in obj.parts}, light, size)
    try:
        rgb, ids = renderer.render({}, CAMERA)
    finally:
        renderer.close()
    return rgb, paint_segmentation(ids, palette)


def write_image(path: Path) -> Path:
    from jax3dc.palette import object_palette

    rgb, _ = direct_render(object_palette(CATEGORY, "x"))
    path.write_bytes(png_bytes(rgb))
    return path


def write_glb(path: Path, names: dict[int, str] | None = None) -> Path:
    """One node per part, named by part id (or by ``names``)."""
    scene = trimesh.Scene()
    for pid, mesh in factory_object().parts.items():
        name = (names or {}).get(pid, str(pid))
        scene.add_geometry(mesh, node_name=name, geom_name=f"mesh_{name}")
    scene.export(str(path))
    return path


def write_obj_groups(path: Path) -> Path:
    """One ``g <id>`` group per part, parts in reverse id order (ids come from the names)."""
    lines, offset = ["# parts as groups"], 0
    for pid, mesh in sorted(factory_object().parts.items(), reverse=True):
        lines.append(f"g {pid}")
        lines += ["v %.9g %.9g %.9g" % tuple(v) for v in np.asarray(mesh.vertices)]
        lines += ["f %d %d %d" % tuple(f + 1 + offset) for f in np.asarray(mesh.faces)]
        offset += len(mesh.vertices)
    path.write_text("\n".join(lines) + "\n")
    return path
