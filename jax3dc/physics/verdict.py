"""Per-joint and per-object verdicts from the check results (pure numpy over the batched tables).

The checks produce typed findings (``jax3dc.physics.findings``: check, severity, joints, parts, depth,
joint values); the verdict JSON carries them and, for readers of text, each as a short stable
string, a joint's failures under "reasons" and its warnings under "warnings" ("limit past contact:
hi (stops at q=V)": a limit a little past where the joint stops; only failures fail). Strings:
"penetrates parent at rest", "penetrates part P at q=V",
"penetrates part P (passes through it) at q=V" (a thin board driven through another, see ``crossing``),
"penetrates part P while joint J moves (q=V)" (another joint's sweep runs into this joint's part, or carries it into P;
"penetrates part P (passes through it) while joint J moves (q=V)" when the two pass through each other),
"penetrates the floor at q=V" (below the rest pose's lowest point, where the gravity test's floor is),
"detached from parent at q=V", "detached from parent at rest (gap G nu)" (a joint needs its two bodies
to meet: REST_CONTACT_TOL_NU), "detached from its guide (part G, ...)" (a slide child carried out of the
part it runs in, see ``guides``), "pivot detached", "limit unreachable: lo|hi", "disagrees with part B
(symmetric|instance): ..." (a related part articulates otherwise, see ``relations``), and object-level
"rest interpenetration: parts A,B" (fails the object), "combination interpenetration: parts A,B"
(a warning), "unstable under gravity". Joint values V are in radians (hinge) or nu (slide).
"""

from __future__ import annotations

import functools
from dataclasses import dataclass
from typing import Any, Callable, Mapping, Protocol, Sequence

import mujoco
import numpy as np
import trimesh

from jax3dc.physics import cpu_backend
from jax3dc.physics.crossing import CrossingPlan, crossing_plan, first_crossings
from jax3dc.physics.dynamics import Rollout, gravity, reachability, tolerated_pairs
from jax3dc.physics.findings import WARNING, Finding, Verdict
from jax3dc.physics.floor import first_below_floor
from jax3dc.physics.guides import carried_out_of_guide, welded
from jax3dc.physics.relations import relation_disagreements
from jax3dc.physics.sim_model import SimModel, SimOptions, build_sim_model
from jax3dc.physics.states import StateBatch, check_states
from jax3dc.physics.tolerances import (ATTACH_TOL_NU, DETACH_TOL_NU, PENETRATION_TOL_NU, REST_CONTACT_TOL_NU, RECONTACT_DEPTH_NU,
                                       REST_PENETRATION_TOL_NU, LIFT_OFF_MAX_NU, SLIDE_GUIDE_OVERLAP_NU)
from jax3dc.export.assembly import frames_nu, tree_order
from jax3dc.structure.schema import Structure

Penetration = Callable[[mujoco.MjModel, np.ndarray], np.ndarray]  # (model, qpos [S, nq]) -> [S, nbody, nbody] distances (m)
LINE_SAMPLES = 4000  # surface points per mesh that a hinge line's distance is measured to (``surface_points``)


def check_object(structure: Structure, parts: dict[int, trimesh.Trimesh], scale: float = 1.0,
                 backend: str = "c", dynamics: bool = True, mounted: bool = False,
                 pieces: dict[int, list[np.ndarray]] | None = None) -> dict[str, Any]:
    """The verdict {"ok", "joints": {id: {"ok", "reasons", "warnings"}}, "checks": {...}, "findings": [...]}
    of one object (``Verdict.to_json``).

    ``backend``: "c" (C MuJoCo) or "mjx" for the kinematic checks and the rollouts; ``dynamics``
    adds limit reachability and the gravity test; ``mounted``: the object is fixed in place in use
    (a faucet, a wall cabinet), so the gravity test holds its root instead of standing it on a floor;
    ``pieces``: the parts' collision pieces (``jax3dc.export.simulation``) when they are given, as an
    exported file gives them, instead of decomposing the meshes.
    """
    return verdict_with_curves(structure, parts, scale, backend, dynamics, mounted, pieces=pieces)[0].to_json()


