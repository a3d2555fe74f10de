"""Structure-grammar masks on the device: which tokens each row may write next, and the step.

Per row the device keeps the automaton state and a few registers (the node being written, joints
and materials so far, relations of each type, the id being read, the tokens left), the ancestor
matrix of the parents written so far (so a parent that would close a cycle is never offered), the
relation pairs written so far (so no relation is written twice) and, for the id slot being read,
the set of ids it may take and the prefixes that still lead to one (``reach``: digit by digit, ids
of any length). A step is a handful of gathers and elementwise ops over ``[rows, vocab]``; nothing
leaves the device.

Guarantees, for any logits, while the tokens left (``remaining``, capped per row by the room the
row was given) cover the shortest document for its prompt (``min_tokens``): every row stops on a
document the validator accepts, with exactly the prompt's part ids and its joint count (the
prompt's ``Joints:`` line, capped at N - 1: one part at least is a root). The count is kept
reachable by a capacity argument: every part before the last can always take a joint (the last
part, not yet written, is a parent that closes no cycle), and the last part can when some earlier
part is a root (nothing hangs it below the last); so a part may stay without a joint only while the
joints still owed fit that capacity. Every list is bounded by the prompt: at most N + 1 materials
(ids 0..N, so no longer than a part id; the factories' globe writes 3 for 2 parts), at most
min(2N, 64) relations, each over two different parts and no (type, pair) twice. The document
closes in time: a token is offered only if the tokens to finish after it
(``jax3dc.constrained.structure_finish``) still fit the tokens left.
"""

from __future__ import annotations

import functools
from typing import NamedTuple, Sequence

import jax
import jax.numpy as jnp
import numpy as np

from jax3dc.constrained import structure_finish as fin
from jax3dc.constrained import structure_grammar as g
from jax3dc.constrained.automaton import lift, token_bytes

ID_LIMIT = 128  # ids 0..127 (the largest training object has 30 parts)
MAX_EVENTS = 6
MATERIALS_MAX = 16
RELATIONS_MAX = 64
N_TYPES = len(g.RELATION_TYPES)
UNLIMITED = 1 << 30  # a row given no room of its own
# Registers.
(K, JOINTS, MATERIALS, RELATIONS, NUM, REL_A, HAS_VALID, PARENT_CLOSED, OPENED, ROOTS, TYPE, B_CLOSED,
 USED) = range(13)  # USED .. USED + N_TYPES - 1: relations of each type
N_REGS = USED + N_TYPES


class Tables(NamedTuple):
    """The lifted grammar on the device (see ``automaton.TokenTable``) and the tokens-to-finish
    tables (``structure_finish.finish_tables``)."""

    columns: jax.Array  # [U] int32: the token id of each column
    column_of: jax.Array  # [V] int32: each token's column, -1 for tokens the grammar never writes
    pair: jax.Array  # [S, U] int32
    next_state: jax.Array  # [P] int32
    events: jax.Array  # [P, E] int32
    accept: jax.Array  # [S] bool
    stop_ids: jax.Array  # [2] int32
    dist: jax.Array  # [ID_DIGITS, N_MODES, S] int32
    phase: jax.Array  # [S] int32
    stage: jax.Array  # [S] int32
    slot_digits: jax.Array  # [S] int32
    hubs: jax.Array  # [2] int32: node_key, node_done


class Rows(NamedTuple):
    """Per-row grammar state."""

    state: jax.Array  # [B] int32
    regs: jax.Array  # [B, N_REGS] int32
    consts: jax.Array  # [B, 2] int32: part count N, joint count J (-1: not given)
    anc: jax.Array  # [B, ID_LIMIT, ID_LIMIT] bool: anc[x, y] = y is an ancestor of x
    valid: jax.Array  # [B, ID_LIMIT] bool: ids the open slot takes
    reach: jax.Array  # [B, ID_LIMIT] bool: digit prefixes that lead to one
    related: jax.Array  # [B, ID_LIMIT, ID_LIMIT] int32: bit t of [a, b] and [b, a]: a relation of type t joins a, b
    left: jax.Array  # [B] int32: tokens this row may still write (its room, counted down)


