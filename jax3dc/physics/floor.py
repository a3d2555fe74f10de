"""The floor the object stands on: a joint may not drive any part through it.

The gravity test stands the object on a floor at its lowest rest point (+Z up, SPEC §2); a joint
that swings or slides a part below that plane (a laptop screen opened the wrong way round, a
telescopic handle pushed out through the bottom) would push the object off the floor in a
simulator. A subtree that itself touches the floor at rest is what the object stands on (a box
body turned under its lid): moving it tips the object, so it is not checked. Pure numpy on the rest-frame meshes, joint values as in the sweep (rad / nu), every
other joint at rest.
"""

from __future__ import annotations

import numpy as np
import trimesh

from jax3dc.physics.kinematics import joint_motion
from jax3dc.physics.tolerances import FLOOR_CONTACT_NU, FLOOR_TOL_NU
from jax3dc.structure.schema import Structure


def first_below_floor(structure: Structure, parts: dict[int, trimesh.Trimesh], part: int,
                      values: np.ndarray) -> float | None:
    """The first of ``values`` (in the given order) at which the subtree moved by ``part``'s joint
    reaches more than ``FLOOR_TOL_NU`` below the rest pose's lowest point (None: never, or the
    subtree is within ``FLOOR_CONTACT_NU`` of the floor at rest)."""
    floor = min(float(np.asarray(m.vertices)[:, 2].min()) for m in parts.values() if len(m.vertices))
    moved, stack = [part], [part]
    while stack:
        children = structure.children(stack.pop())
        moved += children
        stack += children
    points = np.concatenate([_hull_vertices(parts[p]) for p in moved])
    if points[:, 2].min() <= floor + FLOOR_CONTACT_NU:
        return None
    joint = structure.nodes[part].joint
    for v in values:
        if joint_motion(joint, float(v), points)[:, 2].min() < floor - FLOOR_TOL_NU:
            return float(v)
    return None


def _hull_vertices(mesh: trimesh.Trimesh) -> np.ndarray:
    """The points that can be a rigid part's lowest in any pose: its convex hull's vertices."""
    vertices = np.asarray(mesh.vertices, dtype=np.float64)
    if len(vertices) < 5:
        return vertices
    try:
        # repair=False: only the vertices are wanted, and repair divides by a flat hull's zero volume
        return np.asarray(trimesh.convex.convex_hull(vertices, repair=False).vertices, dtype=np.float64)
    except Exception:  # qhull: a flat or degenerate part; every vertex then
        return vertices
