"""The two checks that need dynamics: limit reachability and stability under gravity.

Both are short rollouts from rest, batched: ``cpu_backend.final_qpos`` (C, ``mujoco.rollout``
threads) or ``mjx_dynamics.mjx_final_qpos`` (vmapped MJX steps), passed as ``rollout``. For reachability,
contacts are frictionless and only the part pairs that collide along the kinematic sweeps stay in
contact (``tolerated_pairs``), so a joint stops at a collision the sweep found, at its own limit,
or where its servo loses against gravity.
"""

from __future__ import annotations

from typing import Callable

import mujoco
import numpy as np
import trimesh
from scipy.spatial.transform import Rotation

from jax3dc.export.simulation import hinge_reach
from jax3dc.physics import cpu_backend
from jax3dc.physics.findings import FAILURE, WARNING, Finding
from jax3dc.physics.sim_model import SimModel, SimOptions, build_sim_model
from jax3dc.physics.states import StateBatch
from jax3dc.physics.tolerances import (GRAVITY_DRIFT_NU, GRAVITY_JOINT_DRIFT, GRAVITY_TILT_RAD, LIMIT_PAST_CONTACT_HINGE_RAD,
                                       LIMIT_PAST_CONTACT_SLIDE_FRACTION, LIMIT_TOL_HINGE_RAD, LIMIT_TOL_SLIDE_NU,
                                       REACH_CANDIDATE_NU)
from jax3dc.structure.schema import Structure

SETTLE_STEPS = 400  # 0.8 s at the model's 2 ms step

Rollout = Callable[[mujoco.MjModel, np.ndarray, np.ndarray, int], np.ndarray]  # (model, qpos, ctrl, nstep) -> final qpos


def reachability(structure: Structure, parts: dict[int, trimesh.Trimesh], scale: float,
                 exclude: frozenset[tuple[int, int]], pieces,
                 rollout: Rollout = cpu_backend.final_qpos) -> list[Finding]:
    """A "limit" finding per joint end its servo does not get to within LIMIT_TOL_*: a warning with
    the reachable value when the limit runs at most LIMIT_PAST_CONTACT_* past where the joint stops
    (real data's limits run a little past a contact), a failure beyond that."""
    sim = reachability_model(structure, parts, scale, exclude, pieces)
    rest = sim.model.qpos0
    targets, rows = [], []
    for k in range(len(sim.joint_parts)):
        for end in (0, 1):
            ctrl = rest[sim.joint_qpos].copy()
            ctrl[k] = sim.joint_range[k, end]
            targets.append(ctrl)
            rows.append((k, end))
    if not rows:
        return []
    final = rollout(sim.model, np.repeat(rest[None], len(rows), axis=0), np.asarray(targets), SETTLE_STEPS)
    found = []
    for (k, end), q in zip(rows, final):
        hinge = sim.joint_type[k] == "hinge"
        unit = 1.0 if hinge else scale
        tol = LIMIT_TOL_HINGE_RAD if hinge else LIMIT_TOL_SLIDE_NU * scale
        travel = abs(sim.joint_range[k, 1] - sim.joint_range[k, 0])
        past = LIMIT_PAST_CONTACT_HINGE_RAD if hinge else LIMIT_PAST_CONTACT_SLIDE_FRACTION * travel
        reached = q[sim.joint_qpos[k]]
        short = abs(reached - sim.joint_range[k, end])
        if short > tol:
            found.append(Finding("limit", WARNING if short <= past else FAILURE, joints=(sim.joint_parts[k],),
                                 reachable=float(reached / unit), limit=("lo", "hi")[end]))
    return found


