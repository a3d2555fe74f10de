"""The board-crossing queries of many verdicts in one compiled launch (``crossing``'s numeric cost).

``crossing.crossing_plan`` turns a verdict's crossing check into data: tracks (points carried
along a joint path) and (track, board) queries whose first crossing state decides the answer.
Here the queries of many plans (the K candidates of an object, the objects of a batch) are
answered at once: each track's points are cut into chunks of ``CHUNK_POINTS`` (a point's crossing
is its own, so a query's first state is the earliest of its chunks'), an item is (chunk, track,
board), and one function poses a chunk along its path and finds the first state at which a point
passes through the board, the rule of ``crossing._first_crossing``. The tables are padded to
capacities that only grow (from ``launch_start.CROSSINGS`` on an accelerator: a run compiles once or
twice, and a repeated one, its executables in the persistent cache, never), and the launch loops
over the real items alone, ``ITEMS_PER_STEP`` at a time, so a large capacity costs no time; the
states of a track are padded to a power of two from 32 (at most a few compiles), since every item
poses all of them. Padded states and points are never seen on a side, so they cross nothing.

The launch runs in float32 (a board's coordinates are taken from its centre, so a point's error is
~1e-7 nu against margins of 0.05 nu); ``tests/physics/test_physics_crossing_batch.py`` checks its
states against the numpy path's on factory objects' candidates.
"""

from __future__ import annotations

import dataclasses
import time
from collections.abc import Sequence
from dataclasses import dataclass
from typing import NamedTuple

import jax
import jax.numpy as jnp
import numpy as np

from jax3dc.physics.crossing import CROSSING_CELL_NU, CrossingPlan
from jax3dc.physics.mjx_batch import size_class
from jax3dc.physics.tolerances import CROSSING_MARGIN_NU

CHUNK_POINTS = 512  # points per item: a track of more is several items
ITEMS_PER_STEP = 64  # items posed at once inside the launch (memory: states x CHUNK_POINTS x 3 floats each)
NEVER = np.iinfo(np.int32).max


@dataclass(frozen=True)
class CrossingShapes:
    """The padded sizes a launch is compiled for."""

    items: int = 0
    chunks: int = 0
    tracks: int = 0
    boards: int = 0
    states: int = 0
    cells: tuple[int, int] = (0, 0)

    def grown(self, other: "CrossingShapes") -> "CrossingShapes":
        """The larger of each size (the states excepted: each launch pads its own, see the module docstring)."""
        big = CrossingShapes(*(tuple(max(x, y) for x, y in zip(a, b)) if isinstance(a, tuple) else max(a, b)
                               for a, b in zip(dataclasses.astuple(self), dataclasses.astuple(other))))
        return dataclasses.replace(big, states=other.states)


class Chunks(NamedTuple):
    """Points of tracks, ``CHUNK_POINTS`` a row, at rest (float32, nu)."""

    points: np.ndarray  # [chunks, CHUNK_POINTS, 3]
    mask: np.ndarray  # [chunks, CHUNK_POINTS] the real points


class Tracks(NamedTuple):
    """A joint path per track: the states its points are posed at."""

    hinge: np.ndarray  # [tracks] hinge (else slide)
    axis: np.ndarray  # [tracks, 3] unit joint axis
    pivot: np.ndarray  # [tracks, 3] hinge anchor
    values: np.ndarray  # [tracks, states] joint values (padded states are never seen)
    counts: np.ndarray  # [tracks] the real states


class Boards(NamedTuple):
    """The boards of the queries (``crossing.Board``), padded to ``CrossingShapes.cells``."""

    centre: np.ndarray  # [boards, 3]
    frame: np.ndarray  # [boards, 3, 3] rows: the board's axes, the thin one first
    half: np.ndarray  # [boards, 3] half sizes along them
    inset: np.ndarray  # [boards, 2, 2] the covered area's insets from each end of the two long axes
    covered: np.ndarray  # [boards, cells0, cells1] which cells the board covers
    cell_shape: np.ndarray  # [boards, 2] the real cells


class CrossingTables(NamedTuple):
    """What one launch reads (a pytree: JAX flattens the named tuples): the items' tables and, per
    item, (chunk, track, board) rows; only the first ``steps`` x ITEMS_PER_STEP items are computed."""

    chunks: Chunks
    tracks: Tracks
    boards: Boards
    table: np.ndarray  # [items, 3] int32
    steps: np.int32


