"""One compiled penetration check for many objects: models padded to size classes, the joint
states of many objects in one device launch.

``mjx_backend.PairDistances`` compiles per model: MJX keeps a model's body tree and sizes as
static data, so every object of another structure compiles again (3.6–5.1 s on an H100, minutes
on a CPU). Here the forward kinematics are our own, over arrays (parent index, body and joint
frames, joint type), so the body tree is data too, and every size is rounded up to a class
(``size_class``): padded bodies sit at the origin with no geom, padded geom pairs are masked out,
padded hulls repeat a vertex, face or edge (which changes no support or axis). One compiled check
then serves every object of the same size classes, and a batch holds the states of many objects:
an item is (object, joint state); the broad and narrow phases of ``mjx_backend`` run on the items'
geom pairs. ``tests/physics/test_physics_mjx_batch.py`` checks that padding and batching change no
depth against the per-model check, and the kinematics against C MuJoCo.

The kinematics are MuJoCo's for the models the checks build (``sim_model``): each body has at
most one hinge or slide joint (the kinematic check's model has no free root); another joint type
is a ValueError naming the body.
"""

from __future__ import annotations

import dataclasses
import functools
import math
import time
import warnings
from dataclasses import dataclass

import jax
import jax.numpy as jnp
import mujoco
import numpy as np

from jax3dc.physics.mjx_backend import (BOX_SLACK_M, CHUNK_ITEMS, MIN_CAPACITY, SMALL_HULL_VERTICES, _boxes_overlap,
                                        _candidate_pairs, _cross, _dot, _hull, penetration_depth)

NARROW_STEP = 4096  # narrow-phase entries computed at once (a launch runs as many steps as its entries fill)
HINGE, SLIDE = 1, 2  # body joint kinds in the arrays (0: welded to its parent)
TIER_CLASSES = ((0, 0), (0, 1), (1, 1))  # pair classes by the size tiers of their two hulls (the smaller first)
HULL_FIELDS = ("vert", "inner", "face_normal", "edge", "edge_face_normal")


def size_class(n: int, smallest: int = 8) -> int:
    """``n`` rounded up to a power of two or three quarters of one (8, 12, 16, 24, 32, 48, ...): a
    size grows by less than half, and a sweep over objects of many structures meets few shapes."""
    n = max(n, smallest)
    power = 1 << (n - 1).bit_length()
    return power * 3 // 4 if power >= 4 and power * 3 // 4 >= n else power


@dataclass(frozen=True)
class ObjectArrays:
    """One simulation model as the batched check reads it (host arrays, unpadded)."""

    nbody: int
    nq: int
    body_parent: np.ndarray  # [B] parent body id (world: 0)
    body_pos: np.ndarray  # [B, 3] frame in the parent's
    body_quat: np.ndarray  # [B, 4] (w, x, y, z)
    joint_kind: np.ndarray  # [B] 0 welded, HINGE, SLIDE
    joint_qpos: np.ndarray  # [B] qpos address of the body's joint (0 when welded)
    joint_pos: np.ndarray  # [B, 3] joint anchor in the body frame
    joint_axis: np.ndarray  # [B, 3] joint axis in the body frame
    joint_ref: np.ndarray  # [B] qpos0 of the joint
    geom_body: np.ndarray  # [G]
    geom_pos: np.ndarray  # [G, 3]
    geom_quat: np.ndarray  # [G, 4]
    geom_box: np.ndarray  # [G, 6] mesh box in the geom frame: centre, half sizes
    geom_tier: np.ndarray  # [G] hull size tier (0: at most SMALL_HULL_VERTICES vertices)
    geom_slot: np.ndarray  # [G] the geom's hull in its tier's list
    pairs: np.ndarray  # [P, 2] candidate geom pairs, the smaller tier first
    hulls: tuple[list[tuple[np.ndarray, ...]], list[tuple[np.ndarray, ...]]]  # per tier: ``_hull`` data


