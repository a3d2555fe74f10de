"""The predefined functions of the part-program language (its whole vocabulary).

Each function checks and converts its arguments, raising `ArgumentError` with a message for
the user; the interpreter adds the line number. Lengths are in the program's units (nu for
the dataset), angles in degrees, `axis` is "x", "y" or "z".
"""

from __future__ import annotations

import math
import time
from contextlib import contextmanager
from contextvars import ContextVar
from dataclasses import dataclass
from typing import Any, Callable, Iterator

import numpy as np

from jax3dc.program import csg
from jax3dc.program import solids as S
from jax3dc.program.solids import Solid
from jax3dc.structure.schema import FAMILIES, Material

MIN_SEGMENTS = 3
MAX_SEGMENTS = 256
MAX_COPIES = 1000
MAX_MAGNITUDE = 1e6
"""Largest absolute number a function accepts (keeps every volume and coordinate finite)."""
MIN_LENGTH = 1e-9
"""Smallest positive length (radius, depth, size) a function accepts."""
MAX_PROFILE_POINTS = 256
MAX_PATH_POINTS = 1024
"""Point limits keep every single call fast (the time budget is checked between statements)."""
MAX_OPERANDS = 1000
"""Most meshes one combine() or difference() takes (as many as an array makes)."""


class ArgumentError(ValueError):
    """A predefined function got an argument it cannot use."""


class OutOfTime(Exception):
    """The run's deadline passed inside a function (a long boolean or array); the interpreter
    turns it into a ProgramError naming the line."""


_DEADLINE: ContextVar[float] = ContextVar("part_program_deadline", default=math.inf)


@contextmanager
def deadline(at: float) -> Iterator[None]:
    """Functions called inside this block stop with OutOfTime once ``time.perf_counter()`` passes ``at``."""
    token = _DEADLINE.set(at)
    try:
        yield
    finally:
        _DEADLINE.reset(token)


def check_time() -> None:
    """Called between the steps of long functions, so one call cannot outlast the time budget."""
    if time.perf_counter() > _DEADLINE.get():
        raise OutOfTime()


def _operands(meshes: tuple, what: str) -> None:
    if len(meshes) > MAX_OPERANDS:
        raise ArgumentError(f"{what} takes at most {MAX_OPERANDS} meshes, got {len(meshes)}")


@dataclass(frozen=True)
class PartCall:
    """What `part(...)` returns: the interpreter collects these as the program's parts."""

    part_id: int
    name: str
    solid: Solid
    material: Material | None


# ---- argument conversion ---------------------------------------------------------------

def _number(value: Any, what: str) -> float:
    if isinstance(value, bool) or not isinstance(value, (int, float)):
        raise ArgumentError(f"{what} must be a number, got {_describe(value)}")
    if abs(value) > MAX_MAGNITUDE or not math.isfinite(value):  # magnitude first: a huge int overflows isfinite
        raise ArgumentError(f"{what} must be a finite number within +-{MAX_MAGNITUDE:g}")
    return float(value)


def _positive(value: Any, what: str) -> float:
    x = _number(value, what)
    if x < MIN_LENGTH:
        raise ArgumentError(f"{what} must be > 0, got {x:g}")
    return x


def _count(value: Any, what: str, lo: int, hi: int) -> int:
    if isinstance(value, bool) or not isinstance(value, int):
        if isinstance(value, float) and value.is_integer():
            value = int(value)
        else:
            raise ArgumentError(f"{what} must be a whole number, got {_describe(value)}")
    if not lo <= value <= hi:
        raise ArgumentError(f"{what} must be between {lo} and {hi}, got {value}")
    return int(value)


def _vector(value: Any, what: str, n: int = 3) -> np.ndarray:
    if not isinstance(value, tuple) or len(value) != n:
        raise ArgumentError(f"{what} must be a tuple of {n} numbers, got {_describe(value)}")
    return np.array([_number(v, f"{what}[{i}]") for i, v in enumerate(value)], dtype=np.float64)


