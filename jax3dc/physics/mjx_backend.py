"""MJX evaluation of the kinematic checks: kinematics + penetration depth, batched over joint states.

MJX's own collision driver runs the full convex–convex test, contact manifold included, on every
candidate geom pair of every state, one small kernel per distinct mesh pair, where C MuJoCo's
broad phase skips pairs that are far apart. The checks need one number per pair (how deep it
interpenetrates), so the stages are split and the accelerator does only work that can change it:

1. ``mjx.kinematics`` per state (vmapped): geom poses;
2. broad phase: the separating-axis test of the geoms' oriented bounding boxes (each mesh's box in
   its own frame) for every candidate pair — hulls whose boxes are apart do not touch;
3. narrow phase (``penetration_depth``): the separating-axis test of the hulls (face normals and
   edge pairs pruned on the Gauss map, as MJX's convex test), depth only, on the (state, pair)
   items the broad phase keeps, gathered into one batch per class of hull sizes (blocks of up to
   8 vertices, larger hulls), hulls padded to their class's size (repeated vertices, faces and
   edges change no support or axis).

The hull data come from qhull (``_hull``), not from MJX's convex data, which merge nearly
coplanar facets and were millimetres off on sampled hulls. ``tests/physics/test_physics_mjx_broadphase.py``
checks the depth against a brute-force separating-axis test, the batch against C MuJoCo, and the
broad phase against keeping every pair. Mesh data are inputs of the compiled functions, not
constants: objects whose models have the same shapes share the narrow phase's compiled code.
"""

from __future__ import annotations

import functools
import math
import warnings
from dataclasses import dataclass

import jax
import jax.numpy as jnp
import mujoco
import numpy as np
from mujoco import mjx
from scipy.spatial import ConvexHull

from jax3dc.physics.mjx_private import geom_pairs

BOX_SLACK_M = 1e-5  # boxes apart by less than this on every axis still go to the narrow phase (float32 poses)
CHUNK_ITEMS = 16384  # narrow-phase items per vmapped chunk: bounds the memory of the edge-pair arrays
MIN_CAPACITY = 256  # smallest narrow-phase batch (smaller counts are padded up to it)
COPLANAR_COS = 1.0 - 1e-9  # hull triangles whose normals agree this closely lie in one face
SMALL_HULL_VERTICES = 8  # hulls of at most this many vertices (boxes, blocks) form their own size tier
PAD_MULTIPLE = 4  # hull vertex, face and edge counts are padded up to a multiple of this (a box keeps its 12 edges)


@dataclass(frozen=True)
class _Hulls:
    """Every mesh's convex hull for the separating-axis test, padded to common shapes and stacked."""

    vert: np.ndarray  # [M, V, 3] hull vertices (geom frame)
    inner: np.ndarray  # [M, 3] a point inside the hull (its vertex mean)
    face_normal: np.ndarray  # [M, F, 3] distinct outward face normals
    edge: np.ndarray  # [M, E, 2] vertex indices of the edges where two faces meet at an angle
    edge_face_normal: np.ndarray  # [M, E, 2, 3] normals of the two faces at each edge


def _pad_to(x: np.ndarray, n: int) -> np.ndarray:
    return np.pad(x, [(0, n - len(x))] + [(0, 0)] * (x.ndim - 1), mode="edge")


