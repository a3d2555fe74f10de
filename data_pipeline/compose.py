"""New articulated objects composed from real part meshes: a body, doors, drawers, a flap or a lid,
and handles or knobs from the PartNet cabinet parts of URDFormer's ``partnet_uv`` folder, laid out
anew per seed, so the real part shapes appear in far more arrangements than the cabinets they
came from. The folder is read where it lies (its licence keeps it out of the project tree).

Library frame (URDFormer): front +X, up +Z. ``doorLs`` are plates x in [-0.01, 0], y in [0, 0.247]
hinged at y = 0; ``doorRs`` their mirror images (y in [-0.247, 0]); ``drawers`` run back from their
front at x = 0; a ``cabinet_frames`` mesh has its front opening on the unit square y, z in [0, 1]
at x = 0 (tops, plinths and legs lie outside it); ``handles`` and ``knobs`` stand off x = 0
toward +X, handles long along Z. Every mesh is turned -90 degrees about Z into the project's frame
(SPEC §2: front -Y, up +Z), (x, y) -> (y, -x), so a doorL's hinge is at its smallest x: the left
as the front camera sees it.

A door's handle goes near its free edge, away from its hinge, as on real furniture (68 of 71 real
doors with a handle are hinged on the side away from it): the image shows which way a door opens.
Joints open outward for positive values, as the factories write them: a door hinged at its left
edge turns about (0, 0, -1), at its right edge about (0, 0, 1), the pivot on the door's back edge
at that side (the body's front plane); a flap hinged at its bottom edge about (1, 0, 0), at its
top edge about (-1, 0, 0); a lid hinged at its back edge about (-1, 0, 0); drawers slide along
(0, -1, 0). A handle is fused into its door or drawer (as most real meshes have it) or is a rigid
child part. Objects are built in metres and normalised like the factories' (bounding box centred,
largest extent 1). A library file that cannot be read or is degenerate is passed over with a
warning that names it, and another mesh of its kind is drawn.
"""

from __future__ import annotations

import warnings
from dataclasses import dataclass, field, replace
from functools import lru_cache
from pathlib import Path
from typing import Callable

import numpy as np
import trimesh

from data_pipeline.samples import SourceObject, derived_rng, normalised
from jax3dc.factories.kit import GLASSES, METALS, PLASTICS, WOODS
from jax3dc.relations import with_extracted_relations
from jax3dc.structure import Joint, Material, Node, Structure

KINDS = ("cabinet_frames", "doorLs", "doorRs", "drawers", "handles", "knobs")
LAYOUTS = ("cabinet", "appliance", "chest")
MAX_FACES = 60_000  # per object; heavy library meshes give way to lighter ones beyond it
GAP = 0.003  # m between a moving front and its neighbours or the body
MAX_STANDOFF = 0.05  # m a handle or knob stands off its front
_DESCS = {"Wood": WOODS, "Metal": METALS, "Plastic": PLASTICS, "Glass": GLASSES}


def _rotation(degrees: float, axis: tuple[float, float, float]) -> np.ndarray:
    return trimesh.transformations.rotation_matrix(np.deg2rad(degrees), axis)


_TO_PROJECT = _rotation(-90.0, (0, 0, 1))  # URDFormer (front +X) -> project (front -Y)
_FACE_UP = _rotation(-90.0, (1, 0, 0))  # front (-Y) -> up (+Z), up -> back (+Y)
_QUARTER_Y = _rotation(90.0, (0, 1, 0))  # a vertical handle made horizontal


class BrokenPartError(ValueError):
    """A library mesh that cannot serve as a part (unreadable, no faces, no extent, non-finite)."""


@lru_cache(maxsize=None)
def _load(path: str) -> trimesh.Trimesh:
    """The mesh of one library file in the project's frame, once per process (never modified)."""
    try:
        loaded = trimesh.load(path, force="mesh", process=False)
        vertices = np.asarray(loaded.vertices, dtype=np.float64)
        faces = np.asarray(loaded.faces, dtype=np.int64)
    except Exception as e:  # trimesh's readers raise many types on a bad file
        raise BrokenPartError(f"part mesh {path} cannot be read ({e})") from e
    if len(faces) == 0 or faces.min() < 0 or faces.max() >= len(vertices):
        raise BrokenPartError(f"part mesh {path} has no usable faces")
    if not np.isfinite(vertices).all() or np.ptp(vertices, axis=0).max() <= 0:
        raise BrokenPartError(f"part mesh {path} has non-finite vertices or no extent")
    mesh = trimesh.Trimesh(vertices, faces, process=False)
    mesh.apply_transform(_TO_PROJECT)
    return mesh


