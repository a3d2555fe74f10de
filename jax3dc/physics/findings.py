"""What the physics checks find, as data: one ``Finding`` per fault, text only where it is shown.

A finding names its check, its severity, the joints at fault (by their child part's id), the other
parts involved, a depth or distance (nu), the joint values it was found at and, for a limit, the
value the joint does reach. A ``Verdict`` holds one object's findings and is what the chooser,
the repairer and predict pass around; its pass/fail counts failures only; a warning is something a
user may want to act on that a simulator still runs (a ground-truth limit a few degrees past the
first contact: the joint stops there, ``reachable``), and combination interpenetration (real
objects have dependent joints). ``describe`` turns a finding into the short reason strings of the
verdict JSON (``Verdict.to_json``, see ``jax3dc.physics.verdict``), for reports, the CLI and the viewer,
which are made where a file or page is written; ``Verdict.from_json`` types a verdict file again.
"""

from __future__ import annotations

import dataclasses
import math
from dataclasses import dataclass
from typing import Any, Literal, Mapping

from jax3dc.physics.tolerances import DETACH_TOL_NU

Severity = Literal["failure", "warning"]
RELATION_REASON = "disagrees with part"  # how each reason of the relation check starts
FAILURE: Severity = "failure"
WARNING: Severity = "warning"

# check -> what it found (joint-level unless marked object-level)
CHECKS = {
    "rest": "object-level: two parts interpenetrate at rest",
    "rest parent": "the joint's part interpenetrates its parent at rest",
    "penetration": "a sweep drives the part into another (state: the joint that moves)",
    "crossing": "a sweep drives the part through a thin board of another, or a board through it",
    "floor": "a sweep drives the part below the rest pose's lowest point",
    "detached": "a sweep carries the part away from its parent",
    "lifted off": "an unguided slide (a lid) lifts the part too far off its parent",
    "guide": "a slide carries the part out of the parent it runs in",
    "carried out of guide": "other joints carry the part out of the guide it runs in (parts: the guide)",
    "rest gap": "the part does not meet its parent at rest (depth: the gap; None: farther than measured)",
    "pivot": "the hinge's axis misses the part or its parent",
    "relation parents": "a related part hangs on an unrelated parent (parts: other, parent of a, parent of b)",
    "relation joint type": "a related part has the other joint type (joint_types: a's, b's)",
    "relation motion": "a related part moves otherwise (depth: how far apart once mapped)",
    "limit": "the servo stops short of a limit (limit: lo|hi, reachable: where it stops)",
    "sag": "gravity moves a held joint (depth: by how much, rad or nu)",
    "gravity": "object-level: the object (in a scene, the one whose root is parts[0]) does not stand under gravity (depth: root drift, tilt: rad)",
    "combination": "object-level: parts interpenetrate when several joints move at once",
}


# Decimals of the floats a verdict file holds: C MuJoCo (float64) and MJX (float32) measure the
# same depth 3e-8 apart, and 1e-4 nu is far below every tolerance, so both write the same file.
JSON_DECIMALS = 4
FLOAT_FIELDS = ("depth", "reachable", "tilt")  # a finding's optional floats