def _hull(vertices: np.ndarray) -> tuple[np.ndarray, ...]:
    """Hull data of one mesh from qhull (as C MuJoCo's hull): MJX's own convex data merge nearly
    coplanar facets and thin large faces to 20 vertices, which moves faces by millimetres on
    sampled hulls (a microwave's board read 6 mm apart where it interpenetrates 3 mm)."""
    hull = ConvexHull(vertices)
    used = np.unique(hull.simplices)
    index = np.full(len(vertices), -1)
    index[used] = np.arange(len(used))
    normals = hull.equations[:, :3]
    edges, edge_normals = [], []
    for i, (simplex, neighbours) in enumerate(zip(hull.simplices, hull.neighbors)):
        for k, j in enumerate(neighbours):  # neighbour j lies across the edge opposite vertex k
            if i < j and normals[i] @ normals[j] < COPLANAR_COS:
                edges.append(index[np.delete(simplex, k)])
                edge_normals.append((normals[i], normals[j]))
    distinct = normals[np.unique(np.round(normals, 9), axis=0, return_index=True)[1]]
    points = vertices[used]
    return points, points.mean(axis=0), distinct, np.asarray(edges).reshape(-1, 2), np.asarray(edge_normals).reshape(-1, 2, 3)


def _tiered_hulls(model: mujoco.MjModel) -> tuple[list[_Hulls], np.ndarray, np.ndarray]:
    """Hull data padded and stacked per size tier (small blocks apart, so that a box is not padded
    to a 32-vertex hull's edge count); per mesh its tier and its slot in that tier's stack."""
    hulls = []
    for mesh in range(model.nmesh):
        start = model.mesh_vertadr[mesh]
        hulls.append(_hull(model.mesh_vert[start:start + model.mesh_vertnum[mesh]].astype(np.float64)))
    tier = np.array([int(len(h[0]) > SMALL_HULL_VERTICES) for h in hulls], dtype=np.int32)
    slot = np.zeros(len(hulls), dtype=np.int32)
    stacks = []
    for t in range(2):
        members = [h for h, ht in zip(hulls, tier) if ht == t]
        slot[tier == t] = np.arange(len(members))
        if not members:
            stacks.append(None)
            continue
        # vertex, face and edge counts padded up to a multiple of PAD_MULTIPLE (the inner point is one
        # vector): objects of one structure then share compiled code
        sizes = [1 if i == 1 else PAD_MULTIPLE * math.ceil(max(len(h[i]) for h in members) / PAD_MULTIPLE) for i in range(5)]
        stacked = [np.stack([h[i] if i == 1 else _pad_to(h[i], sizes[i]) for h in members]) for i in range(5)]
        stacks.append(_Hulls(*(x.astype(np.int32 if x.dtype.kind == "i" else np.float32) for x in stacked)))
    return stacks, tier, slot


def _dot(a: jax.Array, b: jax.Array) -> jax.Array:
    """Dot product over the last axis as element-wise work (full float32, fuses; no TF32 matmul)."""
    return a[..., 0] * b[..., 0] + a[..., 1] * b[..., 1] + a[..., 2] * b[..., 2]


def _cross(a: jax.Array, b: jax.Array) -> jax.Array:
    return jnp.stack([a[..., 1] * b[..., 2] - a[..., 2] * b[..., 1],
                      a[..., 2] * b[..., 0] - a[..., 0] * b[..., 2],
                      a[..., 0] * b[..., 1] - a[..., 1] * b[..., 0]], axis=-1)