@lru_cache(maxsize=None)
def _frame_front(path: str) -> float:
    """The y (library units, at most 0) of a frame's frontmost surface inside its opening, where a
    door there must stay in front of: its vertices there, and rays along +Y for faces spanning it."""
    mesh = _load(path)
    grid = np.linspace(0.02, 0.98, 17)
    x, z = (a.ravel() for a in np.meshgrid(grid, grid))
    origins = np.stack([x, np.full(x.size, mesh.bounds[0][1] - 1.0), z], axis=1)
    hits, _, _ = mesh.ray.intersects_location(origins, np.tile((0.0, 1.0, 0.0), (x.size, 1)), multiple_hits=False)
    hits = np.asarray(hits, dtype=np.float64).reshape(-1, 3)  # trimesh's rtree engine gives (0,) for no hit
    v = mesh.vertices
    inside = v[(v[:, 0] > 0.005) & (v[:, 0] < 0.995) & (v[:, 2] > 0.005) & (v[:, 2] < 0.995)]
    return float(np.concatenate([[0.0], hits[:, 1], inside[:, 1]]).min())


@dataclass(frozen=True)
class PartLibrary:
    """The mesh files of a ``partnet_uv`` folder by kind (``KINDS``); meshes load on first use."""

    root: Path
    files: dict[str, tuple[Path, ...]]

    @classmethod
    def open(cls, folder: Path | str) -> PartLibrary:
        """``folder`` is ``partnet_uv`` itself or the folder holding it."""
        folder = Path(folder)
        root = folder / "partnet_uv" if (folder / "partnet_uv").is_dir() else folder
        files = {kind: tuple(sorted((root / kind).glob("*.obj"))) for kind in KINDS}
        empty = [kind for kind, paths in files.items() if not paths]
        if empty:
            raise FileNotFoundError(f"part library {root}: no .obj files in {', '.join(empty)}")
        return cls(root, files)

    def mesh(self, path: Path) -> trimesh.Trimesh:
        """The mesh of ``path`` in the project's frame; a copy the caller may move."""
        cached = _load(str(path))
        return trimesh.Trimesh(cached.vertices.copy(), cached.faces, process=False)


def _warn(notes: list[str], message: str) -> None:
    warnings.warn(message, stacklevel=3)
    notes.append(message)


def _pick(lib: PartLibrary, kind: str, rng: np.random.Generator, notes: list[str], max_faces: float = np.inf,
          accept: Callable[[trimesh.Trimesh], bool] = lambda mesh: True) -> tuple[Path, trimesh.Trimesh]:
    """A random usable mesh of ``kind`` within ``max_faces`` (else the lightest one ``accept`` takes);
    a broken file is reported and passed over."""
    lightest = None
    for i in rng.permutation(len(lib.files[kind])):
        path = lib.files[kind][i]
        try:
            mesh = _load(str(path))
        except BrokenPartError as e:
            _warn(notes, f"skipped: {e}")
            continue
        if not accept(mesh):
            continue
        if len(mesh.faces) <= max_faces:
            return path, lib.mesh(path)
        if lightest is None or len(mesh.faces) < len(_load(str(lightest)).faces):
            lightest = path
    if lightest is None:
        raise BrokenPartError(f"no usable {kind} mesh in {lib.root}")
    return lightest, lib.mesh(lightest)


def _box(lo, hi) -> trimesh.Trimesh:
    lo, hi = np.asarray(lo, dtype=np.float64), np.asarray(hi, dtype=np.float64)
    return trimesh.creation.box(extents=hi - lo, transform=trimesh.transformations.translation_matrix((lo + hi) / 2))


def _fit(mesh: trimesh.Trimesh, lo, hi) -> trimesh.Trimesh:
    """``mesh`` scaled per axis and moved so its bounding box is [lo, hi] (a flat axis is centred)."""
    lo, hi = np.asarray(lo, dtype=np.float64), np.asarray(hi, dtype=np.float64)
    m_lo, m_hi = mesh.bounds
    extent = m_hi - m_lo
    scale = np.where(extent > 0, (hi - lo) / np.where(extent > 0, extent, 1.0), 1.0)
    return trimesh.Trimesh((mesh.vertices - (m_lo + m_hi) / 2) * scale + (lo + hi) / 2, mesh.faces, process=False)