def _size(value: Any, what: str) -> np.ndarray:
    if isinstance(value, (int, float)) and not isinstance(value, bool):
        value = (value, value, value)
    size = _vector(value, what)
    if np.any(size < MIN_LENGTH):
        raise ArgumentError(f"{what} must be > 0 in every direction")
    return size


def _points(value: Any, what: str, dim: int, minimum: int, maximum: int = MAX_PROFILE_POINTS) -> np.ndarray:
    if not isinstance(value, tuple) or len(value) < minimum:
        raise ArgumentError(f"{what} must be a list of at least {minimum} points")
    if len(value) > maximum:
        raise ArgumentError(f"{what} has {len(value)} points; at most {maximum} are allowed")
    return np.stack([_vector(p, f"{what}[{i}]", dim) for i, p in enumerate(value)])


def _axis(value: Any) -> str:
    if value not in S.AXES:
        raise ArgumentError(f'axis must be "x", "y" or "z", got {_describe(value)}')
    return value


def _axis_vector(value: Any) -> np.ndarray:
    if isinstance(value, str):
        return np.eye(3)[S.AXES.index(_axis(value))]
    v = _vector(value, "axis")
    if np.linalg.norm(v) < 1e-12:
        raise ArgumentError("axis must be non-zero")
    return v


def _solid(value: Any, what: str) -> Solid:
    if not isinstance(value, Solid):
        raise ArgumentError(f"{what} must be a mesh, got {_describe(value)}")
    return value


def _segments(value: Any, what: str = "segments") -> int:
    return _count(value, what, MIN_SEGMENTS, MAX_SEGMENTS)


def _describe(value: Any) -> str:
    if isinstance(value, Solid):
        return "a mesh"
    if isinstance(value, Material):
        return "a material"
    if isinstance(value, tuple):
        return f"a list of {len(value)}"
    if isinstance(value, str):
        return f"the text {value!r}"
    return repr(value)


def _geometry(build: Callable[[], Solid]) -> Solid:
    try:
        return build()
    except ValueError as exc:
        raise ArgumentError(str(exc)) from None


# ---- primitives -------------------------------------------------------------------------

def box(size=1.0, center=(0, 0, 0)) -> Solid:
    """Axis-aligned box of `size` (a number for a cube, or (sx, sy, sz)) centred at `center`."""
    return S.box(_size(size, "size"), _vector(center, "center"))


def cylinder(radius=0.5, depth=1.0, center=(0, 0, 0), axis="z", segments=32) -> Solid:
    """Cylinder of length `depth` along `axis`, centred at `center`; `segments` sides."""
    return S.frustum(_positive(radius, "radius"), _positive(radius, "radius"), _positive(depth, "depth"),
                     _vector(center, "center"), _axis(axis), _segments(segments))


def cone(radius1=0.5, radius2=0.0, depth=1.0, center=(0, 0, 0), axis="z", segments=32) -> Solid:
    """Cone (radius2 = 0) or truncated cone; radius1 at the low end of the axis."""
    r2 = _number(radius2, "radius2")
    if r2 < 0:
        raise ArgumentError("radius2 must be >= 0")
    return S.frustum(_positive(radius1, "radius1"), r2, _positive(depth, "depth"),
                     _vector(center, "center"), _axis(axis), _segments(segments))


def sphere(radius=0.5, center=(0, 0, 0), segments=32, rings=16) -> Solid:
    """UV sphere: `segments` around the z axis, `rings` from pole to pole."""
    return S.uv_sphere(_positive(radius, "radius"), _vector(center, "center"), _segments(segments),
                       _count(rings, "rings", 3, MAX_SEGMENTS))


def torus(major_radius=0.5, minor_radius=0.1, center=(0, 0, 0), axis="z", major_segments=32,
          minor_segments=12) -> Solid:
    """Ring around `axis` through `center`: tube of `minor_radius` on a circle of `major_radius`."""
    major, minor = _positive(major_radius, "major_radius"), _positive(minor_radius, "minor_radius")
    if minor >= major:
        raise ArgumentError("minor_radius must be smaller than major_radius")
    return S.torus(major, minor, _vector(center, "center"), _axis(axis), _segments(major_segments),
                   _segments(minor_segments))