def penetration_depth(pos1, mat1, hull1: dict, pos2, mat2, hull2: dict) -> jax.Array:
    """Penetration depth (m) of two convex hulls placed at (pos, mat); negative when they are apart.

    The separating-axis test over face normals and edge–edge axes, the edge pairs pruned to those
    that form a face of the Minkowski difference (their arcs cross on the Gauss map), as in MJX's
    convex narrow phase; the depth is the smallest overlap over all axes, the same quantity as C
    MuJoCo's EPA. The check needs only this depth, not a contact manifold."""
    rot = _dot(mat2.T[:, None, :], mat1.T[None, :, :])  # hull 1 in hull 2's frame (element-wise: no TF32)
    origin = _dot(mat2.T, pos1 - pos2)
    v1 = origin + _dot(hull1["vert"][:, None, :], rot[None, :, :])
    v2 = hull2["vert"]
    n1 = _dot(hull1["face_normal"][:, None, :], rot[None, :, :])
    axes = jnp.concatenate([n1, -hull2["face_normal"]])  # [F1 + F2, 3]
    along1 = _dot(axes[:, None, :], v1[None, :, :])
    along2 = _dot(axes[:, None, :], v2[None, :, :])
    face_overlap = jnp.min(along1.max(axis=1) - along2.min(axis=1))

    e1, e2 = v1[hull1["edge"]], v2[hull2["edge"]]  # [E, 2, 3]
    f1 = _dot(hull1["edge_face_normal"][..., None, :], rot)  # [E1, 2, 3]
    f2 = -hull2["edge_face_normal"]  # the Minkowski difference uses B's Gauss map negated
    d1 = e1[:, 0] - e1[:, 1]
    d2 = e2[:, 0] - e2[:, 1]
    # arcs (f1[:,0], f1[:,1]) and (f2[:,0], f2[:,1]) cross on the unit sphere
    ba, dc = _cross(f1[:, 1], f1[:, 0]), _cross(f2[:, 1], f2[:, 0])
    cba, dba = _dot(f2[None, :, 0], ba[:, None]), _dot(f2[None, :, 1], ba[:, None])
    adc, bdc = _dot(f1[:, None, 0], dc[None, :]), _dot(f1[:, None, 1], dc[None, :])
    minkowski = (cba * dba < 0) & (adc * bdc < 0) & (cba * bdc > 0)
    axis = _cross(d1[:, None, :], d2[None, :, :])  # [E1, E2, 3]
    norm2 = _dot(axis, axis)
    length2 = _dot(d1, d1)[:, None] * _dot(d2, d2)[None, :]
    usable = minkowski & (norm2 > 1e-6 * length2)  # parallel edges give no axis
    # oriented away from a point inside hull 1: the separation is then hull 2's edge beyond hull 1's
    inner = origin + _dot(hull1["inner"][None, :], rot)
    outward = jnp.sign(_dot(axis, (e1[:, 0] - inner)[:, None, :]))
    separation = outward * _dot(axis, e2[None, :, 0] - e1[:, None, 0]) * jax.lax.rsqrt(jnp.maximum(norm2, 1e-30))
    edge_overlap = jnp.min(jnp.where(usable, -separation, jnp.inf))
    return jnp.minimum(face_overlap, edge_overlap)


def _candidate_pairs(model: mujoco.MjModel, ignore_margin: bool = False) -> np.ndarray:
    """[P, 2] geom pairs MJX's driver would test; only mesh–mesh pairs without margin are supported
    (``ignore_margin``: the caller measures penetration of a model whose margin is C's proximity setting)."""
    pairs = []
    for g1, g2, explicit in geom_pairs(model):
        if explicit > -1:
            raise ValueError(f"explicit <pair> {explicit}: the batched MJX check supports only geom-filter pairs")
        for g in (g1, g2):
            if model.geom_type[g] != mujoco.mjtGeom.mjGEOM_MESH:
                name = mujoco.mj_id2name(model, mujoco.mjtObj.mjOBJ_GEOM, g)
                raise ValueError(f"geom {name!r} (id {g}) is not a mesh: the batched MJX check collides convex meshes only")
            if model.geom_margin[g] > 0 and not ignore_margin:
                raise ValueError(f"geom id {g} has margin {model.geom_margin[g]}: the batched check measures contacts, not distances within a margin")
        pairs.append((g1, g2))
    return np.asarray(pairs, dtype=np.int32).reshape(-1, 2)


def _boxes_overlap(c1, r1, h1, c2, r2, h2, slack) -> jax.Array:
    """Separating-axis test of two oriented boxes (centre, rotation whose columns are the box axes,
    half sizes): False only when some axis separates them by more than ``slack``."""
    a1, a2 = r1.T, r2.T  # rows: axes
    axes = jnp.concatenate([a1, a2, _cross(a1[:, None, :], a2[None, :, :]).reshape(9, 3)])  # [15, 3]; a zero axis never separates
    reach1 = (jnp.abs(_dot(axes[:, None, :], a1[None, :, :])) * h1).sum(axis=1)
    reach2 = (jnp.abs(_dot(axes[:, None, :], a2[None, :, :])) * h2).sum(axis=1)
    gap = jnp.abs(_dot(axes, c2 - c1)) - reach1 - reach2
    return ~jnp.any(gap > slack * jnp.sqrt(_dot(axes, axes)))


