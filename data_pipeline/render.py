"""Render the RGB image I and the flat-colour segmentation S of posed parts with MuJoCo.

Every part is a mocap body carrying one mesh geom, so a single compiled model serves all views
of an object: a view only moves mocap bodies (a joint perturbation is a rigid transform of a
subtree) and the free camera. S comes from MuJoCo's segmentation pass (geom ids, no shading),
mapped to part ids and painted with palette colours here, so it has no anti-aliasing: every
pixel is the background or exactly one part's palette colour.

The OpenGL backend is chosen by :func:`jax3dc.gl.configure_gl` before mujoco is imported.
"""

from __future__ import annotations

import io
import os
from dataclasses import dataclass

import numpy as np
import trimesh

from jax3dc.errors import SetupError
from jax3dc.gl import configure_gl
from jax3dc.materials import MATERIALS
from jax3dc.palette import BACKGROUND_RGB, part_colour
from jax3dc.structure import Structure

DEFAULT_SIZE = 448
PNG_COMPRESS_LEVEL = 6

configure_gl()
import mujoco  # noqa: E402  (after the GL backend is chosen)


@dataclass(frozen=True)
class Camera:
    """A free camera looking at ``lookat`` (nu); MuJoCo's azimuth/elevation in degrees."""

    lookat: tuple[float, float, float]
    distance: float
    azimuth: float
    elevation: float

    def to_dict(self) -> dict:
        return {"lookat": [round(v, 4) for v in self.lookat], "distance": round(self.distance, 4),
                "azimuth": round(self.azimuth, 3), "elevation": round(self.elevation, 3)}


@dataclass(frozen=True)
class Lighting:
    """Headlight strength and one directional key light (direction points from light to scene)."""

    ambient: float
    headlight: float
    key_dir: tuple[float, float, float]
    key_strength: float


def sample_camera(rng: np.random.Generator, centre: np.ndarray = np.zeros(3), radius: float = 0.87) -> Camera:
    """A camera in the front hemisphere (the object faces -Y, MuJoCo azimuth 90 looks along +Y),
    slightly above, far enough that a sphere of ``radius`` nu around ``centre`` fits the 45° view."""
    distance = radius / np.sin(np.deg2rad(22.5)) * rng.uniform(1.0, 1.15)
    return Camera(lookat=tuple(float(v) for v in centre), distance=float(distance),
                  azimuth=float(rng.uniform(90.0 - 55.0, 90.0 + 55.0)),
                  elevation=float(rng.uniform(-40.0, -8.0)))


def sample_lighting(rng: np.random.Generator) -> Lighting:
    az, el = rng.uniform(0.0, 2 * np.pi), rng.uniform(np.deg2rad(30.0), np.deg2rad(75.0))
    key = -np.array([np.cos(el) * np.cos(az), np.cos(el) * np.sin(az), np.sin(el)])
    return Lighting(ambient=float(rng.uniform(0.2, 0.4)), headlight=float(rng.uniform(0.3, 0.6)),
                    key_dir=tuple(float(v) for v in key), key_strength=float(rng.uniform(0.3, 0.6)))


def part_rgba(structure: Structure, rng: np.random.Generator) -> dict[int, tuple[float, float, float, float]]:
    """Each part's colour in I: its material family's colour, jittered per material."""
    jitter = {mid: rng.uniform(-0.08, 0.08, size=3) for mid in sorted(structure.materials)}
    out = {}
    for pid, node in sorted(structure.nodes.items()):
        family = structure.materials[node.material].family
        r, g, b, a = MATERIALS[family].rgba
        rgb = np.clip(np.array([r, g, b]) + jitter[node.material], 0.0, 1.0)
        out[pid] = (float(rgb[0]), float(rgb[1]), float(rgb[2]), float(a))
    return out


def _numbers(values: np.ndarray, fmt: str) -> str:
    return " ".join(fmt % v for v in np.asarray(values).ravel())


def scene_xml(parts: dict[int, trimesh.Trimesh], rgba: dict[int, tuple[float, ...]],
              lighting: Lighting, size: int) -> str:
    """MJCF with one mocap body + mesh geom per part (vertices in nu, identity pose at rest)."""
    assets, bodies = [], []
    for pid in sorted(parts):
        mesh = parts[pid]
        assets.append(f'<mesh name="m{pid}" inertia="shell" vertex="{_numbers(mesh.vertices, "%.6f")}" '
                      f'face="{_numbers(mesh.faces, "%d")}"/>')
        colour = _numbers(np.array(rgba[pid]), "%.4f")
        bodies.append(f'<body name="p{pid}" mocap="true"><geom name="g{pid}" type="mesh" mesh="m{pid}" '
                      f'rgba="{colour}" contype="0" conaffinity="0" group="0"/></body>')
    key = _numbers(np.array(lighting.key_dir), "%.4f")
    s = lighting.key_strength
    return (f'<mujoco model="jax3dc_view"><visual><global offwidth="{size}" offheight="{size}"/>'
            f'<quality shadowsize="0"/>'
            f'<headlight ambient="{lighting.ambient:.4f} {lighting.ambient:.4f} {lighting.ambient:.4f}" '
            f'diffuse="{lighting.headlight:.4f} {lighting.headlight:.4f} {lighting.headlight:.4f}" specular="0.1 0.1 0.1"/>'
            f'</visual><asset>{"".join(assets)}</asset><worldbody>'
            f'<light directional="true" castshadow="false" dir="{key}" diffuse="{s:.4f} {s:.4f} {s:.4f}"/>'
            f'{"".join(bodies)}</worldbody></mujoco>')