def verdict_with_curves(structure: Structure, parts: dict[int, trimesh.Trimesh], scale: float = 1.0,
                        backend: str = "c", dynamics: bool = True, mounted: bool = False,
                        threads: int | None = None, pieces: dict[int, list[np.ndarray]] | None = None,
                        penetration: Penetration | None = None, rollout: Rollout | None = None,
                        checks: Sequence[str] | None = None) -> tuple[Verdict, dict[int, Any]]:
    """The typed verdict of ``check_object`` and, per jointed part, (joint values, deepest
    penetration in nu) over its sweep.

    ``threads``: C rollout threads (default: every core; fewer when objects run in parallel processes).
    ``penetration`` and ``rollout`` replace the backend's own (the MJX sweep sends the kinematic
    states to its batched device service and keeps the rollouts in C). ``checks``: names of CHECKS
    to run, in order (default: the kinematic ones, and the dynamic ones with ``dynamics``).
    """
    names = check_names(checks, dynamics)
    inputs = kinematic_inputs(structure, parts, scale, pieces)
    distances = inputs.proximity
    if backend == "mjx":  # MJX has no mesh-mesh margin: it gives penetration, C keeps the proximity check
        if penetration is None:
            # lazy: MJX and jax (0.47 s) for the mjx backend only; the CPU path loads neither
            from jax3dc.physics.mjx_batch import padded_pair_distances as penetration
        distances = penetration(penetration_model(structure, parts, inputs), inputs.states.qpos)
    if rollout is None and backend == "mjx" and set(names) & set(DYNAMIC_CHECKS):
        from jax3dc.physics.mjx_dynamics import mjx_final_qpos as rollout  # lazy: as above (0.45 s)
    elif rollout is None:
        rollout = functools.partial(cpu_backend.final_qpos, threads=threads)
    return verdict_from(structure, parts, inputs, distances, rollout, mounted, names)


def check_names(checks: Sequence[str] | None, dynamics: bool) -> tuple[str, ...]:
    """The checks to run, in order: ``checks`` (names of CHECKS), else the kinematic ones and,
    with ``dynamics``, the dynamic ones (a ValueError names any unknown one)."""
    names = tuple(checks) if checks is not None else KINEMATIC_CHECKS + (DYNAMIC_CHECKS if dynamics else ())
    unknown = [n for n in names if n not in CHECKS]
    if unknown:
        raise ValueError(f"unknown physics checks {unknown}; known: {', '.join(CHECKS)}")
    return names


@dataclass(frozen=True)
class KinematicInputs:
    """What every backend computes on the CPU before the penetration query: the kinematic model
    (with the detachment margin), the joint states the checks visit, and C MuJoCo's contact
    distances within the margin over them ([S, nbody, nbody], m)."""

    sim: SimModel
    states: StateBatch
    proximity: np.ndarray


def kinematic_inputs(structure: Structure, parts: dict[int, trimesh.Trimesh], scale: float,
                     pieces: dict[int, list[np.ndarray]] | None = None) -> KinematicInputs:
    with np.errstate(all="ignore"):  # trimesh's mass integrals divide by the zero volume of flat parts
        kinematic = build_sim_model(structure, parts, scale, SimOptions(margin_m=DETACH_TOL_NU * scale), pieces)
    states = check_states(kinematic)
    return KinematicInputs(kinematic, states, cpu_backend.pair_distances(kinematic.model, states.qpos))


def penetration_model(structure: Structure, parts: dict[int, trimesh.Trimesh], inputs: KinematicInputs) -> mujoco.MjModel:
    """The model MJX measures penetration on: the kinematic one without the margin (same pieces)."""
    return build_sim_model(structure, parts, inputs.sim.scale, SimOptions(), inputs.sim.pieces).model


def verdict_from(structure: Structure, parts: dict[int, trimesh.Trimesh], inputs: KinematicInputs, distances: np.ndarray,
                 rollout: Rollout, mounted: bool, names: Sequence[str]) -> tuple[Verdict, dict[int, Any]]:
    """The verdict of the checks ``names`` and the penetration curves, given the contact distances
    over ``inputs.states`` (C's proximity itself, or a penetration query's)."""
    run = CheckRun(structure, parts, inputs.sim, inputs.states, distances, inputs.proximity, rollout, mounted)
    return run_checks(run, names), penetration_curves(inputs.sim, inputs.states, distances)


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


