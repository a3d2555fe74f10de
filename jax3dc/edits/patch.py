"""An edit by hand (SPEC §9): a small JSON patch on structure.json, as data.

A patch names one part and sets fields of its joint (or its parent), each at most once::

    {"part": 3, "ops": [
      {"op": "set_type", "value": "hinge"},          # hinge | slide | fixed (fixed removes the joint)
      {"op": "set_axis", "value": "+z"},             # +x -x +y -y +z -z, or a free vector [x, y, z]
      {"op": "set_line", "value": "edge +x -y"},     # a line of the part's box along the axis
                                                     # (jax3dc.edits.lines), or a point [x, y, z] (nu)
      {"op": "set_range", "value": [0.0, 1.571]},    # radians for a hinge, nu for a slide
      {"op": "set_parent", "value": 1}]}             # a part id, or null

The command line (``jax3dc edit``) and the local app read and apply patches here, so both accept
and refuse the same ones. A patch that is malformed, or whose result breaks a rule of SPEC §2,
raises one EditError naming the rule and its place in the patch (``ops[1].value``); the structure
is then unchanged, as nothing is applied before everything is checked.

Fields the patch leaves alone keep their values, with two exceptions that spare a person from
working out a range by hand: a new joint (or one that changes type) gets a default range, and a
joint whose line moves keeps its range's span but turns it, if need be, so the part opens away
from its parent (``jax3dc.grounding.ground.opening_outward``), unless the patch sets the range
too. A new joint needs its axis in the same patch; its line defaults to the part's centre line.
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from dataclasses import dataclass, replace

from jax3dc.errors import EditError, StructureError
from jax3dc.edits.lines import AXES, hinge_lines
from jax3dc.grounding.ground import HINGE_OPENING, MAX_SLIDE, SLIDE_OPENING, opening_outward
from jax3dc.structure.schema import Box, Joint, Structure, Vec3
from jax3dc.structure.serialize import to_dict, to_json
from jax3dc.structure.validate import parse_structure, read_json, validate

OPS = ("set_type", "set_axis", "set_line", "set_range", "set_parent")
TYPES = ("hinge", "slide", "fixed")
FIXED = "fixed"
JOINT_OPS = ("set_axis", "set_line", "set_range")
PATCH_KEYS = ("part", "ops")
OP_KEYS = ("op", "value")
MIN_SLIDE = 0.02  # nu: the shortest default travel of a new slide

# Which op a rule of SPEC §2 broken by the edited structure comes from (the first one the patch has).
_RULE_OPS: dict[str, tuple[str, ...]] = {
    "parent_exists": ("set_parent",), "self_parent": ("set_parent",), "cycle": ("set_parent",),
    "joint_without_parent": ("set_parent", "set_type"),
    "axis_finite": ("set_axis",), "axis_zero": ("set_axis",), "pivot_finite": ("set_line",),
    "range_finite": ("set_range", "set_type"), "range_order": ("set_range", "set_type"),
    "hinge_range": ("set_range", "set_type"),
}


@dataclass(frozen=True)
class Op:
    """One operation of a patch: its name, its value as read, and its place in the patch's list."""

    name: str
    value: object
    index: int

    @property
    def where(self) -> str:
        return f"ops[{self.index}] {self.name}"


@dataclass(frozen=True)
class Patch:
    """A read patch: the part it edits and its operations by name (each at most once)."""

    part: int
    ops: dict[str, Op]

    def to_dict(self) -> dict:
        """The patch as JSON data again (ops in their given order; free vectors normalised)."""
        ordered = sorted(self.ops.values(), key=lambda op: op.index)
        return {"part": self.part, "ops": [{"op": op.name, "value": op.value} for op in ordered]}


def _number(value: object) -> bool:
    return isinstance(value, (int, float)) and not isinstance(value, bool)


def _numbers(value: object, size: int, where: str) -> tuple[float, ...]:
    if not (isinstance(value, (list, tuple)) and len(value) == size and all(_number(v) for v in value)):
        raise EditError("value_type", where, f"must be a list of {size} numbers, got {_shown(value)}")
    return tuple(_float(v) for v in value)


def _float(value: int | float) -> float:
    try:
        return float(value)
    except OverflowError:  # an integer literal too large for a float
        return math.inf


def _shown(value: object, limit: int = 60) -> str:
    text = repr(value)
    return text if len(text) <= limit else text[: limit - 3] + "..."