def batch_first_crossings(plans: Sequence[CrossingPlan], at_least: CrossingShapes | None = None,
                          timings: dict[str, float] | None = None) -> tuple[list[list[int | None]], CrossingShapes]:
    """Each plan's queries' first crossing states (None: never), as ``crossing.first_crossings``
    gives them, and the shapes the launch was padded to (pass them back as ``at_least``)."""
    start = time.perf_counter()
    at_least = at_least or CrossingShapes()
    if not any(p.queries for p in plans):
        return [[] for _ in plans], at_least
    host, shapes, owners = _host_arrays(plans, at_least)
    state = np.asarray(_launch(host))[:len(owners)]
    first = np.full(sum(len(p.queries) for p in plans), NEVER, np.int64)
    np.minimum.at(first, owners, state)
    out, at = [], 0
    for p in plans:
        out.append([None if s == NEVER else int(s) for s in first[at:at + len(p.queries)]])
        at += len(p.queries)
    if timings is not None:
        timings["crossings"] = timings.get("crossings", 0.0) + time.perf_counter() - start
    return out, shapes


def _host_arrays(plans: Sequence[CrossingPlan], at_least: CrossingShapes
                 ) -> tuple[CrossingTables, CrossingShapes, np.ndarray]:
    """The padded tables of a launch, its shapes and, per real item, the query (numbered over all
    plans) it answers."""
    chunks, chunk_mask, track_rows, boards, items, owners = [], [], [], [], [], []
    board_row: dict[int, int] = {}  # id(board) -> its row: the candidates of an object share their parts' boards
    query_base = 0
    for plan in plans:
        track_chunks = []
        for track in plan.tracks:
            first = len(chunks)
            for c in range(0, max(1, len(track.rest)), CHUNK_POINTS):
                part = track.rest[c:c + CHUNK_POINTS]
                block = np.zeros((CHUNK_POINTS, 3))
                block[:len(part)] = part
                chunks.append(block)
                chunk_mask.append(np.arange(CHUNK_POINTS) < len(part))
            track_chunks.append((first, len(chunks)))
            axis = np.asarray(track.joint.axis, dtype=np.float64)
            track_rows.append((track.joint.type == "hinge", axis / np.linalg.norm(axis),
                               np.asarray(track.joint.pivot, dtype=np.float64), track.values))
        track_base = len(track_rows) - len(plan.tracks)
        for q, (t, board) in enumerate(plan.queries):
            b = board_row.setdefault(id(board), len(boards))
            if b == len(boards):
                boards.append(board)
            for c in range(*track_chunks[t]):
                items.append((c, track_base + t, b))
                owners.append(query_base + q)
        query_base += len(plan.queries)
    states = max((len(r[3]) for r in track_rows), default=1)
    need = CrossingShapes(
        items=_power(len(items), ITEMS_PER_STEP), chunks=size_class(len(chunks)), tracks=size_class(len(track_rows)),
        boards=size_class(len(boards)), states=_power(states, 32),
        cells=tuple(size_class(max((b.covered.shape[i] for b in boards), default=1)) for i in (0, 1)))
    shapes = at_least.grown(need)
    f32 = np.float32
    points = np.zeros((shapes.chunks, CHUNK_POINTS, 3), f32)
    points[:len(chunks)] = chunks
    point_mask = np.zeros((shapes.chunks, CHUNK_POINTS), bool)
    point_mask[:len(chunks)] = chunk_mask
    hinge = np.zeros(shapes.tracks, bool)
    axes_ = np.zeros((shapes.tracks, 3), f32)
    axes_[:, 2] = 1.0
    pivots = np.zeros((shapes.tracks, 3), f32)
    values = np.zeros((shapes.tracks, shapes.states), f32)
    counts = np.zeros(shapes.tracks, np.int32)
    for i, (is_hinge, axis, pivot, vals) in enumerate(track_rows):
        hinge[i], axes_[i], pivots[i], counts[i] = is_hinge, axis, pivot, len(vals)
        values[i, :len(vals)] = vals
    centre = np.zeros((shapes.boards, 3), f32)
    frame = np.tile(np.eye(3, dtype=f32), (shapes.boards, 1, 1))
    half = np.ones((shapes.boards, 3), f32)
    inset = np.zeros((shapes.boards, 2, 2), f32)
    covered = np.zeros((shapes.boards,) + shapes.cells, bool)
    cell_shape = np.ones((shapes.boards, 2), np.int32)
    for i, b in enumerate(boards):
        centre[i], frame[i], half[i], inset[i] = b.centre, b.axes, b.half, b.inset
        covered[i, :b.covered.shape[0], :b.covered.shape[1]] = b.covered
        cell_shape[i] = b.covered.shape
    table = np.zeros((shapes.items, 3), np.int32)
    table[:len(items)] = items
    host = CrossingTables(Chunks(points, point_mask), Tracks(hinge, axes_, pivots, values, counts),
                          Boards(centre, frame, half, inset, covered, cell_shape), table,
                          np.int32(-(-len(items) // ITEMS_PER_STEP)))
    return host, shapes, np.asarray(owners, np.int64)


def _power(n: int, smallest: int) -> int:
    """``n`` rounded up to a power of two, at least ``smallest``."""
    return max(smallest, 1 << max(0, n - 1).bit_length())


@jax.jit
def _launch(tables: CrossingTables) -> jax.Array:
    """[items]: each item's first crossing state (NEVER: none, and every item past the first
    ``tables.steps`` x ITEMS_PER_STEP, which are not computed)."""

    def one(row):
        return _first_state(_row(tables.chunks, row[0]), _row(tables.tracks, row[1]), _row(tables.boards, row[2]))

    rows = tables.table.reshape(-1, ITEMS_PER_STEP, 3)

    def step(i, out):
        return out.at[i].set(jax.vmap(one)(rows[i]))

    out = jax.lax.fori_loop(0, tables.steps, step, jnp.full(rows.shape[:2], NEVER, jnp.int32))
    return out.reshape(-1)


def _row(tables: tuple, i: jax.Array) -> tuple:
    """Row ``i`` of every array of a named tuple of tables."""
    return jax.tree.map(lambda x: x[i], tables)


def _first_state(chunk: Chunks, track: Tracks, board: Boards) -> jax.Array:
    """``crossing._first_crossing`` of one chunk of points along one track against one board."""
    rest, mask = chunk
    hinge, axis, pivot, values, count = track
    centre, frame, half, inset, covered, cell_shape = board
    states = values.shape[0]
    live = jnp.arange(states) < count  # [S]
    rel = rest - pivot
    angle = values[:, None, None]
    cos, sin = jnp.cos(angle), jnp.sin(angle)
    turned = rel * cos + jnp.cross(axis, rel)[None] * sin + axis * (rel @ axis)[None, :, None] * (1 - cos) + pivot
    posed = jnp.where(hinge, turned, rest[None] + angle * axis)  # [S, n, 3]
    local = (posed - centre) @ frame.T
    at_rest = (rest - centre) @ frame.T
    limit = half[0] + CROSSING_MARGIN_NU
    seen = live[:, None] & mask[None]
    side = jnp.where(seen, jnp.where(local[..., 0] > limit, 1, jnp.where(local[..., 0] < -limit, -1, 0)), 0)
    rest_side = jnp.where(mask & (jnp.abs(at_rest[:, 0]) > half[0]), jnp.sign(at_rest[:, 0]).astype(side.dtype), 0)
    sides = jnp.concatenate([rest_side[None], side])  # row 0: the rest pose
    rows = jnp.arange(states + 1)[:, None]
    marked = jnp.concatenate([jnp.ones_like(side[:1], bool), side != 0])
    last = jax.lax.cummax(jnp.where(marked, rows, 0), axis=0)
    before = last[:-1]  # [S, n]: the row each point was last seen in
    point = jnp.arange(rest.shape[0])[None]
    was = sides[before, point]
    flipped = (side != 0) & (was != 0) & (side != was)
    a = jnp.where((before == 0)[..., None], at_rest[None], local[jnp.maximum(before - 1, 0), point])
    b = local
    w = a[..., 0] / jnp.where(flipped, a[..., 0] - b[..., 0], 1.0)
    met = a[..., 1:] + w[..., None] * (b[..., 1:] - a[..., 1:])
    inside = jnp.all((met >= -half[1:] + inset[:, 0]) & (met <= half[1:] - inset[:, 1]), axis=-1)
    cell = jnp.clip(jnp.floor((met + half[1:]) / CROSSING_CELL_NU).astype(jnp.int32), 0, cell_shape - 1)
    through = flipped & inside & covered[cell[..., 0], cell[..., 1]]
    state = jnp.where(through, jnp.arange(states)[:, None], NEVER)
    return jnp.min(state)
