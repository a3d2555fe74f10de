"""The byte automaton of a part program (SPEC §6), as the factories' program writer spells it.

One statement per line, each ending in a newline: ``name = fn(args)`` with ``fn`` a predefined
function, ``name = material('<Family>', '<desc>')``, or ``part(<id>, '<name>', mesh[, material=m])``.
Arguments are literal numbers, strings, tuples / lists of numbers (nested once), or names bound
earlier; positional arguments come first, keywords are ``kw=value``, separators are ``", "``.
The first argument of a function that needs one (``mesh``, ``base``, ``profile``, ``path``) is
positional and spelled here; the rest of an argument list is one shared sub-automaton whose
function is a device register, so the per-function rules are events:

* ``CALL(f)`` opens function f; ``POSVAL(kind)`` / ``KWVAL(kind)`` start a value of a kind
  (number, string, sequence, name) that the parameter must take; ``KW_END`` closes a keyword,
  whose hash must be a parameter of f not given yet; ``REF_END`` / ``REF_POS_END`` close a name,
  whose hash must be bound; ``DEF_END`` closes an assigned name (not a predefined or reserved
  word), ``DEF_COMMIT`` binds it at the line's end; ``PART_OPEN``, ``PDIGIT(d)``, ``PID_END``,
  ``PART_COMMIT`` make the part ids 1, 2, 3, ...

Identifiers (``[A-Za-z_][A-Za-z0-9_]*`` without ``__``) are *segments*: edges reading them carry a
hash op (``OP_*``), so the device keeps a 32-bit polynomial hash of the name being read
(``jax3dc.constrained.program``). What stays outside the grammar: tuple lengths, number ranges,
axis / plane strings and a name's type (mesh or material), which the functions check when run.
"""

from __future__ import annotations

import functools
import heapq
import inspect
import keyword
from dataclasses import dataclass, field

import numpy as np

from jax3dc.constrained.automaton import Automaton
from jax3dc.program.library import FUNCTIONS
from jax3dc.structure.schema import FAMILIES

# Event codes: type << 8 | argument.
(CALL, POSVAL, KWVAL, KW_END, REF_END, REF_POS_END, DEF_END, DEF_COMMIT, DEF_ROOM, NEED_BOUND,
 PART_OPEN, PDIGIT, PID_END, PART_COMMIT) = range(1, 15)
# Value kinds (bit masks).
NUM, STR, SEQ, REF = 1, 2, 4, 8
# Identifier hash ops on an edge.
OP_NONE, OP_CHAR, OP_START, OP_DEF_CHAR, OP_DEF_START = range(5)
# Segment classes of a state: not in a name, an assigned name, a name that must be bound, an
# argument name (a keyword or a bound name).
SEG_NONE, SEG_DEF, SEG_REF, SEG_ARG = range(4)

IDMAX = 32  # longest identifier
HASH_MUL = 0x01000193
HASH_START = 0x811C9DC5
LETTERS = b"ABCDEFGHIJKLMNOPQRSTUVWXYZabcdefghijklmnopqrstuvwxyz"
DIGITS = b"0123456789"
STRING_CHARS = bytes(c for c in range(0x20, 0x7F) if c not in b"'\\")
INT_DIGITS, FRAC_DIGITS = 6, 6  # |numbers| < 1e6, the library's MAX_MAGNITUDE

# Parameter kinds by name where the default does not say (no default, or None), and axes that
# may be a vector (radial_array, rotate).
_VECTOR_AXIS = {"radial_array", "rotate"}
_KIND_BY_NAME = {"mesh": REF, "base": REF, "cutters": REF, "meshes": REF, "profile": SEQ, "path": SEQ,
                 "radius": NUM, "size": NUM | SEQ, "factor": NUM | SEQ}


def ev(kind: int, arg: int = 0) -> int:
    return kind << 8 | arg


def name_hash(name: str) -> int:
    """The device's identifier hash: h = h * HASH_MUL + byte + 1 (mod 2^32) from HASH_START."""
    h = HASH_START
    for b in name.encode():
        h = (h * HASH_MUL + b + 1) & 0xFFFFFFFF
    return h


@dataclass(frozen=True)
class Function:
    """A predefined function as the grammar sees it: its positional-or-keyword parameters with
    the kinds each takes, and the kind of ``*args`` (0 if none)."""

    name: str
    params: tuple[str, ...]
    kinds: tuple[int, ...]
    varargs: int
    first: str  # "ref", "seq" or "" : the required first argument the automaton spells


