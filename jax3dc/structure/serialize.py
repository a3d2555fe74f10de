"""Canonical JSON text of a structure O (SPEC §2), the training target the model learns to write.

Number format: every float is rounded to 3 decimals and written as Python's shortest round-trip
text of that rounded value (``0.45``, ``1.0``, ``-1.571``), with ``-0.0`` written as ``0.0``. Ids are
JSON object keys written as decimal strings in ascending integer order; there are no spaces.
The same structure therefore always gives the same bytes, and ``to_json(parse_structure(t)) == t``
for every ``t`` that ``to_json`` wrote.

Axes are written as a rounded unit vector that is a fixed point of "normalise, then round":
the parser normalises axes on load, so a plain rounding (e.g. ``0.577 0.577 0.577``, norm 0.9994)
could round differently after reloading and the bytes would drift on every round trip.
"""

from __future__ import annotations

import json
import math
from collections.abc import Iterable

from jax3dc.errors import StructureError
from jax3dc.structure.schema import Joint, Node, Relation, Structure

DECIMALS = 3
_FIXED_POINT_ITERATIONS = 8


def round_number(x: float, where: str = "") -> float:
    """``x`` rounded to DECIMALS, ``-0.0`` folded into ``0.0``; non-finite values are refused."""
    x = float(x)
    if not math.isfinite(x):
        raise StructureError("not_finite", where, f"cannot write the non-finite number {x}")
    r = round(x, DECIMALS)
    return 0.0 if r == 0 else r


def _round_all(values: Iterable[float], where: str) -> list[float]:
    return [round_number(v, where) for v in values]


def rounded_axis(axis: Iterable[float], where: str = "") -> list[float]:
    """The unit direction of ``axis`` rounded to DECIMALS so that normalising and re-rounding it
    gives the same numbers (see the module docstring)."""
    v = [float(c) for c in axis]
    if len(v) != 3 or not all(math.isfinite(c) for c in v):
        raise StructureError("axis_finite", where, f"axis {v} is not a finite 3-vector")
    norm = math.sqrt(sum(c * c for c in v))
    if norm == 0:
        raise StructureError("axis_zero", where, "axis is the zero vector")
    r = _round_all((c / norm for c in v), where)
    for _ in range(_FIXED_POINT_ITERATIONS):
        n = math.sqrt(sum(c * c for c in r))
        nxt = _round_all((c / n for c in r), where)
        if nxt == r:
            break
        r = nxt
    return r


def joint_to_dict(j: Joint, where: str = "") -> dict:
    return {
        "type": j.type,
        "axis": rounded_axis(j.axis, f"{where} joint.axis"),
        "pivot": _round_all(j.pivot, f"{where} joint.pivot"),
        "range": _round_all(j.range, f"{where} joint.range"),
    }


def node_to_dict(pid: int, n: Node, names: bool) -> dict:
    out: dict = {"parent": None if n.parent is None else int(n.parent), "material": int(n.material)}
    if n.joint is not None:
        out["joint"] = joint_to_dict(n.joint, f"node {pid}")
    if names and n.name is not None:
        out["name"] = n.name
    return out


def relation_to_dict(r: Relation) -> dict:
    out: dict = {"type": r.type, "a": int(r.a), "b": int(r.b)}
    if r.plane is not None:
        out["plane"] = r.plane
    return out


def to_dict(s: Structure, names: bool = False) -> dict:
    """The JSON-ready dictionary of ``s`` (string keys in integer order, rounded numbers).

    ``names``: also write each node's semantic ``name`` (metadata; not in the training target).
    """
    return {
        "materials": {str(int(i)): {"family": m.family, "desc": m.desc} for i, m in sorted(s.materials.items())},
        "nodes": {str(int(i)): node_to_dict(i, n, names) for i, n in sorted(s.nodes.items())},
        "relations": [relation_to_dict(r) for r in s.relations],
    }


def to_json(s: Structure, names: bool = False) -> str:
    """Canonical compact JSON of ``s`` (module docstring gives the exact format)."""
    return json.dumps(to_dict(s, names), separators=(",", ":"), ensure_ascii=False, allow_nan=False)
