"""The byte automaton of a structure document (SPEC §2), as the canonical writer spells it.

Compact JSON, keys in the writer's order: ``materials`` (ids 0, 1, ... in order), ``nodes`` (the
prompt's part ids 1..N in order), ``relations``. What depends on the prompt or on earlier choices
is not spelled here but marked by events, checked on the device against registers
(``jax3dc.constrained.structure``):

* ids: ``SLOT_OPEN(role)`` before an id, ``DIGIT(d)`` per digit, ``SLOT_CLOSE(role)`` after it;
  the registers decide which ids a slot takes (the next node id, a parent that closes no cycle,
  a defined material, a relation endpoint other than ``a``);
* ``PARENT_NULL``, ``JOINT_OPEN``, ``NODE_CLOSE(path)``, ``NODES_MORE``/``NODES_END``,
  ``MATERIAL_MORE``, ``RELATION_OPEN``, ``REL_TYPE(t)``: the joint count, the number of nodes, and
  the lists' bounds (materials at most one more than parts, no relation twice). A list's "more" event rides
  on the separator (``,``) itself, so a row never writes a comma it may not follow.

Which states are slots' entries and digits, and where the pieces of a document (materials,
nodes, relations) meet, is kept (``slots``, ``named``) for the tokens-to-finish tables
(``jax3dc.constrained.structure_finish``).

Regular rules are spelled out: a joint only below a parent; an axis that is not zero; a range
[lo, hi] with lo <= 0 <= hi (the pose shown lies within its limits, so lo <= hi follows; 99.6 % of
the training targets are so), hinge bounds within 2pi; numbers with 1 to 3 decimals; a ``desc``
of at most ``DESC_MAX`` characters of ``DESC_CHARS`` (letters, digits, space, light punctuation:
what the factories and importers write, and few enough tokens of a large vocabulary).
"""

from __future__ import annotations

import functools
from dataclasses import dataclass, field

from jax3dc.constrained.automaton import Automaton, embed
from jax3dc.structure.schema import FAMILIES

# Event codes: type << 8 | argument.
(DIGIT, SLOT_OPEN, SLOT_CLOSE, PARENT_NULL, JOINT_OPEN, NODE_CLOSE, NODES_MORE, NODES_END, MATERIAL_MORE, RELATION_OPEN,
 REL_TYPE) = range(1, 12)
# Slot roles (SLOT_OPEN / SLOT_CLOSE argument).
NODE_KEY, PARENT, MATERIAL_REF, MATERIAL_KEY, RELATION_A, RELATION_B = range(6)
# NODE_CLOSE argument: which path closed the node.
CLOSE_ROOT, CLOSE_RIGID, CLOSE_JOINT = range(3)
RELATION_TYPES = ("symmetric", "instance", "support")  # REL_TYPE argument: the index

DESC_MAX = 48  # characters of a material description (the training data's longest is 40)
DESC_CHARS = "ABCDEFGHIJKLMNOPQRSTUVWXYZabcdefghijklmnopqrstuvwxyz0123456789 -:,.'()/"
HINGE_BOUND = 6283  # thousandths: 2pi rounded down, so a written range stays within [-2pi, 2pi]
VALUE_BOUND = 9999  # thousandths: pivots and slide ranges in nu


def ev(kind: int, arg: int = 0) -> int:
    return kind << 8 | arg


def _numbers(bound: int, sign: str) -> list[tuple[str, int]]:
    """Decimal numbers with 1 to 3 decimals and |value| <= bound/1000, labelled 0 for zero and 1
    otherwise; ``sign``: "any", "neg" (<= 0, zero unsigned) or "pos" (>= 0, no sign)."""
    out = []
    for thousandths in range(bound + 1):
        whole, frac = divmod(thousandths, 1000)
        texts = {f"{whole}.{frac:03d}"}
        if frac % 10 == 0:
            texts.add(f"{whole}.{frac // 10:02d}")
        if frac % 100 == 0:
            texts.add(f"{whole}.{frac // 100}")
        label = int(thousandths != 0)
        for t in texts:
            if sign in ("any", "pos") or thousandths == 0:
                out.append((t, label))
            if sign in ("any", "neg") and thousandths != 0:
                out.append(("-" + t, label))
    return out