def object_arrays(model: mujoco.MjModel, ignore_margin: bool = False) -> ObjectArrays:
    """The arrays of ``model`` (a ValueError names a body with a joint the check does not move).

    ``ignore_margin``: read a model whose contact margin is C MuJoCo's proximity setting (the
    verdict's kinematic model) as the same model without it: the margin changes no array here, and
    the check measures penetration, never distances within a margin."""
    kind = np.zeros(model.nbody, np.int32)
    qadr = np.zeros(model.nbody, np.int32)
    jpos, jaxis, ref = np.zeros((model.nbody, 3)), np.zeros((model.nbody, 3)), np.zeros(model.nbody)
    for b in range(1, model.nbody):
        if model.body_jntnum[b] == 0:
            continue
        j = model.body_jntadr[b]
        name = mujoco.mj_id2name(model, mujoco.mjtObj.mjOBJ_BODY, b)
        jtype = int(model.jnt_type[j])
        if model.body_jntnum[b] > 1 or jtype not in (int(mujoco.mjtJoint.mjJNT_HINGE), int(mujoco.mjtJoint.mjJNT_SLIDE)):
            raise ValueError(f"body {name!r}: the batched check moves one hinge or slide joint per body")
        kind[b] = HINGE if jtype == int(mujoco.mjtJoint.mjJNT_HINGE) else SLIDE
        qadr[b] = model.jnt_qposadr[j]
        jpos[b], jaxis[b], ref[b] = model.jnt_pos[j], model.jnt_axis[j], model.qpos0[model.jnt_qposadr[j]]
    pairs = _candidate_pairs(model, ignore_margin)
    hulls = [_hull(model.mesh_vert[model.mesh_vertadr[m]:model.mesh_vertadr[m] + model.mesh_vertnum[m]].astype(np.float64))
             for m in range(model.nmesh)]
    mesh_tier = np.array([int(len(h[0]) > SMALL_HULL_VERTICES) for h in hulls], np.int32)
    mesh_slot = np.zeros(len(hulls), np.int32)
    for t in (0, 1):
        mesh_slot[mesh_tier == t] = np.arange(int((mesh_tier == t).sum()))
    geom_mesh = np.where(model.geom_dataid >= 0, model.geom_dataid, 0)
    geom_tier = mesh_tier[geom_mesh] if len(hulls) else np.zeros(model.ngeom, np.int32)
    geom_slot = mesh_slot[geom_mesh] if len(hulls) else np.zeros(model.ngeom, np.int32)
    if len(pairs):
        swap = geom_tier[pairs[:, 0]] > geom_tier[pairs[:, 1]]
        pairs = np.where(swap[:, None], pairs[:, ::-1], pairs)
    return ObjectArrays(
        nbody=model.nbody, nq=model.nq, body_parent=model.body_parentid.astype(np.int32),
        body_pos=model.body_pos.copy(), body_quat=model.body_quat.copy(), joint_kind=kind, joint_qpos=qadr,
        joint_pos=jpos, joint_axis=jaxis, joint_ref=ref, geom_body=model.geom_bodyid.astype(np.int32),
        geom_pos=model.geom_pos.copy(), geom_quat=model.geom_quat.copy(), geom_box=model.geom_aabb.copy(),
        geom_tier=geom_tier.astype(np.int32), geom_slot=geom_slot.astype(np.int32), pairs=pairs.astype(np.int32),
        hulls=tuple([h for h, t in zip(hulls, mesh_tier) if t == tier] for tier in (0, 1)))


def _qmul(a: jax.Array, b: jax.Array) -> jax.Array:
    aw, ax, ay, az = a[..., 0], a[..., 1], a[..., 2], a[..., 3]
    bw, bx, by, bz = b[..., 0], b[..., 1], b[..., 2], b[..., 3]
    return jnp.stack([aw * bw - ax * bx - ay * by - az * bz, aw * bx + ax * bw + ay * bz - az * by,
                      aw * by - ax * bz + ay * bw + az * bx, aw * bz + ax * by - ay * bx + az * bw], axis=-1)


def _rotate(q: jax.Array, v: jax.Array) -> jax.Array:
    """v rotated by the unit quaternion q (element-wise: full float32 on GPUs)."""
    u, w = q[..., 1:], q[..., :1]
    t = 2.0 * _cross(u, v)
    return v + w * t + _cross(u, t)