@functools.lru_cache(maxsize=4)
def structure_tables(tokenizer, vocab_size: int) -> Tables:
    """The grammar lifted to ``tokenizer``, as device arrays; cached per tokenizer object, so every
    batch of a run reuses one copy (Qwen3's vocabulary takes 46 s to lift and 370 MB)."""
    auto = g.structure_automaton()
    tokens = token_bytes(tokenizer)[:vocab_size]
    missing = [d for d in "0123456789" if d.encode() not in tokens]
    if missing:
        raise ValueError(f"the tokenizer has no single-digit token for {missing}: the structure grammar writes ids "
                         "digit by digit")
    table = lift(auto, tokens, MAX_EVENTS, through=[auto.named["node_done"]])
    column_of = np.full(vocab_size, -1, np.int32)  # the model's embedding may be padded past the tokenizer
    column_of[table.columns] = np.arange(len(table.columns), dtype=np.int32)
    finish = fin.finish_tables(auto, table)
    host = Tables(table.columns, column_of, table.pair, table.next_state, table.events, table.accept,
                  np.asarray(tokenizer.special.stop_ids, np.int32), finish["dist"], finish["phase"], finish["stage"],
                  finish["slot_digits"], np.asarray([auto.named["node_key"], auto.named["node_done"]], np.int32))
    return Tables(*(jnp.asarray(x) for x in host))


def initial_rows(part_counts: Sequence[int], joint_counts: Sequence[int], room: Sequence[int] | None = None) -> Rows:
    """Rows at the document start; ``joint_counts[i]`` is -1 where the prompt gives no count;
    ``room[i]``: the most tokens row i may write, its stop token included (None: only the decode's
    own ``max_new_tokens``)."""
    n = np.asarray(part_counts, np.int32)
    if n.min() < 1 or n.max() >= ID_LIMIT:
        raise ValueError(f"constrained decoding takes 1 to {ID_LIMIT - 1} parts, got {int(n.min())}..{int(n.max())}")
    batch = len(n)
    regs = np.zeros((batch, N_REGS), np.int32)
    regs[:, K] = 1
    regs[:, OPENED] = -1
    regs[:, PARENT_CLOSED] = -1
    regs[:, B_CLOSED] = -1
    joints = np.asarray(joint_counts, np.int32)
    consts = np.stack([n, np.where(joints >= 0, np.minimum(joints, n - 1), -1)], axis=1)
    left = np.full(batch, UNLIMITED, np.int32) if room is None else np.asarray(room, np.int32)
    return Rows(jnp.zeros((batch,), jnp.int32), jnp.asarray(regs), jnp.asarray(consts),
                jnp.zeros((batch, ID_LIMIT, ID_LIMIT), bool), jnp.zeros((batch, ID_LIMIT), bool),
                jnp.zeros((batch, ID_LIMIT), bool), jnp.zeros((batch, ID_LIMIT, ID_LIMIT), jnp.int32), jnp.asarray(left))


def _caps(r, n, j):
    """(joints owed, joints the later parts surely take if this part is a root, ... if it hangs
    below a parent) for the part being written."""
    owed = j - r[JOINTS]
    last = r[K] >= n
    cap_root = jnp.where(last, 0, n - r[K])
    cap_rigid = jnp.where(last, 0, n - 1 - r[K] + (r[ROOTS] >= 1))
    return owed, cap_root, cap_rigid


def _pairs(n):
    return n * (n - 1) // 2


