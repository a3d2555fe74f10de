"""Structure-grammar masks on the device: which tokens each row may write next, and the step.

Per row the device keeps the automaton state and a few registers (the node being written, joints
and materials so far, the id being read), the ancestor matrix of the parents written so far (so
a parent that would close a cycle is never offered) and, for the id slot being read, the set of
ids it may take and the prefixes that still lead to one (``reach``: digit by digit, ids of any
length). A step is a handful of gathers and elementwise ops over ``[rows, vocab]``; nothing
leaves the device.

Guarantees, for any logits: every document ends in a state the validator accepts, with exactly
the prompt's part ids; its joint count is the prompt's ``Joints:`` line (capped at N - 1: one
part at least is a root). The count is kept reachable by a capacity argument: every part before
the last can always take a joint (the last part, not yet written, is a parent that closes no
cycle), and the last part can when some earlier part is a root (nothing hangs it below the last);
so a part may stay without a joint only while the joints still owed fit that capacity. Optional
content (another material, a relation, a joint when the count is unknown) is opened only while
the token budget keeps room to finish, counted in the tokenizer's own tokens of each piece.
"""

from __future__ import annotations

import functools
from dataclasses import dataclass
from typing import NamedTuple

import jax
import jax.numpy as jnp
import numpy as np

from jax3dc.constrained import structure_grammar as g
from jax3dc.constrained.automaton import lift, token_bytes

ID_LIMIT = 128  # ids 0..127 (the largest training object has 30 parts)
MAX_EVENTS = 6
MATERIALS_MAX = 16
RELATIONS_MAX = 64
# Registers.
K, JOINTS, MATERIALS, RELATIONS, NUM, REL_A, HAS_VALID, PARENT_CLOSED, OPENED, ROOTS = range(10)
N_REGS = 10


@dataclass(frozen=True)
class Budget:
    """Tokens (of this tokenizer, canonical spelling, longest numbers) of each piece."""

    node: int
    joint: int
    material: int
    relation: int
    end: int

    @classmethod
    def of(cls, tokenizer) -> "Budget":
        count = lambda s: len(tokenizer.encode(s))  # noqa: E731
        number = "-0.577"
        return cls(
            node=count(',"127":{"parent":126,"material":15}'),
            joint=count(f',"joint":{{"type":"hinge","axis":[{number},{number},{number}],"pivot":[{number},{number},{number}],'
                        f'"range":[{number},{number}]}}'),
            material=count(',"15":{"family":"Leather","desc":"' + "brushed stainless steel with a satin" + '"}'),
            relation=count(',{"type":"symmetric","a":127,"b":126,"plane":"xy"}'),
            end=count('}},"relations":[]}') + 1,
        )


class Tables(NamedTuple):
    """The lifted grammar on the device (see ``automaton.TokenTable``) and the budget counts."""

    columns: jax.Array  # [U] int32: the token id of each column
    column_of: jax.Array  # [V] int32: each token's column, -1 for tokens the grammar never writes
    pair: jax.Array  # [S, U] int32
    next_state: jax.Array  # [P] int32
    events: jax.Array  # [P, E] int32
    accept: jax.Array  # [S] bool
    stop_ids: jax.Array  # [2] int32
    budget: jax.Array  # [5] int32: node, joint, material, relation, end


class Rows(NamedTuple):
    """Per-row grammar state."""

    state: jax.Array  # [B] int32
    regs: jax.Array  # [B, N_REGS] int32
    consts: jax.Array  # [B, 2] int32: part count N, joint count J (-1: not given)
    anc: jax.Array  # [B, ID_LIMIT, ID_LIMIT] bool: anc[x, y] = y is an ancestor of x
    valid: jax.Array  # [B, ID_LIMIT] bool: ids the open slot takes
    reach: jax.Array  # [B, ID_LIMIT] bool: digit prefixes that lead to one


@functools.lru_cache(maxsize=4)
def structure_tables(tokenizer, vocab_size: int) -> Tables:
    """The grammar lifted to ``tokenizer``, as device arrays; cached per tokenizer object, so every
    batch of a run reuses one copy (Qwen3's vocabulary takes 46 s to lift and 370 MB)."""
    table = lift(g.structure_automaton(), token_bytes(tokenizer)[:vocab_size], MAX_EVENTS)
    column_of = np.full(vocab_size, -1, np.int32)  # the model's embedding may be padded past the tokenizer
    column_of[table.columns] = np.arange(len(table.columns), dtype=np.int32)
    budget = Budget.of(tokenizer)
    host = (table.columns, column_of, table.pair, table.next_state, table.events, table.accept,
            np.asarray(tokenizer.special.stop_ids, np.int32),
            np.asarray([budget.node, budget.joint, budget.material, budget.relation, budget.end], np.int32))
    return Tables(*(jnp.asarray(x) for x in host))