def _turned(mesh: trimesh.Trimesh, matrix: np.ndarray) -> trimesh.Trimesh:
    out = mesh.copy()
    out.apply_transform(matrix)
    return out


def _moved(mesh: trimesh.Trimesh, offset) -> trimesh.Trimesh:
    return trimesh.Trimesh(mesh.vertices + np.asarray(offset, dtype=np.float64), mesh.faces, process=False)


def _material(rng: np.random.Generator, weights: dict[str, float]) -> Material:
    families = list(weights)
    family = families[rng.choice(len(families), p=np.array(list(weights.values())) / sum(weights.values()))]
    descs = _DESCS[family]
    return Material(family, descs[int(rng.integers(len(descs)))])


@dataclass
class _Parts:
    """One object's parts in metres while it is composed; ids 1..N in the order they are added,
    one material id per distinct material."""

    meshes: dict[int, trimesh.Trimesh] = field(default_factory=dict)
    nodes: dict[int, Node] = field(default_factory=dict)
    materials: dict[Material, int] = field(default_factory=dict)

    def add(self, name: str, mesh: trimesh.Trimesh, material: Material, parent: int | None = None,
            joint: Joint | None = None) -> int:
        pid = len(self.nodes) + 1
        self.meshes[pid] = mesh
        self.nodes[pid] = Node(parent, self.materials.setdefault(material, len(self.materials)), joint, name)
        return pid

    def normalised(self) -> tuple[Structure, dict[int, trimesh.Trimesh], float]:
        """Structure, meshes and metres per unit, the whole object centred with largest extent 1."""
        structure, meshes, size = normalised(Structure({mid: mat for mat, mid in self.materials.items()}, self.nodes),
                                             self.meshes)
        return with_extracted_relations(structure, meshes), meshes, size


@dataclass(frozen=True)
class _Opening:
    """Where a body's fronts go (metres): x0..x1 by z0..z1 in the plane y, ``depth`` free behind it."""

    x0: float
    x1: float
    z0: float
    z1: float
    y: float
    depth: float

    def cell(self, u0: float, u1: float, v0: float, v1: float) -> tuple[float, float, float, float]:
        """The front of a cell given in fractions of the opening, less the gap on every side."""
        w, h = self.x1 - self.x0, self.z1 - self.z0
        return self.x0 + u0 * w + GAP, self.x0 + u1 * w - GAP, self.z0 + v0 * h + GAP, self.z0 + v1 * h - GAP


def _shell(w: float, d: float, h: float, t: float, plinth: float) -> tuple[trimesh.Trimesh, _Opening]:
    """Five boards around a w x h front opening at y = 0, on a set-back plinth when ``plinth`` > 0."""
    z0 = plinth + t
    boards = [_box((-w / 2 - t, 0, plinth), (-w / 2, d, z0 + h + t)),
              _box((w / 2, 0, plinth), (w / 2 + t, d, z0 + h + t)),
              _box((-w / 2, 0, plinth), (w / 2, d, z0)), _box((-w / 2, 0, z0 + h), (w / 2, d, z0 + h + t)),
              _box((-w / 2, d - t, z0), (w / 2, d, z0 + h))]
    if plinth > 0:
        boards.append(_box((-w / 2, 0.04, 0), (w / 2, d - 0.02, plinth)))
    return trimesh.util.concatenate(boards), _Opening(-w / 2, w / 2, z0, z0 + h, 0.0, d - t)


def _frame_body(lib: PartLibrary, rng: np.random.Generator, notes: list[str], w: float, d: float,
                h: float) -> tuple[trimesh.Trimesh, _Opening] | None:
    """A library frame stretched so its opening is w x h and its depth d; None when none is usable."""
    try:
        path, mesh = _pick(lib, "cabinet_frames", rng, notes, 0.4 * MAX_FACES, lambda m: m.bounds[1][1] > 0.2)
    except BrokenPartError as e:
        _warn(notes, f"a procedural body instead: {e}")
        return None
    depth = mesh.bounds[1][1]
    scale = np.array([w, d / depth, h])
    body = trimesh.Trimesh(mesh.vertices * scale + (-w / 2, 0.0, 0.0), mesh.faces, process=False)
    return body, _Opening(-w / 2, w / 2, 0.0, h, _frame_front(str(path)) * scale[1], 0.9 * d)