@dataclass
class CheckRun:
    """What every check reads: the object, its kinematic model, the checked joint states and the
    contact distances over them ([S, nbody, nbody], m; ``proximity``: contacts within the
    detachment margin, the same array on the C path), and how the dynamic checks roll out. The
    arrays the kinematic checks share are computed once, on first use. ``distances`` is None in a
    run of the DISTANCE_FREE_CHECKS alone; ``given_crossings``: the board crossings when a batched
    launch found them (``crossing_plan_of``), else ``crossed`` finds them."""

    structure: Structure
    parts: dict[int, trimesh.Trimesh]
    sim: SimModel
    states: StateBatch
    distances: np.ndarray
    proximity: np.ndarray
    rollout: Rollout
    mounted: bool
    given_crossings: dict[int, tuple[int, float]] | None = None

    @functools.cached_property
    def crossed(self) -> dict[int, tuple[int, float]]:
        """Thin boards driven through each other (``crossing``): too shallow for the depth test."""
        if self.given_crossings is not None:
            return self.given_crossings
        plan = crossing_plan_of(self.structure, self.parts, self.sim, self.states)
        return plan.resolve(first_crossings(plan))

    @functools.cached_property
    def body_part(self) -> dict[int, int]:
        return {b: p for p, b in self.sim.part_body.items()}

    @functools.cached_property
    def distinct(self) -> np.ndarray:
        """[nbody, nbody]: bodies of two different rigid groups (welded bodies never collide)."""
        group = self.sim.group_of_body
        return (group[:, None] != group[None, :]) & (group[:, None] >= 0) & (group[None, :] >= 0)

    @functools.cached_property
    def rest_pen(self) -> np.ndarray:
        return (self.distances[0] < -REST_PENETRATION_TOL_NU * self.sim.scale) & self.distinct

    @functools.cached_property
    def pen(self) -> np.ndarray:
        """[S, nbody, nbody]: pairs deeper than the sweep tolerance; pairs already that deep at rest
        are the rest check's business (at its own tolerance)."""
        rest_deep = self.distances[0] < -PENETRATION_TOL_NU * self.sim.scale
        return (self.distances < -PENETRATION_TOL_NU * self.sim.scale) & self.distinct[None] & ~rest_deep[None]

    def pair(self, a: int, b: int) -> tuple[int, int]:
        return tuple(sorted((self.body_part[a], self.body_part[b])))


class Check(Protocol):
    """A physics check: its findings on one object, in a stable order."""

    def __call__(self, run: CheckRun) -> list[Finding]: ...


def rest_check(run: CheckRun) -> list[Finding]:
    """Object-level: two parts interpenetrate in the rest pose."""
    return [Finding("rest", parts=run.pair(a, b), depth=float(-run.distances[0][a, b]) / run.sim.scale)
            for a, b in zip(*np.nonzero(run.rest_pen)) if a < b]


def joint_checks(run: CheckRun) -> list[Finding]:
    """Per joint, over its sweep: what it drives into (or through) and whether its part stays on its parent."""
    sim, states, crossed = run.sim, run.states, run.crossed
    found: list[Finding] = []
    for k, part in enumerate(sim.joint_parts):
        rows = _nearest_rest_first(np.nonzero(states.joint == k)[0], states.value, sim.model.qpos0[sim.joint_qpos[k]])
        _motion_findings(run, k, part, rows, crossed, found)
        _attachment_findings(run, k, part, rows, found)
    return found


def crossing_plan_of(structure: Structure, parts: dict[int, trimesh.Trimesh], sim: SimModel,
                     states: StateBatch) -> CrossingPlan:
    """The board-crossing check of every joint's sweep (nearest rest first), as data
    (``crossing.crossing_plan``): a batched launch answers many verdicts' at once."""
    sweeps = {}
    for k, part in enumerate(sim.joint_parts):
        rows = _nearest_rest_first(np.nonzero(states.joint == k)[0], states.value, sim.model.qpos0[sim.joint_qpos[k]])
        sweeps[part] = states.value[rows] / (1.0 if sim.joint_type[k] == "hinge" else sim.scale)
    return crossing_plan(structure, parts, sweeps, _pieces_nu(structure, sim))


def _has(found: list[Finding], part: int, checks: set[str]) -> bool:
    return any(f.joints[0] == part and f.check in checks for f in found if f.joints)