@dataclass
class StructureAutomaton(Automaton):
    """The automaton plus where its id slots and pieces are."""

    slots: list[tuple[int, tuple[int, int, int, int]]] = field(default_factory=list)  # entry, (zero, d1, d2, d3)
    named: dict[str, int] = field(default_factory=dict)


def _id_slot(a: StructureAutomaton, entry: int, role: int, exits: dict[int, tuple[int, tuple[int, ...]]]) -> None:
    """An id after ``entry``: '0' or [1-9] then up to 2 more digits, each digit a DIGIT event; any
    exit byte closes the slot (SLOT_CLOSE(role) before the exit's own events)."""
    closing = {b: (t, (ev(SLOT_CLOSE, role),) + e) for b, (t, e) in exits.items()}
    zero, d1, d2, d3 = a.new(), a.new(), a.new(), a.new()
    a.edge(entry, ord("0"), zero, (ev(DIGIT, 0),))
    for d in range(1, 10):
        a.edge(entry, ord(str(d)), d1, (ev(DIGIT, d),))
    for d in range(10):
        a.edge(d1, ord(str(d)), d2, (ev(DIGIT, d),))
        a.edge(d2, ord(str(d)), d3, (ev(DIGIT, d),))
    for state in (zero, d1, d2, d3):
        for b, (t, e) in closing.items():
            a.edge(state, b, t, e)
    a.slots.append((entry, (zero, d1, d2, d3)))


def _vector(a: Automaton, entry: int, end: int, nonzero: bool) -> None:
    """``x,y,z]`` from ``entry`` (after '['), to ``end`` (after ']'); with ``nonzero`` the three
    cannot all be zero (an axis), with components in [-1, 1]."""
    bound = 1000 if nonzero else VALUE_BOUND
    words = _numbers(bound, "any")
    if not nonzero:
        second, third = a.new(), a.new()
        embed(a, entry, words, {0: {ord(","): (second, ())}, 1: {ord(","): (second, ())}})
        embed(a, second, words, {0: {ord(","): (third, ())}, 1: {ord(","): (third, ())}})
        embed(a, third, words, {0: {ord("]"): (end, ())}, 1: {ord("]"): (end, ())}})
        return
    # (zero so far?) for the first two components; the third must be non-zero after two zeros.
    second_zero, second_any, third_zero, third_any = a.new(), a.new(), a.new(), a.new()
    embed(a, entry, words, {0: {ord(","): (second_zero, ())}, 1: {ord(","): (second_any, ())}})
    embed(a, second_zero, words, {0: {ord(","): (third_zero, ())}, 1: {ord(","): (third_any, ())}})
    embed(a, second_any, words, {0: {ord(","): (third_any, ())}, 1: {ord(","): (third_any, ())}})
    embed(a, third_zero, [w for w in words if w[1] == 1], {1: {ord("]"): (end, ())}})
    embed(a, third_any, words, {0: {ord("]"): (end, ())}, 1: {ord("]"): (end, ())}})


def _joint(a: Automaton, entry: int, node_done: int) -> None:
    """``"joint":{...}}`` after ``,`` (entry) up to the closed node (node_done)."""
    after_type = a.text(entry, '"joint":{"type":"')
    for kind, bound in (("hinge", HINGE_BOUND), ("slide", VALUE_BOUND)):
        axis = a.text(after_type, f'{kind}","axis":[')
        axis_end = a.new()
        _vector(a, axis, axis_end, nonzero=True)
        pivot = a.text(axis_end, ',"pivot":[')
        pivot_end = a.new()
        _vector(a, pivot, pivot_end, nonzero=False)
        lo = a.text(pivot_end, ',"range":[')
        hi, range_end = a.new(), a.new()
        embed(a, lo, _numbers(bound, "neg"), {0: {ord(","): (hi, ())}, 1: {ord(","): (hi, ())}})
        embed(a, hi, _numbers(bound, "pos"), {0: {ord("]"): (range_end, ())}, 1: {ord("]"): (range_end, ())}})
        a.text(range_end, "}}", end=node_done, events={1: (ev(NODE_CLOSE, CLOSE_JOINT),)})


