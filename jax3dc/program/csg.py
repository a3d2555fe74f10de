"""Boolean difference of solids.

Exact path for the common furniture case (an axis-aligned box minus axis-aligned boxes:
carcasses, drawers, trays, frames): the box is cut into the grid of cells that every box face
spans, the cells inside a cutter are dropped and the faces between kept and dropped cells form
the result. Vertices sit on the shared grid, so the mesh is watertight with exact volume.
Other shapes go through manifold3d when it is installed (through trimesh).
"""

from __future__ import annotations

from typing import Callable

import numpy as np

from jax3dc.program.solids import Solid

_BOX_TOL = 1e-9
MAX_GRID_CELLS = 1_000_000
"""Cells of the box-difference grid; each cutter adds up to two planes per axis."""


def is_axis_aligned_box(solid: Solid) -> bool:
    """A closed mesh whose volume equals that of its bounding box fills the box."""
    lo, hi = solid.bounds()
    box_volume = float(np.prod(hi - lo))
    return box_volume > 0 and abs(solid.signed_volume() - box_volume) <= _BOX_TOL * max(1.0, box_volume)


def _no_deadline() -> None:
    return None


def box_difference(base: Solid, cutters: list[Solid], check_time: Callable[[], None] = _no_deadline) -> Solid:
    lo, hi = base.bounds()
    cut_bounds = [c.bounds() for c in cutters]
    edges = []
    for ax in range(3):
        values = [lo[ax], hi[ax]] + [bound[ax] for pair in cut_bounds for bound in pair]
        inside = np.clip(np.asarray(values), lo[ax], hi[ax])
        edges.append(np.unique(inside))
    nx, ny, nz = (len(e) - 1 for e in edges)
    if nx * ny * nz > MAX_GRID_CELLS:
        raise ValueError(f"too many cutters: their faces cut the box into more than {MAX_GRID_CELLS} cells")
    centres = np.meshgrid(*[(e[:-1] + e[1:]) / 2 for e in edges], indexing="ij")
    filled = np.ones((nx, ny, nz), dtype=bool)
    for c_lo, c_hi in cut_bounds:
        check_time()
        inside = np.ones_like(filled)
        for ax in range(3):
            inside &= (centres[ax] > c_lo[ax]) & (centres[ax] < c_hi[ax])
        filled &= ~inside
    if not filled.any():
        raise ValueError("the difference removes the whole solid")
    shape = (nx + 1, ny + 1, nz + 1)

    def vid(i, j, k):
        return np.ravel_multi_index((i, j, k), shape)

    padded = np.pad(filled, 1)
    quads = []
    for ax in range(3):
        # a face on the low side of cell c along `ax` where filled changes
        here = np.take(padded, range(1, padded.shape[ax]), axis=ax)
        before = np.take(padded, range(0, padded.shape[ax] - 1), axis=ax)
        other = [a for a in range(3) if a != ax]
        sl = [slice(1, -1)] * 3
        sl[ax] = slice(None)
        here, before = here[tuple(sl)], before[tuple(sl)]
        for sign, mask in ((1, here & ~before), (-1, before & ~here)):
            idx = np.nonzero(mask)
            if len(idx[0]) == 0:
                continue
            base_idx = list(idx)
            u, v = other
            corners = []
            for du, dv in ((0, 0), (1, 0), (1, 1), (0, 1)):
                c = [base_idx[0].copy(), base_idx[1].copy(), base_idx[2].copy()]
                c[u] = c[u] + du
                c[v] = c[v] + dv
                corners.append(vid(*c))
            quad = np.stack(corners, axis=1)
            # (u, v, ax) is cyclic for ax = 0 and 2 and odd for ax = 1
            outward_is_negative = sign == 1
            flip = outward_is_negative != (ax == 1)
            quads.append(quad[:, ::-1] if flip else quad)
    quads = np.concatenate(quads)
    tris = np.concatenate([quads[:, [0, 1, 2]], quads[:, [0, 2, 3]]])
    used, remap = np.unique(tris, return_inverse=True)
    i, j, k = np.unravel_index(used, shape)
    verts = np.stack([edges[0][i], edges[1][j], edges[2][k]], axis=1)
    return Solid(verts, remap.reshape(-1, 3).astype(np.int64))


def difference(base: Solid, cutters: list[Solid], check_time: Callable[[], None] = _no_deadline) -> Solid:
    """`base` minus every cutter; ValueError when no available method can do it.

    ``check_time`` is called between cutters and raises when the caller's time budget is spent:
    one call with thousands of cutters must not outlast it.
    """
    if is_axis_aligned_box(base) and all(is_axis_aligned_box(c) for c in cutters):
        return box_difference(base, cutters, check_time)
    try:
        import manifold3d  # noqa: F401  (trimesh's boolean engine)
        import trimesh
    except ImportError:
        raise ValueError(
            "difference of shapes other than axis-aligned boxes needs the manifold3d package"
        ) from None
    out = trimesh.Trimesh(base.vertices, base.faces, process=False)
    for cutter in cutters:  # one cutter at a time, so the deadline is checked between them
        check_time()
        out = trimesh.boolean.difference([out, trimesh.Trimesh(cutter.vertices, cutter.faces, process=False)],
                                         engine="manifold")
    return Solid(np.asarray(out.vertices, dtype=np.float64), np.asarray(out.faces, dtype=np.int64))