def reachability_model(structure: Structure, parts: dict[int, trimesh.Trimesh], scale: float,
                       exclude: frozenset[tuple[int, int]], pieces) -> SimModel:
    """The frictionless servo model of the reachability rollouts: the part pairs not in ``exclude``
    collide through those of their collision pieces that come within REACH_CANDIDATE_NU of each
    other somewhere on a sweep of each joint from its lower to its upper limit, the others at rest
    (a rollout drives one joint there). Far pieces cannot meet, and each piece pair MJX may test
    costs it a compiled function (a PartNet-Mobility safe: 2,057 pairs of its door's and dial's
    pieces, minutes of compiling)."""
    near = build_sim_model(structure, parts, scale, SimOptions(margin_m=REACH_CANDIDATE_NU * scale), pieces)
    pairs = _near_piece_pairs(near, exclude)
    return build_sim_model(structure, parts, scale, SimOptions(actuators=True, exclude=exclude, frictionless=True,
                                                              contact_pairs=pairs), pieces)


def _near_piece_pairs(sim: SimModel, exclude: frozenset[tuple[int, int]]) -> frozenset[tuple[str, str]]:
    """Names of the collision geom pairs of different, not excluded parts that some state of the
    joints' sweeps brings within the model's margin. Each sweep is dense enough that no point of the
    moved parts travels more than half the margin between states, so no pair meets unseen."""
    model = sim.model
    body_part = {b: p for p, b in sim.part_body.items()}
    data = mujoco.MjData(model)
    step_m = 0.5 * float(model.geom_margin.max())
    found: set[tuple[int, int]] = set()
    for k, adr in enumerate(sim.joint_qpos):
        lo, hi = sim.joint_range[k]
        joint = int(np.nonzero(model.jnt_qposadr == adr)[0][0])
        travel = (hi - lo) * (hinge_reach(model, data, joint) if sim.joint_type[k] == "hinge" else 1.0)
        for value in np.linspace(lo, hi, max(2, int(np.ceil(travel / max(step_m, 1e-9))) + 1)):
            data.qpos[:] = model.qpos0
            data.qpos[adr] = value
            mujoco.mj_kinematics(model, data)
            mujoco.mj_collision(model, data)
            found.update(zip(data.contact.geom1[:data.ncon].tolist(), data.contact.geom2[:data.ncon].tolist()))
    out = set()
    for g1, g2 in found:
        a, b = body_part.get(int(model.geom_bodyid[g1])), body_part.get(int(model.geom_bodyid[g2]))
        if a is None or b is None or a == b or (min(a, b), max(a, b)) in exclude:
            continue
        names = sorted((mujoco.mj_id2name(model, mujoco.mjtObj.mjOBJ_GEOM, g1), mujoco.mj_id2name(model, mujoco.mjtObj.mjOBJ_GEOM, g2)))
        out.add((names[0], names[1]))
    return frozenset(out)


def gravity(structure: Structure, parts: dict[int, trimesh.Trimesh], scale: float, pieces,
            rollout: Rollout = cpu_backend.final_qpos, mounted: bool = False) -> list[Finding]:
    """Object-level "gravity" (shown "unstable under gravity ...") and per-joint "sag" findings on a
    floor, joints held (not for full-turn hinges: a wheel or dial turned is still a pose the object has).

    Parts touch only the floor here, and in a scene the other objects' parts (an object may rest on
    another, SPEC §2 ``support``): an object's own contacts are the kinematic checks' concern. A
    scene's findings name the root of the object that does not stand.
    A ``mounted`` object (a faucet on its sink, a toilet bolted down) keeps its root fixed: only
    the held joints are tested.
    """
    sim = build_sim_model(structure, parts, scale, SimOptions(floor=not mounted, free_root=not mounted, actuators=True,
                                                              floor_contacts_only=True), pieces)
    model = sim.model
    rest = model.qpos0.copy()
    final = rollout(model, rest[None], rest[sim.joint_qpos][None], SETTLE_STEPS)[0]
    found: list[Finding] = []
    for j in range(model.njnt):
        if int(model.jnt_type[j]) != int(mujoco.mjtJoint.mjJNT_FREE):
            continue
        adr = model.jnt_qposadr[j]
        drift = float(np.linalg.norm(final[adr:adr + 3] - rest[adr:adr + 3])) / scale
        tilt = _tilt(final[adr + 3:adr + 7])
        if not np.isfinite(drift) or drift > GRAVITY_DRIFT_NU or tilt > GRAVITY_TILT_RAD:
            root = (int(model.joint(j).name.removeprefix("free_")),) if len(structure.roots()) > 1 else ()
            found.append(Finding("gravity", parts=root, depth=drift, tilt=tilt))
    for k, part in enumerate(sim.joint_parts):
        if _full_turn(sim, k):  # every angle is a pose of the object (a wheel rolled by settling: C 0.196 rad, MJX 0.201)
            continue
        unit = 1.0 if sim.joint_type[k] == "hinge" else scale
        moved = abs(final[sim.joint_qpos[k]] - rest[sim.joint_qpos[k]]) / unit
        if not np.isfinite(moved) or moved > GRAVITY_JOINT_DRIFT:
            found.append(Finding("sag", joints=(part,), depth=float(moved)))
    return found


