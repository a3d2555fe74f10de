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

from eval.physics import cpu_backend
from eval.physics.sim_model import SimModel, SimOptions, build_sim_model
from eval.physics.states import StateBatch
from eval.physics.tolerances import (GRAVITY_DRIFT_NU, GRAVITY_JOINT_DRIFT, GRAVITY_TILT_RAD, LIMIT_TOL_HINGE_RAD,
                                     LIMIT_TOL_SLIDE_NU)
from jax3dc.structure.schema import Structure

SETTLE_STEPS = 400  # 0.8 s at the model's 2 ms step

Rollout = Callable[[mujoco.MjModel, np.ndarray, np.ndarray, int], np.ndarray]  # (model, qpos, ctrl, nstep) -> final qpos


def reachability(structure: Structure, parts: dict[int, trimesh.Trimesh], scale: float,
                 exclude: frozenset[tuple[int, int]], pieces,
                 rollout: Rollout = cpu_backend.final_qpos) -> dict[int, list[str]]:
    """Per jointed part: "limit unreachable: lo|hi (stops at q=V)" when its servo cannot get there."""
    sim = build_sim_model(structure, parts, scale, SimOptions(actuators=True, exclude=exclude, frictionless=True), pieces)
    rest = sim.model.qpos0
    targets, rows = [], []
    for k in range(len(sim.joint_parts)):
        for end in (0, 1):
            ctrl = rest[sim.joint_qpos].copy()
            ctrl[k] = sim.joint_range[k, end]
            targets.append(ctrl)
            rows.append((k, end))
    if not rows:
        return {}
    final = rollout(sim.model, np.repeat(rest[None], len(rows), axis=0), np.asarray(targets), SETTLE_STEPS)
    reasons: dict[int, list[str]] = {p: [] for p in sim.joint_parts}
    for (k, end), q in zip(rows, final):
        unit = 1.0 if sim.joint_type[k] == "hinge" else scale
        tol = LIMIT_TOL_HINGE_RAD if sim.joint_type[k] == "hinge" else LIMIT_TOL_SLIDE_NU * scale
        reached = q[sim.joint_qpos[k]]
        if abs(reached - sim.joint_range[k, end]) > tol:
            reasons[sim.joint_parts[k]].append(
                f"limit unreachable: {('lo', 'hi')[end]} (stops at q={reached / unit:.3f})")
    return reasons


def gravity(structure: Structure, parts: dict[int, trimesh.Trimesh], scale: float, pieces,
            rollout: Rollout = cpu_backend.final_qpos) -> tuple[list[str], dict[int, list[str]]]:
    """Object-level "unstable under gravity ..." and per-joint "sags under gravity" on a floor, joints held.

    Parts touch only the floor here: the object's own contacts are the kinematic checks' concern.
    """
    sim = build_sim_model(structure, parts, scale, SimOptions(floor=True, free_root=True, actuators=True,
                                                              floor_contacts_only=True), pieces)
    model = sim.model
    rest = model.qpos0.copy()
    final = rollout(model, rest[None], rest[sim.joint_qpos][None], SETTLE_STEPS)[0]
    problems: list[str] = []
    for j in range(model.njnt):
        if int(model.jnt_type[j]) != int(mujoco.mjtJoint.mjJNT_FREE):
            continue
        adr = model.jnt_qposadr[j]
        drift = float(np.linalg.norm(final[adr:adr + 3] - rest[adr:adr + 3])) / scale
        tilt = _tilt(final[adr + 3:adr + 7])
        if not np.isfinite(drift) or drift > GRAVITY_DRIFT_NU or tilt > GRAVITY_TILT_RAD:
            problems.append(f"unstable under gravity: root moved {drift:.3f} nu, tilted {tilt:.2f} rad")
    sag: dict[int, list[str]] = {p: [] for p in sim.joint_parts}
    for k, part in enumerate(sim.joint_parts):
        unit = 1.0 if sim.joint_type[k] == "hinge" else scale
        moved = abs(final[sim.joint_qpos[k]] - rest[sim.joint_qpos[k]]) / unit
        if not np.isfinite(moved) or moved > GRAVITY_JOINT_DRIFT:
            sag[part].append(f"sags under gravity by {moved:.3f}")
    return problems, sag


def _tilt(quat: np.ndarray) -> float:
    """Angle between the body's z axis and the world's (quaternion w, x, y, z)."""
    w, x, y, z = quat / np.linalg.norm(quat)
    zz = 1 - 2 * (x * x + y * y)
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
