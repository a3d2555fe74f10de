"""Thin parts passing through each other while a joint sweeps: what contact depth cannot see.

A contact's depth is the shortest move that separates two convex pieces, so a thin panel driven
right through another (a laptop screen folded through its base, a lid swung through a wall) is
never deeper than the thinner panel: below ``PENETRATION_TOL_NU`` for boards a few hundredths of
the object thick. Here a moved part *passes through* a board (a thin connected component of another
part, in its own oriented box, at most ``BOARD_MAX_THICKNESS_NU`` thick) when, along the joint's path
from rest, one of its points goes from more than ``CROSSING_MARGIN_NU`` beyond one face to more than
that beyond the other, meeting the board's plane over its material (a cell of its face the board
covers, a cell in from its edges: not a ring's hole, nor round a rim's edge). A board may also be
a thin convex collision piece of a part modelled as one closed mesh (a bucket's wall); where such a
piece meets another piece of its part (a carcass's back wall on its floor) the wall goes on, so
that edge is no edge to pass round (a turntable swung out through the corner). The
moving part may be the board (a door leaf swung through a handle that stays). Parts lying across
a board's plane at rest (a sash in its frame, a shaft through its panel) are left alone. Pure numpy on the
rest-frame meshes; joint values as in the sweep (rad / nu), every other joint at rest.

A part's boards and surface points depend on its rest-frame mesh (and pieces) alone, and finding
them (an oriented box per component and piece) was 70 % of a verdict: the K candidates of one
object, and a repair's alternatives, share their parts, so they are kept per content digest in the
process (the last ``CACHE_ENTRIES`` parts: three entries each, its mesh's boards, its pieces' boards and
its surface points), read-only, the same arrays a fresh computation gives; and on disk beside the
collision pieces (``geometry.piece_disk_cache``, keyed also by this file's source), so a repeated
command on the same objects finds none of them again.
"""

from __future__ import annotations

import functools
import hashlib
import threading
from collections import OrderedDict
from collections.abc import Callable, Sequence
from dataclasses import dataclass
from pathlib import Path

import numpy as np
import trimesh
from scipy.ndimage import binary_erosion
from scipy.spatial.transform import Rotation

from jax3dc.geometry import piece_disk_cache
from jax3dc.physics.tolerances import CROSSING_MARGIN_NU
from jax3dc.structure.schema import Joint, Structure

MAX_BOARDS_PER_PART = 128  # beyond this a part counts as one component (its oriented box)
SURFACE_SAMPLES = 600  # points per moved part
MIN_BOARD_NU = 0.05  # boards smaller than this across their face are left out (screws, hinge pins)
CROSSING_CELL_NU = 0.03  # resolution of a board's face map (where its material is)
FLUSH_NU = 0.005  # a point this close to a board's face at rest is flush with it, not past it
CROSSING_STEP_NU = 0.02  # largest point travel between the path states checked (a board's margin)
JOIN_GAP_NU = 0.01  # a collision piece this close beyond a piece board's edge, across its thickness, continues the wall
BOARD_MAX_THICKNESS_NU = 0.06  # thicker components are not boards: a part through them is deeper than
# PENETRATION_TOL_NU, and a bulky concave one (a bucket as one mesh) is straddled, not crossed
CACHE_ENTRIES = 512  # parts whose boards and surface points stay in memory (see the module docstring)


@dataclass(frozen=True)
class Board:
    """A thin component in its oriented box: centre, axes (rows, thin axis first), half extents,
    which CROSSING_CELL_NU cells of its face its material covers (less a cell at its free edges),
    and how far inside each edge a crossing must meet its plane."""

    centre: np.ndarray
    axes: np.ndarray
    half: np.ndarray
    covered: np.ndarray  # [n_u, n_w] bool
    inset: np.ndarray  # [2 (u, w), 2 (low, high edge)]: CROSSING_MARGIN_NU at a free edge, 0 where the wall goes on

    def cells_of(self, uw: np.ndarray) -> np.ndarray:
        grid = np.zeros(self.covered.shape, dtype=bool)
        index = np.floor((uw + self.half[1:]) / CROSSING_CELL_NU).astype(int)
        index = np.clip(index, 0, np.array(self.covered.shape) - 1)
        grid[index[:, 0], index[:, 1]] = True
        return grid