def _grip(design: trimesh.Trimesh, length: float, horizontal: bool) -> trimesh.Trimesh:
    """A handle or knob ``length`` long (a knob: wide) across its longer face-plane axis, standing off
    y = 0 toward -Y, centred on x = z = 0. Thickness and standoff follow the length up to 1.5 times
    the library's and MAX_STANDOFF: a long fridge handle is a stretched bar, not a thick one."""
    lo, hi = design.bounds
    extent = hi - lo
    along = 2 if extent[2] >= extent[0] else 0
    rest = min(length / extent[along], MAX_STANDOFF / extent[1] if extent[1] > 0 else np.inf, 1.5)
    scale = np.full(3, rest)
    scale[along] = length / extent[along]
    v = (design.vertices - ((lo[0] + hi[0]) / 2, hi[1], (lo[2] + hi[2]) / 2)) * scale
    mesh = trimesh.Trimesh(v, design.faces, process=False)
    return _turned(mesh, _QUARTER_Y) if horizontal == (along == 2) else mesh


def _stands_off(mesh: trimesh.Trimesh) -> bool:
    """A grip with depth and a face-plane size (a flat one would lie in its front's surface)."""
    extent = mesh.extents
    return bool(extent[1] > 1e-3 and max(extent[0], extent[2]) > 1e-3)


@dataclass(frozen=True)
class _Style:
    """One object's choices shared by all its fronts (real furniture repeats one design)."""

    door_left: trimesh.Trimesh
    door_right: trimesh.Trimesh
    drawer: trimesh.Trimesh
    door_grip: tuple[str, trimesh.Trimesh]  # ("handle" | "knob", design)
    drawer_grip: tuple[str, trimesh.Trimesh]
    vertical: bool  # door handles stand vertical
    thickness: float
    fused: bool
    front: Material
    grip: Material


def _style(lib: PartLibrary, rng: np.random.Generator, notes: list[str], counts: tuple[int, int], budget: int,
           knob_chance: float, thickness: tuple[float, float], front: Material, grip: Material) -> _Style:
    """Designs drawn within ``budget`` faces for ``counts`` (doors, drawers), each with a grip."""
    doors, drawers = counts
    per_front = 0.5 * budget / max(1, doors + drawers)
    left_path, door_left = _pick(lib, "doorLs", rng, notes, per_front)
    twin = left_path.parent.parent / "doorRs" / left_path.name
    try:
        door_right = lib.mesh(twin) if twin in lib.files["doorRs"] else _pick(lib, "doorRs", rng, notes, per_front)[1]
    except BrokenPartError as e:
        _warn(notes, f"skipped: {e}")
        door_right = _pick(lib, "doorRs", rng, notes, per_front)[1]
    drawer = _pick(lib, "drawers", rng, notes, per_front)[1] if drawers else door_left
    used = doors * max(len(door_left.faces), len(door_right.faces)) + drawers * len(drawer.faces)
    per_grip = max(0.0, budget - used) / max(1, doors + drawers)
    door_kind = "knob" if rng.random() < knob_chance else "handle"
    door_grip = (door_kind, _pick(lib, door_kind + "s", rng, notes, per_grip, _stands_off)[1])
    drawer_kind = "knob" if rng.random() < knob_chance else "handle"
    drawer_grip = door_grip
    if drawers and (drawer_kind != door_kind or rng.random() < 0.4):
        drawer_grip = (drawer_kind, _pick(lib, drawer_kind + "s", rng, notes, per_grip, _stands_off)[1])
    return _Style(door_left, door_right, drawer, door_grip, drawer_grip, vertical=bool(rng.random() < 0.8),
                  thickness=float(rng.uniform(*thickness)), fused=bool(rng.random() < 0.7), front=front, grip=grip)


def _add_front(parts: _Parts, style: _Style, name: str, mesh: trimesh.Trimesh, joint: Joint,
               grip: tuple[str, trimesh.Trimesh] | None) -> None:
    if grip is not None and style.fused:
        mesh = trimesh.util.concatenate([mesh, grip[1]])
    pid = parts.add(name, mesh, style.front, parent=1, joint=joint)
    if grip is not None and not style.fused:
        parts.add(grip[0], grip[1], style.grip, parent=pid)


def _grip_size(rng: np.random.Generator, kind: str, along: float, across: float) -> float:
    """Length of a handle lying ``along`` a front side, or the width of a knob (which fits both sides)."""
    if kind == "knob":
        return float(min(rng.uniform(0.02, 0.045), 0.4 * along, 0.4 * across))
    return float(min(np.clip(rng.uniform(0.25, 0.5) * along, 0.06, 0.4), 0.5 * along))