def extrude(profile, depth=1.0, center=(0, 0, 0), axis="z") -> Solid:
    """A 2-D polygon (relative to `center`) extruded by `depth` along `axis`, centred.

    The profile's (u, v) are (x, y) for axis z, (x, z) for axis y and (y, z) for axis x.
    """
    pts = _points(profile, "profile", 2, 3)
    return _geometry(lambda: S.prism(pts, _positive(depth, "depth"), _vector(center, "center"), _axis(axis)))


def lathe(profile, center=(0, 0, 0), axis="z", segments=32) -> Solid:
    """A closed outline of (radius, height) points, relative to `center`, revolved about `axis`."""
    pts = _points(profile, "profile", 2, 3)
    if np.any(pts[:, 0] < 0):
        raise ArgumentError("lathe profile radii must be >= 0")
    if np.all(pts[:, 0] <= 1e-12):
        raise ArgumentError("lathe profile lies on the axis")
    return _geometry(lambda: S.revolve(pts, _vector(center, "center"), _axis(axis), _segments(segments)))


def sweep(path, radius=None, profile=None, segments=16) -> Solid:
    """A circle of `radius` (or a 2-D `profile` polygon) carried along an open polyline `path`."""
    pts = _points(path, "path", 3, 2, MAX_PATH_POINTS)
    if (radius is None) == (profile is None):
        raise ArgumentError("sweep needs exactly one of radius= or profile=")
    if radius is not None:
        r = _positive(radius, "radius")
        t = np.linspace(0.0, 2 * np.pi, _segments(segments), endpoint=False)
        section = np.stack([r * np.cos(t), r * np.sin(t)], axis=1)
    else:
        section = _points(profile, "profile", 2, 3)
    return _geometry(lambda: S.sweep(pts, section))


def bevel(size=1.0, width=0.05, center=(0, 0, 0)) -> Solid:
    """A box whose edges are chamfered at 45 degrees by `width` (less than half the smallest side)."""
    s = _size(size, "size")
    w = _positive(width, "width")
    if w >= s.min() / 2:
        raise ArgumentError("bevel width must be less than half the smallest side")
    return S.chamfered_box(s, w, _vector(center, "center"))


# ---- combining ----------------------------------------------------------------------------

def difference(base, *cutters) -> Solid:
    """`base` with every cutter removed; all must be closed meshes (any shape, through manifold3d)."""
    if not cutters:
        raise ArgumentError("difference needs at least one mesh to remove")
    _operands(cutters, "difference")
    b = _solid(base, "base")
    cs = [_solid(c, f"cutter {i + 1}") for i, c in enumerate(cutters)]
    return _geometry(lambda: csg.difference(b, cs, check_time))


def combine(*meshes) -> Solid:
    """Several meshes as one (they are kept as separate shells, not fused)."""
    if not meshes:
        raise ArgumentError("combine needs at least one mesh")
    _operands(meshes, "combine")
    return S.combine([_solid(m, f"mesh {i + 1}") for i, m in enumerate(meshes)])


def linear_array(mesh, count=2, offset=(1, 0, 0)) -> Solid:
    """`count` copies, each shifted by `offset` from the previous one."""
    m, n, step = _solid(mesh, "mesh"), _count(count, "count", 1, MAX_COPIES), _vector(offset, "offset")
    return S.combine([S.translated(m, step * i) for i in range(n)])


def grid_array(mesh, counts=(2, 2, 1), spacing=(1, 1, 1)) -> Solid:
    """Copies on a 3-D grid: counts (nx, ny, nz), spacing (dx, dy, dz)."""
    m = _solid(mesh, "mesh")
    if not isinstance(counts, tuple) or len(counts) != 3:
        raise ArgumentError("counts must be a tuple of 3 whole numbers")
    nx, ny, nz = (_count(c, f"counts[{i}]", 1, MAX_COPIES) for i, c in enumerate(counts))
    if nx * ny * nz > MAX_COPIES:
        raise ArgumentError(f"grid_array makes at most {MAX_COPIES} copies")
    d = _vector(spacing, "spacing")
    return S.combine([S.translated(m, d * (i, j, k)) for i in range(nx) for j in range(ny) for k in range(nz)])