def _axis(value: object, where: str) -> Vec3 | str:
    if isinstance(value, str):
        if value not in AXES:
            raise EditError("axis_name", where, f"unknown axis {value!r} (one of: {', '.join(AXES)}, or [x, y, z])")
        return value
    axis = _numbers(value, 3, where)
    if not all(math.isfinite(c) for c in axis):
        raise EditError("axis_finite", where, f"axis {list(axis)} is not finite")
    norm = math.sqrt(sum(c * c for c in axis))
    if norm == 0 or not math.isfinite(norm):
        raise EditError("axis_zero", where, "axis is the zero vector" if norm == 0 else "axis is too long to normalise")
    return tuple(c / norm for c in axis)


def _line(value: object, where: str) -> Vec3 | str:
    if isinstance(value, str):
        return value  # a name, checked against the part's box and axis when applied
    point = _numbers(value, 3, where)
    if not all(math.isfinite(c) for c in point):
        raise EditError("pivot_finite", where, f"point {list(point)} is not finite")
    return point


def _range(value: object, where: str) -> tuple[float, float]:
    lo, hi = _numbers(value, 2, where)
    if not (math.isfinite(lo) and math.isfinite(hi)):
        raise EditError("range_finite", where, f"range {[lo, hi]} is not finite")
    if lo > hi:
        raise EditError("range_order", where, f"range lower bound {lo} exceeds upper bound {hi}")
    return lo, hi


def _op_value(name: str, value: object, where: str) -> object:
    if name == "set_type":
        if value not in TYPES:
            raise EditError("joint_type", where, f"unknown joint type {_shown(value)} (one of: {', '.join(TYPES)})")
        return value
    if name == "set_axis":
        return _axis(value, where)
    if name == "set_line":
        return _line(value, where)
    if name == "set_range":
        return _range(value, where)
    if value is not None and not (isinstance(value, int) and not isinstance(value, bool)):
        raise EditError("value_type", where, f"must be a part id or null, got {_shown(value)}")
    return value


def _keys(obj: Mapping, where: str, keys: tuple[str, ...]) -> None:
    for key in keys:
        if key not in obj:
            raise EditError("missing_key", where, f"missing key {key!r}")
    for key in obj:
        if key not in keys:
            raise EditError("unknown_key", where, f"unknown key {_shown(key)} (allowed: {', '.join(keys)})")


def read_patch(doc: str | bytes | Mapping) -> Patch:
    """The patch in ``doc`` (JSON text or data) with every value checked on its own; the checks
    that need the structure (the part exists, a line's name) are ``apply_patch``'s."""
    if isinstance(doc, (str, bytes)):
        try:
            doc = read_json(doc)
        except StructureError as e:
            raise EditError(e.rule, f"patch {e.where}".strip(), e.message) from None
    if not isinstance(doc, Mapping):
        raise EditError("top_level", "patch", f"must be a JSON object, got {type(doc).__name__}")
    _keys(doc, "patch", PATCH_KEYS)
    part = doc["part"]
    if not (isinstance(part, int) and not isinstance(part, bool)):
        raise EditError("value_type", "part", f"must be a part id (an integer), got {_shown(part)}")
    raw = doc["ops"]
    if not isinstance(raw, (list, tuple)):
        raise EditError("value_type", "ops", f"must be a list of operations, got {_shown(raw)}")
    if not raw:
        raise EditError("no_ops", "ops", "the list is empty: nothing to edit")
    ops: dict[str, Op] = {}
    for k, item in enumerate(raw):
        where = f"ops[{k}]"
        if not isinstance(item, Mapping):
            raise EditError("value_type", where, f"must be an object {{\"op\": ..., \"value\": ...}}, got {_shown(item)}")
        _keys(item, where, OP_KEYS)
        name = item["op"]
        if name not in OPS:
            raise EditError("unknown_op", f"{where}.op", f"unknown operation {_shown(name)} (one of: {', '.join(OPS)})")
        if name in ops:
            raise EditError("op_twice", where, f"{name} is already {ops[name].where}: each field is set at most once")
        ops[name] = Op(name, _op_value(name, item["value"], f"{where}.value"), k)
    return Patch(part, ops)