def initial_rows(part_counts, joint_counts) -> Rows:
    """Rows at the document start; ``joint_counts[i]`` is -1 where the prompt gives no count."""
    n = np.asarray(part_counts, np.int32)
    if n.min() < 1 or n.max() >= ID_LIMIT:
        raise ValueError(f"constrained decoding takes 1 to {ID_LIMIT - 1} parts, got {int(n.min())}..{int(n.max())}")
    batch = len(n)
    regs = np.zeros((batch, N_REGS), np.int32)
    regs[:, K] = 1
    regs[:, OPENED] = -1
    joints = np.asarray(joint_counts, np.int32)
    consts = np.stack([n, np.where(joints >= 0, np.minimum(joints, n - 1), -1)], axis=1)
    return Rows(jnp.zeros((batch,), jnp.int32), jnp.asarray(regs), jnp.asarray(consts),
                jnp.zeros((batch, ID_LIMIT, ID_LIMIT), bool), jnp.zeros((batch, ID_LIMIT), bool),
                jnp.zeros((batch, ID_LIMIT), bool))


def _run_events(events: jax.Array, regs: jax.Array, consts: jax.Array, valid: jax.Array, reach: jax.Array,
                remaining: jax.Array, budget: jax.Array) -> tuple[jax.Array, jax.Array]:
    """Check and apply each token's events in order. Shapes: events [B, X, E], regs [B, X, R]
    (X: candidate tokens, or 1), consts [B, 1, 2], valid / reach [B, ID_LIMIT], remaining [B, 1]
    (tokens left after this one). Returns (ok [B, X], regs after)."""
    n, j = consts[..., 0], consts[..., 1]
    ok = jnp.ones(events.shape[:2], bool)
    stale = jnp.zeros(events.shape[:2], bool)  # a slot opened inside this token: its id sets are not built yet
    r = [regs[..., i] for i in range(N_REGS)]

    def lookup(table, index):  # table [B, L] at index [B, X]
        return jnp.take_along_axis(table, jnp.clip(index, 0, ID_LIMIT - 1), axis=1) & (index < ID_LIMIT) & (index >= 0)

    def room(item):
        need = budget[item] + (n - r[K] + 1).clip(0) * budget[0] + jnp.where(j >= 0, (j - r[JOINTS]).clip(0), 0) * budget[1] + budget[4]
        return need <= remaining

    for e in range(events.shape[2]):
        code = events[..., e]
        kind, arg = code >> 8, code & 255
        digit = r[NUM] * 10 + arg
        owed = j - r[JOINTS]
        last = r[K] >= n
        cap_root = jnp.where(last, 0, n - r[K])  # joints the later parts surely take if this one is a root
        cap_rigid = jnp.where(last, 0, n - 1 - r[K] + (r[ROOTS] >= 1))  # ... if it hangs below a parent
        checks = {
            g.DIGIT: ~stale & lookup(reach, digit),
            g.SLOT_CLOSE: ~stale & lookup(valid, r[NUM]),
            g.PARENT_NULL: ~stale & ((j < 0) | (owed <= cap_root) | (r[HAS_VALID] == 0)),
            g.JOINT_OPEN: jnp.where(j >= 0, r[JOINTS] < j, room(1)),
            g.NODE_CLOSE: (arg != g.CLOSE_RIGID) | (j < 0) | (owed <= cap_rigid),
            g.NODES_MORE: r[K] <= n,
            g.NODES_END: r[K] > n,
            g.MATERIAL_MORE: (r[MATERIALS] < MATERIALS_MAX) & room(2),
            g.RELATION_OPEN: (n >= 2) & (r[RELATIONS] < jnp.minimum(2 * n, RELATIONS_MAX)) & room(3),
        }
        for k, check in checks.items():
            ok = ok & ((kind != k) | check)
        opening = kind == g.SLOT_OPEN
        closing = kind == g.SLOT_CLOSE
        r[NUM] = jnp.where(kind == g.DIGIT, digit, jnp.where(opening, 0, r[NUM]))
        r[OPENED] = jnp.where(opening, arg, r[OPENED])
        r[MATERIALS] = r[MATERIALS] + (closing & (arg == g.MATERIAL_KEY))
        r[REL_A] = jnp.where(closing & (arg == g.RELATION_A), r[NUM], r[REL_A])
        r[PARENT_CLOSED] = jnp.where(closing & (arg == g.PARENT), r[NUM], r[PARENT_CLOSED])
        r[JOINTS] = r[JOINTS] + (kind == g.JOINT_OPEN)
        r[K] = r[K] + (kind == g.NODE_CLOSE)
        r[ROOTS] = r[ROOTS] + ((kind == g.NODE_CLOSE) & (arg == g.CLOSE_ROOT))
        r[RELATIONS] = r[RELATIONS] + (kind == g.RELATION_OPEN)
        stale = stale | opening
    return ok, jnp.stack(r, axis=-1)


