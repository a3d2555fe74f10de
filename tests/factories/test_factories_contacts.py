"""At rest, parts meet but do not intersect: a check ground-truth objects need for physics (SPEC §8).

The shared volume of two parts is estimated from points inside the smaller part (rejection
sampling in its bounding box), each tested against the other part with the generalised winding
number (solid angles), a numpy reference independent of the interpreter. Parts that can move relative to each other may share at most 1 % of the
smaller one's volume, rigidly joined parts up to 3 % (joinery), unless the overlap is a slab
thinner than 1 mm: programs write 4 decimals, so faces that touch may cross by ~0.1 mm.
"""

import numpy as np
import pytest

from data_pipeline.factories import FACTORIES, generate_object

SAMPLES = 600
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
    import trimesh
    box = trimesh.creation.box((1, 1, 1))
    w = winding_number(box, np.array([[0, 0, 0], [0.4, -0.4, 0.3], [2, 0, 0], [0, 0.6, 0]]))
    assert np.allclose(w, [1, 1, 0, 0], atol=1e-9)


def penetration_depth(shared_volume, a, b):
    """Shared volume spread over the largest face of the two boxes' intersection: the thickness
    of the overlap when two parts press face to face (nu)."""
    extent = np.sort(np.minimum(a.bounds[1], b.bounds[1]) - np.maximum(a.bounds[0], b.bounds[0]))
    return shared_volume / (extent[1] * extent[2])


def shared_fraction(small, other, rng):
    """Fraction of `small`'s volume that lies inside `other` (interior points by rejection)."""
    lo, hi = small.bounds
    q = lo + rng.random((SAMPLES, 3)) * (hi - lo)
    q = q[winding_number(small, q) > 0.5]
    if len(q) == 0:
        return 0.0
    return float(np.mean(winding_number(other, q) > 0.5))


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
                a, b = obj.parts[i], obj.parts[j]
                if np.any(np.minimum(a.bounds[1], b.bounds[1]) - np.maximum(a.bounds[0], b.bounds[0]) <= 1e-6):
                    continue
                small, other = (a, b) if a.volume <= b.volume else (b, a)
                share = shared_fraction(small, other, rng)
                tol = RIGID_TOL if rigid_body(s, i) == rigid_body(s, j) else MOVING_TOL
                depth_m = penetration_depth(share * small.volume, a, b) * obj.scale_m_per_nu
                assert share <= tol or depth_m <= MAX_DEPTH_M, \
                    (obj.object_id, i, obj.names[i], j, obj.names[j], round(share, 3), round(depth_m * 1000, 2))