@dataclass(frozen=True)
class Finding:
    """One fault found by one check. Joint values are radians (hinge) or nu (slide)."""

    check: str
    severity: Severity = FAILURE
    joints: tuple[int, ...] = ()  # the joints at fault (child part ids); empty for object-level checks
    parts: tuple[int, ...] = ()  # the other parts involved
    depth: float | None = None  # penetration depth or distance, nu (rad or nu for a sag)
    state: tuple[tuple[int, float], ...] = ()  # (joint, value) of the joints moved where it was found
    reachable: float | None = None  # a limit finding: the value the joint reaches
    limit: str | None = None  # a limit finding: "lo" or "hi"
    relation: str | None = None  # a relation finding: "symmetric" or "instance"
    joint_types: tuple[str, ...] = ()  # a relation joint-type finding: the two parts' joint types
    tilt: float | None = None  # the gravity finding: the root's tilt, rad

    def __post_init__(self) -> None:
        if self.check not in CHECKS:
            raise ValueError(f"unknown check {self.check!r}")
        if self.severity not in (FAILURE, WARNING):
            raise ValueError(f"severity must be {FAILURE!r} or {WARNING!r}, got {self.severity!r}")
        # plain ints and floats whatever the checks computed them with (numpy scalars do not compare,
        # hash or serialise as plain numbers do)
        for name in ("joints", "parts"):
            object.__setattr__(self, name, tuple(int(p) for p in getattr(self, name)))
        object.__setattr__(self, "state", tuple((int(j), float(v)) for j, v in self.state))
        for name in FLOAT_FIELDS:
            if getattr(self, name) is not None:
                object.__setattr__(self, name, float(getattr(self, name)))

    def to_json(self) -> dict[str, Any]:
        """The finding as plain JSON (lists for tuples, state as [[joint, value], ...], no empty fields)."""
        out = {}
        for f in dataclasses.fields(self):
            value = getattr(self, f.name)
            if value is None or (isinstance(value, tuple) and not value):
                continue
            if isinstance(value, float):  # a blown-up rollout: JSON has no NaN
                value = round(value, JSON_DECIMALS) if math.isfinite(value) else None
            if f.name == "state":
                value = [[j, round(v, JSON_DECIMALS)] for j, v in value]
            out[f.name] = list(value) if isinstance(value, tuple) else value
        return out

    @classmethod
    def from_json(cls, data: Mapping[str, Any]) -> Finding:
        """The finding ``to_json`` wrote; a float written as null (a blown-up rollout's) is NaN again,
        as a field ``to_json`` leaves out is None."""
        names = {f.name for f in dataclasses.fields(cls)}
        args = {k: v for k, v in data.items() if k in names}
        for key in FLOAT_FIELDS:
            if key in args and args[key] is None:
                args[key] = math.nan
        for key in ("joints", "parts", "joint_types"):
            if key in args:
                args[key] = tuple(args[key])
        if "state" in args:
            args["state"] = tuple((int(j), float(v)) for j, v in args["state"])
        return cls(**args)


def describe(finding: Finding) -> str:
    """The finding's reason string (the stable phrases listed in ``jax3dc.physics.verdict``)."""
    f = finding
    q = f"{f.state[0][1]:.3f}" if f.state else ""
    own = bool(f.state) and bool(f.joints) and f.state[0][0] == f.joints[0]
    mover = "" if own or not f.state else f" while joint {f.state[0][0]} moves (q={q})"
    if f.check == "rest":
        return f"rest interpenetration: parts {min(f.parts)},{max(f.parts)}"
    if f.check == "combination":
        return f"combination interpenetration: parts {min(f.parts)},{max(f.parts)}"
    if f.check == "rest parent":
        return "penetrates parent at rest"
    if f.check == "penetration":
        return f"penetrates part {f.parts[0]} at q={q}" if own else f"penetrates part {f.parts[0]}{mover}"
    if f.check == "crossing":
        return f"penetrates part {f.parts[0]} (passes through it)" + (f" at q={q}" if own else mover)
    if f.check == "floor":
        return f"penetrates the floor at q={q}"
    if f.check == "detached":
        return f"detached from parent at q={q}"
    if f.check == "lifted off":
        return f"detached from parent (lifted off too far) at q={q}"
    if f.check == "guide":
        return f"detached from parent (slides out of its guide) at q={q}"
    if f.check == "carried out of guide":
        opened = ", ".join(f"joint {p} at {v:.3f}" for p, v in f.state)
        return f"detached from its guide (part {f.parts[0]}, runs out of it with {opened})"
    if f.check == "rest gap":
        return f"detached from parent at rest (gap {f.depth:.3f} nu)" if f.depth is not None and math.isfinite(f.depth) \
            else f"detached from parent at rest (gap over {DETACH_TOL_NU} nu)"
    if f.check == "pivot":
        return "pivot detached"
    if f.check.startswith("relation"):
        head = f"{RELATION_REASON} {f.parts[0]} ({f.relation}): "
        if f.check == "relation parents":
            return head + f"their parents {f.parts[1]} and {f.parts[2]} differ and are not related"
        if f.check == "relation joint type":
            return head + f"a {f.joint_types[1]} where the other is a {f.joint_types[0]}"
        return head + f"they move differently ({f.depth:.3f} nu apart once mapped onto each other)"
    if f.check == "limit":
        if f.severity == WARNING:
            return f"limit past contact: {f.limit} (stops at q={f.reachable:.3f})"
        return f"limit unreachable: {f.limit} (stops at q={f.reachable:.3f})"
    if f.check == "sag":
        return f"sags under gravity by {f.depth:.3f}"
    which = f"the object of root part {f.parts[0]}" if f.parts else "root"
    return f"unstable under gravity: {which} moved {f.depth:.3f} nu, tilted {f.tilt:.2f} rad"