def _motion_findings(run: CheckRun, k: int, part: int, rows: np.ndarray, crossed: dict, found: list[Finding]) -> None:
    """Joint ``k``'s sweep (``rows``, nearest rest first): its part driven into or through another,
    or below the floor, and the jointed parts the sweep runs into or carries into others."""
    sim, states, distances, pen, body_part, scale = run.sim, run.states, run.distances, run.pen, run.body_part, run.sim.scale
    group = sim.group_of_body
    joint_of_group = {sim.part_body[p]: j for j, p in enumerate(sim.joint_parts)}  # the joint that moves a rigid group
    unit = 1.0 if sim.joint_type[k] == "hinge" else scale
    moved = sim.moved_by[k]
    child, parent = sim.part_body[part], sim.parent_body[k]
    if run.rest_pen[child, parent]:
        found.append(Finding("rest parent", joints=(part,), parts=(body_part[parent],),
                             depth=float(-distances[0][child, parent]) / scale))
    across = moved[:, None] ^ moved[None, :]
    hit = None
    for s in rows:
        pairs = np.argwhere(pen[s] & across)
        if len(pairs):
            a, b = pairs[0]
            other = b if moved[a] else a
            hit = Finding("penetration", joints=(part,), parts=(body_part[other],), depth=float(-distances[s][a, b]) / scale,
                          state=((part, float(states.value[s] / unit)),))
            break
    if hit is None and part in crossed:
        other, value = crossed[part]
        hit = Finding("crossing", joints=(part,), parts=(other,), state=((part, value),))
    if part in crossed:  # ... and a jointed part it passes through (or that passes through it) while staying put
        other, value = crossed[part]
        k2 = joint_of_group.get(int(group[sim.part_body[other]]))
        hurt = None if k2 is None or sim.moved_by[k2][child] else sim.joint_parts[k2]
        if hurt is not None and not _has(found, hurt, PENETRATES):
            found.append(Finding("crossing", joints=(hurt,), parts=(part,), state=((part, value),)))
    if hit:
        found.append(hit)
    below = first_below_floor(run.structure, run.parts, part, states.value[rows] / unit)
    if below is not None:
        found.append(Finding("floor", joints=(part,), state=((part, below),)))
    # a jointed part that this sweep runs into is at fault too: it stays put while the part
    # it should move with (a handle on a door, given the wrong parent) swings through it
    for s in rows:
        state = ((part, float(states.value[s] / unit)),)
        for a, b in np.argwhere(pen[s] & across):
            other = b if moved[a] else a
            depth = float(-distances[s][a, b]) / scale
            k2 = joint_of_group.get(int(group[other]))
            hurt = None if k2 is None or sim.moved_by[k2][child] else sim.joint_parts[k2]  # not an ancestor
            if hurt is not None and not _has(found, hurt, PENETRATES):
                found.append(Finding("penetration", joints=(hurt,), parts=(body_part[a if other == b else b],),
                                     depth=depth, state=state))
            # ... and so is a jointed part that this sweep carries into another (a rack hung on the
            # dishwasher door instead of the tub: the door swings it through the tub)
            k3 = joint_of_group.get(int(group[a if other == b else b]))
            carried = None if k3 is None or k3 == k else sim.joint_parts[k3]
            if carried is not None and not _has(found, carried, PENETRATES):
                found.append(Finding("penetration", joints=(carried,), parts=(body_part[other],), depth=depth, state=state))


def _attachment_findings(run: CheckRun, k: int, part: int, rows: np.ndarray, found: list[Finding]) -> None:
    """Joint ``k``'s part stays on its parent: not lifted off, detached or out of its guide over the
    sweep, meeting its parent at rest, and hinged on an axis through both."""
    sim, states, structure, parts, body_part, scale = run.sim, run.states, run.structure, run.parts, run.body_part, run.sim.scale
    group = sim.group_of_body
    unit = 1.0 if sim.joint_type[k] == "hinge" else scale
    moved = sim.moved_by[k]
    child, parent = sim.part_body[part], sim.parent_body[k]
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
            found.append(Finding("lifted off", joints=(part,), depth=-overlap(gone[0]), state=((part, float(gone[0])),)))
    else:
        for s in rows:
            near = run.proximity[s][np.ix_(moved, parent_group)]
            if not np.any(near < DETACH_TOL_NU * scale):
                found.append(Finding("detached", joints=(part,), state=((part, float(states.value[s] / unit)),)))
                break
    if guided and not _has(found, part, DETACHED):
        out = [v for v in values_nu if overlap(v) <= 0.0]  # a drawer or rack in its guide must stay in it
        if out:
            found.append(Finding("guide", joints=(part,), depth=-overlap(out[0]), state=((part, float(out[0])),)))
    carried = carried_out_of_guide(structure, parts, part)  # a drawer hung on its neighbour leaves its slot
    if carried is not None and not _has(found, part, DETACHED):
        guide, values = carried
        found.append(Finding("carried out of guide", joints=(part,), parts=(guide,),
                             state=tuple((p, float(v)) for p, v in values.items())))
    # a joint connects two bodies that meet: a part given a parent it does not touch at rest (a
    # drawer hung on the drawer beside it, which would carry it out of its own slot) is not held by it
    gap = float(np.min(run.proximity[0][np.ix_(group == group[child], parent_group)], initial=np.inf)) / scale
    if gap > REST_CONTACT_TOL_NU:
        found.append(Finding("rest gap", joints=(part,), parts=(body_part[parent],), depth=gap if np.isfinite(gap) else None))
    if not _pivot_attached(structure, parts, part):
        found.append(Finding("pivot", joints=(part,), parts=(body_part[parent],)))