def _door(parts: _Parts, style: _Style, rng: np.random.Generator, rect, y: float, hinge: str, outer: bool) -> None:
    """A door on ``rect`` (x0, x1, z0, z1) with its back at y, hinged at its ``hinge`` edge
    (left / right: vertical axis; bottom / top: a flap), its grip near the opposite edge. Only a
    door hinged at the body's outer edge (``outer``) swings past square: inside, a neighbour is in the way."""
    x0, x1, z0, z1 = rect
    t, w, h = style.thickness, x1 - x0, z1 - z0
    design = style.door_right if hinge == "right" else style.door_left
    if hinge in ("bottom", "top"):  # the panel's own hinge edge (its left) turned to the flap's hinge
        design = _turned(design, _rotation(-90.0 if hinge == "bottom" else 90.0, (0, 1, 0)))
    mesh = _fit(design, (x0, y - t, z0), (x1, y, z1))
    kind, grip_design = style.door_grip
    side = hinge in ("left", "right")
    horizontal = not side or not style.vertical
    size = _grip_size(rng, kind, w if horizontal else h, h if horizontal else w)
    grip = _grip(grip_design, size, horizontal)
    half = (grip.bounds[1] - grip.bounds[0]) / 2
    margin = float(np.clip(0.05 * min(w, h), 0.015, 0.05))
    if side:
        free = 1.0 if hinge == "left" else -1.0
        gx = (x0 + x1) / 2 + free * (w / 2 - margin - half[0])
        gz = (z0 + z1) / 2 + rng.uniform(-0.5, 0.5) * max(0.0, h / 2 - margin - half[2])
        pivot, axis = ((x0 if hinge == "left" else x1), y, (z0 + z1) / 2), (0.0, 0.0, -free)
        opening = rng.uniform(1.2, 2.0 if outer else 1.57)
    else:
        up = 1.0 if hinge == "bottom" else -1.0
        gx, gz = (x0 + x1) / 2, (z0 + z1) / 2 + up * (h / 2 - margin - half[2])
        pivot, axis = ((x0 + x1) / 2, y, z0 if hinge == "bottom" else z1), (up, 0.0, 0.0)
        opening = rng.uniform(1.0, 1.57) if hinge == "bottom" else rng.uniform(0.8, 1.4)
    joint = Joint("hinge", axis, tuple(float(v) for v in pivot), (0.0, float(opening)))
    _add_front(parts, style, "door", mesh, joint, (kind, _moved(grip, (gx, y - t, gz))))


def _drawer(parts: _Parts, style: _Style, rng: np.random.Generator, rect, y: float, depth: float) -> None:
    """A drawer on ``rect`` with its front flush with the doors (back of the front panel at y)."""
    x0, x1, z0, z1 = rect
    t, w, h = style.thickness, x1 - x0, z1 - z0
    length = float(rng.uniform(0.6, 0.9) * depth)
    mesh = _fit(style.drawer, (x0, y - t, z0), (x1, y - t + length, z1))
    kind, design = style.drawer_grip
    grip = _grip(design, _grip_size(rng, kind, w, h), horizontal=True)
    half = (grip.bounds[1] - grip.bounds[0]) / 2
    margin = float(np.clip(0.05 * h, 0.01, 0.05))
    gz = max((z0 + z1) / 2, z1 - margin - half[2] - rng.uniform(0.0, 0.25) * h)
    centre = tuple(float(v) for v in mesh.bounds.mean(axis=0))
    joint = Joint("slide", (0.0, -1.0, 0.0), centre, (0.0, float(rng.uniform(0.5, 0.9) * length)))
    _add_front(parts, style, "drawer", mesh, joint, (kind, _moved(grip, ((x0 + x1) / 2, y - t, gz))))