def capacity_for(count: int) -> int:
    """Narrow-phase batch size for ``count`` items: a few sizes per octave (each compiles once)."""
    if count == 0:
        return 0
    if count <= MIN_CAPACITY:
        return MIN_CAPACITY
    if count <= CHUNK_ITEMS:
        return 1 << math.ceil(math.log2(count))
    return CHUNK_ITEMS * math.ceil(count / CHUNK_ITEMS)


Classes = tuple[tuple[int, int, tuple[int, ...]], ...]  # (tier 1, tier 2, pair indices) per class of hull sizes


@functools.partial(jax.jit, static_argnames=("classes",))
def _poses_and_mask(mx: mjx.Model, consts: dict, qpos: jax.Array, classes: Classes):
    """Geom poses [S, G, 3] / [S, G, 3, 3], the broad phase's verdict [S, P] and its count per class."""
    def one(q):
        with jax.default_matmul_precision("highest"):  # MJX's frame products: no TF32 on GPUs
            dx = mjx.kinematics(mx, mjx.make_data(mx).replace(qpos=q))
        box = consts["box"]
        g1, g2 = consts["g1"], consts["g2"]
        rot = dx.geom_xmat
        centre = dx.geom_xpos + _dot(rot, box[:, None, :3])
        keep = jax.vmap(_boxes_overlap, in_axes=(0, 0, 0, 0, 0, 0, None))(
            centre[g1], rot[g1], box[g1, 3:], centre[g2], rot[g2], box[g2, 3:], consts["slack"])
        return dx.geom_xpos, rot, keep

    pos, rot, keep = jax.vmap(one)(qpos)
    counts = jnp.stack([keep[:, np.asarray(members)].sum() for _, _, members in classes])
    return pos, rot, keep, counts


