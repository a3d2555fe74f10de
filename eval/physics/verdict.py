"""Per-joint and per-object verdicts from the check results (pure numpy over the batched tables).

Reasons are short stable strings: "penetrates parent at rest", "penetrates part P at q=V",
"penetrates part P (passes through it) at q=V" (a thin board driven through another, see ``crossing``),
"penetrates part P while joint J moves (q=V)" (another joint's sweep runs into this joint's part, or carries it into P;
"penetrates part P (passes through it) while joint J moves (q=V)" when the two pass through each other),
"penetrates the floor at q=V" (below the rest pose's lowest point, where the gravity test's floor is),
"detached from parent at q=V", "detached from parent at rest (gap G nu)" (a joint needs its two bodies
to meet: REST_CONTACT_TOL_NU), "detached from its guide (part G, ...)" (a slide child carried out of the
part it runs in, see ``guides``), "pivot detached", "limit unreachable: lo|hi", "disagrees with part B
(symmetric|instance): ..." (a related part articulates otherwise, see ``relations``), and object-level
"rest interpenetration: parts A,B" (fails the object), "combination interpenetration: parts A,B"
(reported only), "unstable under gravity". Joint values V are in radians (hinge) or nu (slide).
"""

from __future__ import annotations

import functools
from typing import Any

import numpy as np
import trimesh

from eval.physics import cpu_backend
from eval.physics.crossing import crossings
from eval.physics.dynamics import gravity, reachability, tolerated_pairs
from eval.physics.floor import first_below_floor
from eval.physics.guides import carried_out_of_guide, welded
from eval.physics.relations import relation_disagreements
from eval.physics.sim_model import SimModel, SimOptions, build_sim_model
from eval.physics.states import StateBatch, check_states
from eval.physics.tolerances import (ATTACH_TOL_NU, DETACH_TOL_NU, PENETRATION_TOL_NU, REST_CONTACT_TOL_NU, RECONTACT_DEPTH_NU,
                                     REST_PENETRATION_TOL_NU, LIFT_OFF_MAX_NU, SLIDE_GUIDE_OVERLAP_NU)
from jax3dc.export.assembly import frames_nu, tree_order
from jax3dc.structure.schema import Structure

def check_object(structure: Structure, parts: dict[int, trimesh.Trimesh], scale: float = 1.0,
                 backend: str = "c", dynamics: bool = True, mounted: bool = False) -> dict[str, Any]:
    """The verdict {"ok", "joints": {id: {"ok", "reasons"}}, "checks": {...}} of one object.

    ``backend``: "c" (C MuJoCo) or "mjx" for the kinematic checks and the rollouts; ``dynamics``
    adds limit reachability and the gravity test; ``mounted``: the object is fixed in place in use
    (a faucet, a wall cabinet), so the gravity test holds its root instead of standing it on a floor.
    """
    return check_object_with_curves(structure, parts, scale, backend, dynamics, mounted)[0]


def check_object_with_curves(structure: Structure, parts: dict[int, trimesh.Trimesh], scale: float = 1.0,
                             backend: str = "c", dynamics: bool = True, mounted: bool = False,
                             threads: int | None = None) -> tuple[dict[str, Any], dict[int, Any]]:
    """``check_object`` and, per jointed part, (joint values, deepest penetration in nu) over its sweep.

    ``threads``: C rollout threads (default: every core; fewer when objects run in parallel processes).
    """
    with np.errstate(all="ignore"):  # trimesh's mass integrals divide by the zero volume of flat parts
        kinematic = build_sim_model(structure, parts, scale, SimOptions(margin_m=DETACH_TOL_NU * scale))
    states = check_states(kinematic)
    proximity = cpu_backend.pair_distances(kinematic.model, states.qpos)
    distances = proximity
    if backend == "mjx":  # MJX has no mesh-mesh margin: it gives penetration, C keeps the proximity check
        from eval.physics.mjx_backend import mjx_pair_distances
        bare = build_sim_model(structure, parts, scale, SimOptions(), kinematic.pieces)
        distances = mjx_pair_distances(bare.model, states.qpos)
    verdict = verdict_from(structure, parts, kinematic, states, distances, proximity)
    if dynamics:
        if backend == "mjx":
            from eval.physics.mjx_dynamics import mjx_final_qpos
            rollout = mjx_final_qpos
        else:
            rollout = functools.partial(cpu_backend.final_qpos, threads=threads)
        exclude = tolerated_pairs(kinematic, distances, PENETRATION_TOL_NU * scale, states, RECONTACT_DEPTH_NU * scale)
        extra = reachability(structure, parts, scale, exclude, kinematic.pieces, rollout)
        problems, sag = gravity(structure, parts, scale, kinematic.pieces, rollout, mounted)
        verdict["checks"]["gravity"] = problems
        for part, joint in verdict["joints"].items():
            joint["reasons"] += extra.get(int(part), []) + sag.get(int(part), [])
            joint["ok"] = not joint["reasons"]
        verdict["ok"] = verdict["ok"] and not problems and all(j["ok"] for j in verdict["joints"].values())
    return verdict, penetration_curves(kinematic, states, distances)