def _fronts(parts: _Parts, style: _Style, rng: np.random.Generator, opening: _Opening, slots) -> None:
    """Each slot (kind, (u0, u1, v0, v1)) in fractions of the opening, as doors or drawers."""
    y = opening.y - GAP
    for kind, cell in slots:
        x0, x1, z0, z1 = opening.cell(*cell)
        if kind == "drawer":
            _drawer(parts, style, rng, (x0, x1, z0, z1), y, opening.depth)
        elif kind == "pair":
            mid = (x0 + x1) / 2
            _door(parts, style, rng, (x0, mid - GAP, z0, z1), y, "left", cell[0] == 0.0)
            _door(parts, style, rng, (mid + GAP, x1, z0, z1), y, "right", cell[1] == 1.0)
        else:
            hinge = kind.removeprefix("door_")
            outer = (hinge == "left" and cell[0] == 0.0) or (hinge == "right" and cell[1] == 1.0)
            _door(parts, style, rng, (x0, x1, z0, z1), y, hinge, outer)


def _counts(slots) -> tuple[int, int]:
    drawers = sum(kind == "drawer" for kind, _ in slots)
    return sum(2 if kind == "pair" else 1 for kind, _ in slots) - drawers, drawers


def _grid(rng: np.random.Generator, w: float, h: float) -> list[tuple[float, float, float, float]]:
    """Cells of a front (u0, u1, v0, v1 in fractions, rows from the bottom): a grid of uneven rows and
    columns, one column's run of rows sometimes merged into a tall cell and some rows into one."""
    rows = min(int(rng.integers(1, 5)), max(1, int(h / 0.15)))
    cols = min(int(rng.integers(1, 4)), max(1, int(w / 0.25)))
    v = np.concatenate([[0.0], np.cumsum(rng.uniform(0.6, 1.4, rows))])
    u = np.concatenate([[0.0], np.cumsum(rng.uniform(0.7, 1.3, cols))])
    v, u = v / v[-1], u / u[-1]
    label = np.arange(rows * cols).reshape(rows, cols)
    tall: set[int] = set()
    if rows > 1 and rng.random() < 0.3:
        c, r0 = int(rng.integers(cols)), int(rng.integers(rows - 1))
        r1 = int(rng.integers(r0 + 1, rows))
        label[r0:r1 + 1, c] = label[r0, c]
        tall = set(range(r0, r1 + 1))
    for r in range(rows):
        if cols > 1 and r not in tall and rng.random() < 0.35:
            label[r, :] = label[r, 0]
    cells = []
    for name in np.unique(label):
        rs, cs = np.nonzero(label == name)
        cells.append((float(u[cs.min()]), float(u[cs.max() + 1]), float(v[rs.min()]), float(v[rs.max() + 1])))
    return sorted(cells, key=lambda c: (c[2], c[0]))


def _cabinet_slot(rng: np.random.Generator, cell, w: float, h: float) -> str:
    """What a cabinet cell holds, likelier drawers in low cells, door pairs in wide ones; a single
    door is hinged on the cabinet's outer side more often than not."""
    cw, ch = (cell[1] - cell[0]) * w, (cell[3] - cell[2]) * h
    weights = {"open": 0.35, "drawer": 3.0 if ch < 0.3 else (1.0 if ch < 0.6 else 0.15),
               "door": 2.0 if ch >= 0.25 else 0.3, "pair": 0.0 if cw < 0.3 else (1.5 if cw >= 0.5 else 0.3)}
    kind = list(weights)[rng.choice(len(weights), p=np.array(list(weights.values())) / sum(weights.values()))]
    if kind != "door":
        return kind
    left = 0.75 if cell[0] == 0.0 and cell[1] < 1.0 else (0.25 if cell[1] == 1.0 and cell[0] > 0.0 else 0.5)
    return "door_left" if rng.random() < left else "door_right"


def _cabinet(lib: PartLibrary, rng: np.random.Generator, notes: list[str], parts: _Parts) -> None:
    """A library frame stretched to a new size (or boards) whose front is a grid of cells, each a
    door, a pair of doors, a drawer or an open shelf."""
    w, d, h = rng.uniform(0.4, 1.6), rng.uniform(0.3, 0.65), rng.uniform(0.4, 2.0)
    body_material = _material(rng, {"Wood": 0.8, "Metal": 0.1, "Plastic": 0.1})
    front = body_material if rng.random() < 0.7 else _material(rng, {"Wood": 0.5, "Glass": 0.2, "Plastic": 0.2,
                                                                      "Metal": 0.1})
    grip = _material(rng, {"Metal": 0.7, "Plastic": 0.15, "Wood": 0.15})
    cells = _grid(rng, w, h)
    slots = [(kind, cell) for cell in cells if (kind := _cabinet_slot(rng, cell, w, h)) != "open"]
    if not slots:  # an object with nothing to move teaches nothing about joints
        slots = [("door_left" if rng.random() < 0.5 else "door_right",
                  max(cells, key=lambda c: (c[1] - c[0]) * (c[3] - c[2])))]
    built = _frame_body(lib, rng, notes, w, d, h) if rng.random() < 0.65 else None
    body, opening = built or _shell(w, d, h, rng.uniform(0.015, 0.03), rng.uniform(0.04, 0.12) * (rng.random() < 0.5))
    parts.add("body", body, body_material)
    style = _style(lib, rng, notes, _counts(slots), MAX_FACES - len(body.faces), 0.3, (0.015, 0.03), front, grip)
    _fronts(parts, style, rng, opening, slots)