@dataclass(frozen=True)
class Track:
    """Points carried along one joint path: rest points [n, 3] (object frame, nu) and the joint's
    values [S] from just past rest outwards (the path's states; rest is not among them)."""

    joint: Joint
    values: np.ndarray
    rest: np.ndarray

    def posed(self) -> np.ndarray:
        """[S, n, 3]: the points at each state (``_path``)."""
        return _path(self.joint, self.values, self.rest)


@dataclass(frozen=True)
class Direction:
    """One direction of one jointed part's sweep: its path's values and the (query, other part)
    pairs checked along it, in the order that breaks a tie at one state (boards of the parts that
    stay first, then the carried ones)."""

    part: int
    path: np.ndarray
    hits: tuple[tuple[int, int], ...]


@dataclass(frozen=True)
class CrossingPlan:
    """A board-crossing check as data (``crossing_plan``): the tracks, the (track, board) queries
    whose first crossing state decides it, and how those states become the answer (``resolve``).
    The queries are the whole numeric cost: numpy answers them (``first_crossings``), or a batched
    evaluator (``crossing_batch``) those of many plans at once."""

    tracks: tuple[Track, ...]
    queries: tuple[tuple[int, Board], ...]  # (index into tracks, board)
    directions: tuple[Direction, ...]
    sweeps: dict[int, np.ndarray]

    def resolve(self, first: Sequence[int | None]) -> dict[int, tuple[int, float]]:
        """Per jointed part of the sweeps: (other part, joint value) of the first value of its sweep
        (in the given order) by which the subtree its joint moves has passed through a board of
        another part, or a board of the subtree through another part (absent: never), given each
        query's first crossing state (None: never)."""
        reached: dict[int, dict[float, int]] = {}  # per part: the value at which each direction first crosses -> part
        for d in self.directions:
            crossed = [(first[q], n, p) for n, (q, p) in enumerate(d.hits) if first[q] is not None]
            if crossed:
                state, _, p = min(crossed)
                reached.setdefault(d.part, {})[float(d.path[state])] = p
        out = {}
        for part, values in self.sweeps.items():
            at = reached.get(part, {})
            for v in values:  # the first of the given values that lies at or past a crossing
                past = [c for c in at if (c > 0 and v >= c - 1e-12) or (c < 0 and v <= c + 1e-12)]
                if past:
                    out[part] = (at[past[0]], float(v))
                    break
        return out


def first_crossings(plan: CrossingPlan) -> list[int | None]:
    """Each query's first crossing state, in numpy (each track posed once)."""
    posed: dict[int, np.ndarray] = {}
    out = []
    for t, board in plan.queries:
        if t not in posed:
            posed[t] = plan.tracks[t].posed()
        out.append(_first_crossing(board, plan.tracks[t].rest, posed[t]))
    return out