def offscreen_renderer(model: mujoco.MjModel, height: int, width: int) -> mujoco.Renderer:
    """``mujoco.Renderer``, or a SetupError that names the OpenGL backend tried and what to install
    (MuJoCo's own message for a missing context speaks of mjr_makeContext, not of the machine)."""
    try:
        return mujoco.Renderer(model, height, width)
    except (mujoco.FatalError, RuntimeError, ImportError) as error:
        backend = os.environ.get("MUJOCO_GL", "glfw (MuJoCo's default; MUJOCO_GL unset)")
        raise SetupError(
            f"cannot render: no OpenGL context with MUJOCO_GL={backend} ({error}). Without a display, install "
            "Mesa's EGL or OSMesa (bash scripts/setup.sh installs libegl1 libegl-mesa0 libosmesa6 libgl1-mesa-dri) or set MUJOCO_GL "
            "to a backend this machine has") from None


class PartRenderer:
    """One compiled scene of parts and its renderer; render any pose of the parts from any camera."""

    def __init__(self, parts: dict[int, trimesh.Trimesh], rgba: dict[int, tuple[float, ...]],
                 lighting: Lighting, size: int = DEFAULT_SIZE):
        self.size = size
        self.model = mujoco.MjModel.from_xml_string(scene_xml(parts, rgba, lighting, size))
        self.data = mujoco.MjData(self.model)
        self.part_of_geom = np.full(self.model.ngeom + 1, 0, dtype=np.int64)  # last slot: background
        self.mocap_of_part = {}
        for pid in parts:
            self.part_of_geom[mujoco.mj_name2id(self.model, mujoco.mjtObj.mjOBJ_GEOM, f"g{pid}")] = pid
            body = mujoco.mj_name2id(self.model, mujoco.mjtObj.mjOBJ_BODY, f"p{pid}")
            self.mocap_of_part[pid] = int(self.model.body_mocapid[body])
        self.renderer = offscreen_renderer(self.model, size, size)

    def close(self) -> None:
        self.renderer.close()

    def render(self, poses: dict[int, np.ndarray], camera: Camera) -> tuple[np.ndarray, np.ndarray]:
        """RGB uint8 [H,W,3] and part-id int [H,W] (0 = background) for parts posed by 4x4 ``poses``
        (missing parts stay at rest)."""
        self.data.mocap_pos[:] = 0.0
        self.data.mocap_quat[:] = (1.0, 0.0, 0.0, 0.0)
        for pid, pose in poses.items():
            m = self.mocap_of_part[pid]
            self.data.mocap_pos[m] = pose[:3, 3]
            quat = np.zeros(4)
            mujoco.mju_mat2Quat(quat, np.ascontiguousarray(pose[:3, :3]).ravel())
            self.data.mocap_quat[m] = quat
        mujoco.mj_forward(self.model, self.data)
        cam = mujoco.MjvCamera()
        cam.type = mujoco.mjtCamera.mjCAMERA_FREE
        cam.lookat[:] = camera.lookat
        cam.distance, cam.azimuth, cam.elevation = camera.distance, camera.azimuth, camera.elevation
        self.renderer.disable_segmentation_rendering()
        self.renderer.update_scene(self.data, camera=cam)
        rgb = self.renderer.render().copy()
        self.renderer.enable_segmentation_rendering()
        self.renderer.update_scene(self.data, camera=cam)
        seg = self.renderer.render()
        self.renderer.disable_segmentation_rendering()
        geom = np.where(seg[..., 1] == int(mujoco.mjtObj.mjOBJ_GEOM), seg[..., 0], -1)
        ids = self.part_of_geom[geom]  # -1 indexes the background slot
        rgb[ids == 0] = BACKGROUND_RGB
        return rgb, ids


def paint_segmentation(ids: np.ndarray, palette: np.ndarray) -> np.ndarray:
    """S: background colour where id 0, else the part's palette colour (exact, no blending)."""
    out = np.empty(ids.shape + (3,), dtype=np.uint8)
    out[:] = BACKGROUND_RGB
    for pid in np.unique(ids):
        if pid:
            out[ids == pid] = part_colour(palette, int(pid))
    return out


def decode_segmentation(seg_rgb: np.ndarray, palette: np.ndarray) -> np.ndarray:
    """Part ids [H,W] of an S image; raises ValueError on a colour that is neither background
    nor in the palette (S must never contain blended colours)."""
    flat = seg_rgb.reshape(-1, 3).astype(np.int64)
    code = (flat[:, 0] << 16) | (flat[:, 1] << 8) | flat[:, 2]
    table = {int((r << 16) | (g << 8) | b): i + 1 for i, (r, g, b) in enumerate(palette.astype(np.int64))}
    bg = (BACKGROUND_RGB[0] << 16) | (BACKGROUND_RGB[1] << 8) | BACKGROUND_RGB[2]
    table[int(bg)] = 0
    values, inverse = np.unique(code, return_inverse=True)
    missing = [v for v in values.tolist() if v not in table]
    if missing:
        raise ValueError(f"S holds {len(missing)} colours outside the palette, e.g. #{missing[0]:06x}")
    return np.array([table[v] for v in values.tolist()], dtype=np.int64)[inverse].reshape(seg_rgb.shape[:2])


def png_bytes(image: np.ndarray) -> bytes:
    """Deterministic PNG (fixed compression, no metadata chunks)."""
    from PIL import Image

    buf = io.BytesIO()
    Image.fromarray(np.ascontiguousarray(image)).save(buf, format="PNG", compress_level=PNG_COMPRESS_LEVEL)
    return buf.getvalue()


def png_array(data: bytes) -> np.ndarray:
    from PIL import Image

    return np.asarray(Image.open(io.BytesIO(data)).convert("RGB"))