def _run_events(events: jax.Array, regs: jax.Array, consts: jax.Array, valid: jax.Array,
                reach: jax.Array) -> tuple[jax.Array, list[jax.Array]]:
    """Check and apply each token's events in order. Shapes: events [B, X, E], regs [B, X, R]
    (X: candidate tokens, or 1), consts [B, 1, 2], valid / reach [B, ID_LIMIT]. Returns
    (ok [B, X], the registers after, each [B, X])."""
    n, j = consts[..., 0], consts[..., 1]
    ok = jnp.ones(events.shape[:2], bool)
    stale = jnp.zeros(events.shape[:2], bool)  # a slot opened inside this token: its id sets are not built yet
    r = [regs[..., i] for i in range(N_REGS)]

    def lookup(table, index):  # table [B, L] at index [B, X]
        return jnp.take_along_axis(table, jnp.clip(index, 0, ID_LIMIT - 1), axis=1) & (index < ID_LIMIT) & (index >= 0)

    for e in range(events.shape[2]):
        code = events[..., e]
        kind, arg = code >> 8, code & 255
        digit = r[NUM] * 10 + arg
        owed, cap_root, cap_rigid = _caps(r, n, j)
        used = jnp.stack([r[USED + t] for t in range(N_TYPES)], axis=-1)
        type_free = used < _pairs(n)[..., None]
        checks = {
            g.DIGIT: ~stale & lookup(reach, digit),
            g.SLOT_CLOSE: ~stale & lookup(valid, r[NUM]),
            g.PARENT_NULL: ~stale & ((j < 0) | (owed <= cap_root) | (r[HAS_VALID] == 0)),
            g.JOINT_OPEN: (j < 0) | (r[JOINTS] < j),
            g.NODE_CLOSE: (arg != g.CLOSE_RIGID) | (j < 0) | (owed <= cap_rigid),
            g.NODES_MORE: r[K] <= n,
            g.NODES_END: r[K] > n,
            g.MATERIAL_MORE: r[MATERIALS] < jnp.minimum(n + 1, MATERIALS_MAX),
            g.RELATION_OPEN: (r[RELATIONS] < jnp.minimum(2 * n, RELATIONS_MAX)) & jnp.any(type_free, axis=-1),
            g.REL_TYPE: jnp.take_along_axis(type_free, jnp.clip(arg, 0, N_TYPES - 1)[..., None], axis=-1)[..., 0],
        }
        for k, check in checks.items():
            ok = ok & ((kind != k) | check)
        opening = kind == g.SLOT_OPEN
        closing = kind == g.SLOT_CLOSE
        b_closing = closing & (arg == g.RELATION_B)
        r[NUM] = jnp.where(kind == g.DIGIT, digit, jnp.where(opening, 0, r[NUM]))
        r[OPENED] = jnp.where(opening, arg, r[OPENED])
        r[MATERIALS] = r[MATERIALS] + (closing & (arg == g.MATERIAL_KEY))
        r[REL_A] = jnp.where(closing & (arg == g.RELATION_A), r[NUM], r[REL_A])
        r[B_CLOSED] = jnp.where(b_closing, r[NUM], r[B_CLOSED])
        r[PARENT_CLOSED] = jnp.where(closing & (arg == g.PARENT), r[NUM], r[PARENT_CLOSED])
        r[JOINTS] = r[JOINTS] + (kind == g.JOINT_OPEN)
        r[K] = r[K] + (kind == g.NODE_CLOSE)
        r[ROOTS] = r[ROOTS] + ((kind == g.NODE_CLOSE) & (arg == g.CLOSE_ROOT))
        r[RELATIONS] = r[RELATIONS] + (kind == g.RELATION_OPEN)
        r[TYPE] = jnp.where(kind == g.REL_TYPE, arg, r[TYPE])
        for t in range(N_TYPES):
            r[USED + t] = r[USED + t] + (b_closing & (r[TYPE] == t))
        stale = stale | opening
    return ok, r


def _to_finish(tables: Tables, state: jax.Array, r: list[jax.Array], consts: jax.Array) -> jax.Array:
    """Tokens to finish the document after reaching ``state [B, X]`` with registers ``r``, the
    stop token included (see ``structure_finish``); consts [B, 1, 2]."""
    n, j = consts[..., 0], consts[..., 1]
    idd = 1 + (n >= 10) + (n >= 100)  # digits of the largest id

    def dist(mode, at):
        return tables.dist[idd - 1, mode, at]

    node_key, node_done = tables.hubs[0], tables.hubs[1]
    sep, end = dist(fin.MAT, node_done), dist(fin.END, node_done) + 1
    c_root, c_rigid, c_joint = dist(fin.R_PRE, node_key), dist(fin.P, node_key), dist(fin.J, node_key)
    # A part without a joint is a root where the joint count allows any (no count, or none owed
    # beyond what later parts take), else a root or a child, whichever the registers then allow.
    c_plain = jnp.where(j < 0, c_root, jnp.maximum(c_root, c_rigid))
    owed, cap_root, cap_rigid = _caps(r, n, j)
    owed_now = jnp.where(j >= 0, jnp.maximum(owed, 0), 0)

    def nodes_from(k, w):  # from node_done with part k next and w joints owed
        count = jnp.maximum(n - k + 1, 0)
        return count * sep + (count - w) * c_plain + w * c_joint + end

    rest_plain = nodes_from(r[K] + 1, owed_now)
    rest_joint = nodes_from(r[K] + 1, jnp.maximum(owed_now - 1, 0))
    inf = fin.INF
    root_ok = (j < 0) | (owed <= cap_root)
    as_child = jnp.minimum(jnp.where((j < 0) | (owed <= cap_rigid), dist(fin.P, state) + rest_plain, inf),
                           jnp.where((j < 0) | (owed > 0), dist(fin.J, state) + rest_joint, inf))
    stage = tables.stage[state]
    in_node = jnp.select(
        [stage == fin.STAGE_OPEN, stage == fin.STAGE_CHILD, stage == fin.STAGE_JOINT, stage == fin.STAGE_ROOT],
        [jnp.where(root_ok, dist(fin.R_PRE, state) + rest_plain, as_child), as_child,
         dist(fin.J, state) + rest_plain, dist(fin.R_POST, state) + rest_plain], inf)
    used = jnp.stack([r[USED + t] for t in range(N_TYPES)], axis=-1)
    typed = jnp.min(jnp.where(used < _pairs(n)[..., None],
                              jnp.stack([dist(fin.REL + t, state) for t in range(N_TYPES)], axis=-1), inf), axis=-1)
    in_relations = jnp.minimum(dist(fin.END, state), typed) + 1
    phase = tables.phase[state]
    total = jnp.select(
        [phase == fin.PHASE_MAT, phase == fin.PHASE_NODE, phase == fin.PHASE_HUB, phase == fin.PHASE_REL],
        [dist(fin.MAT, state) + nodes_from(1, owed_now) - sep, in_node, nodes_from(r[K], owed_now), in_relations], inf)
    digits = tables.slot_digits[state]
    return total + jnp.where(digits > 0, jnp.maximum(idd - digits, 0), 0)