OBJECT_CHECKS = {"rest": "rest", "combination": "combinations", "gravity": "gravity"}  # check -> key of "checks"


@dataclass(frozen=True)
class Verdict:
    """One object's verdict: the joints checked (their child part ids) and every finding, in the
    order the checks found them. Only failures fail a joint or the object."""

    joint_parts: tuple[int, ...]
    findings: tuple[Finding, ...]
    gravity_checked: bool = True  # the gravity test ran (the JSON then has its "gravity" list)

    @property
    def ok(self) -> bool:
        return not any(f.severity == FAILURE for f in self.findings)

    @property
    def failed_joints(self) -> frozenset[int]:
        """The joints a failure is blamed on."""
        return frozenset(f.joints[0] for f in self.findings if f.severity == FAILURE and f.check not in OBJECT_CHECKS)

    @property
    def flagged(self) -> int:
        """How many joints fail."""
        return len(self.failed_joints)

    def merit(self) -> tuple[bool, int]:
        """Larger is better: the object passes, then fewer failing joints."""
        return self.ok, -self.flagged

    def joint_findings(self, part: int, severity: Severity | None = None) -> tuple[Finding, ...]:
        """The findings blamed on the joint of ``part`` in the order found (only those of ``severity``
        when given): what a report or the viewer shows beside that joint."""
        return tuple(f for f in self.findings if f.check not in OBJECT_CHECKS and f.joints[0] == part
                     and severity in (None, f.severity))

    def joint_reasons(self, part: int, severity: Severity) -> list[str]:
        """The reason strings of the joint's findings of ``severity`` (the JSON's "reasons" for
        failures, "warnings" for warnings), for every place that shows them."""
        return [describe(f) for f in self.joint_findings(part, severity)]

    def object_reasons(self) -> dict[str, list[str]]:
        """The reason strings of the object-level findings per key of the JSON's "checks": "rest" and
        "combinations" (each sorted), "gravity" when the test ran."""
        checks: dict[str, list[str]] = {"rest": [], "combinations": []}
        if self.gravity_checked:
            checks["gravity"] = []
        for f in self.findings:
            if f.check in OBJECT_CHECKS:
                checks[OBJECT_CHECKS[f.check]].append(describe(f))
        checks["rest"].sort()
        checks["combinations"].sort()
        return checks

    def to_json(self) -> dict[str, Any]:
        """The verdict JSON: "ok", per joint "ok", its failure "reasons" and its "warnings",
        object-level "checks" (rest, combinations, gravity when it ran) as reason strings, and the
        typed "findings" themselves."""
        joints = {}
        for p in self.joint_parts:
            reasons = self.joint_reasons(p, FAILURE)
            joints[str(p)] = {"ok": not reasons, "reasons": reasons, "warnings": self.joint_reasons(p, WARNING)}
        return {"ok": self.ok, "joints": joints, "checks": self.object_reasons(),
                "findings": [f.to_json() for f in self.findings]}

    @classmethod
    def from_json(cls, data: Mapping[str, Any]) -> Verdict:
        """The verdict ``to_json`` wrote (physics.json, a verdicts line): its joints are the keys of
        "joints", in their order; its reason strings are made again from the findings. An
        AttributeError, KeyError, TypeError or ValueError says the data is not a verdict."""
        return cls(tuple(int(p) for p in data["joints"]), tuple(Finding.from_json(f) for f in data["findings"]),
                   "gravity" in data["checks"])
