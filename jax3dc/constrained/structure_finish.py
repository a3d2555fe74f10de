"""Tokens to finish a structure document, per automaton state, in the tokenizer's own tokens.

A document is pieces joined at hub states: the materials (up to the first node's key), each node
(from its key to ``node_done``), and the relations (from ``node_done`` to the end). Per piece kind
("mode") a shortest path over the lifted token table gives, for every state, the fewest tokens to
the piece's hub; the device (``jax3dc.constrained.structure``) adds what the registers say is still
owed (nodes left, joints owed) from the same tables. The sum is the length of one completion the
grammar really allows, so while it fits the tokens left there is always a token that keeps it
fitting (the next token of that completion lowers it by at least one); a token is offered only if
it does.

The paths use only tokens whose events the registers surely pass on that path: no digit inside a
token (an id is written digit by digit, one single-byte token each, so an id of any value costs at
most ``digits(N)`` tokens, N the prompt's part count: ids are parts 1..N, or materials 0..N), no optional content (another material, a relation), no token crossing a hub (its
cost would belong to the next piece), and no token that opens a slot and reads in it (the device
refuses those). Modes of a node: a root (``R_PRE`` before ``null``, ``R_POST`` after), a rigid
child (``P``), a child with a joint (``J``); of a relation: finished without choosing a type
(``END``) or with type t (``REL + t``).
"""

from __future__ import annotations

from collections import deque

import numpy as np
from scipy.sparse import coo_matrix
from scipy.sparse.csgraph import dijkstra

from jax3dc.constrained import structure_grammar as g
from jax3dc.constrained.automaton import TokenTable

MAT, R_PRE, R_POST, P, J, END, REL = range(7)  # REL + t for each relation type
N_MODES = REL + len(g.RELATION_TYPES)
# Phases of a state: materials, inside a node, between nodes, relations.
PHASE_MAT, PHASE_NODE, PHASE_HUB, PHASE_REL = range(4)
# Stages inside a node: before the parent is chosen, parent digits written, in the joint, a root.
STAGE_OPEN, STAGE_CHILD, STAGE_JOINT, STAGE_ROOT = range(4)
INF = 1 << 20
ID_DIGITS = 3  # ids < 1000


def _has(kinds: np.ndarray, args: np.ndarray, kind: int, arg: int | None = None) -> np.ndarray:
    hit = kinds == kind
    if arg is not None:
        hit &= args == arg
    return hit.any(axis=1)


def _mode_edges(events: np.ndarray, passes: np.ndarray) -> list[np.ndarray]:
    """Per mode, [P] bool: the pairs its paths may use."""
    kinds, args = events >> 8, events & 255
    opened = np.cumsum(kinds == g.SLOT_OPEN, axis=1) - (kinds == g.SLOT_OPEN) > 0  # a slot opened earlier in the token
    stale = ((opened & np.isin(kinds, (g.DIGIT, g.SLOT_CLOSE, g.PARENT_NULL))).any(axis=1))
    base = ~(_has(kinds, args, g.DIGIT) | stale | _has(kinds, args, g.MATERIAL_MORE) | _has(kinds, args, g.RELATION_OPEN))
    close = lambda path: _has(kinds, args, g.NODE_CLOSE) & ~_has(kinds, args, g.NODE_CLOSE, path)  # noqa: E731
    node = base & ~passes & ~_has(kinds, args, g.NODES_END)
    parent_null, joint_open = _has(kinds, args, g.PARENT_NULL), _has(kinds, args, g.JOINT_OPEN)
    rel = base & ~_has(kinds, args, g.NODES_MORE)
    typed = _has(kinds, args, g.REL_TYPE)
    modes = [None] * N_MODES
    modes[MAT] = base
    modes[R_PRE] = node & ~joint_open & ~close(g.CLOSE_ROOT)
    modes[R_POST] = modes[R_PRE] & ~parent_null
    modes[P] = node & ~parent_null & ~joint_open & ~close(g.CLOSE_RIGID)
    modes[J] = node & ~parent_null & ~close(g.CLOSE_JOINT)
    modes[END] = rel & ~typed
    for t in range(len(g.RELATION_TYPES)):
        modes[REL + t] = rel & ~(typed & ~_has(kinds, args, g.REL_TYPE, t))
    return modes