def _appliance(lib: PartLibrary, rng: np.random.Generator, notes: list[str], parts: _Parts) -> None:
    """A microwave / safe (small), oven / dishwasher (mid) or fridge (tall) like box: one main door
    hinged at a side or a flap hinged at its bottom or top edge, a control panel strip, drawers below."""
    size = ("small", "mid", "tall")[rng.choice(3)]
    w, d, h = {"small": ((0.4, 0.65), (0.3, 0.5), (0.25, 0.45)), "mid": ((0.5, 0.9), (0.5, 0.7), (0.6, 0.95)),
               "tall": ((0.55, 0.95), (0.55, 0.8), (1.2, 1.95))}[size]
    w, d, h = rng.uniform(*w), rng.uniform(*d), rng.uniform(*h)
    shell = _material(rng, {"Metal": 0.6, "Plastic": 0.4})
    front = shell if rng.random() < 0.6 else _material(rng, {"Glass": 0.6, "Metal": 0.2, "Plastic": 0.2})
    grip = _material(rng, {"Metal": 0.6, "Plastic": 0.4})
    side_chance, bottom_chance = {"small": (0.6, 0.3), "mid": (0.3, 0.6), "tall": (0.9, 0.0)}[size]
    draw = rng.random()
    main = "door_left" if rng.random() < 0.5 else "door_right"
    if draw >= side_chance:
        main = "door_bottom" if draw < side_chance + bottom_chance else "door_top"
    u0, u1, v0, v1 = 0.0, 1.0, 0.0, 1.0
    slots, panels = [], []
    if size != "small" and rng.random() < 0.35:
        for _ in range(int(rng.integers(1, 3))):
            row = rng.uniform(0.12, 0.2) * (0.6 if size == "tall" else 1.0)
            halves = ((0.0, 0.5), (0.5, 1.0)) if w > 0.6 and rng.random() < 0.5 else ((0.0, 1.0),)
            slots += [("drawer", (a, b, v0, v0 + row)) for a, b in halves]
            v0 += row
    if size != "tall" and rng.random() < 0.45:
        if main in ("door_left", "door_right") and rng.random() < 0.6:  # a microwave's key panel beside the door
            strip = rng.uniform(0.2, 0.3)
            panels.append((1.0 - strip, 1.0, v0, v1) if main == "door_left" else (0.0, strip, v0, v1))
            u0, u1 = (0.0, 1.0 - strip) if main == "door_left" else (strip, 1.0)
        else:
            v1 = 1.0 - rng.uniform(0.1, 0.18)
            panels.append((0.0, 1.0, v1, 1.0))
    if size == "tall" and rng.random() < 0.5:  # fridge and freezer doors, one above the other
        split = v0 + rng.uniform(0.3, 0.45) * (v1 - v0)
        slots += [(main, (u0, u1, v0, split)), (main, (u0, u1, split, v1))]
    else:
        slots.append((main, (u0, u1, v0, v1)))
    built = _frame_body(lib, rng, notes, w, d, h) if rng.random() < 0.25 else None
    body, opening = built or _shell(w, d, h, rng.uniform(0.02, 0.05), rng.uniform(0.03, 0.08) * (rng.random() < 0.3))
    for cell in panels:  # the strip's board, flush with the body's front plane
        x0, x1, z0, z1 = opening.cell(*cell)
        body = trimesh.util.concatenate([body, _box((x0 - GAP, opening.y, z0 - GAP),
                                                    (x1 + GAP, opening.y + 0.02, z1 + GAP))])
    parts.add("body", body, shell)
    style = _style(lib, rng, notes, _counts(slots), MAX_FACES - len(body.faces), 0.05, (0.03, 0.06), front, grip)
    _fronts(parts, style, rng, opening, slots)


