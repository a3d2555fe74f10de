"""The parameter-text grammar as a byte automaton (``jax3dc.parameters.text``).

The language is finite and regular: a category of the schemas, ``(``, then that category's
entries in schema order, ``name=value`` joined by ``", "``, then ``)``. Each value slot accepts
exactly the canonical spellings of the values its entry allows (every multiple of 10^-DECIMALS
in a Number's [lo, hi] with trailing zeros dropped; the integers of a Count; 0/1; the option
indices), so every text the automaton accepts parses and fits its schema, and every record's text
is accepted. No events and no registers: the state alone decides the mask.
"""

from __future__ import annotations

from collections import deque
from typing import Mapping

import numpy as np

from jax3dc.constrained.automaton import Automaton, embed
from jax3dc.parameters import DECIMALS, Chance, Choice, Count, Number, Schema, Spec, format_number


def value_words(spec: Spec) -> list[str]:
    """Every canonical spelling one value of ``spec`` may take."""
    if isinstance(spec, Number):
        scale = 10 ** DECIMALS
        lo, hi = round(spec.lo * scale), round(spec.hi * scale)
        return [format_number(k / scale) for k in range(lo, hi + 1)]
    if isinstance(spec, Count):
        return [str(k) for k in range(spec.lo, spec.hi + 1)]
    if isinstance(spec, Chance):
        return ["0", "1"]
    assert isinstance(spec, Choice)
    return [str(k) for k in range(len(spec.options))]


def _value(auto: Automaton, entry: int, words: list[str], after: str) -> int:
    """``words`` from ``entry``, then the literal ``after``; returns the state after it."""
    head = auto.new()
    end = auto.text(head, after[1:]) if len(after) > 1 else head
    embed(auto, entry, [(w, 0) for w in words], {0: {ord(after[0]): (head, ())}})
    return end


def _pieces(schema: Schema) -> list[str | Spec]:
    """The text of ``schema`` as literals and value slots, consecutive literals joined."""
    raw: list[str | Spec] = [f"{schema.category}("]
    for i, spec in enumerate(schema.specs):
        raw.append(f"{', ' if i else ''}{spec.name}=")
        if spec.slots:
            raw.append("(")
            for j in range(spec.slots):
                raw += [", "] * bool(j) + [spec]
            raw.append(")")
        else:
            raw.append(spec)
    raw.append(")")
    out: list[str | Spec] = []
    for piece in raw:
        if isinstance(piece, str) and out and isinstance(out[-1], str):
            out[-1] += piece
        else:
            out.append(piece)
    return out


def parameters_automaton(schemas: Mapping[str, Schema]) -> Automaton:
    """The automaton of every category's text; a category's accepting state follows its final ``)``."""
    auto = Automaton()
    words: dict[Spec, list[str]] = {}
    for category in sorted(schemas):
        pieces = _pieces(schemas[category])
        state = auto.text(auto.start, pieces[0])
        for value, after in zip(pieces[1::2], pieces[2::2]):
            if value not in words:
                words[value] = value_words(value)
            state = _value(auto, state, words[value], after)
        auto.accept.add(state)
    return auto


def close_costs(auto: Automaton) -> np.ndarray:
    """[S] bytes on a shortest path from each state to an accepting one (large where none)."""
    n = len(auto.edges)
    cost = np.full(n, np.iinfo(np.int32).max // 4, np.int64)
    reverse: list[list[int]] = [[] for _ in range(n)]
    for s, edges in enumerate(auto.edges):
        for t, _ in edges.values():
            reverse[t].append(s)
    queue = deque()
    for s in auto.accept:
        cost[s] = 0
        queue.append(s)
    while queue:  # every edge is one byte: breadth first
        t = queue.popleft()
        for s in reverse[t]:
            if cost[s] > cost[t] + 1:
                cost[s] = cost[t] + 1
                queue.append(s)
    return cost.astype(np.int32)
