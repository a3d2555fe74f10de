"""Render the RGB image I and the flat-colour segmentation S of posed parts with MuJoCo.

Every part is a mocap body carrying one mesh geom, so a single compiled model serves all views
of an object: a view only moves mocap bodies (a joint perturbation is a rigid transform of a
subtree) and the free camera. S comes from MuJoCo's segmentation pass (geom ids, no shading),
mapped to part ids and painted with palette colours here, so it has no anti-aliasing: every
pixel is the background or exactly one part's palette colour.

Two looks for I. "plain" (no :class:`Appearance`): one headlight and one key light, material
colours, a black background. "varied" (an :class:`Appearance` per object, a
:class:`ViewLighting` per view, a jittered camera): several coloured lights, a gradient / noisy
sky, a floor or none, per-part colour jitter, specular and checker / noise textures. Only the RGB
pass sees any of it: the floor is added to the RGB pass's scene only (no model geom, so the
model's extent and clipping planes are those of the plain model), textures and lights do not
reach the segmentation pass, so S of a view depends only on the parts, poses and camera.

The OpenGL backend is chosen by :func:`jax3dc.gl.configure_gl` when the package is imported, before mujoco is.
"""

from __future__ import annotations

import colorsys
import io
import os
from dataclasses import dataclass, replace

import numpy as np
import trimesh
from PIL import Image

from jax3dc.errors import SetupError
from jax3dc.materials import MATERIALS
from jax3dc.palette import BACKGROUND_RGB, part_colour
from jax3dc.structure import Structure

DEFAULT_SIZE = 448
PNG_COMPRESS_LEVEL = 6
FOVY_DEGREES = 45.0  # MuJoCo's default vertical field of view: the plain renders' only one
APPEARANCES = ("plain", "varied")

import mujoco  # the package's import chose the GL backend first


@dataclass(frozen=True)
class Camera:
    """A free camera looking at ``lookat`` (nu); MuJoCo's azimuth/elevation in degrees."""

    lookat: tuple[float, float, float]
    distance: float
    azimuth: float
    elevation: float
    fovy: float = FOVY_DEGREES  # vertical field of view in degrees (square images: horizontal too)

    def to_dict(self) -> dict:
        """The record-meta form; ``"fovy"`` only when it is not MuJoCo's default 45 degrees."""
        doc = {"lookat": [round(v, 4) for v in self.lookat], "distance": round(self.distance, 4),
               "azimuth": round(self.azimuth, 3), "elevation": round(self.elevation, 3)}
        if self.fovy != FOVY_DEGREES:
            doc["fovy"] = round(self.fovy, 3)
        return doc


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


# ---- the "varied" look -------------------------------------------------------------------------

MAX_LIGHTS = 3  # directional lights of a varied scene (unused ones are switched off per view)
TEXTURE_SIZE = 64  # side of every texture image (the skybox's: of each of its six faces)
FLOOR_HALF_SIZE = 20.0  # nu; the object fits a unit cube, so the floor reaches the horizon
FLOOR_GAP = 1e-3  # nu below the lowest vertex of the view
FOVY_RANGE = (30.0, 60.0)  # degrees, varied cameras
DISTANCE_MARGIN = (1.0, 1.3)  # x the distance at which the bounding sphere just fits the view


Rgb = tuple[float, float, float]
Vec3 = tuple[float, float, float]


@dataclass(frozen=True)
class Surface:
    """A part's look in a varied I: colour, specular highlight and an optional texture
    (``"checker"`` with ``cells`` squares along the part's longest side, or ``"noise"``, mapped by
    :func:`planar_texcoords`) whose value runs from ``1 - contrast`` to 1 and multiplies ``rgba``."""

    rgba: tuple[float, float, float, float]
    specular: float
    shininess: float
    texture: str | None = None
    cells: int = 8
    contrast: float = 0.0


@dataclass(frozen=True)
class Backdrop:
    """Sky (a gradient from ``sky_top`` above to ``sky_bottom`` below, plus pixel / blotch noise of
    amplitude ``sky_noise``) and a floor: None, ``"flat"``, ``"checker"`` or ``"noise"`` between
    ``floor_rgb`` and ``floor_rgb2``, repeated ``floor_repeat`` times per nu."""

    sky_top: Rgb
    sky_bottom: Rgb
    sky_noise: float
    floor: str | None
    floor_rgb: Rgb
    floor_rgb2: Rgb
    floor_repeat: float