def penetration_curves(sim: SimModel, states: StateBatch, distances: np.ndarray) -> dict[int, Any]:
    """Per jointed part: joint values (rad / nu) and the deepest contact (nu, ≥ 0) between the parts
    it moves and the rest of the object, in sweep order."""
    group = sim.group_of_body
    curves = {}
    for k, part in enumerate(sim.joint_parts):
        rows = np.nonzero(states.joint == k)[0]
        moved = sim.moved_by[k]
        across = (moved[:, None] ^ moved[None, :]) & (group[:, None] != group[None, :])
        depth = [max(0.0, float(-np.min(np.where(across, distances[s], np.inf), initial=0.0))) / sim.scale for s in rows]
        unit = 1.0 if sim.joint_type[k] == "hinge" else sim.scale
        curves[part] = (states.value[rows] / unit, np.asarray(depth))
    return curves


def verdict_from(structure: Structure, parts: dict[int, trimesh.Trimesh], sim: SimModel, states: StateBatch,
                 distances: np.ndarray, proximity: np.ndarray | None = None) -> dict[str, Any]:
    """Kinematic verdict from [S, nbody, nbody] contact distances (penetration) and proximity
    distances (contacts within the detachment margin; the same array on the C path)."""
    proximity = distances if proximity is None else proximity
    scale = sim.scale
    body_part = {b: p for p, b in sim.part_body.items()}
    group = sim.group_of_body
    distinct = (group[:, None] != group[None, :]) & (group[:, None] >= 0) & (group[None, :] >= 0)
    rest_pen = (distances[0] < -REST_PENETRATION_TOL_NU * scale) & distinct
    reasons: dict[int, list[str]] = {p: [] for p in sim.joint_parts}
    checks: dict[str, Any] = {}
    checks["rest"] = sorted({f"rest interpenetration: parts {min(body_part[a], body_part[b])},{max(body_part[a], body_part[b])}"
                             for a, b in zip(*np.nonzero(rest_pen)) if a < b})
    # pairs already deeper than the sweep tolerance at rest are the rest check's business (at its own tolerance)
    rest_deep = distances[0] < -PENETRATION_TOL_NU * scale
    pen = (distances < -PENETRATION_TOL_NU * scale) & distinct[None] & ~rest_deep[None]
    # the joint that moves a body's rigid group (None: the group of a root)
    joint_of_group = {sim.part_body[p]: k for k, p in enumerate(sim.joint_parts)}
    sweeps = {}
    for k, part in enumerate(sim.joint_parts):
        rows = _nearest_rest_first(np.nonzero(states.joint == k)[0], states.value, sim.model.qpos0[sim.joint_qpos[k]])
        sweeps[part] = states.value[rows] / (1.0 if sim.joint_type[k] == "hinge" else scale)
    crossed = crossings(structure, parts, sweeps, _pieces_nu(structure, sim))  # thin boards driven through each other: too shallow for the depth test
    for k, part in enumerate(sim.joint_parts):
        unit = 1.0 if sim.joint_type[k] == "hinge" else scale
        moved = sim.moved_by[k]
        child, parent = sim.part_body[part], sim.parent_body[k]
        if rest_pen[child, parent]:
            reasons[part].append("penetrates parent at rest")
        across = moved[:, None] ^ moved[None, :]
        rows = _nearest_rest_first(np.nonzero(states.joint == k)[0], states.value, sim.model.qpos0[sim.joint_qpos[k]])
        hit = None
        for s in rows:
            pairs = np.argwhere(pen[s] & across)
            if len(pairs):
                a, b = pairs[0]
                other = b if moved[a] else a
                hit = f"penetrates part {body_part[other]} at q={states.value[s] / unit:.3f}"
                break
        if hit is None and part in crossed:
            other, value = crossed[part]
            hit = f"penetrates part {other} (passes through it) at q={value:.3f}"
        if part in crossed:  # ... and a jointed part it passes through (or that passes through it) while staying put
            other, value = crossed[part]
            k2 = joint_of_group.get(int(group[sim.part_body[other]]))
            hurt = None if k2 is None or sim.moved_by[k2][child] else sim.joint_parts[k2]
            if hurt is not None and not any(r.startswith("penetrates part") for r in reasons[hurt]):
                reasons[hurt].append(f"penetrates part {part} (passes through it) while joint {part} moves (q={value:.3f})")
        if hit:
            reasons[part].append(hit)
        below = first_below_floor(structure, parts, part, states.value[rows] / unit)
        if below is not None:
            reasons[part].append(f"penetrates the floor at q={below:.3f}")
        # a jointed part that this sweep runs into is at fault too: it stays put while the part
        # it should move with (a handle on a door, given the wrong parent) swings through it
        for s in rows:
            for a, b in np.argwhere(pen[s] & across):
                other = b if moved[a] else a
                k2 = joint_of_group.get(int(group[other]))
                hurt = None if k2 is None or sim.moved_by[k2][child] else sim.joint_parts[k2]  # not an ancestor
                if hurt is not None and not any(r.startswith("penetrates part") for r in reasons[hurt]):
                    reasons[hurt].append(f"penetrates part {body_part[a if other == b else b]} "
                                         f"while joint {part} moves (q={states.value[s] / unit:.3f})")
                # ... and so is a jointed part that this sweep carries into another (a rack hung on the
                # dishwasher door instead of the tub: the door swings it through the tub)
                k3 = joint_of_group.get(int(group[a if other == b else b]))
                carried = None if k3 is None or k3 == k else sim.joint_parts[k3]
                if carried is not None and not any(r.startswith("penetrates part") for r in reasons[carried]):
                    reasons[carried].append(f"penetrates part {body_part[other]} "
                                            f"while joint {part} moves (q={states.value[s] / unit:.3f})")
        parent_group = group == group[parent]
        overlap = None  # slides: the child's overlap with its parent along the axis, per sweep value (nu)
        guided = False  # ... and whether it runs in a guide there
        if sim.joint_type[k] == "slide":
            overlap, guide_overlap = _overlap_along_axis(structure, parts, part, [body_part[b] for b in np.nonzero(moved)[0]],
                                                         [body_part[b] for b in np.nonzero(parent_group)[0]])
            guided = overlap(0.0) >= guide_overlap
        values_nu = states.value[rows] / unit
        if overlap is not None and not guided and _lifts_off(overlap, values_nu):  # a lid: parting from its parent is the motion
            gone = [v for v in values_nu if -overlap(v) > LIFT_OFF_MAX_NU]
            if gone:
                reasons[part].append(f"detached from parent (lifted off too far) at q={gone[0]:.3f}")
        else:
            for s in rows:
                near = proximity[s][np.ix_(moved, parent_group)]
                if not np.any(near < DETACH_TOL_NU * scale):
                    reasons[part].append(f"detached from parent at q={states.value[s] / unit:.3f}")
                    break
        if guided and not any(r.startswith("detached") for r in reasons[part]):
            out = [v for v in values_nu if overlap(v) <= 0.0]  # a drawer or rack in its guide must stay in it
            if out:
                reasons[part].append(f"detached from parent (slides out of its guide) at q={out[0]:.3f}")
        carried = carried_out_of_guide(structure, parts, part)  # a drawer hung on its neighbour leaves its slot
        if carried is not None and not any(r.startswith("detached") for r in reasons[part]):
            guide, values = carried
            opened = ", ".join(f"joint {p} at {v:.3f}" for p, v in values.items())
            reasons[part].append(f"detached from its guide (part {guide}, runs out of it with {opened})")
        # a joint connects two bodies that meet: a part given a parent it does not touch at rest (a
        # drawer hung on the drawer beside it, which would carry it out of its own slot) is not held by it
        gap = float(np.min(proximity[0][np.ix_(group == group[child], parent_group)], initial=np.inf)) / scale
        if gap > REST_CONTACT_TOL_NU:
            shown = f"{gap:.3f} nu" if np.isfinite(gap) else f"over {DETACH_TOL_NU} nu"
            reasons[part].append(f"detached from parent at rest (gap {shown})")
        if not _pivot_attached(structure, parts, part):
            reasons[part].append("pivot detached")
    for part, found in relation_disagreements(structure, parts).items():
        reasons[part] += found
    combos = states.joint == -2
    found = set()
    for s in np.nonzero(combos)[0]:
        for a, b in np.argwhere(pen[s]):
            if a < b:
                found.add(f"combination interpenetration: parts {min(body_part[a], body_part[b])},{max(body_part[a], body_part[b])}")
    single = {tuple(sorted((a, b))) for s in np.nonzero(states.joint >= 0)[0] for a, b in np.argwhere(pen[s])}
    checks["combinations"] = sorted(r for r in found if not _pair_of(r) & {(body_part[a], body_part[b]) for a, b in single})
    joints = {str(p): {"ok": not r, "reasons": r} for p, r in reasons.items()}
    # combinations are reported, not failed: real objects have dependent joints (a dishwasher rack
    # slides out only with the door open, folded eyeglass temples cross)
    ok = all(j["ok"] for j in joints.values()) and not checks["rest"]
    return {"ok": ok, "joints": joints, "checks": checks}