def _full_turn(sim: SimModel, k: int) -> bool:
    """A hinge whose range is a whole turn (to within the limit tolerance): no angle is a sag."""
    lo, hi = sim.joint_range[k]
    return sim.joint_type[k] == "hinge" and hi - lo >= 2 * np.pi - LIMIT_TOL_HINGE_RAD


def _tilt(quat: np.ndarray) -> float:
    """Angle between the body's z axis and the world's (MuJoCo's quaternion order w, x, y, z)."""
    zz = Rotation.from_quat(quat, scalar_first=True).as_matrix()[2, 2]
    return float(np.arccos(np.clip(zz, -1.0, 1.0)))


def tolerated_pairs(sim: SimModel, distances: np.ndarray, depth_m: float, states: StateBatch | None = None,
                    recontact_m: float = 0.0) -> frozenset[tuple[int, int]]:
    """Part pairs that never interpenetrate deeper than ``depth_m`` over the kinematic states, or
    already do at rest: left out of the reachability model, so that a servo is stopped only by a
    collision that the kinematic checks also report (or by gravity and its own limits).

    With ``states``, a pair that a joint's sweep first parts (or leaves grazing) and then, farther from rest, drives
    ``recontact_m`` deeper into each other is kept too (RECONTACT_DEPTH_NU): a door opened
    past lying flat folds back round its carcass's corner, a contact a real stop would meet."""
    body_part = {b: p for p, b in sim.part_body.items()}
    deep_later = (distances[1:] < -depth_m).any(axis=0) if len(distances) > 1 else np.zeros_like(distances[0], bool)
    blocking = deep_later & ~(distances[0] < -depth_m)
    if states is not None:
        blocking = blocking | _recontacts(sim, distances, states, recontact_m)
    ids = sorted(body_part)
    return frozenset((min(body_part[a], body_part[b]), max(body_part[a], body_part[b]))
                     for i, a in enumerate(ids) for b in ids[i + 1:] if not blocking[a, b])


def _recontacts(sim: SimModel, distances: np.ndarray, states: StateBatch, depth_m: float) -> np.ndarray:
    """[nbody, nbody] bool: some joint's sweep, followed from rest towards either limit, has the
    pair apart or grazing (shallower than ``depth_m``) and later ``depth_m`` deeper than that.
    Deeper than the graze, not than zero: a sash sliding along a rail it grazes at rest, its
    sampled hull tapered by 1.4 degrees, deepens by a few mm over its travel without meeting a stop.
    Pairs interlocked at rest (a bucket handle through its lugs) never graze, whatever their depth does."""
    out = np.zeros(distances.shape[1:], dtype=bool)
    for k, adr in enumerate(sim.joint_qpos):
        rest = sim.model.qpos0[adr]
        rows = np.nonzero(states.joint == k)[0]
        for side in (1.0, -1.0):
            ahead = rows[(states.value[rows] - rest) * side > 0]
            ahead = ahead[np.argsort(np.abs(states.value[ahead] - rest))]
            shallowest = np.full(out.shape, np.inf)
            for s in ahead:
                depth = np.maximum(-distances[s], 0.0)
                out |= (shallowest < depth_m) & (depth - shallowest > depth_m)
                shallowest = np.minimum(shallowest, depth)
    return out | out.T