def crossing_plan(structure: Structure, parts: dict[int, trimesh.Trimesh], sweeps: dict[int, np.ndarray],
                  pieces: dict[int, list[np.ndarray]] | None = None) -> CrossingPlan:
    """The board-crossing check of ``sweeps`` (per jointed part, its joint values in the order they
    are tried) as a plan, its boards and surfaces found (or read from this process's cache) on the
    way. The path from rest to each value is followed in steps of at most CROSSING_STEP_NU of point
    travel, so a part that goes round a board's edge is not crossing it.

    ``pieces``: per part, the vertices (object frame, nu) of its convex collision pieces; the thin
    ones are boards too (the walls of a bucket or carcass modelled as one closed mesh)."""
    boards = {p: _mesh_boards(mesh) + _cached_piece_boards((pieces or {}).get(p, [])) for p, mesh in parts.items()}
    surfaces = {p: _cached_surface(mesh) for p, mesh in parts.items()}
    tracks: list[Track] = []
    queries: list[tuple[int, Board]] = []
    directions: list[Direction] = []
    for part, values in sweeps.items():
        joint = structure.nodes[part].joint
        moved = structure.subtree(part)
        points = np.concatenate([surfaces[p] for p in sorted(moved)])
        still = [p for p in sorted(structure.nodes) if p not in moved]
        candidates = [(p, b) for p in still for b in boards[p]]
        # ... and a moving board through a part that stays (a door swung through a handle left on
        # the frame): in the board's own frame that part's points move back along the path
        carried = [(q, b) for q in sorted(moved) for b in boards[q]]
        if not candidates and not carried:
            continue
        everything = np.concatenate([points] + [surfaces[p] for p in still]) if carried else points
        reach = float(np.max(np.linalg.norm(everything - np.asarray(joint.pivot), axis=1))) if joint.type == "hinge" else 1.0
        for end in (max(float(np.max(values)), 0.0), min(float(np.min(values)), 0.0)):
            steps = int(np.ceil(abs(end) * reach / CROSSING_STEP_NU))
            if steps == 0:
                continue
            path = np.linspace(0.0, end, steps + 1)[1:]
            hits = []

            def query(track: int, board: Board, other: int) -> None:
                hits.append((len(queries), other))
                queries.append((track, board))

            tracks.append(Track(joint, path, points))
            for p, b in candidates:
                if not _straddles(points, b):
                    query(len(tracks) - 1, b, p)
            if carried:
                for p in still:
                    tracks.append(Track(joint, -path, surfaces[p]))
                    for _, b in carried:
                        if not _straddles(surfaces[p], b):
                            query(len(tracks) - 1, b, p)
            directions.append(Direction(part, path, tuple(hits)))
    return CrossingPlan(tuple(tracks), tuple(queries), tuple(directions), sweeps)


def _straddles(points: np.ndarray, board: Board) -> bool:
    """The part lies across the board's plane at rest (a sash in its frame, a shaft through its
    panel): it has no one side to pass from."""
    t = (points - board.centre) @ board.axes[0]
    return bool(t.max() > board.half[0] + FLUSH_NU and t.min() < -board.half[0] - FLUSH_NU)


def _path(joint: Joint, values: np.ndarray, points: np.ndarray) -> np.ndarray:
    """[len(values), n, 3]: ``points`` moved by ``joint`` to each value (``joint_motion`` at once)."""
    axis = np.asarray(joint.axis, dtype=np.float64)
    axis = axis / np.linalg.norm(axis)
    if joint.type == "slide":
        return points[None] + values[:, None, None] * axis
    pivot = np.asarray(joint.pivot, dtype=np.float64)
    turns = Rotation.from_rotvec(values[:, None] * axis).as_matrix()
    return (points - pivot) @ turns.transpose(0, 2, 1) + pivot