@dataclass(frozen=True)
class Appearance:
    """The per-object part of a varied look; ``texture_seed`` seeds the texture images."""

    surfaces: dict[int, Surface]
    backdrop: Backdrop
    texture_seed: int


@dataclass(frozen=True)
class Light:
    dir: Vec3  # from the light towards the scene
    diffuse: Rgb
    specular: float


@dataclass(frozen=True)
class ViewLighting:
    """The per-view lighting of a varied look: ambient, headlight and 1..MAX_LIGHTS directional lights."""

    ambient: Rgb
    headlight: Rgb
    headlight_specular: float
    lights: tuple[Light, ...]


def _hsv_jitter(rgb: np.ndarray, dh: float, s_scale: float, s_add: float, v_scale: float) -> np.ndarray:
    h, s, v = colorsys.rgb_to_hsv(*(float(c) for c in np.clip(rgb, 0.0, 1.0)))
    s = min(max(s * s_scale + s_add, 0.0), 1.0)
    v = min(max(v * v_scale, 0.0), 1.0)
    return np.array(colorsys.hsv_to_rgb((h + dh) % 1.0, s, v))


def _random_colour(rng: np.random.Generator, saturation: tuple[float, float], value: tuple[float, float]) -> np.ndarray:
    return np.array(colorsys.hsv_to_rgb(rng.uniform(), rng.uniform(*saturation), rng.uniform(*value)))


def _tint(rng: np.random.Generator) -> np.ndarray:
    """A light colour of mean 1: warm to cool white, sometimes a mild colour."""
    if rng.uniform() < 0.2:
        c = np.array(colorsys.hsv_to_rgb(rng.uniform(), rng.uniform(0.15, 0.4), 1.0))
    else:
        t = rng.uniform(-1.0, 1.0)
        c = np.array([1.0 + 0.18 * t, 1.0 + 0.03 * t, 1.0 - 0.2 * t])
    return c / c.mean()


def _rgb(c: np.ndarray) -> Rgb:
    return (float(c[0]), float(c[1]), float(c[2]))


def sample_appearance(structure: Structure, rng: np.random.Generator) -> Appearance:
    """Per-object varied look: each material's colour jittered in hue / saturation / value around
    its family's colour and each part's a little around that; specular and shininess per
    material; on some objects a checker or noise texture on some parts; sky and floor."""
    base = {}
    for mid in sorted(structure.materials):
        family = structure.materials[mid].family
        rgb = _hsv_jitter(np.array(MATERIALS[family].rgba[:3]), rng.uniform(-0.05, 0.05), rng.uniform(0.6, 1.5),
                          rng.uniform(0.0, 0.08), rng.uniform(0.7, 1.2))
        base[mid] = (rgb, float(rng.uniform(0.0, 0.7)), float(rng.uniform(0.05, 0.9)))
    texture_p = 0.35 if rng.uniform() < 0.4 else 0.0
    surfaces = {}
    for pid, node in sorted(structure.nodes.items()):
        rgb, specular, shininess = base[node.material]
        rgb = _hsv_jitter(rgb, rng.uniform(-0.01, 0.01), rng.uniform(0.9, 1.1), 0.0, rng.uniform(0.92, 1.08))
        alpha = MATERIALS[structure.materials[node.material].family].rgba[3]
        texture, cells, contrast = None, 8, 0.0
        if rng.uniform() < texture_p:
            texture = "checker" if rng.uniform() < 0.5 else "noise"
            cells = int(rng.choice([4, 6, 8, 12, 16]))
            contrast = float(rng.uniform(0.15, 0.5))
        surfaces[pid] = Surface((*_rgb(rgb), float(alpha)), specular, shininess, texture, cells, contrast)
    top = _random_colour(rng, (0.0, 0.5), (0.2, 0.95))
    mode = rng.choice(["flat", "gradient", "noise"], p=[0.3, 0.4, 0.3])
    bottom = top if mode == "flat" else _hsv_jitter(top, rng.uniform(-0.1, 0.1), rng.uniform(0.5, 1.5),
                                                    0.0, rng.uniform(0.3, 1.0))
    floor = rng.choice(["none", "flat", "checker", "noise"], p=[0.3, 0.3, 0.2, 0.2])
    floor_rgb = _random_colour(rng, (0.0, 0.4), (0.25, 0.85))
    floor_rgb2 = _hsv_jitter(floor_rgb, rng.uniform(-0.05, 0.05), 1.0, 0.0, rng.uniform(0.45, 0.85))
    backdrop = Backdrop(_rgb(top), _rgb(bottom), float(rng.uniform(0.03, 0.12)) if mode == "noise" else 0.0,
                        None if floor == "none" else str(floor), _rgb(floor_rgb), _rgb(floor_rgb2),
                        float(rng.uniform(0.4, 2.5)))
    return Appearance(surfaces, backdrop, int(rng.integers(1 << 62)))