def relation_check(run: CheckRun) -> list[Finding]:
    """Related parts (symmetric, instance) that articulate otherwise (``relations``)."""
    return relation_disagreements(run.structure, run.parts)


def combination_check(run: CheckRun) -> list[Finding]:
    """Warnings: part pairs that interpenetrate only when several joints move at once. Reported, not
    failed: real objects have dependent joints (a dishwasher rack slides out only with the door
    open, folded eyeglass temples cross)."""
    states, pen = run.states, run.pen
    pairs = {run.pair(a, b) for s in np.nonzero(states.joint == -2)[0] for a, b in np.argwhere(pen[s]) if a < b}
    single = {run.pair(a, b) for s in np.nonzero(states.joint >= 0)[0] for a, b in np.argwhere(pen[s])}
    return [Finding("combination", WARNING, parts=pair) for pair in sorted(pairs - single)]


def limit_check(run: CheckRun) -> list[Finding]:
    """Joint ends the servo does not reach (``dynamics.reachability``), colliding only the pairs the
    kinematic checks would report."""
    scale = run.sim.scale
    exclude = tolerated_pairs(run.sim, run.distances, PENETRATION_TOL_NU * scale, run.states, RECONTACT_DEPTH_NU * scale)
    return reachability(run.structure, run.parts, scale, exclude, run.sim.pieces, run.rollout)


def gravity_check(run: CheckRun) -> list[Finding]:
    """The object stands (or, mounted, holds its joints) under gravity (``dynamics.gravity``)."""
    return gravity(run.structure, run.parts, run.sim.scale, run.sim.pieces, run.rollout, run.mounted)


def run_checks(run: CheckRun, names: Sequence[str], done: Mapping[str, list[Finding]] | None = None) -> Verdict:
    """The verdict of the checks ``names`` (keys of CHECKS), their findings in that order;
    ``done``: findings of some of them already run (DISTANCE_FREE_CHECKS, while the distances were
    being measured)."""
    done = done or {}
    found = tuple(finding for name in names for finding in (done[name] if name in done else CHECKS[name](run)))
    return Verdict(tuple(run.sim.joint_parts), found, "gravity" in names)


CHECKS: dict[str, Check] = {"rest": rest_check, "joints": joint_checks, "relations": relation_check,
                            "combinations": combination_check, "limits": limit_check, "gravity": gravity_check}
KINEMATIC_CHECKS = ("rest", "joints", "relations", "combinations")  # collision and distance queries only
DYNAMIC_CHECKS = ("limits", "gravity")  # short rollouts
DISTANCE_FREE_CHECKS = ("relations", "gravity")  # read neither the distances nor the crossings: run before they are in


PENETRATES = {"penetration", "crossing"}  # a joint blamed for one penetration is not blamed for another
DETACHED = {"detached", "lifted off", "guide", "carried out of guide", "rest gap"}


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
    # the parent is the rigid body it is welded into: a stapler's arm parented to the base hinges on
    # the block fixed to that base, the same body in a simulator
    holder = min(line_distance(surface_points(parts[p]), pivot, axis) for p in welded(structure, node.parent))
    return line_distance(surface_points(parts[part]), pivot, axis) <= ATTACH_TOL_NU and holder <= ATTACH_TOL_NU


def surface_points(mesh: trimesh.Trimesh) -> np.ndarray:
    """A mesh's vertices and ``LINE_SAMPLES`` points on its faces (seeded, so the same every time),
    the points a hinge line's distance to the part is measured to: vertices alone miss a large flat
    face that the line runs across."""
    points = np.asarray(mesh.vertices, dtype=np.float64)
    if len(mesh.faces):
        points = np.concatenate([points, mesh.sample(LINE_SAMPLES, seed=0)])
    return points


def line_distance(points: np.ndarray, pivot: np.ndarray, axis: np.ndarray) -> float:
    """The smallest distance of ``points`` [N, 3] to the line through ``pivot`` along the unit ``axis``."""
    rel = points - pivot
    return float(np.min(np.linalg.norm(rel - np.outer(rel @ axis, axis), axis=1)))


def _pieces_nu(structure: Structure, sim: SimModel) -> dict[int, list[np.ndarray]]:
    """The collision pieces' vertices in the rest pose's object frame (nu); the model holds them in
    each part's frame, in metres."""
    frames = frames_nu(structure, tree_order(structure))
    return {p: [v / sim.scale + frames[p] for v in pieces] for p, pieces in sim.pieces.items()}