def _pair_of(reason: str) -> set[tuple[int, int]]:
    a, b = (int(x) for x in reason.rsplit(" ", 1)[1].split(","))
    return {(a, b), (b, a)}


def _nearest_rest_first(rows: np.ndarray, values: np.ndarray, rest: float) -> np.ndarray:
    return rows[np.argsort(np.abs(values[rows] - rest), kind="stable")]


def _overlap_along_axis(structure: Structure, parts: dict[int, trimesh.Trimesh], part: int, moved: list[int],
                        holders: list[int]):
    """(v (nu) -> how far the moved parts' extent along the slide axis overlaps the parent group's
    once slid by v (negative: the gap between them), the rest overlap from which the child runs in a
    guide). A drawer in its carcass overlaps by most of its depth (SLIDE_GUIDE_OVERLAP_NU), a
    toaster's lever in its slot by all of its own length (shorter than that): both run in a guide;
    a lid sitting on its pot overlaps by about 0."""
    axis = np.asarray(structure.nodes[part].joint.axis, dtype=np.float64)
    axis /= np.linalg.norm(axis)

    def extent(ids: list[int]) -> tuple[float, float]:
        t = np.concatenate([np.asarray(parts[i].vertices, dtype=np.float64) for i in ids]) @ axis
        return float(t.min()), float(t.max())

    (clo, chi), (plo, phi) = extent(moved), extent(holders)
    return (lambda v: min(chi + v, phi) - max(clo + v, plo)), min(SLIDE_GUIDE_OVERLAP_NU, chi - clo - 1e-6)