def _pivot(op: Op, box: Box, axis: Vec3) -> Vec3:
    """The pivot a set_line op names: a point as given, or the named line of the part's box."""
    if not isinstance(op.value, str):
        return op.value
    lines = hinge_lines(box, axis)
    if not lines:
        raise EditError("line_axis", f"{op.where}.value", f"a named line runs along one of the part's box axes "
                        f"({', '.join(AXES)}); the axis {[round(c, 3) for c in axis]} is free: give the line as "
                        "a point [x, y, z] on it")
    if op.value not in lines:
        raise EditError("line_name", f"{op.where}.value", f"unknown line {op.value!r} (one of: {', '.join(lines)})")
    return lines[op.value]


def _default_range(kind: str, box: Box, axis: Vec3) -> tuple[float, float]:
    """A new joint's range: a quarter turn for a hinge; for a slide, the travel grounding gives a
    new one (SLIDE_OPENING of the part's size along the axis, within [MIN_SLIDE, MAX_SLIDE])."""
    if kind == "hinge":
        return 0.0, HINGE_OPENING
    size = sum(abs(a) * e for a, e in zip(axis, box.extent))
    return 0.0, min(MAX_SLIDE, max(MIN_SLIDE, SLIDE_OPENING * size))


def _joint(patch: Patch, joint: Joint | None, box: Box, parent_box: Box | None) -> Joint | None:
    """The part's joint after the patch (None: fixed to its parent)."""
    ops = patch.ops
    kind = ops["set_type"].value if "set_type" in ops else (joint.type if joint is not None else None)
    joint_ops = [ops[name] for name in JOINT_OPS if name in ops]
    if kind == FIXED or kind is None:
        if joint_ops:
            first = min(joint_ops, key=lambda op: op.index)
            reason = ("set_type fixed removes the joint" if kind == FIXED else
                      f"part {patch.part} has no joint (it is fixed to its parent): set its type to hinge or slide")
            raise EditError("no_joint", first.where, f"{reason}, so it has no axis, line or range to set")
        return None
    fresh = joint is None or joint.type != kind
    if "set_axis" in ops:
        value = ops["set_axis"].value
        axis = AXES[value] if isinstance(value, str) else value
    elif joint is not None:
        axis = joint.axis
    else:
        raise EditError("axis_needed", ops["set_type"].where, f"part {patch.part} has no joint: a new {kind} needs "
                        "its axis in the same patch (set_axis)")
    pivot = _pivot(ops["set_line"], box, axis) if "set_line" in ops else (
        joint.pivot if joint is not None else box.centroid)
    if "set_range" in ops:
        return Joint(kind, axis, pivot, ops["set_range"].value)
    rng = _default_range(kind, box, axis) if fresh else joint.range
    new = Joint(kind, axis, pivot, rng)
    return opening_outward(new, box, parent_box) if fresh or "set_line" in ops else new


def _blame(patch: Patch, error: StructureError) -> EditError:
    """The edited structure's broken rule as an error at the op that broke it."""
    for name in _RULE_OPS.get(error.rule, ()):
        if name in patch.ops:
            return EditError(error.rule, patch.ops[name].where, error.message)
    return EditError(error.rule, "part", f"{error.message} (in the edited structure: {error.where})")


def apply_patch(structure: Structure, patch: Patch, boxes: Mapping[int, Box]) -> Structure:
    """``structure`` with ``patch`` applied and validated as any structure (SPEC §2), its numbers
    rounded as structure.json writes them, so the exports made from it match the file."""
    node = structure.nodes.get(patch.part)
    if node is None:
        raise EditError("part_exists", "part", f"part {patch.part} is not a part of this object "
                        f"(its parts: {', '.join(str(p) for p in structure.part_ids)})")
    parent = patch.ops["set_parent"].value if "set_parent" in patch.ops else node.parent
    joint = _joint(patch, node.joint, boxes[patch.part], boxes.get(parent) if parent is not None else None)
    edited = replace(structure, nodes={**structure.nodes, patch.part: replace(node, parent=parent, joint=joint)})
    errors = validate(to_dict(edited, names=True), part_ids=structure.nodes)
    if errors:
        raise _blame(patch, errors[0])
    return parse_structure(to_json(edited, names=True))


def edit_structure(structure: Structure, doc: str | bytes | Mapping, boxes: Mapping[int, Box]) -> tuple[Structure, Patch]:
    """``apply_patch`` of the patch in ``doc``: (the edited structure, the patch as read)."""
    patch = read_patch(doc)
    return apply_patch(structure, patch, boxes), patch