@functools.cache
def functions() -> tuple[Function, ...]:
    """The callable functions of ``name = fn(...)`` (``material`` and ``part`` have their own forms)."""
    out = []
    for name, fn in FUNCTIONS.items():
        if name in ("material", "part"):
            continue
        params, kinds, varargs = [], [], 0
        for p in inspect.signature(fn).parameters.values():
            if p.kind is p.VAR_POSITIONAL:
                varargs = _KIND_BY_NAME[p.name]
                continue
            default = p.default
            if p.name == "axis" and name in _VECTOR_AXIS:
                kind = STR | SEQ
            elif p.name in _KIND_BY_NAME:
                kind = _KIND_BY_NAME[p.name]
            elif isinstance(default, tuple):
                kind = SEQ
            elif isinstance(default, str):
                kind = STR
            else:
                kind = NUM
            params.append(p.name)
            kinds.append(kind)
        required = [p for p in inspect.signature(fn).parameters.values()
                    if p.default is p.empty and p.kind is not p.VAR_POSITIONAL]
        if len(required) > 1:
            raise ValueError(f"{name}: the grammar spells one required argument, not {len(required)}")
        first = "" if not required else ("ref" if kinds[0] == REF else "seq")
        out.append(Function(name, tuple(params), tuple(kinds), varargs, first))
    return tuple(out)


def reserved_words() -> list[str]:
    """Names a program may not assign: the predefined functions, ``range`` and Python keywords."""
    return sorted(set(FUNCTIONS) | {"range"} | set(keyword.kwlist))


@dataclass
class ProgramAutomaton(Automaton):
    """The automaton plus what the device needs per state and edge."""

    ops: dict[tuple[int, int], int] = field(default_factory=dict)
    segment: dict[int, int] = field(default_factory=dict)  # state -> SEG_*
    id_digits: dict[int, int] = field(default_factory=dict)  # part-id states -> digits written
    line_start: int = 0

    def op_edge(self, a: int, byte: int, b: int, op: int, events: tuple[int, ...] = ()) -> None:
        self.edge(a, byte, b, events)
        self.ops[(a, byte)] = op


def _segment(a: ProgramAutomaton, cls: int, exits: dict[int, tuple[int, tuple[int, ...]]],
             entries: list[tuple[int, tuple[int, ...]]]) -> tuple[int, int]:
    """An identifier segment (states: last byte not '_', last byte '_'); ``entries``: (state,
    events on the first byte); ``exits``: byte -> (target, events). Returns (plain, underscore)."""
    plain, under = a.new(), a.new()
    a.segment[plain] = a.segment[under] = cls
    start, char = (OP_DEF_START, OP_DEF_CHAR) if cls == SEG_DEF else (OP_START, OP_CHAR)
    for src, events in entries:
        for c in LETTERS:
            a.op_edge(src, c, plain, start, events)
        a.op_edge(src, ord("_"), under, start, events)
    for c in LETTERS + DIGITS:
        a.op_edge(plain, c, plain, char)
        a.op_edge(under, c, plain, char)
    a.op_edge(plain, ord("_"), under, char)
    for s in (plain, under):
        for byte, (target, events) in exits.items():
            a.edge(s, byte, target, events)
    return plain, under


def _number(a: ProgramAutomaton, entry: int, first_events: tuple[int, ...],
            exits: dict[int, tuple[int, tuple[int, ...]]]) -> None:
    """-?(0|[1-9][0-9]{0,5})(.[0-9]{1,6})? after ``entry``; any exit byte ends it."""
    sign, zero, dot = a.new(), a.new(), a.new()
    ints = [a.new() for _ in range(INT_DIGITS)]
    fracs = [a.new() for _ in range(FRAC_DIGITS)]
    a.edge(entry, ord("-"), sign, first_events)
    for src, events in ((entry, first_events), (sign, ())):
        a.edge(src, ord("0"), zero, events)
        for d in b"123456789":
            a.edge(src, d, ints[0], events)
    for i in range(INT_DIGITS - 1):
        for d in DIGITS:
            a.edge(ints[i], d, ints[i + 1])
    for s in [zero] + ints:
        a.edge(s, ord("."), dot)
    for d in DIGITS:
        a.edge(dot, d, fracs[0])
        for i in range(FRAC_DIGITS - 1):
            a.edge(fracs[i], d, fracs[i + 1])
    for s in [zero] + ints + fracs:
        for byte, (target, events) in exits.items():
            a.edge(s, byte, target, events)