def allowed(tables: Tables, rows: Rows, remaining: jax.Array) -> jax.Array:
    """[B, V] bool: tokens each row may write now; ``remaining``: tokens left, this one included.
    Stop tokens only where the document is complete (and, as a last resort, where nothing else is)."""
    pair = tables.pair[rows.state]  # [B, U]
    events = tables.events[jnp.maximum(pair, 0)]  # [B, V, E]
    regs = jnp.broadcast_to(rows.regs[:, None, :], pair.shape + (N_REGS,))
    left = jnp.broadcast_to(jnp.asarray(remaining, jnp.int32).reshape(-1, 1) - 1, pair.shape[:1] + (1,))
    ok, _ = _run_events(events, regs, rows.consts[:, None, :], rows.valid, rows.reach, left, tables.budget)
    mask = (pair >= 0) & ok
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


def _slot_sets(role: jax.Array, regs: jax.Array, consts: jax.Array, anc: jax.Array) -> tuple[jax.Array, jax.Array]:
    """(valid, reach) [B, ID_LIMIT] for the slot each row just opened."""
    v = jnp.arange(ID_LIMIT)[None, :]
    k, mats, rel_a = regs[:, K:K + 1], regs[:, MATERIALS:MATERIALS + 1], regs[:, REL_A:REL_A + 1]
    n = consts[:, 0:1]
    part = (v >= 1) & (v <= n)
    # anc[b, x, k]: k is an ancestor of x, i.e. x hangs below k; such an x as k's parent closes a cycle.
    under_k = _column(anc, k[:, 0])
    role = role[:, None]
    valid = jnp.select(
        [role == g.NODE_KEY, role == g.PARENT, role == g.MATERIAL_REF, role == g.MATERIAL_KEY,
         role == g.RELATION_A, role == g.RELATION_B],
        [v == k, part & (v != k) & ~under_k, v < mats, v == mats, part, part & (v != rel_a)],
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
    column = tables.column_of[token]
    pair = jnp.where(column >= 0, tables.pair[rows.state, jnp.maximum(column, 0)], -1)
    events = tables.events[jnp.maximum(pair, 0)][:, None, :] * (pair >= 0)[:, None, None]
    before = rows.regs.at[:, OPENED].set(-1).at[:, PARENT_CLOSED].set(-1)
    left = jnp.asarray(remaining, jnp.int32).reshape(-1, 1) - 1
    _, regs = _run_events(events, before[:, None, :], rows.consts[:, None, :], rows.valid, rows.reach, left, tables.budget)
    regs = regs[:, 0, :]
    state = jnp.where(pair >= 0, tables.next_state[jnp.maximum(pair, 0)], rows.state)
    # A parent written: the child and everything below it gain the parent and its ancestors.
    parent, child = regs[:, PARENT_CLOSED], rows.regs[:, K]
    ids = jnp.arange(ID_LIMIT)
    below_child = (ids[None, :] == child[:, None]) | _column(rows.anc, child)
    above = _row(rows.anc, parent) | (ids[None, :] == parent[:, None])
    anc = jnp.where((parent >= 0)[:, None, None], rows.anc | (below_child[:, :, None] & above[:, None, :]), rows.anc)
    # A slot opened: its id sets, and whether it takes any part at all.
    opened = regs[:, OPENED]
    valid, reach = _slot_sets(opened, regs, rows.consts, anc)
    new_slot = (opened >= 0)[:, None]
    valid = jnp.where(new_slot, valid, rows.valid)
    reach = jnp.where(new_slot, reach, rows.reach)
    regs = regs.at[:, HAS_VALID].set(jnp.where(opened >= 0, jnp.any(valid[:, 1:], axis=1), regs[:, HAS_VALID]))
    return Rows(state, regs, rows.consts, anc, valid, reach)