def _chest(lib: PartLibrary, rng: np.random.Generator, notes: list[str], parts: _Parts) -> None:
    """A box open at the top (boards, or a clean library frame turned to face up) and a lid from a
    door panel laid flat, hinged at its back edge, with a handle on top near its front edge or none."""
    w, d, h, t = rng.uniform(0.4, 1.2), rng.uniform(0.3, 0.7), rng.uniform(0.25, 0.7), rng.uniform(0.012, 0.03)
    material = _material(rng, {"Wood": 0.6, "Plastic": 0.2, "Metal": 0.2})
    lid_material = material if rng.random() < 0.8 else _material(rng, {"Wood": 0.6, "Plastic": 0.2, "Metal": 0.2})
    body = None
    if rng.random() < 0.4:
        def clean(m: trimesh.Trimesh) -> bool:  # nothing sticking out beyond the opening: it would stand above the lid
            lo, hi = m.bounds
            return hi[1] > 0.3 and lo[1] > -0.01 and min(lo[0], lo[2]) > -0.06 and max(hi[0], hi[2]) < 1.06
        try:
            _, frame = _pick(lib, "cabinet_frames", rng, notes, 0.4 * MAX_FACES, clean)
            up = _turned(frame, _FACE_UP)  # x in [0, 1], y in [0, 1], z in [-depth, 0]
            body = _fit(up, (-w / 2, -d / 2, 0.0), (w / 2, d / 2, h))
        except BrokenPartError as e:
            _warn(notes, f"a procedural body instead: {e}")
    if body is None:
        body = trimesh.util.concatenate([
            _box((-w / 2, -d / 2, 0), (w / 2, d / 2, t)), _box((-w / 2, -d / 2, t), (-w / 2 + t, d / 2, h)),
            _box((w / 2 - t, -d / 2, t), (w / 2, d / 2, h)), _box((-w / 2 + t, -d / 2, t), (w / 2 - t, -d / 2 + t, h)),
            _box((-w / 2 + t, d / 2 - t, t), (w / 2 - t, d / 2, h))])
    parts.add("body", body, material)
    style = _style(lib, rng, notes, (1, 0), MAX_FACES - len(body.faces), 0.4, (0.015, 0.04), lid_material,
                   _material(rng, {"Metal": 0.7, "Plastic": 0.3}))
    overhang = rng.uniform(0.0, 0.025)
    (bx0, by0, _), (bx1, by1, top) = body.bounds
    x0, x1, y0, y1, z0 = bx0 - overhang, bx1 + overhang, by0 - overhang, by1, top + GAP
    lid = _fit(_turned(style.door_left, _FACE_UP), (x0, y0, z0), (x1, y1, z0 + style.thickness))
    grip = None
    if rng.random() < 0.5:
        kind, design = style.door_grip
        flat = _grip(design, _grip_size(rng, kind, x1 - x0, y1 - y0), horizontal=True)
        depth = (flat.bounds[1][2] - flat.bounds[0][2]) / 2  # the grip's height on a front: its depth on the lid
        offset = ((x0 + x1) / 2, y0 + float(np.clip(0.08 * (y1 - y0), 0.02, 0.06)) + depth, z0 + style.thickness)
        grip = (kind, _moved(_turned(flat, _FACE_UP), offset))
    joint = Joint("hinge", (-1.0, 0.0, 0.0), ((x0 + x1) / 2, y1, z0), (0.0, float(rng.uniform(1.2, 1.9))))
    _add_front(parts, style, "lid", lid, joint, grip)


_LAYOUTS = {"cabinet": _cabinet, "appliance": _appliance, "chest": _chest}


def composed_source(seed: int, library: PartLibrary | Path | str, object_id: str | None = None) -> SourceObject:
    """Object ``seed`` composed from ``library`` (a PartLibrary or its folder): the same seed and
    library give the same object. Category ``composed_<layout>``; library files passed over are
    named in ``warnings``."""
    lib = library if isinstance(library, PartLibrary) else PartLibrary.open(library)
    rng = derived_rng("composed", seed)
    layout = LAYOUTS[rng.choice(len(LAYOUTS), p=(0.55, 0.3, 0.15))]
    notes: list[str] = []
    parts = _Parts()
    _LAYOUTS[layout](lib, rng, notes, parts)
    structure, meshes, size = parts.normalised()
    category = f"composed_{layout}"
    return SourceObject(category, object_id or f"{category}_{int(seed):06d}", structure, meshes, size,
                        warnings=tuple(notes))