def _sequence(a: ProgramAutomaton, entry: int, first_events: tuple[int, ...], done: int, depth: int = 2) -> None:
    """``(...)`` or ``[...]`` of numbers (and, at depth 2, of such sequences), items separated by
    ``", "``, a trailing comma allowed; ``done`` is the state after the closing bracket."""
    for opener, closer in ((b"(", b")"), (b"[", b"]")):
        start, after, comma = a.new(), a.new(), a.new()
        a.edge(entry, opener[0], start, first_events)
        a.edge(start, closer[0], done)
        a.edge(comma, closer[0], done)
        a.edge(comma, ord(" "), start)
        a.edge(after, ord(","), comma)
        a.edge(after, closer[0], done)
        _number(a, start, (), {ord(","): (comma, ()), closer[0]: (done, ())})
        if depth > 1:
            _sequence(a, start, (), after, depth - 1)


@functools.cache
def program_automaton() -> ProgramAutomaton:
    """The automaton of every part program (built once)."""
    a = ProgramAutomaton()
    line = a.start
    a.line_start = line
    a.accept.add(line)
    funcs = functions()
    call_end = a.new()  # after ')' of an assignment's call
    a.edge(call_end, ord("\n"), line, (ev(DEF_COMMIT),))

    # Argument list shared by every function: the function is the CALL register.
    args, after_value, comma = a.new(), a.new(), a.new()
    a.edge(args, ord(")"), call_end)
    a.edge(after_value, ord(","), comma)
    a.edge(after_value, ord(")"), call_end)
    a.edge(comma, ord(" "), args)
    value_exits = {ord(","): (comma, ()), ord(")"): (call_end, ())}
    kw_value = a.new()
    for start, tag in ((args, POSVAL), (kw_value, KWVAL)):
        _number(a, start, (ev(tag, NUM),), value_exits)
        string = a.new()
        a.edge(start, ord("'"), string, (ev(tag, STR),))
        for c in STRING_CHARS:
            a.edge(string, c, string)
        a.edge(string, ord("'"), after_value)
        _sequence(a, start, (ev(tag, SEQ),), after_value)
    _segment(a, SEG_ARG, {ord(","): (comma, (ev(REF_POS_END),)), ord(")"): (call_end, (ev(REF_POS_END),)),
                          ord("="): (kw_value, (ev(KW_END),))}, [(args, ())])
    _segment(a, SEG_REF, {ord(","): (comma, (ev(REF_END),)), ord(")"): (call_end, (ev(REF_END),))},
             [(kw_value, (ev(KWVAL, REF),))])
    # A required first argument: a bound name, or a sequence.
    first_ref, first_seq = a.new(), a.new()
    _segment(a, SEG_REF, {ord(","): (comma, (ev(REF_POS_END),)), ord(")"): (call_end, (ev(REF_POS_END),))},
             [(first_ref, ())])
    _sequence(a, first_seq, (ev(POSVAL, SEQ),), after_value)

    # name = fn(...)
    assign = a.new()
    after_eq = a.text(assign, "= ")
    for index, f in enumerate(funcs):
        target = {"ref": first_ref, "seq": first_seq, "": args}[f.first]
        events = (ev(CALL, index),) + ((ev(NEED_BOUND),) if f.first == "ref" else ())
        a.text(after_eq, f.name + "(", end=target, events={len(f.name): events})
    family = a.text(after_eq, "material('")
    desc = a.new()
    for name in FAMILIES:
        a.text(family, f"{name}', '", end=desc)
    for c in STRING_CHARS:
        a.edge(desc, c, desc)
    a.text(desc, "')", end=call_end)

    # part(<id>, '<name>', mesh[, material=m])
    part_end = a.new()
    a.edge(part_end, ord("\n"), line, (ev(PART_COMMIT),))
    pid = a.new()
    a.id_digits[pid] = 0
    digits = [a.new() for _ in range(3)]
    for k, s in enumerate(digits):
        a.id_digits[s] = k + 1
    name_open = a.new()
    for d in b"123456789":
        a.edge(pid, d, digits[0], (ev(PDIGIT, d - 48),))
    for k in range(2):
        for d in DIGITS:
            a.edge(digits[k], d, digits[k + 1], (ev(PDIGIT, d - 48),))
    for s in digits:
        a.edge(s, ord(","), name_open, (ev(PID_END),))
    part_name = a.text(name_open, " '")
    for c in STRING_CHARS:
        a.edge(part_name, c, part_name)
    mesh = a.text(part_name, "', ")
    material_key = a.new()
    _segment(a, SEG_REF, {ord(")"): (part_end, (ev(REF_END),)), ord(","): (material_key, (ev(REF_END),))},
             [(mesh, ())])
    material_ref = a.text(material_key, " material=")
    _segment(a, SEG_REF, {ord(")"): (part_end, (ev(REF_END),))}, [(material_ref, ())])

    # Line start: an assigned name, or 'part(' (whose first letters are also a name's).
    space = {ord(" "): (assign, (ev(DEF_END),))}
    plain, under = _segment(a, SEG_DEF, space, [])
    room = (ev(DEF_ROOM),)
    prefix = [line] + [a.new() for _ in range(4)]
    for s in prefix[1:]:
        a.segment[s] = SEG_DEF
    for i, c in enumerate(b"part"):
        a.op_edge(prefix[i], c, prefix[i + 1], OP_DEF_START if i == 0 else OP_DEF_CHAR)
    for i, s in enumerate(prefix):
        op = OP_DEF_START if i == 0 else OP_DEF_CHAR
        for c in LETTERS + (DIGITS if i else b"") + b"_":
            if (s, c) not in a.ops:
                a.op_edge(s, c, under if c == ord("_") else plain, op, room)
        if i:
            a.edge(s, ord(" "), assign, (ev(DEF_END),) + room)
    a.edge(prefix[4], ord("("), pid, (ev(PART_OPEN),))
    return a