def sample_view_lighting(rng: np.random.Generator) -> ViewLighting:
    """Per-view varied lighting: total light (ambient + headlight + keys, on a surface facing all
    of them) 0.95..1.55 so nothing is black or washed out, split at random; 1..MAX_LIGHTS key lights
    from above (15..80 degrees), any azimuth, each with its own colour."""
    total = rng.uniform(0.95, 1.55)
    ambient = total * rng.uniform(0.15, 0.4)
    headlight = (total - ambient) * rng.uniform(0.2, 0.55)
    n = int(rng.integers(1, MAX_LIGHTS + 1))
    shares = rng.dirichlet(np.full(n, 2.0)) * (total - ambient - headlight)
    lights = []
    for share in shares:
        az, el = rng.uniform(0.0, 2 * np.pi), rng.uniform(np.deg2rad(15.0), np.deg2rad(80.0))
        key = -np.array([np.cos(el) * np.cos(az), np.cos(el) * np.sin(az), np.sin(el)])
        lights.append(Light(_rgb(key), _rgb(share * _tint(rng)), float(rng.uniform(0.0, 0.4))))
    return ViewLighting(_rgb(ambient * _tint(rng)), _rgb(headlight * _tint(rng)), float(rng.uniform(0.0, 0.3)),
                        tuple(lights))


def vary_camera(camera: Camera, radius: float, rng: np.random.Generator) -> Camera:
    """``camera`` with a field of view in FOVY_RANGE and a distance at which a sphere of ``radius``
    around the look-at point still fits the (square) view, DISTANCE_MARGIN times the closest one.
    Values are rounded as the record meta writes them, so the meta is the camera rendered."""
    fovy = round(float(rng.uniform(*FOVY_RANGE)), 2)
    distance = radius / np.sin(np.deg2rad(fovy / 2.0)) * rng.uniform(*DISTANCE_MARGIN)
    return replace(camera, lookat=tuple(round(float(v), 4) for v in camera.lookat),
                   distance=round(float(distance), 4), azimuth=round(float(camera.azimuth), 3),
                   elevation=round(float(camera.elevation), 3), fovy=fovy)


def planar_texcoords(vertices: np.ndarray) -> np.ndarray:
    """Texture coordinates [V, 2] of a planar projection onto the plane of the mesh's two longest
    box sides, 0..1 along the longest (a decal: exact on the large faces of panels, stretched
    along the thin sides). MuJoCo's own mapping of mesh geoms without texture coordinates is by
    direction from the centre, which streaks radially across thin panels."""
    lo, hi = vertices.min(axis=0), vertices.max(axis=0)
    axes = np.argsort(hi - lo, kind="stable")[::-1][:2]
    return (vertices[:, axes] - lo[axes]) / max(float((hi - lo)[axes[0]]), 1e-9)


def _mesh_assets(parts: dict[int, trimesh.Trimesh], textured: set[int] = frozenset()) -> list[str]:
    out = []
    for pid in sorted(parts):
        v = np.asarray(parts[pid].vertices, dtype=np.float64)
        uv = f' texcoord="{_numbers(planar_texcoords(v), "%.5f")}"' if pid in textured else ""
        out.append(f'<mesh name="m{pid}" inertia="shell" vertex="{_numbers(v, "%.6f")}" '
                   f'face="{_numbers(parts[pid].faces, "%d")}"{uv}/>')
    return out


