"""Ground-truth objects for measuring the checks: procedural factories and imported fixtures.

``false_alarms`` counts flagged joints on correct objects; ``mutation_detection`` counts mutated
joints flagged by an expected check (``Mutation.expected``), per mutation kind. Mutations that do
not change the motion (the mutated and the original joint sweep the moved parts through the same
poses) are skipped.
A joint is flagged by a failure or a warning (a limit a little past where it stops: the verdict
passes, the user is told), the same joints as before warnings existed; both counts also say how
many of their joints fail ("failing", "failed right reason"), which is what the verdict counts.
"""

from __future__ import annotations

from collections import Counter
from dataclasses import dataclass
from pathlib import Path
from typing import Callable, Iterable, Iterator

import numpy as np
import trimesh

from data_pipeline.importers.source import import_object
from eval.verdict_accuracy.mutations import Mutation, mutations_of
from jax3dc.factories import FACTORIES, generate_object
from jax3dc.mounted import is_mounted
from jax3dc.physics.findings import FAILURE, WARNING, Finding, Verdict
from jax3dc.physics.kinematics import (SAME_MOTION_TOL_NU, same_line, subtree_points, subtree_vertices_at,
                                       sweep_distance, symmetric_about)
from jax3dc.physics.verdict import verdict_with_curves
from jax3dc.structure.schema import Structure


@dataclass(frozen=True)
class GroundTruthObject:
    name: str
    structure: Structure
    parts: dict[int, trimesh.Trimesh]
    scale: float
    mounted: bool = False  # fixed in place in use (a faucet, a toilet): the gravity test holds its root


def factory_objects(categories: Iterable[str], seeds: Iterable[int]) -> Iterator[GroundTruthObject]:
    for category in categories:
        for seed in seeds:
            obj = generate_object(category, seed)
            yield GroundTruthObject(obj.object_id, obj.structure, obj.parts, obj.scale_m_per_nu,
                                    FACTORIES[category].mounted)


def imported_objects(directories: Iterable[Path]) -> Iterator[GroundTruthObject]:
    """Imported objects, mounted where their category is (a PartNet-Mobility door, window or switch
    is set in a wall: stood free on a floor its frame would fall over)."""
    for directory in directories:
        obj = import_object(Path(directory))
        yield GroundTruthObject(Path(directory).name, obj.structure, obj.parts, float(obj.meta.get("scale", 1.0)),
                                is_mounted(obj.meta.get("category")))


def check(obj: GroundTruthObject, structure: Structure, backend: str) -> Verdict:
    """The verdict of ``structure`` (the object's own or a mutation of it) on the object's parts."""
    return verdict_with_curves(structure, obj.parts, obj.scale, backend=backend, mounted=obj.mounted)[0]


def false_alarms(objects: Iterable[GroundTruthObject], on_result: Callable | None = None, backend: str = "c") -> dict:
    """Flagged ground-truth joints (the issue's rate), their findings (joint by joint, each joint's
    failures then its warnings), and objects whose whole verdict fails."""
    joints = flagged = failing = 0
    findings: list[Finding] = []
    failed: list[str] = []
    for obj in objects:
        verdict = check(obj, obj.structure, backend)
        if not verdict.ok:
            failed.append(obj.name)
        for part in verdict.joint_parts:
            failures, warnings = verdict.joint_findings(part, FAILURE), verdict.joint_findings(part, WARNING)
            joints += 1
            flagged += bool(failures or warnings)
            failing += bool(failures)
            findings.extend(failures + warnings)
        if on_result:
            on_result(obj, verdict)
    return {"joints": joints, "flagged": flagged, "rate": flagged / max(joints, 1), "failing": failing,
            "findings": findings, "objects_failed": failed}


def changes_motion(original: Structure, mutation: Mutation, parts: dict[int, trimesh.Trimesh]) -> bool:
    """Whether the mutated structure moves the part (and its subtree) through other poses.

    A changed joint (same parent) is compared by the SET of poses its sweep reaches, not state by
    state: a flipped axis over a symmetric range or a full turn, or a longer range of a full turn,
    reach the same poses. A turn about the same axis line of a subtree that is round about it (a
    knob, a wheel) occupies the same space whatever its range. A changed parent is compared state
    by state over random states of all joints (a new parent welded to the old one moves the same).
    """
    before, after = original.nodes[mutation.part], mutation.structure.nodes[mutation.part]
    if before.parent != after.parent:
        a = subtree_vertices_at(original, parts, mutation.part)
        b = subtree_vertices_at(mutation.structure, parts, mutation.part)
        return a.shape != b.shape or not np.allclose(a, b, atol=SAME_MOTION_TOL_NU)
    points = subtree_points(original, parts, mutation.part)
    ja, jb = before.joint, after.joint
    if ja.type == jb.type == "hinge" and same_line(ja, jb) and symmetric_about(points, ja):
        return False
    return sweep_distance(ja, jb, points) > SAME_MOTION_TOL_NU


def mutation_detection(objects: Iterable[GroundTruthObject], on_result: Callable | None = None,
                       backend: str = "c") -> dict:
    per_kind: dict[str, Counter] = {}
    for obj in objects:
        for mutation in mutations_of(obj.structure, obj.parts):
            counts = per_kind.setdefault(mutation.kind, Counter())
            if not changes_motion(obj.structure, mutation, obj.parts):
                counts["skipped (same motion)"] += 1
                continue
            verdict = check(obj, mutation.structure, backend)
            found = verdict.joint_findings(mutation.part)
            counts["total"] += 1
            counts["flagged"] += bool(found)
            counts["right reason"] += mutation.caught(found)
            counts["failed right reason"] += mutation.caught(verdict.joint_findings(mutation.part, FAILURE))
            if on_result:
                on_result(obj, mutation, verdict)
    return {kind: dict(c) for kind, c in per_kind.items()}