def _quat_mat(q: jax.Array) -> jax.Array:
    """[..., 3, 3] rotation matrix of unit quaternions (columns: the rotated axes)."""
    eye = jnp.eye(3, dtype=q.dtype)
    return jnp.stack([_rotate(q, eye[i]) for i in range(3)], axis=-1)


def _forward(arrays: dict, qpos: jax.Array) -> tuple[jax.Array, jax.Array]:
    """Geom positions [G, 3] and rotations [G, 3, 3] of one object at ``qpos``, as mj_kinematics:
    bodies in id order (a parent before its children); a hinge turns its body about the anchor,
    a slide moves it along the axis, both by qpos - qpos0."""
    nbody = arrays["body_parent"].shape[0]

    def body(b, frames):
        xpos, xquat = frames
        p = arrays["body_parent"][b]
        pos = xpos[p] + _rotate(xquat[p], arrays["body_pos"][b])
        quat = _qmul(xquat[p], arrays["body_quat"][b])
        kind, axis, anchor = arrays["joint_kind"][b], arrays["joint_axis"][b], arrays["joint_pos"][b]
        value = qpos[arrays["joint_qpos"][b]] - arrays["joint_ref"][b]
        half = 0.5 * value
        turned = _qmul(quat, jnp.concatenate([jnp.cos(half)[None], jnp.sin(half) * axis]))
        turned = turned / jnp.sqrt(jnp.sum(turned * turned))
        hinge_pos = pos + _rotate(quat, anchor) - _rotate(turned, anchor)
        slide_pos = pos + _rotate(quat, axis) * value
        pos = jnp.where(kind == HINGE, hinge_pos, jnp.where(kind == SLIDE, slide_pos, pos))
        quat = jnp.where(kind == HINGE, turned, quat)
        return xpos.at[b].set(pos), xquat.at[b].set(quat)

    start = (jnp.zeros((nbody, 3), qpos.dtype), jnp.zeros((nbody, 4), qpos.dtype).at[:, 0].set(1.0))
    xpos, xquat = jax.lax.fori_loop(1, nbody, body, start)
    gb = arrays["geom_body"]
    gpos = xpos[gb] + _rotate(xquat[gb], arrays["geom_pos"])
    return gpos, _quat_mat(_qmul(xquat[gb], arrays["geom_quat"]))


@jax.jit
def _broad_phase(arrays: dict, item_object: jax.Array, qpos: jax.Array, item_valid: jax.Array):
    """Per item: geom poses [I, G, ...] and which of its object's pairs the boxes keep [I, P]."""
    def one(obj, q, valid):
        mine = {k: v[obj] for k, v in arrays.items() if k in _PER_OBJECT}
        pos, rot = _forward(mine, q)
        box = mine["geom_box"]
        centre = pos + _dot(rot, box[:, None, :3])
        g1, g2 = mine["pairs"][:, 0], mine["pairs"][:, 1]
        keep = jax.vmap(_boxes_overlap, in_axes=(0, 0, 0, 0, 0, 0, None))(
            centre[g1], rot[g1], box[g1, 3:], centre[g2], rot[g2], box[g2, 3:], BOX_SLACK_M)
        return pos, rot, keep & mine["pair_valid"] & valid

    pos, rot, keep = jax.vmap(one)(item_object, qpos, item_valid)
    tiers = arrays["pair_tier"][item_object]  # [I, P]
    counts = jnp.stack([(keep & (tiers == k)).sum() for k in range(len(TIER_CLASSES))])
    return pos, rot, keep, counts


_PER_OBJECT = ("body_parent", "body_pos", "body_quat", "joint_kind", "joint_qpos", "joint_pos", "joint_axis", "joint_ref",
               "geom_body", "geom_pos", "geom_quat", "geom_box", "pairs", "pair_valid")