def varied_scene_xml(parts: dict[int, trimesh.Trimesh], appearance: Appearance, size: int) -> str:
    """MJCF of a varied look: the same bodies and meshes as :func:`scene_xml`, a material (and
    texture) per part, a skybox, a floor material (drawn by :meth:`PartRenderer.render`, not a
    geom) and MAX_LIGHTS directional lights that each view sets."""
    b = appearance.backdrop
    n = TEXTURE_SIZE
    textured = {pid for pid in parts if appearance.surfaces[pid].texture is not None}
    assets = _mesh_assets(parts, textured) + [
        f'<texture name="sky" type="skybox" builtin="gradient" rgb1="{_numbers(np.array(b.sky_top), "%.4f")}" '
        f'rgb2="{_numbers(np.array(b.sky_bottom), "%.4f")}" width="{n}" height="{n}"/>',
        f'<texture name="floor" type="2d" builtin="flat" rgb1="1 1 1" width="{n}" height="{n}"/>',
        f'<material name="floor" texture="floor" texuniform="true" '
        f'texrepeat="{b.floor_repeat:.4f} {b.floor_repeat:.4f}" specular="0.1" shininess="0.1" reflectance="0"/>']
    bodies = []
    for pid in sorted(parts):
        surface = appearance.surfaces[pid]
        texture = ""
        if surface.texture is not None:
            assets.append(f'<texture name="t{pid}" type="2d" builtin="flat" rgb1="1 1 1" width="{n}" height="{n}"/>')
            texture = f' texture="t{pid}"'
        assets.append(f'<material name="s{pid}" rgba="{_numbers(np.array(surface.rgba), "%.4f")}"{texture} '
                      f'specular="{surface.specular:.4f}" shininess="{surface.shininess:.4f}" reflectance="0"/>')
        bodies.append(f'<body name="p{pid}" mocap="true"><geom name="g{pid}" type="mesh" mesh="m{pid}" '
                      f'material="s{pid}" contype="0" conaffinity="0" group="0"/></body>')
    lights = "".join(f'<light name="l{i}" directional="true" castshadow="false" dir="0 0 -1" diffuse="0 0 0" '
                     f'specular="0 0 0"/>' for i in range(MAX_LIGHTS))
    return (f'<mujoco model="jax3dc_view"><visual><global offwidth="{size}" offheight="{size}"/>'
            f'<quality shadowsize="0"/>'
            f'<headlight ambient="0.3 0.3 0.3" diffuse="0.5 0.5 0.5" specular="0.1 0.1 0.1"/>'
            f'</visual><asset>{"".join(assets)}</asset><worldbody>{lights}{"".join(bodies)}</worldbody></mujoco>')


def _periodic_noise(rng: np.random.Generator, n: int, cells: int) -> np.ndarray:
    """Smooth value noise in [0, 1] on an n x n tile that wraps around (bilinear over a cells grid)."""
    grid = rng.uniform(size=(cells, cells))
    t = np.arange(n) * cells / n
    i = np.floor(t).astype(int)
    f = t - i
    f = f * f * (3 - 2 * f)
    rows = grid[i] * (1 - f)[:, None] + grid[(i + 1) % cells] * f[:, None]
    return rows[:, i] * (1 - f)[None, :] + rows[:, (i + 1) % cells] * f[None, :]