def min_tokens(tables: Tables, rows: Rows) -> np.ndarray:
    """[B]: the fewest tokens, stop token included, in which each row can still finish (at the
    document start: the shortest document this grammar lets its prompt have, as it counts)."""
    r = [rows.regs[:, None, i] for i in range(N_REGS)]
    return np.asarray(_to_finish(tables, rows.state[:, None], r, rows.consts[:, None, :]))[:, 0]


def allowed(tables: Tables, rows: Rows, remaining: jax.Array) -> jax.Array:
    """[B, V] bool: tokens each row may write now; ``remaining``: tokens left, this one included
    (capped by the row's own room). Stop tokens only where the document is complete (and, as a
    last resort, where nothing else is: only a row given less room than ``min_tokens``)."""
    pair = tables.pair[rows.state]  # [B, U]
    events = tables.events[jnp.maximum(pair, 0)]  # [B, V, E]
    regs = jnp.broadcast_to(rows.regs[:, None, :], pair.shape + (N_REGS,))
    consts = rows.consts[:, None, :]
    ok, r = _run_events(events, regs, consts, rows.valid, rows.reach)
    left = jnp.minimum(jnp.asarray(remaining, jnp.int32).reshape(-1), rows.left)[:, None] - 1  # after this token
    fits = _to_finish(tables, tables.next_state[jnp.maximum(pair, 0)], r, consts) <= left
    mask = (pair >= 0) & ok & fits
    batch, vocab = mask.shape[0], tables.column_of.shape[0]
    stop = jnp.zeros((batch, vocab), bool).at[:, tables.stop_ids].set(True)
    finish = tables.accept[rows.state] | ~jnp.any(mask, axis=1)
    full = jnp.zeros((batch, vocab), bool).at[:, tables.columns].set(mask)
    return jnp.where(finish[:, None], stop, full)


def _row(anc: jax.Array, index: jax.Array) -> jax.Array:
    """anc[b, index[b], :]: the ancestors of each row's part ``index``."""
    return anc[jnp.arange(anc.shape[0]), jnp.clip(index, 0, ID_LIMIT - 1)]


def _column(anc: jax.Array, index: jax.Array) -> jax.Array:
    """anc[b, :, index[b]]: the parts below each row's part ``index``."""
    return anc[jnp.arange(anc.shape[0]), :, jnp.clip(index, 0, ID_LIMIT - 1)]