def _class_depths(consts, pos, rot, keep, count, tiers, members, capacity):
    """Depth of the first ``count`` kept items of one class, computed in chunks of CHUNK_ITEMS."""
    chunk = min(CHUNK_ITEMS, capacity)
    members = np.asarray(members)
    item = jnp.nonzero(keep[:, members].reshape(-1), size=capacity, fill_value=0)[0]
    valid = jnp.arange(capacity) < count
    s, p = item // len(members), jnp.asarray(members)[item % len(members)]
    g1, g2 = consts["g1"][p], consts["g2"][p]
    hulls1, hulls2 = (consts["hulls"][t] for t in tiers)

    def collide(args):
        def one(s, a, b):
            hull_a = {k: v[consts["slot"][a]] for k, v in hulls1.items()}
            hull_b = {k: v[consts["slot"][b]] for k, v in hulls2.items()}
            return penetration_depth(pos[s, a], rot[s, a], hull_a, pos[s, b], rot[s, b], hull_b)

        return jax.vmap(one)(*args)

    shaped = [x.reshape(capacity // chunk, chunk) for x in (s, g1, g2)]
    depth = jax.lax.map(collide, shaped).reshape(capacity)
    dist = jnp.where(valid & (depth >= 0.0), -depth, jnp.inf)
    return s, consts["b1"][p], consts["b2"][p], dist


@functools.partial(jax.jit, static_argnames=("classes", "capacities", "nbody"))
def _narrow_phase(consts, pos, rot, keep, counts, classes: Classes, capacities: tuple[int, ...], nbody: int):
    out = jnp.full((pos.shape[0], nbody, nbody), jnp.inf, pos.dtype)
    for k, ((t1, t2, members), capacity) in enumerate(zip(classes, capacities)):
        if capacity:
            s, b1, b2, dist = _class_depths(consts, pos, rot, keep, counts[k], (t1, t2), members, capacity)
            out = out.at[s, b1, b2].min(dist).at[s, b2, b1].min(dist)
    return out


class PairDistances:
    """qpos [S, nq] -> [S, nbody, nbody] deepest contact distance per body pair (metres, ≤ 0; +inf: none).

    Pairs fall in classes by the size tiers of their two hulls; ``__call__`` counts the broad
    phase's survivors of each class on the host and runs each class's narrow phase at the matching
    capacity (``capacity_for``). The narrow phase, the costly compile, is shared by every model with
    the same pair classes, body count and padded hull sizes (mesh data are its inputs); the
    kinematics compile per model, as MJX keeps a model's index and size arrays as static data."""

    def __init__(self, model: mujoco.MjModel):
        pairs = _candidate_pairs(model)
        self.nbody = model.nbody
        with warnings.catch_warnings():  # about MJX's own convex data of large faces, which this path does not use
            warnings.simplefilter("ignore", UserWarning)
            self.mx = mjx.put_model(model)
        stacks, mesh_tier, mesh_slot = _tiered_hulls(model)
        geom_tier = mesh_tier[model.geom_dataid] if len(mesh_tier) else np.zeros(model.ngeom, dtype=np.int32)
        swap = geom_tier[pairs[:, 0]] > geom_tier[pairs[:, 1]]  # the smaller hull first: classes (0,0), (0,1), (1,1)
        self.pairs = np.where(swap[:, None], pairs[:, ::-1], pairs)
        tiers = geom_tier[self.pairs]
        classes = [(t1, t2, tuple(int(i) for i in np.nonzero((tiers[:, 0] == t1) & (tiers[:, 1] == t2))[0]))
                   for t1, t2 in ((0, 0), (0, 1), (1, 1))]
        self.classes: Classes = tuple(c for c in classes if c[2])
        self._consts = {
            "g1": jnp.asarray(self.pairs[:, 0]), "g2": jnp.asarray(self.pairs[:, 1]),
            "b1": jnp.asarray(model.geom_bodyid[self.pairs[:, 0]]), "b2": jnp.asarray(model.geom_bodyid[self.pairs[:, 1]]),
            "slot": jnp.asarray(mesh_slot[model.geom_dataid] if len(mesh_slot) else np.zeros(model.ngeom, np.int32)),
            "box": jnp.asarray(model.geom_aabb, dtype=jnp.float32), "slack": jnp.float32(BOX_SLACK_M),
            "hulls": [None if h is None else jax.tree_util.tree_map(jnp.asarray, vars(h)) for h in stacks],
        }

    def _broad_phase(self, qpos: jax.Array):
        return _poses_and_mask(self.mx, self._consts, jnp.asarray(qpos, dtype=jnp.float32), self.classes)

    def survivors(self, qpos: jax.Array) -> int:
        """How many (state, geom pair) items the broad phase passes to the narrow phase."""
        return int(self._broad_phase(qpos)[3].sum())

    def __call__(self, qpos: jax.Array) -> jax.Array:
        qpos = jnp.asarray(qpos, dtype=jnp.float32)
        if not len(self.pairs):
            return jnp.full((qpos.shape[0], self.nbody, self.nbody), jnp.inf, jnp.float32)
        pos, rot, keep, counts = self._broad_phase(qpos)
        capacities = tuple(capacity_for(int(c)) for c in np.asarray(counts))
        return _narrow_phase(self._consts, pos, rot, keep, counts, self.classes, capacities, self.nbody)


def compile_pair_distances(model: mujoco.MjModel) -> PairDistances:
    """The batched check for ``model`` (kept as the name callers use): a callable qpos [S, nq] -> [S, nbody, nbody]."""
    return PairDistances(model)