@functools.cache
def structure_automaton() -> StructureAutomaton:
    """The automaton of every structure document (the same for every prompt; built once)."""
    a = StructureAutomaton()
    # materials: {"0":{"family":"F","desc":"..."},"1":...}
    key = a.text(a.start, '{"materials":{"', events={14: (ev(SLOT_OPEN, MATERIAL_KEY),)})
    after_key = a.new()
    _id_slot(a, key, MATERIAL_KEY, {ord('"'): (after_key, ())})
    family = a.text(after_key, ':{"family":"')
    desc = a.new()
    for name in FAMILIES:
        a.text(family, f'{name}","desc":"', end=desc)
    material_done = a.new()
    chars = list(DESC_CHARS.encode())
    here = desc
    for length in range(DESC_MAX + 1):
        a.text(here, '"}', end=material_done)
        if length < DESC_MAX:
            nxt = a.new()
            for c in chars:
                a.edge(here, c, nxt)
            here = nxt
    a.edge(material_done, ord(","), a.new(), (ev(MATERIAL_MORE),))
    more = a.edges[material_done][ord(",")][0]
    a.edge(more, ord('"'), key, (ev(SLOT_OPEN, MATERIAL_KEY),))
    # nodes: ,"nodes":{"1":{"parent":P,"material":M[,"joint":{...}]},...}
    node_key = a.text(material_done, '},"nodes":{"', events={11: (ev(SLOT_OPEN, NODE_KEY),)})
    after_node_key = a.new()
    _id_slot(a, node_key, NODE_KEY, {ord('"'): (after_node_key, ())})
    parent = a.text(after_node_key, ':{"parent":', events={10: (ev(SLOT_OPEN, PARENT),)})
    node_done = a.new()
    # root: null, a material, no joint
    root_material = a.text(parent, 'null,"material":', events={0: (ev(PARENT_NULL),), 15: (ev(SLOT_OPEN, MATERIAL_REF),)})
    _id_slot(a, root_material, MATERIAL_REF, {ord("}"): (node_done, (ev(NODE_CLOSE, CLOSE_ROOT),))})
    # child: a parent id, a material, an optional joint
    after_parent = a.new()
    _id_slot(a, parent, PARENT, {ord(","): (after_parent, ())})
    child_material = a.text(after_parent, '"material":', events={10: (ev(SLOT_OPEN, MATERIAL_REF),)})
    joint = a.new()
    _id_slot(a, child_material, MATERIAL_REF, {ord("}"): (node_done, (ev(NODE_CLOSE, CLOSE_RIGID),)),
                                               ord(","): (joint, (ev(JOINT_OPEN),))})
    _joint(a, joint, node_done)
    a.text(node_done, ',"', end=node_key, events={0: (ev(NODES_MORE),), 1: (ev(SLOT_OPEN, NODE_KEY),)})

    # relations: ,"relations":[{"type":"symmetric","a":A,"b":B,"plane":"xy"},{"type":"instance",...}]
    relations = a.text(node_done, '},"relations":[', events={0: (ev(NODES_END),)})
    end = a.new()
    a.accept.add(end)
    listed = a.new()  # after a relation's closing brace
    a.text(relations, "]}", end=end)
    a.text(listed, "]}", end=end)
    rel_type = a.text(relations, '{"type":"', events={0: (ev(RELATION_OPEN),)})
    a.text(listed, ',{"type":"', end=rel_type, events={0: (ev(RELATION_OPEN),)})
    for index, kind in enumerate(RELATION_TYPES):  # byte 1 tells the types apart ("symmetric", "support")
        first = a.text(rel_type, f'{kind}","a":', events={1: (ev(REL_TYPE, index),),
                                                          len(kind) + 5: (ev(SLOT_OPEN, RELATION_A),)})
        after_a = a.new()
        _id_slot(a, first, RELATION_A, {ord(","): (after_a, ())})
        second = a.text(after_a, '"b":', events={3: (ev(SLOT_OPEN, RELATION_B),)})
        if kind == "symmetric":
            after_b = a.new()
            _id_slot(a, second, RELATION_B, {ord(","): (after_b, ())})
            plane = a.text(after_b, '"plane":"')
            for name in ("xy", "yz", "xz"):
                a.text(plane, f'{name}"}}', end=listed)
        else:
            _id_slot(a, second, RELATION_B, {ord("}"): (listed, ())})
    a.named.update(node_key=node_key, node_done=node_done, parent=parent, end=end)
    return a