def _first_crossing(board: Board, rest: np.ndarray, posed: np.ndarray) -> int | None:
    """The first state of ``posed`` [S, n, 3] (the points ``rest`` [n, 3] along a path) at which
    one of them passes through ``board``; None: none does.

    Each point's side is where it was last seen clearly beyond a face (CROSSING_MARGIN_NU past it,
    or outside the board at all at rest); a point next seen beyond the other face went through the
    board's plane in between, over its material if the line between the two sightings meets the
    plane over a covered cell, inside the insets of the board's edges."""
    centre, axes, half = board.centre, board.axes, board.half
    limit = half[0] + CROSSING_MARGIN_NU
    at_rest = (rest - centre) @ axes.T
    thin = (posed - centre) @ axes[0]  # [S, n]
    side = np.where(thin > limit, 1, np.where(thin < -limit, -1, 0))
    # row 0 is the rest pose: every point is seen there, on a side only if outside the board at all
    sides = np.concatenate([np.where(np.abs(at_rest[:, 0]) > half[0], np.sign(at_rest[:, 0]), 0)[None].astype(int), side])
    rows = np.arange(len(sides))[:, None]
    last = np.maximum.accumulate(np.where(np.concatenate([np.ones_like(side[:1], bool), side != 0]), rows, 0), axis=0)
    before = last[:-1]  # per state, the row each point was last seen in
    was = np.take_along_axis(sides, before, axis=0)
    state, point = np.nonzero((side != 0) & (was != 0) & (side != was))
    if not len(state):
        return None
    seen = before[state, point]
    a = np.where((seen == 0)[:, None], at_rest[point], (posed[np.maximum(seen - 1, 0), point] - centre) @ axes.T)
    b = (posed[state, point] - centre) @ axes.T
    w = (a[:, 0] / (a[:, 0] - b[:, 0]))[:, None]
    met = a[:, 1:] + w * (b[:, 1:] - a[:, 1:])  # where each point met the mid-plane
    inside = np.all((met >= -half[1:] + board.inset[:, 0]) & (met <= half[1:] - board.inset[:, 1]), axis=1)
    cell = np.clip(np.floor((met + half[1:]) / CROSSING_CELL_NU).astype(int), 0, np.array(board.covered.shape) - 1)
    through = inside & board.covered[cell[:, 0], cell[:, 1]]
    return int(state[through].min()) if through.any() else None


_cache: OrderedDict[bytes, object] = OrderedDict()
_cache_lock = threading.Lock()


def _memo(kind: str, arrays: Sequence[np.ndarray], compute: Callable[[], object]) -> object:
    """``compute()``, once per ``kind``, content of ``arrays`` and the module's constants (read at
    call time, so a changed constant never returns older boards) in this process, and, with the
    disk cache on (``geometry.piece_disk_cache``), once on this machine."""
    digest = hashlib.blake2b(kind.encode(), digest_size=32)
    digest.update(np.asarray([MAX_BOARDS_PER_PART, SURFACE_SAMPLES, MIN_BOARD_NU, CROSSING_CELL_NU, FLUSH_NU,
                              JOIN_GAP_NU, BOARD_MAX_THICKNESS_NU, CROSSING_MARGIN_NU], dtype=np.float64).tobytes())
    for array in arrays:
        array = np.ascontiguousarray(array)
        digest.update(f"{array.dtype.str}{array.shape}".encode())
        digest.update(array.tobytes())
    key = digest.digest()
    with _cache_lock:
        if key in _cache:
            _cache.move_to_end(key)
            return _cache[key]
    encode, decode, names = _CODECS[kind]
    stored = piece_disk_cache.load_arrays(key, _disk_version(), names)
    value = None if stored is None else decode(stored)
    if value is None:
        value = compute()
        piece_disk_cache.save_arrays(key, _disk_version(), encode(value))
    with _cache_lock:
        _cache[key] = value
        while len(_cache) > 3 * CACHE_ENTRIES:
            _cache.popitem(last=False)
    return value


@functools.cache
def _disk_version() -> bytes:
    """What computes the boards and surface points (this file) and stores them (the pieces' code
    version: the disk format and the libraries' versions)."""
    return hashlib.blake2b(Path(__file__).read_bytes() + piece_disk_cache.code_version(), digest_size=32).digest()


def _encode_boards(boards: tuple[Board, ...]) -> dict[str, np.ndarray]:
    return {"centre": np.asarray([b.centre for b in boards]).reshape(-1, 3),
            "axes": np.asarray([b.axes for b in boards]).reshape(-1, 3, 3),
            "half": np.asarray([b.half for b in boards]).reshape(-1, 3),
            "inset": np.asarray([b.inset for b in boards], dtype=np.float64).reshape(-1, 2, 2),
            "cells": np.asarray([b.covered.shape for b in boards], dtype=np.int64).reshape(-1, 2),
            "covered": np.concatenate([b.covered.reshape(-1) for b in boards]) if boards else np.zeros(0, bool)}