@functools.partial(jax.jit, static_argnames=("pair_class", "capacity"))
def _class_depths(pairs, geom_hull, pair_tier, hull1: dict, hull2: dict, item_object, pos, rot, keep, count,
                  pair_class: int, capacity: int):
    """The narrow phase of one pair class: the first ``capacity`` kept (item, pair) entries of the
    class, as flat indices into [I, P], and their contact distance (-depth where they
    interpenetrate, else +inf). Compiled per class and capacity: the other shapes are the sweep's.
    Only the ``NARROW_STEP`` chunks that hold the ``count`` kept entries are computed, so a
    capacity larger than a launch needs (``Shapes.capacity``) costs it no time."""
    n_pairs = keep.shape[1]
    chunk = min(NARROW_STEP, capacity)
    mine = keep & (pair_tier[item_object] == pair_class)
    flat = jnp.nonzero(mine.reshape(-1), size=capacity, fill_value=0)[0]
    item, pair = flat // n_pairs, flat % n_pairs
    obj = item_object[item]
    g1, g2 = pairs[obj, pair, 0], pairs[obj, pair, 1]
    slot1, slot2 = geom_hull[obj, g1], geom_hull[obj, g2]

    def collide(args):
        def one(i, a, b, s1, s2):
            hull_a = {f: v[s1] for f, v in hull1.items()}
            hull_b = {f: v[s2] for f, v in hull2.items()}
            return penetration_depth(pos[i, a], rot[i, a], hull_a, pos[i, b], rot[i, b], hull_b)

        return jax.vmap(one)(*args)

    shaped = [x.reshape(capacity // chunk, chunk) for x in (item, g1, g2, slot1, slot2)]

    def step(i, out):
        return out.at[i].set(collide([x[i] for x in shaped]))

    depth = jax.lax.fori_loop(0, (count + chunk - 1) // chunk, step, jnp.full((capacity // chunk, chunk), -1.0, pos.dtype))
    depth = depth.reshape(capacity)
    valid = jnp.arange(capacity) < count
    return flat, jnp.where(valid & (depth >= 0.0), -depth, jnp.inf)


@dataclass(frozen=True)
class Shapes:
    """Every padded size of a batch: what its compiled code is keyed by. A sweep passes the largest
    it has met as ``at_least``, so its shapes only grow and a handful of compiles serve it."""

    objects: int = 1
    bodies: int = 8
    geoms: int = 8
    pairs: int = 16
    nq: int = 1
    items: int = 64
    hulls: tuple[int, int] = (1, 1)  # per tier: how many hulls
    hull_sizes: tuple[tuple[int, int, int], ...] = ((SMALL_HULL_VERTICES, 8, 8), (8, 8, 8))  # per tier: vertices, faces, edges
    capacity: int = 0  # the least narrow-phase capacity of a launch (0: each launch its own, ``narrow_capacity``)

    def grown(self, other: "Shapes") -> "Shapes":
        """The elementwise largest of two."""
        def big(a, b):
            return tuple(big(x, y) for x, y in zip(a, b)) if isinstance(a, tuple) else max(a, b)

        return Shapes(*(big(getattr(self, f), getattr(other, f)) for f in self.__dataclass_fields__))


EXACT = Shapes(objects=1, bodies=1, geoms=1, pairs=1, nq=1, items=1, hulls=(1, 1), hull_sizes=((1, 1, 1), (1, 1, 1)))


def _exact(n: int, smallest: int = 1) -> int:
    return max(n, 1)


def _needed(objects: list[ObjectArrays], qpos: list[np.ndarray], size_classes: bool = True) -> Shapes:
    """The size classes ``objects`` need (``size_classes=False``: their exact sizes)."""
    tiers = [[h for o in objects for h in o.hulls[t]] for t in (0, 1)]
    smallest = (SMALL_HULL_VERTICES, 8, 8)
    round_up = size_class if size_classes else _exact
    return Shapes(
        objects=round_up(len(objects), 1), bodies=round_up(max(o.nbody for o in objects)),
        geoms=round_up(max(len(o.geom_body) for o in objects)), pairs=round_up(max(len(o.pairs) for o in objects), 16),
        nq=round_up(max(o.nq for o in objects), 1), items=round_up(sum(len(q) for q in qpos), 64),
        hulls=tuple(round_up(len(m), 1) for m in tiers),
        hull_sizes=tuple(tuple(round_up(max((len(h[i]) for h in m), default=(4, 4, 6)[k]), smallest[k]) for k, i in enumerate((0, 2, 3)))
                         for m in tiers))


def _stack_hulls(members: list[tuple[np.ndarray, ...]], count: int, sizes: tuple[int, int, int]) -> dict[str, np.ndarray]:
    """One tier's hulls of a batch, each padded to the tier's sizes, ``count`` of them (copies of
    the last hull, or of a tetrahedron, which fits the smallest sizes, where the batch has none of
    the tier, fill the stack: no pair refers to them, and the stack keeps the shape a sweep's
    compiled code was made for)."""
    members = members or [_hull(np.array([[0, 0, 0], [1, 0, 0], [0, 1, 0], [0, 0, 1]], np.float64))]
    lengths = dict(zip((0, 2, 3, 4), (sizes[0], sizes[1], sizes[2], sizes[2])))
    stacked = []
    for i in range(5):
        if i == 1:
            stacked.append(np.stack([h[1] for h in members] + [members[-1][1]] * (count - len(members))))
            continue
        out = np.empty((count, lengths[i]) + members[0][i].shape[1:], members[0][i].dtype)
        for k, h in enumerate(members):  # each padded with its own last entry
            out[k, :len(h[i])] = h[i]
            out[k, len(h[i]):] = h[i][-1]
        out[len(members):] = out[len(members) - 1]
        stacked.append(out)
    return {f: x.astype(np.int32) if x.dtype.kind == "i" else x.astype(np.float32) for f, x in zip(HULL_FIELDS, stacked)}


def narrow_capacity(count: int) -> int:
    """Narrow-phase batch size for ``count`` kept items: powers of four from MIN_CAPACITY, then
    whole chunks in powers of two: a sweep meets a few capacities per pair class, each a compile."""
    capacity = MIN_CAPACITY
    while capacity < min(count, CHUNK_ITEMS):
        capacity *= 4
    if count <= CHUNK_ITEMS:
        return min(capacity, CHUNK_ITEMS)
    return CHUNK_ITEMS * (1 << (math.ceil(count / CHUNK_ITEMS) - 1).bit_length())


def _padded(objects: list[ObjectArrays], shapes: Shapes) -> tuple[dict[str, np.ndarray], list]:
    """The batch's per-object arrays, each object padded to ``shapes``, and the hull stacks per
    tier (an object's hulls at its offset in each tier's stack)."""
    n, nb, ng, npair = shapes.objects, shapes.bodies, shapes.geoms, shapes.pairs
    out = {
        "body_parent": np.zeros((n, nb), np.int32), "body_pos": np.zeros((n, nb, 3), np.float32),
        "body_quat": np.tile(np.array([1, 0, 0, 0], np.float32), (n, nb, 1)), "joint_kind": np.zeros((n, nb), np.int32),
        "joint_qpos": np.zeros((n, nb), np.int32), "joint_pos": np.zeros((n, nb, 3), np.float32),
        "joint_axis": np.zeros((n, nb, 3), np.float32), "joint_ref": np.zeros((n, nb), np.float32),
        "geom_body": np.zeros((n, ng), np.int32), "geom_pos": np.zeros((n, ng, 3), np.float32),
        "geom_quat": np.tile(np.array([1, 0, 0, 0], np.float32), (n, ng, 1)), "geom_box": np.zeros((n, ng, 6), np.float32),
        "geom_hull": np.zeros((n, ng), np.int32), "pairs": np.zeros((n, npair, 2), np.int32),
        "pair_valid": np.zeros((n, npair), bool), "pair_tier": np.zeros((n, npair), np.int32),
    }
    members: list[list] = [[], []]
    for i, o in enumerate(objects):
        b, g, p = o.nbody, len(o.geom_body), len(o.pairs)
        for key in ("body_parent", "body_pos", "body_quat", "joint_kind", "joint_qpos", "joint_pos", "joint_axis", "joint_ref"):
            out[key][i, :b] = getattr(o, key)
        for key in ("geom_body", "geom_pos", "geom_quat", "geom_box"):
            out[key][i, :g] = getattr(o, key)
        out["geom_hull"][i, :g] = o.geom_slot + np.where(o.geom_tier == 0, len(members[0]), len(members[1]))
        out["pairs"][i, :p] = o.pairs
        out["pair_valid"][i, :p] = True
        tiers = o.geom_tier[o.pairs] if p else np.zeros((0, 2), np.int32)
        out["pair_tier"][i, :p] = [TIER_CLASSES.index((int(a), int(c))) for a, c in tiers]
        members[0] += o.hulls[0]
        members[1] += o.hulls[1]
    return out, [_stack_hulls(members[t], shapes.hulls[t], shapes.hull_sizes[t]) for t in (0, 1)]


def batch_pair_distances(objects: list[ObjectArrays], qpos: list[np.ndarray], at_least: Shapes = Shapes(),
                         timings: dict[str, float] | None = None, size_classes: bool = True
                         ) -> tuple[list[np.ndarray], Shapes]:
    """Per object, [S, nbody, nbody] deepest contact distance per body pair (metres, < 0; +inf:
    none) at its joint states ``qpos[i]`` ([S_i, nq_i]), all objects in one launch; and the
    shapes the launch was padded to (at least ``at_least``). ``timings`` gathers the seconds of
    the host's padding ("pad"), the broad phase ("broad"), the narrow phase ("narrow") and the
    tables ("tables"). ``size_classes=False`` pads no size (with ``at_least=EXACT``; the
    narrow phase's capacity aside): every launch compiles, the reference padding is tested against."""
    clock = [time.perf_counter()]

    def lap(name: str) -> None:
        clock.append(time.perf_counter())
        if timings is not None:
            timings[name] = timings.get(name, 0.0) + clock[-1] - clock[-2]

    shapes = _needed(objects, qpos, size_classes).grown(at_least)
    arrays, hulls = _padded(objects, shapes)
    item_object = np.zeros(shapes.items, np.int32)  # padded items (object 0's first state) are masked out
    first_item = np.zeros(len(objects), np.int64)
    states = np.zeros((shapes.items, shapes.nq), np.float32)
    row = 0
    for i, q in enumerate(qpos):
        item_object[row:row + len(q)] = i
        states[row:row + len(q), :q.shape[1]] = q
        first_item[i] = row
        row += len(q)
    states[row:] = states[0]
    valid = np.arange(shapes.items) < row
    lap("pad")
    pos, rot, keep, counts = _broad_phase(arrays, item_object, states, valid)  # numpy in: no staging compile per shape
    counts = np.asarray(counts)
    lap("broad")
    found_flat, found_dist = [], []
    for k, ((t1, t2), count) in enumerate(zip(TIER_CLASSES, counts)):
        if count:  # capacities stay per launch (narrow_capacity): a sweep's largest would cost every launch its time
            capacity = narrow_capacity(int(count))
            if shapes.capacity:  # a floor that grows as the other shapes do: compiles only as it grows
                capacity = max(capacity, shapes.capacity)
                shapes = dataclasses.replace(shapes, capacity=capacity)
            flat, dist = _class_depths(arrays["pairs"], arrays["geom_hull"], arrays["pair_tier"], hulls[t1], hulls[t2],
                                       item_object, pos, rot, keep, count, pair_class=k, capacity=capacity)
            flat, dist = np.asarray(flat)[:count], np.asarray(dist, np.float64)[:count]
            found_flat.append(flat[np.isfinite(dist)])
            found_dist.append(dist[np.isfinite(dist)])
    lap("narrow")
    flat = np.concatenate(found_flat) if found_flat else np.zeros(0, np.int64)
    dist = np.concatenate(found_dist) if found_dist else np.zeros(0)
    item, pair = flat // shapes.pairs, flat % shapes.pairs
    owner = item_object[item]
    out = []
    for i, (o, q) in enumerate(zip(objects, qpos)):  # only the interpenetrating entries travel to the tables
        table = np.full((len(q), o.nbody, o.nbody), np.inf)
        mine = owner == i
        rows, geoms = item[mine] - first_item[i], o.pairs[pair[mine]]
        b1, b2 = o.geom_body[geoms[:, 0]], o.geom_body[geoms[:, 1]]
        np.minimum.at(table, (rows, b1, b2), dist[mine])
        np.minimum.at(table, (rows, b2, b1), dist[mine])
        out.append(table)
    lap("tables")
    return out, shapes


def padded_pair_distances(model: mujoco.MjModel, qpos: np.ndarray) -> np.ndarray:
    """``batch_pair_distances`` of one model: its compile serves every model of the same size classes."""
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", UserWarning)
        return batch_pair_distances([object_arrays(model)], [np.asarray(qpos)])[0][0]
