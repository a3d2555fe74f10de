"""At rest, parts meet but do not intersect: a check ground-truth objects need for physics (SPEC §8).

The shared volume of two parts is estimated from points drawn in the intersection of their
bounding boxes, each tested against both parts with the generalised winding number (solid
angles), a numpy reference independent of the interpreter. Parts that can move relative to each other may share at most 1 % of the
smaller one's volume, rigidly joined parts up to 3 % (joinery), unless the overlap is a slab
thinner than 1 mm: programs write 4 decimals, so faces that touch may cross by ~0.1 mm.
"""

import math

import numpy as np
import pytest
import trimesh

from jax3dc.factories import FACTORIES, generate_object

SAMPLES = 2000
MOVING_TOL, RIGID_TOL = 0.01, 0.03
MAX_DEPTH_M = 0.001  # overlaps thinner than 1 mm are number rounding in the program text, not design


def winding_number(mesh, points):
    tri = mesh.vertices[mesh.faces]
    a, b, c = (tri[None, :, k] - points[:, None] for k in range(3))
    la, lb, lc = (np.linalg.norm(x, axis=-1) for x in (a, b, c))
    det = np.einsum("qfi,qfi->qf", a, np.cross(b, c))
    dot = lambda x, y: np.einsum("qfi,qfi->qf", x, y)  # noqa: E731
    den = la * lb * lc + dot(a, b) * lc + dot(b, c) * la + dot(c, a) * lb
    return (2 * np.arctan2(det, den)).sum(axis=1) / (4 * np.pi)


def rigid_body(structure, pid):
    """The part that carries the nearest joint above `pid` (or the root): one rigid body each."""
    while structure.nodes[pid].joint is None and structure.nodes[pid].parent is not None:
        pid = structure.nodes[pid].parent
    return pid


def test_winding_number_reference():
    box = trimesh.creation.box((1, 1, 1))
    w = winding_number(box, np.array([[0, 0, 0], [0.4, -0.4, 0.3], [2, 0, 0], [0, 0.6, 0]]))
    assert np.allclose(w, [1, 1, 0, 0], atol=1e-9)


def overlap(a, b, rng):
    """(shared volume / smaller part's volume, overlap thickness in nu) of two parts.

    Points are drawn in the intersection of the two bounding boxes; the thickness is the shared
    volume spread over the largest face of that box (a slab when two parts press face to face),
    so it never exceeds the box's thinnest side.
    """
    lo, hi = np.maximum(a.bounds[0], b.bounds[0]), np.minimum(a.bounds[1], b.bounds[1])
    extent = hi - lo
    if np.any(extent <= 1e-6):
        return 0.0, 0.0
    q = lo + rng.random((SAMPLES, 3)) * extent
    inside = winding_number(a, q) > 0.5
    inside[inside] = winding_number(b, q[inside]) > 0.5
    shared = inside.mean() * np.prod(extent)
    e = np.sort(extent)
    return shared / min(a.volume, b.volume), shared / (e[1] * e[2])


@pytest.mark.parametrize("category", sorted(FACTORIES))
def test_parts_do_not_intersect(category):
    rng = np.random.default_rng(0)
    for seed in (0, 1, 2):
        obj = generate_object(category, seed)
        s = obj.structure
        ids = sorted(obj.parts)
        for i in ids:
            for j in ids:
                if j <= i:
                    continue
                share, depth = overlap(obj.parts[i], obj.parts[j], rng)
                tol = RIGID_TOL if rigid_body(s, i) == rigid_body(s, j) else MOVING_TOL
                depth_m = depth * obj.scale_m_per_nu
                assert share <= tol or depth_m <= MAX_DEPTH_M, \
                    (obj.object_id, i, obj.names[i], j, obj.names[j], round(share, 3), round(depth_m * 1000, 2))


def _subtree(structure, pid):
    out = {pid}
    changed = True  # repeat: a child's id may be smaller than its parent's
    while changed:
        changed = False
        for i, n in structure.nodes.items():
            if n.parent in out and i not in out:
                out.add(i)
                changed = True
    return out


def _moved(mesh, joint, q):
    if joint.type == "slide":
        return trimesh.Trimesh(mesh.vertices + np.asarray(joint.axis) * q, mesh.faces, process=False)
    a = np.asarray(joint.axis)
    k = np.array([[0, -a[2], a[1]], [a[2], 0, -a[0]], [-a[1], a[0], 0]])
    r = np.eye(3) + math.sin(q) * k + (1 - math.cos(q)) * (k @ k)
    p = np.asarray(joint.pivot)
    return trimesh.Trimesh((mesh.vertices - p) @ r.T + p, mesh.faces, process=False)


@pytest.mark.parametrize("category", sorted(c for c in FACTORIES if not FACTORIES[c].instance_heavy))
def test_each_joint_reaches_its_limits_without_collisions(category):
    """Moving one joint to either end of its range (others at rest) runs its subtree into nothing."""
    rng = np.random.default_rng(1)
    for seed in (0, 1, 2):
        obj = generate_object(category, seed)
        s = obj.structure
        for pid, joint in s.joints().items():
            moving = _subtree(s, pid)
            for q in joint.range:
                if q == 0:
                    continue
                for i in moving:
                    a = _moved(obj.parts[i], joint, q)
                    for j in obj.parts:
                        if j in moving:
                            continue
                        share, depth = overlap(a, obj.parts[j], rng)
                        depth_m = depth * obj.scale_m_per_nu
                        assert share <= MOVING_TOL or depth_m <= MAX_DEPTH_M, (
                            obj.object_id, f"joint of {pid} at {q:.2f}", i, obj.names[i], j, obj.names[j],
                            round(share, 3), round(depth_m * 1000, 2))