def _slot_sets(role: jax.Array, regs: jax.Array, consts: jax.Array, anc: jax.Array,
               related: jax.Array) -> tuple[jax.Array, jax.Array]:
    """(valid, reach) [B, ID_LIMIT] for the slot each row just opened."""
    v = jnp.arange(ID_LIMIT)[None, :]
    k, mats, rel_a = regs[:, K:K + 1], regs[:, MATERIALS:MATERIALS + 1], regs[:, REL_A:REL_A + 1]
    n = consts[:, 0:1]
    part = (v >= 1) & (v <= n)
    # anc[b, x, k]: k is an ancestor of x, i.e. x hangs below k; such an x as k's parent closes a cycle.
    under_k = _column(anc, k[:, 0])
    # Relations of the type being written: a takes a part with a partner left, b a partner of a.
    taken = ((related >> jnp.clip(regs[:, TYPE], 0, N_TYPES - 1)[:, None, None]) & 1) == 1  # [B, ID, ID]
    partners = jnp.sum(taken & part[:, None, :], axis=2)
    free_b = ~_row(taken, rel_a[:, 0])
    role = role[:, None]
    valid = jnp.select(
        [role == g.NODE_KEY, role == g.PARENT, role == g.MATERIAL_REF, role == g.MATERIAL_KEY,
         role == g.RELATION_A, role == g.RELATION_B],
        [v == k, part & (v != k) & ~under_k, v < mats, v == mats, part & (partners < n - 1),
         part & (v != rel_a) & free_b],
        False)
    # reach[x]: x is valid or some longer id starting with x's digits is (two more digits at most).
    children = 10 * np.arange(ID_LIMIT)[:, None] + np.arange(10)[None, :]
    children = np.where((children < ID_LIMIT) & (np.arange(ID_LIMIT)[:, None] > 0), children, ID_LIMIT)
    padded = lambda x: jnp.concatenate([x, jnp.zeros_like(x[:, :1])], axis=1)  # noqa: E731
    reach = valid
    for _ in range(2):
        reach = valid | jnp.any(padded(reach)[:, children], axis=2)
    return valid, reach


def advance(tables: Tables, rows: Rows, token: jax.Array, remaining: jax.Array) -> Rows:
    """The rows after writing ``token`` [B] (a stop token leaves a row where it is)."""
    del remaining  # the mask already kept room to finish; the row's own room counts down below
    column = tables.column_of[token]
    pair = jnp.where(column >= 0, tables.pair[rows.state, jnp.maximum(column, 0)], -1)
    events = tables.events[jnp.maximum(pair, 0)][:, None, :] * (pair >= 0)[:, None, None]
    before = rows.regs.at[:, OPENED].set(-1).at[:, PARENT_CLOSED].set(-1).at[:, B_CLOSED].set(-1)
    _, r = _run_events(events, before[:, None, :], rows.consts[:, None, :], rows.valid, rows.reach)
    regs = jnp.stack([x[:, 0] for x in r], axis=-1)
    state = jnp.where(pair >= 0, tables.next_state[jnp.maximum(pair, 0)], rows.state)
    # A parent written: the child and everything below it gain the parent and its ancestors.
    parent, child = regs[:, PARENT_CLOSED], rows.regs[:, K]
    ids = jnp.arange(ID_LIMIT)
    below_child = (ids[None, :] == child[:, None]) | _column(rows.anc, child)
    above = _row(rows.anc, parent) | (ids[None, :] == parent[:, None])
    anc = jnp.where((parent >= 0)[:, None, None], rows.anc | (below_child[:, :, None] & above[:, None, :]), rows.anc)
    # A relation written: its pair is taken for its type, both ways round.
    a, b = regs[:, REL_A], regs[:, B_CLOSED]
    bit = jnp.left_shift(1, jnp.clip(regs[:, TYPE], 0, N_TYPES - 1))[:, None, None]
    hit = ((ids[None, :, None] == a[:, None, None]) & (ids[None, None, :] == b[:, None, None])) | (
        (ids[None, :, None] == b[:, None, None]) & (ids[None, None, :] == a[:, None, None]))
    related = jnp.where((b >= 0)[:, None, None] & hit, rows.related | bit, rows.related)
    # A slot opened: its id sets, and whether it takes any part at all.
    opened = regs[:, OPENED]
    valid, reach = _slot_sets(opened, regs, rows.consts, anc, related)
    new_slot = (opened >= 0)[:, None]
    valid = jnp.where(new_slot, valid, rows.valid)
    reach = jnp.where(new_slot, reach, rows.reach)
    regs = regs.at[:, HAS_VALID].set(jnp.where(opened >= 0, jnp.any(valid[:, 1:], axis=1), regs[:, HAS_VALID]))
    return Rows(state, regs, rows.consts, anc, valid, reach, related, rows.left - 1)