def _lifts_off(overlap, values_nu: np.ndarray) -> bool:
    """An unguided slide that only ever parts the child from its parent, one way (a lid lifted off
    a pot; a part slid off to either side is not a lid)."""
    rest = overlap(0.0)
    one_way = bool(np.all(values_nu >= -1e-9) or np.all(values_nu <= 1e-9))
    return one_way and all(overlap(v) <= rest + 1e-9 for v in values_nu)


def _pivot_attached(structure: Structure, parts: dict[int, trimesh.Trimesh], part: int) -> bool:
    """A hinge's axis line passes within ATTACH_TOL_NU of the child and of its parent (nu, rest pose).

    Slides are not checked: their pivot does not change the motion.
    """
    node = structure.nodes[part]
    if node.joint is None or node.joint.type != "hinge":
        return True
    axis = np.asarray(node.joint.axis, dtype=np.float64)
    axis /= np.linalg.norm(axis)
    pivot = np.asarray(node.joint.pivot, dtype=np.float64)

    def line_distance(mesh: trimesh.Trimesh) -> float:
        points = np.concatenate([mesh.vertices, mesh.sample(4000, seed=0)]) if len(mesh.faces) else mesh.vertices
        rel = points - pivot
        return float(np.min(np.linalg.norm(rel - np.outer(rel @ axis, axis), axis=1)))

    # the parent is the rigid body it is welded into: a stapler's arm parented to the base hinges on
    # the block fixed to that base, the same body in a simulator
    holder = min(line_distance(parts[p]) for p in welded(structure, node.parent))
    return line_distance(parts[part]) <= ATTACH_TOL_NU and holder <= ATTACH_TOL_NU


def _pieces_nu(structure: Structure, sim: SimModel) -> dict[int, list[np.ndarray]]:
    """The collision pieces' vertices in the rest pose's object frame (nu); the model holds them in
    each part's frame, in metres."""
    frames = frames_nu(structure, tree_order(structure))
    return {p: [v / sim.scale + frames[p] for v in pieces] for p, pieces in sim.pieces.items()}