def _decode_boards(e: dict[str, np.ndarray]) -> tuple[Board, ...] | None:
    """The stored boards, or None where the entry does not hold boards (a miss)."""
    n = len(e["centre"])
    shapes = {"centre": (n, 3), "axes": (n, 3, 3), "half": (n, 3), "inset": (n, 2, 2), "cells": (n, 2)}
    if any(e[k].shape != shape or e[k].dtype.kind != ("i" if k == "cells" else "f") for k, shape in shapes.items()):
        return None
    sizes = np.prod(e["cells"], axis=1)
    if e["covered"].dtype != bool or e["covered"].ndim != 1 or np.any(e["cells"] < 1) or sizes.sum() != len(e["covered"]):
        return None
    covered = np.split(e["covered"], np.cumsum(sizes)[:-1]) if n else []
    return _shared_boards([Board(e["centre"][i], e["axes"][i], e["half"][i], covered[i].reshape(e["cells"][i]), e["inset"][i])
                           for i in range(n)])


def _decode_surface(e: dict[str, np.ndarray]) -> np.ndarray | None:
    points = e["points"]
    if points.dtype != np.float64 or points.ndim != 2 or points.shape[1] != 3:
        return None
    _read_only(points)
    return points


_CODECS = {"boards": (_encode_boards, _decode_boards, ("centre", "axes", "half", "inset", "cells", "covered")),
           "piece boards": (_encode_boards, _decode_boards, ("centre", "axes", "half", "inset", "cells", "covered")),
           "surface": (lambda points: {"points": points}, _decode_surface, ("points",))}


def _read_only(*arrays: np.ndarray) -> None:
    for array in arrays:
        array.setflags(write=False)


def _shared_boards(boards: list[Board]) -> tuple[Board, ...]:
    for b in boards:
        _read_only(b.centre, b.axes, b.half, b.covered, b.inset)
    return tuple(boards)


def _mesh_key(mesh: trimesh.Trimesh) -> tuple[np.ndarray, np.ndarray]:
    return np.asarray(mesh.vertices, dtype=np.float64), np.asarray(mesh.faces, dtype=np.int64)


def _mesh_boards(mesh: trimesh.Trimesh) -> list[Board]:
    """``_boards(mesh)``, shared (see the module docstring)."""
    return list(_memo("boards", _mesh_key(mesh), lambda: _shared_boards(_boards(mesh))))


def _cached_piece_boards(pieces: list[np.ndarray]) -> list[Board]:
    """``_piece_boards(pieces)``, shared: keyed by every piece, since each board's edges depend on the others."""
    arrays = [np.asarray(v, dtype=np.float64) for v in pieces]
    return list(_memo("piece boards", arrays, lambda: _shared_boards(_piece_boards(arrays))))


def _cached_surface(mesh: trimesh.Trimesh) -> np.ndarray:
    """``_surface(mesh)``, shared and read-only."""
    def compute() -> np.ndarray:
        points = _surface(mesh)
        _read_only(points)
        return points
    return _memo("surface", _mesh_key(mesh), compute)