def _pattern(rng: np.random.Generator, kind: str, n: int, cells: int) -> np.ndarray:
    """An n x n image in [0, 1]: 1 everywhere (flat), a checker of cells x cells squares, or noise."""
    if kind == "checker":
        y, x = np.mgrid[0:n, 0:n] * cells // n
        return ((x + y) % 2).astype(np.float64)
    if kind == "noise":
        v = 0.6 * _periodic_noise(rng, n, max(cells // 2, 2)) + 0.3 * _periodic_noise(rng, n, cells)
        return np.clip(v + 0.1 * rng.uniform(size=(n, n)), 0.0, 1.0)
    return np.ones((n, n))


def _texture(model: mujoco.MjModel, name: str) -> np.ndarray:
    """The texture's pixels as a writable [height, width, channels] view of ``model.tex_data``."""
    t = mujoco.mj_name2id(model, mujoco.mjtObj.mjOBJ_TEXTURE, name)
    h, w, c = int(model.tex_height[t]), int(model.tex_width[t]), int(model.tex_nchannel[t])
    adr = int(model.tex_adr[t])
    return model.tex_data[adr:adr + h * w * c].reshape(h, w, c)


def paint_textures(model: mujoco.MjModel, appearance: Appearance) -> None:
    """Write the varied look's texture images into ``model`` (before a renderer uploads them)."""
    rng = np.random.default_rng(appearance.texture_seed)
    b = appearance.backdrop
    n = TEXTURE_SIZE
    if b.sky_noise > 0:
        sky = _texture(model, "sky")
        faces = sky.reshape(-1, n, n, sky.shape[-1]).astype(np.float64)
        blotch = np.stack([_periodic_noise(rng, n, 4) for _ in range(len(faces))]) - 0.5
        noise = 255.0 * b.sky_noise * (blotch + 0.5 * rng.uniform(-1.0, 1.0, size=blotch.shape))
        sky[:] = np.clip(faces + noise[..., None], 0, 255).astype(np.uint8).reshape(sky.shape)
    if b.floor is not None:
        v = _pattern(rng, b.floor, n, 2 if b.floor == "checker" else 8)[..., None]
        floor = _texture(model, "floor")
        floor[:] = np.round(255.0 * (np.array(b.floor_rgb2) * (1 - v) + np.array(b.floor_rgb) * v)).astype(np.uint8)
    for pid, surface in sorted(appearance.surfaces.items()):
        if surface.texture is None:
            continue
        tex = _texture(model, f"t{pid}")
        faces = [1.0 - surface.contrast * (1.0 - _pattern(rng, surface.texture, n, surface.cells))
                 for _ in range(tex.shape[0] // n)]
        tex[:] = np.round(255.0 * np.concatenate(faces))[..., None].astype(np.uint8)


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


def compile_scene(xml: str) -> mujoco.MjModel:
    """The model of a scene's MJCF, with MuJoCo's ``balanceinertia`` on.

    The scenes only render (mocap bodies, geoms that collide with nothing), so body inertia is
    never used, but MuJoCo refuses a body whose inertia derived from its mesh breaks A + B >= C
    (e.g. a zero-thickness panel, as in some PartNet-Mobility safes). Balancing changes only such
    bodies, so every scene MuJoCo accepted before compiles to the same model and renders the same
    bytes. (Not deriving inertia at all, inertiafromgeom="false", would also do, but it changes the
    model's extent and with it the clip planes, and so pixels of other objects.)"""
    spec = mujoco.MjSpec.from_string(xml)
    spec.compiler.balanceinertia = True
    return spec.compile()


def offscreen_renderer(model: mujoco.MjModel, height: int, width: int) -> mujoco.Renderer:
    """``mujoco.Renderer``, or a SetupError that names the OpenGL backend tried and what to install
    (MuJoCo's own message for a missing context speaks of mjr_makeContext, not of the machine)."""
    try:
        return mujoco.Renderer(model, height, width)
    except (mujoco.FatalError, RuntimeError, ImportError) as error:
        raise _gl_setup_error(error) from None


def _gl_setup_error(error: Exception) -> SetupError:
    backend = os.environ.get("MUJOCO_GL", "glfw (MuJoCo's default; MUJOCO_GL unset)")
    return SetupError(
        f"cannot render: no OpenGL context with MUJOCO_GL={backend} ({error}). Without a display, install "
        "Mesa's EGL or OSMesa (bash scripts/setup.sh installs libegl1 libegl-mesa0 libosmesa6 libgl1-mesa-dri) or set MUJOCO_GL "
        "to a backend this machine has")


_SHARED_GL: dict[str, object] = {}  # the one GL context of this process for varied renders


class SharedContextRenderer:
    """The part of ``mujoco.Renderer`` PartRenderer uses (update_scene, render, segmentation on /
    off, scene, close), drawing on one GL context per process instead of a new one per model.

    A fresh GL context pays Mesa's first texture upload (mipmap generation, about 60 ms on
    llvmpipe) again; the varied look has textures, so each object would. Here each model only
    gets its own MjrContext (textures, offscreen buffer) on the shared context. Segmentation
    output is computed as ``mujoco.Renderer`` computes it: (object id, object type) per pixel,
    (-1, -1) for the background."""

    def __init__(self, model: mujoco.MjModel, height: int, width: int, max_geom: int = 10000):
        self._model = model
        self._rect = mujoco.MjrRect(0, 0, width, height)
        self._height, self._width = height, width
        self._scene = mujoco.MjvScene(model=model, maxgeom=max_geom)
        self._option = mujoco.MjvOption()
        self._segmentation = False
        self._mjr_context = None
        try:
            if mujoco.GLContext is not None and "gl" not in _SHARED_GL:
                _SHARED_GL["gl"] = mujoco.GLContext(DEFAULT_SIZE, DEFAULT_SIZE)
            self._gl = _SHARED_GL.get("gl")
            if self._gl is not None:
                self._gl.make_current()
            self._mjr_context = mujoco.MjrContext(model, mujoco.mjtFontScale.mjFONTSCALE_150.value)
        except (mujoco.FatalError, RuntimeError, ImportError) as error:
            raise _gl_setup_error(error) from None

    @property
    def scene(self) -> mujoco.MjvScene:
        return self._scene

    def enable_segmentation_rendering(self) -> None:
        self._segmentation = True

    def disable_segmentation_rendering(self) -> None:
        self._segmentation = False

    def update_scene(self, data: mujoco.MjData, camera: mujoco.MjvCamera) -> None:
        mujoco.mjv_updateScene(self._model, data, self._option, None, camera,
                               mujoco.mjtCatBit.mjCAT_ALL.value, self._scene)

    def render(self) -> np.ndarray:
        """RGB uint8 [H,W,3], or with segmentation on int32 [H,W,2] (object id, object type)."""
        if self._mjr_context is None:
            raise RuntimeError("render cannot be called after close")
        if self._gl is not None:
            self._gl.make_current()
        flags = self._scene.flags.copy()
        try:
            if self._segmentation:
                self._scene.flags[mujoco.mjtRndFlag.mjRND_SEGMENT] = True
                self._scene.flags[mujoco.mjtRndFlag.mjRND_IDCOLOR] = True
            mujoco.mjr_setBuffer(mujoco.mjtFramebuffer.mjFB_OFFSCREEN.value, self._mjr_context)
            mujoco.mjr_render(self._rect, self._scene, self._mjr_context)
            rgb = np.empty((self._height, self._width, 3), dtype=np.uint8)
            mujoco.mjr_readPixels(rgb, None, self._rect, self._mjr_context)
        finally:
            np.copyto(self._scene.flags, flags)
        rgb = np.flipud(rgb) if self._gl is not None else rgb
        if not self._segmentation:
            return np.ascontiguousarray(rgb)
        segid = rgb[..., 0].astype(np.int64) | (rgb[..., 1].astype(np.int64) << 8) | (rgb[..., 2].astype(np.int64) << 16)
        table = np.full((self._scene.ngeom + 1, 2), -1, dtype=np.int32)
        for g in self._scene.geoms[:self._scene.ngeom]:
            if g.segid != -1:
                table[g.segid + 1] = (g.objid, g.objtype)
        return table[segid]

    def close(self) -> None:
        if self._mjr_context is not None:
            if self._gl is not None:
                self._gl.make_current()
            self._mjr_context.free()
        self._mjr_context = None


class PartRenderer:
    """One compiled scene of parts and its renderer; render any pose of the parts from any camera."""

    def __init__(self, parts: dict[int, trimesh.Trimesh], rgba: dict[int, tuple[float, ...]],
                 lighting: Lighting, size: int = DEFAULT_SIZE, appearance: Appearance | None = None):
        """``appearance`` None: the plain look (``rgba`` and ``lighting``); else the varied look it
        describes (``rgba`` and ``lighting`` unused)."""
        self.size = size
        self.appearance = appearance
        if appearance is None:
            self.model = compile_scene(scene_xml(parts, rgba, lighting, size))
        else:
            self.model = compile_scene(varied_scene_xml(parts, appearance, size))
            paint_textures(self.model, appearance)
            self.floor_material = mujoco.mj_name2id(self.model, mujoco.mjtObj.mjOBJ_MATERIAL, "floor")
            self.rest_vertices = {pid: np.asarray(mesh.vertices, dtype=np.float64) for pid, mesh in parts.items()}
        self.data = mujoco.MjData(self.model)
        self.part_of_geom = np.full(self.model.ngeom + 1, 0, dtype=np.int64)  # last slot: background
        self.mocap_of_part = {}
        for pid in parts:
            self.part_of_geom[mujoco.mj_name2id(self.model, mujoco.mjtObj.mjOBJ_GEOM, f"g{pid}")] = pid
            body = mujoco.mj_name2id(self.model, mujoco.mjtObj.mjOBJ_BODY, f"p{pid}")
            self.mocap_of_part[pid] = int(self.model.body_mocapid[body])
        if appearance is None:
            self.renderer = offscreen_renderer(self.model, size, size)
        else:
            self.renderer = SharedContextRenderer(self.model, size, size)

    def close(self) -> None:
        self.renderer.close()

    def _set_lighting(self, lighting: ViewLighting) -> None:
        vis = self.model.vis.headlight
        vis.ambient[:], vis.diffuse[:] = lighting.ambient, lighting.headlight
        vis.specular[:] = lighting.headlight_specular
        for i in range(MAX_LIGHTS):
            light = lighting.lights[i] if i < len(lighting.lights) else None
            self.model.light_dir[i] = light.dir if light else (0.0, 0.0, -1.0)
            self.model.light_diffuse[i] = light.diffuse if light else 0.0
            self.model.light_specular[i] = light.specular if light else 0.0

    def _floor_z(self, poses: dict[int, np.ndarray]) -> float:
        """Just below the lowest vertex of the parts posed by ``poses``."""
        low = []
        for pid, v in self.rest_vertices.items():
            pose = poses.get(pid)
            low.append(v[:, 2].min() if pose is None else (v @ pose[2, :3] + pose[2, 3]).min())
        return float(min(low)) - FLOOR_GAP

    def _add_floor(self, z: float) -> None:
        scene = self.renderer.scene
        if scene.ngeom >= scene.maxgeom:
            return
        geom = scene.geoms[scene.ngeom]
        mujoco.mjv_initGeom(geom, int(mujoco.mjtGeom.mjGEOM_PLANE), np.array([FLOOR_HALF_SIZE, FLOOR_HALF_SIZE, 1.0]),
                            np.array([0.0, 0.0, z]), np.eye(3).ravel(), np.ones(4, dtype=np.float32))
        geom.matid = self.floor_material
        geom.category = int(mujoco.mjtCatBit.mjCAT_DECOR)
        scene.ngeom += 1

    def render(self, poses: dict[int, np.ndarray], camera: Camera,
               lighting: ViewLighting | None = None) -> tuple[np.ndarray, np.ndarray]:
        """RGB uint8 [H,W,3] and part-id int [H,W] (0 = background) for parts posed by 4x4 ``poses``
        (missing parts stay at rest); ``lighting`` sets a varied renderer's lights for this view.
        The part ids depend only on poses and camera, never on the look."""
        self.model.vis.global_.fovy = camera.fovy
        if lighting is not None:
            if self.appearance is None:
                raise ValueError("view lighting needs a renderer made with an Appearance")
            self._set_lighting(lighting)
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
        if self.appearance is not None and self.appearance.backdrop.floor is not None:
            self._add_floor(self._floor_z(poses))  # RGB pass only
        rgb = self.renderer.render().copy()
        self.renderer.enable_segmentation_rendering()
        self.renderer.update_scene(self.data, camera=cam)
        seg = self.renderer.render()
        self.renderer.disable_segmentation_rendering()
        geom = np.where(seg[..., 1] == int(mujoco.mjtObj.mjOBJ_GEOM), seg[..., 0], -1)
        ids = self.part_of_geom[geom]  # -1 indexes the background slot
        if self.appearance is None:
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


def png_bytes(image: np.ndarray) -> bytes:
    """Deterministic PNG (fixed compression, no metadata chunks)."""
    buf = io.BytesIO()
    Image.fromarray(np.ascontiguousarray(image)).save(buf, format="PNG", compress_level=PNG_COMPRESS_LEVEL)
    return buf.getvalue()


def png_array(data: bytes) -> np.ndarray:
    return np.asarray(Image.open(io.BytesIO(data)).convert("RGB"))