def radial_array(mesh, count=4, axis="z", center=(0, 0, 0), angle=360.0) -> Solid:
    """`count` copies rotated about an axis through `center`, spread evenly over `angle` degrees."""
    m, n = _solid(mesh, "mesh"), _count(count, "count", 1, MAX_COPIES)
    a, c, span = _axis_vector(axis), _vector(center, "center"), _number(angle, "angle")
    step = math.radians(span) / (n if abs(abs(span) - 360.0) < 1e-9 else max(n - 1, 1))
    return S.combine([S.transformed(m, S.rotation_matrix(a, step * i), c) for i in range(n)])


def mirror(mesh, plane="yz", center=(0, 0, 0)) -> Solid:
    """The mirror image across `plane` ("yz": x -> -x, "xz": y -> -y, "xy": z -> -z) through `center`."""
    planes = {"yz": 0, "xz": 1, "xy": 2}
    if not isinstance(plane, str) or plane not in planes:
        raise ArgumentError(f'plane must be "yz", "xz" or "xy", got {_describe(plane)}')
    flip = np.eye(3)
    flip[planes[plane], planes[plane]] = -1.0
    return S.transformed(_solid(mesh, "mesh"), flip, _vector(center, "center"))


# ---- transforms ---------------------------------------------------------------------------

def translate(mesh, offset=(0, 0, 0)) -> Solid:
    """The mesh moved by `offset` (dx, dy, dz)."""
    return S.translated(_solid(mesh, "mesh"), _vector(offset, "offset"))


def rotate(mesh, angle=0.0, axis="z", center=(0, 0, 0)) -> Solid:
    """Rotation by `angle` degrees (right-hand rule) about an axis through `center`."""
    return S.transformed(_solid(mesh, "mesh"), S.rotation_matrix(_axis_vector(axis), math.radians(_number(angle, "angle"))),
                         _vector(center, "center"))


def scale(mesh, factor=1.0, center=(0, 0, 0)) -> Solid:
    """Scaling about `center` by a number or per-axis (fx, fy, fz); factors must be non-zero."""
    f = _size(factor, "factor") if not isinstance(factor, tuple) else _vector(factor, "factor")
    if np.any(np.abs(f) < 1e-12):
        raise ArgumentError("scale factors must be non-zero")
    return S.transformed(_solid(mesh, "mesh"), np.diag(f), _vector(center, "center"))


# ---- naming ---------------------------------------------------------------------------------

def make_material(family="Other", desc="") -> Material:
    """A material: `family` is one of Wood, Metal, Plastic, Glass, Fabric, Leather, Ceramic, Stone,
    Rubber, Other; `desc` is free text."""
    if family not in FAMILIES:
        raise ArgumentError(f"material family must be one of {', '.join(FAMILIES)}, got {_describe(family)}")
    if not isinstance(desc, str):
        raise ArgumentError("desc must be text")
    return Material(family, desc)


def part(part_id, name, mesh, material=None) -> PartCall:
    """Names `mesh` as part `part_id` (1, 2, ...) with a semantic `name` and optional material."""
    pid = _count(part_id, "part id", 1, 100_000)
    if not isinstance(name, str) or not name:
        raise ArgumentError("part name must be non-empty text")
    if isinstance(material, str):
        material = make_material(material)
    elif material is not None and not isinstance(material, Material):
        raise ArgumentError(f"material must be a material(...) or a family name, got {_describe(material)}")
    return PartCall(pid, name, _solid(mesh, "mesh"), material)


FUNCTIONS: dict[str, Callable[..., Any]] = {
    "box": box, "cube": box, "cylinder": cylinder, "cone": cone, "sphere": sphere, "torus": torus,
    "extrude": extrude, "lathe": lathe, "sweep": sweep, "bevel": bevel,
    "difference": difference, "combine": combine,
    "linear_array": linear_array, "grid_array": grid_array, "radial_array": radial_array, "mirror": mirror,
    "translate": translate, "rotate": rotate, "scale": scale,
    "material": make_material, "part": part,
}
"""Every name a program may call (plus `range` in a for loop header)."""