def _distances(src: np.ndarray, dst: np.ndarray, use: np.ndarray, slots, id_digits: int, n_states: int,
               target: int) -> np.ndarray:
    """Fewest tokens from each state to ``target`` over the pairs ``use`` and, at each slot's
    entry, ``id_digits`` single-digit tokens to its first digit state."""
    entries = np.asarray([e for e, _ in slots])
    firsts = np.asarray([d[1] for _, d in slots])
    rows = np.concatenate([dst[use], firsts])  # reversed graph: from the target outwards
    cols = np.concatenate([src[use], entries])
    weight = np.concatenate([np.ones(int(use.sum())), np.full(len(slots), float(id_digits))])
    key = rows.astype(np.int64) * n_states + cols
    order = np.lexsort((weight, key))
    first = np.unique(key[order], return_index=True)[1]  # the lightest edge of each (state, state)
    graph = coo_matrix((weight[order][first], (rows[order][first], cols[order][first])), shape=(n_states, n_states))
    dist = dijkstra(graph.tocsr(), indices=target)
    return np.where(np.isfinite(dist), np.minimum(dist, INF), INF).astype(np.int32)


def _label(auto: g.StructureAutomaton) -> tuple[np.ndarray, np.ndarray]:
    """(phase [S], stage [S]) by walking the byte automaton from each piece's entry to its hub."""
    n = len(auto.edges)
    phase = np.full(n, -1, np.int32)
    stage = np.full(n, -1, np.int32)
    named = auto.named
    node_done, node_key, parent = named["node_done"], named["node_key"], named["parent"]
    more_nodes = [t for t, ev in auto.edges[node_done].values() if g.ev(g.NODES_MORE) in ev]
    to_relations = [t for t, ev in auto.edges[node_done].values() if g.ev(g.NODES_END) in ev]
    digits = {ord(str(d)) for d in range(10)}

    def walk(starts, which, stop, stage_of=None):
        queue = deque(starts)
        for s in starts:
            phase[s] = which
        while queue:
            s = queue.popleft()
            for byte, (t, events) in auto.edges[s].items():
                if t in stop:
                    continue
                if stage_of is not None:
                    kinds = {e >> 8 for e in events}
                    new = (STAGE_ROOT if g.PARENT_NULL in kinds else STAGE_JOINT if g.JOINT_OPEN in kinds
                           else STAGE_CHILD if s == parent and byte in digits else stage[s])
                    if stage[t] not in (-1, new):
                        raise ValueError(f"state {t} is in two node stages ({stage[t]}, {new})")
                    stage[t] = new
                if phase[t] == -1:
                    phase[t] = which
                    queue.append(t)
                elif phase[t] != which:
                    raise ValueError(f"state {t} is in two phases ({phase[t]}, {which})")

    walk([auto.start], PHASE_MAT, {node_key})
    stage[more_nodes + [node_key]] = STAGE_OPEN
    walk(more_nodes + [node_key], PHASE_NODE, {node_done}, stage_of=True)
    phase[node_done] = PHASE_HUB
    walk(to_relations, PHASE_REL, set())
    return phase, stage


def finish_tables(auto: g.StructureAutomaton, table: TokenTable) -> dict[str, np.ndarray]:
    """What the device needs to compute the tokens to finish (see the module docstring):
    ``dist [ID_DIGITS, N_MODES, S]`` (index: digits(N) - 1), ``phase``, ``stage``, and
    ``slot_digits [S]``: digits read in a slot's digit state (a '0' is complete: ID_DIGITS), else 0."""
    n = len(auto.edges)
    s_idx, c_idx = np.nonzero(table.pair >= 0)
    p = table.pair[s_idx, c_idx]
    src, dst = s_idx.astype(np.int32), table.next_state[p]
    modes = _mode_edges(table.events[p], table.passes[p])
    named = auto.named
    targets = {MAT: named["node_key"], **{m: named["node_done"] for m in (R_PRE, R_POST, P, J)},
               **{m: named["end"] for m in range(END, N_MODES)}}
    dist = np.stack([np.stack([_distances(src, dst, modes[m], auto.slots, k, n, targets[m]) for m in range(N_MODES)])
                     for k in range(1, ID_DIGITS + 1)])
    slot_digits = np.zeros(n, np.int32)
    for _, (zero, *nonzero) in auto.slots:
        slot_digits[zero] = ID_DIGITS
        for k, s in enumerate(nonzero, start=1):
            slot_digits[s] = k
    phase, stage = _label(auto)
    return dict(dist=dist, phase=phase, stage=stage, slot_digits=slot_digits)