def close_costs(a: ProgramAutomaton) -> np.ndarray:
    """[S, 2, 2] bytes to a complete program from each state, given (any name bound, any part
    written): a shortest path where a name counts IDMAX bytes (the device adds IDMAX - the
    length read inside one), names need a bound one where they close as a reference, and 'part('
    needs a bound name. Argument-name states take their dearest way out (keyword or reference),
    since the device does not know which one the name read so far leads to."""
    n = len(a.edges)
    inf = np.iinfo(np.int32).max // 4
    cost = np.full((n, 2, 2), inf, np.int64)
    reverse: list[list[tuple[int, int, tuple[int, ...]]]] = [[] for _ in range(n)]
    for s, edges in enumerate(a.edges):
        for byte, (t, events) in edges.items():
            reverse[t].append((s, byte, events))

    def weight(s: int, t: int) -> int:
        inside_s, inside_t = a.segment.get(s, SEG_NONE), a.segment.get(t, SEG_NONE)
        if inside_t and not inside_s:
            return IDMAX
        return 0 if inside_s and inside_t else 1

    def step(s: int, events: tuple[int, ...], bound: int, parts: int):
        """(bound, parts) before an edge from (bound', parts') after it, or None if it is blocked."""
        kinds = {e >> 8 for e in events}
        if not bound and kinds & {REF_END, REF_POS_END, NEED_BOUND, PART_OPEN}:
            return None
        return kinds

    heap = []
    for bound in (0, 1):
        cost[a.line_start, bound, 1] = 0
        heapq.heappush(heap, (0, a.line_start, bound, 1))
    while heap:
        c, t, bound_t, parts_t = heapq.heappop(heap)
        if c > cost[t, bound_t, parts_t]:
            continue
        for s, byte, events in reverse[t]:
            kinds = {e >> 8 for e in events}
            for bound in (0, 1):
                for parts in (0, 1):
                    after_bound = bound | (DEF_COMMIT in kinds)
                    after_parts = parts | (PART_COMMIT in kinds)
                    if (after_bound, after_parts) != (bound_t, parts_t) or step(s, events, bound, parts) is None:
                        continue
                    new = c + weight(s, t)
                    if new < cost[s, bound, parts]:
                        cost[s, bound, parts] = new
                        heapq.heappush(heap, (new, s, bound, parts))
    # Argument names: the dearest finite way out.
    for s, cls in a.segment.items():
        if cls != SEG_ARG:
            continue
        for bound in (0, 1):
            for parts in (0, 1):
                outs = []
                for byte, (t, events) in a.edges[s].items():
                    if a.segment.get(t, SEG_NONE) or step(s, events, bound, parts) is None:
                        continue
                    kinds = {e >> 8 for e in events}
                    c = cost[t, bound | (DEF_COMMIT in kinds), parts | (PART_COMMIT in kinds)]
                    if c < inf:
                        outs.append(1 + c)
                if outs:
                    cost[s, bound, parts] = max(outs)
    return np.minimum(cost, inf).astype(np.int32)