def _surface(mesh: trimesh.Trimesh) -> np.ndarray:
    vertices = np.asarray(mesh.vertices, dtype=np.float64)
    if not len(mesh.faces):
        return vertices.copy()
    return np.concatenate([vertices[:: max(1, len(vertices) // SURFACE_SAMPLES)],
                           np.asarray(mesh.sample(SURFACE_SAMPLES, seed=0), dtype=np.float64)])


def _boards(mesh: trimesh.Trimesh) -> list[Board]:
    """The thin connected components of ``mesh`` (see BOARD_MAX_THICKNESS_NU, MIN_BOARD_NU)."""
    components = mesh.split(only_watertight=False) if len(mesh.faces) else []
    if not components or len(components) > MAX_BOARDS_PER_PART:
        components = [mesh]
    out = []
    for c in components:
        v = np.asarray(c.vertices, dtype=np.float64)
        frame = _thin_frame(v)
        if frame is None:
            continue
        centre, axes, half = frame
        shape = np.maximum(1, np.ceil(2 * half[1:] / CROSSING_CELL_NU).astype(int))
        inset = np.full((2, 2), CROSSING_MARGIN_NU)
        empty = Board(centre, axes, half, np.zeros(shape, dtype=bool), inset)
        material = np.concatenate([v, np.asarray(c.sample(2000, seed=0), dtype=np.float64)]) if len(c.faces) else v
        # one cell in from the material's edges: passing a rim's edge is not passing through it
        covered = binary_erosion(empty.cells_of(((material - centre) @ axes.T)[:, 1:]), np.ones((3, 3)), border_value=0)
        out.append(Board(centre, axes, half, covered, inset))
    return out


def _piece_boards(pieces: list[np.ndarray]) -> list[Board]:
    """The thin convex collision pieces of a part as boards: convex, each covers its whole face but
    a cell at each free edge (an edge where another piece goes on is not free, see ``_joined``)."""
    out = []
    pieces = [np.asarray(v, dtype=np.float64) for v in pieces]
    for i, v in enumerate(pieces):
        frame = _thin_frame(v)
        if frame is None:
            continue
        centre, axes, half = frame
        shape = np.maximum(1, np.ceil(2 * half[1:] / CROSSING_CELL_NU).astype(int))
        joined = _joined(centre, axes, half, [w for j, w in enumerate(pieces) if j != i])
        covered = np.ones(shape, dtype=bool)
        for end, index in ((0, 0), (1, -1)):
            if not joined[0, end]:
                covered[index, :] = False
            if not joined[1, end]:
                covered[:, index] = False
        out.append(Board(centre, axes, half, covered, np.where(joined, 0.0, CROSSING_MARGIN_NU)))
    return out


def _joined(centre: np.ndarray, axes: np.ndarray, half: np.ndarray, others: list[np.ndarray]) -> np.ndarray:
    """[2 (u, w), 2 (low, high)] bool: another piece lies across the board's thickness and along
    its edge, reaching from within JOIN_GAP_NU of that edge on past it (the wall goes on there)."""
    out = np.zeros((2, 2), dtype=bool)
    for v in others:
        local = (v - centre) @ axes.T
        lo, hi = local.min(axis=0), local.max(axis=0)
        if hi[0] < -half[0] or lo[0] > half[0]:
            continue  # not across the board's thickness
        for axis in (1, 2):
            along = 3 - axis  # the in-plane axis running along this edge
            if hi[along] < -half[along] or lo[along] > half[along]:
                continue
            out[axis - 1, 0] |= bool(lo[axis] < -half[axis] and hi[axis] >= -half[axis] - JOIN_GAP_NU)
            out[axis - 1, 1] |= bool(hi[axis] > half[axis] and lo[axis] <= half[axis] + JOIN_GAP_NU)
    return out


def _thin_frame(v: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray] | None:
    """(centre, axes (rows, thin axis first), half extents) of the points' oriented box when it is
    a board (see BOARD_MAX_THICKNESS_NU, MIN_BOARD_NU); None otherwise."""
    if len(v) < 4:
        return None
    try:  # trimesh divides by the zero volume of a flat component's hull on the way
        with np.errstate(invalid="ignore", divide="ignore"):
            transform, extents = trimesh.bounds.oriented_bounds(v)
    except Exception:  # qhull: a flat or degenerate component
        return None
    order = np.argsort(extents)
    half = extents[order] / 2
    if half[1] * 2 < MIN_BOARD_NU or half[0] * 2 > BOARD_MAX_THICKNESS_NU:
        return None
    to_local = transform[:3, :3]  # rows: the box axes in the mesh frame
    return -to_local.T @ transform[:3, 3], to_local[order], half
