"""Part-program masks on the device: which tokens each row may write next, and the step.

Per row the device keeps the automaton state, a few registers (the function being called, its
positional count and the parameters given, the part count, the part id being read, the length
of the name being read), the 32-bit hash of that name, and two sorted tables: the hashes of the
names bound so far and of all their prefixes. A name is offered byte run by byte run only while
it is a prefix of a bound name (or of a keyword of the function), so a reference never ends up
unbound; a keyword must be a parameter of the function not given yet.

Each (state, token) pair of the lifted table also carries how the token changes the name hash
(an affine map ``h -> h * m + a`` mod 2^32, and the same at each of its events), so a whole
vocabulary is checked with a few gathers and sorted-table searches. Hashes can collide: a name
that was never bound passes only if its 32-bit hash equals a bound one's (about 2^-32 per name).

Termination: ``grammar.close_costs`` gives, per state, the bytes to a complete program (at least
one part); a token is allowed only while that cost, plus what the name or part id being read
still needs, fits the tokens left (every byte is a token, so a byte count bounds the tokens).
"""

from __future__ import annotations

import functools
from typing import NamedTuple, Sequence

import jax
import jax.numpy as jnp
import numpy as np

from jax3dc.constrained import program_grammar as g
from jax3dc.constrained.automaton import TokenTable, lift, token_bytes

MAX_EVENTS = 6
MAX_TOKEN_BYTES = 24
BOUND_MAX = 256  # names bound (rebinding counts again)
PREFIX_MAX = 4096  # their prefixes
SENTINEL = 0xFFFFFFFF
UNLIMITED = 1 << 30  # a row given no room of its own
DEF_START_BIT = 1 << 30
KEY_MIX = 0x9E3779B1  # (function + 1) * KEY_MIX xor a prefix hash: one sorted table for all functions
# Registers.
FUNC, POS, FILLED, KWPHASE, CUR, PARTS, NUM, NBOUND, NPREFIX, IDLEN, DEFLEN = range(11)
N_REGS = 11


class Tables(NamedTuple):
    """The lifted program grammar on the device."""

    columns: jax.Array  # [U] int32
    column_of: jax.Array  # [V] int32
    pair: jax.Array  # [S, U] int32
    next_state: jax.Array  # [P] int32
    events: jax.Array  # [P, E] int32
    snap_mul: jax.Array  # [P, E] uint32: the name hash at each event is h * snap_mul + snap_add
    snap_add: jax.Array  # [P, E] uint32
    end_mul: jax.Array  # [P] uint32: the name hash after the token
    end_add: jax.Array  # [P] uint32
    name_bytes: jax.Array  # [P] int32: bytes of the name in progress read by the token
    name_reset: jax.Array  # [P] bool: that name starts inside the token
    def_bits: jax.Array  # [P] int32: bit j: byte j belongs to an assigned name; DEF_START_BIT: it starts here
    token_bytes: jax.Array  # [V, MAX_TOKEN_BYTES] int32
    segment: jax.Array  # [S] int32 (grammar.SEG_*)
    id_digits: jax.Array  # [S] int32: part-id digits written, -1 elsewhere
    close: jax.Array  # [S, 2, 2] int32
    accept: jax.Array  # [S] bool
    kinds: jax.Array  # [F, K + 1] int32: kinds of positional parameter j; column npos[f]: *args
    npos: jax.Array  # [F] int32
    keyword_hash: jax.Array  # [F, K] uint32 (SENTINEL past npos)
    keyword_prefix: jax.Array  # [Q] uint32, sorted: keyword prefix hashes mixed with their function
    keyword_prefix_bits: jax.Array  # [Q] int32: parameters having that prefix
    reserved: jax.Array  # [R] uint32, sorted
    stop_ids: jax.Array  # [2] int32


class Rows(NamedTuple):
    """Per-row grammar state."""

    state: jax.Array  # [B] int32
    regs: jax.Array  # [B, N_REGS] int32
    hash: jax.Array  # [B] uint32: the name being read
    bound: jax.Array  # [B, BOUND_MAX] uint32, sorted, SENTINEL-padded
    prefixes: jax.Array  # [B, PREFIX_MAX] uint32, sorted, SENTINEL-padded
    pending: jax.Array  # [B, IDMAX] uint32: prefix hashes of the name being assigned
    left: jax.Array  # [B] int32: tokens this row may still write (its room, counted down)


def _hash_walk(auto: g.ProgramAutomaton, table: TokenTable, tokens: list[bytes | None]) -> dict[str, np.ndarray]:
    """Per pair of ``table``: the affine name-hash maps (at each event and at the end), the
    name bytes read, and which bytes belong to an assigned name (bit 30: one starts here); and
    which pairs to drop (a token holding two assigned names, or one before a DEF_COMMIT: rare
    tokens whose order the step does not follow)."""
    n_states = len(auto.edges)
    ops = np.zeros((n_states + 1, 256), np.int8)
    n_events = np.zeros((n_states + 1, 256), np.int8)
    commits = np.zeros((n_states + 1, 256), bool)
    step = np.full((n_states + 1, 256), n_states, np.int32)
    for s, edges in enumerate(auto.edges):
        for byte, (t, events) in edges.items():
            step[s, byte] = t
            n_events[s, byte] = len(events)
            commits[s, byte] = any(e >> 8 == g.DEF_COMMIT for e in events)
    for (s, byte), op in auto.ops.items():
        ops[s, byte] = op
    s_idx, c_idx = np.nonzero(table.pair >= 0)
    order = table.pair[s_idx, c_idx]
    s_idx, c_idx = s_idx[np.argsort(order)], c_idx[np.argsort(order)]  # pair index order
    ids = table.columns[c_idx]
    count = len(ids)
    data = np.zeros((count, MAX_TOKEN_BYTES), np.int64)
    lengths = np.zeros(count, np.int32)
    by_token = {}
    for i in np.unique(ids):
        by_token[int(i)] = np.frombuffer(tokens[i], np.uint8)
    for j, i in enumerate(ids):
        t = by_token[int(i)]
        data[j, :len(t)] = t
        lengths[j] = len(t)
    mask32 = np.uint64(0xFFFFFFFF)
    mul = np.ones(count, np.uint64)
    add = np.zeros(count, np.uint64)
    snap_mul = np.zeros((count, MAX_EVENTS), np.uint64)
    snap_add = np.zeros((count, MAX_EVENTS), np.uint64)
    used = np.zeros(count, np.int32)
    name_bytes = np.zeros(count, np.int32)
    reset = np.zeros(count, bool)
    def_bits = np.zeros(count, np.int64)
    def_starts = np.zeros(count, np.int32)
    drop = np.zeros(count, bool)
    cur = s_idx.astype(np.int32)
    rows = np.arange(count)
    for pos in range(MAX_TOKEN_BYTES):
        active = pos < lengths
        byte = data[:, pos]
        op = np.where(active, ops[cur, byte], g.OP_NONE)
        start = (op == g.OP_START) | (op == g.OP_DEF_START)
        char = (op == g.OP_CHAR) | (op == g.OP_DEF_CHAR)
        is_def = (op == g.OP_DEF_START) | (op == g.OP_DEF_CHAR)
        b1 = (byte + 1).astype(np.uint64)
        mul = np.where(start, 0, np.where(char, (mul * g.HASH_MUL) & mask32, mul)).astype(np.uint64)
        add = np.where(start, (g.HASH_START * g.HASH_MUL + b1) & mask32,
                       np.where(char, (add * g.HASH_MUL + b1) & mask32, add)).astype(np.uint64)
        name_bytes = np.where(start, 1, name_bytes + char)
        reset |= start
        drop |= active & commits[cur, byte] & (def_bits != 0)
        def_starts += op == g.OP_DEF_START
        def_bits |= np.where(is_def, 1 << pos, 0) | np.where(op == g.OP_DEF_START, DEF_START_BIT, 0)
        k = np.where(active, n_events[cur, byte], 0)
        for e in range(int(k.max()) if count else 0):
            has = k > e
            slot = np.minimum(used + e, MAX_EVENTS - 1)
            snap_mul[rows[has], slot[has]] = mul[has]
            snap_add[rows[has], slot[has]] = add[has]
        used += k
        cur = np.where(active, step[cur, byte], cur)
    drop |= def_starts > 1
    return dict(snap_mul=snap_mul.astype(np.uint32), snap_add=snap_add.astype(np.uint32), end_mul=mul.astype(np.uint32),
                end_add=add.astype(np.uint32), name_bytes=name_bytes, name_reset=reset,
                def_bits=def_bits.astype(np.int32), drop=drop, pairs=(s_idx, c_idx))


def _function_tables() -> dict[str, np.ndarray]:
    funcs = g.functions()
    width = max(len(f.params) for f in funcs)
    kinds = np.zeros((len(funcs), width + 1), np.int32)
    npos = np.zeros(len(funcs), np.int32)
    kw = np.full((len(funcs), width), SENTINEL, np.uint32)
    table: dict[int, int] = {}
    for i, f in enumerate(funcs):
        npos[i] = len(f.params)
        kinds[i, :len(f.params)] = f.kinds
        kinds[i, len(f.params)] = f.varargs
        for j, name in enumerate(f.params):
            kw[i, j] = g.name_hash(name)
            for k in range(1, len(name) + 1):
                key = g.name_hash(name[:k]) ^ (((i + 1) * KEY_MIX) & 0xFFFFFFFF)
                table[key] = table.get(key, 0) | (1 << j)
    keys = sorted(table)
    pre = np.asarray(keys, np.uint32)
    bits = np.asarray([table[k] for k in keys], np.int32)
    reserved = np.asarray(sorted(g.name_hash(w) for w in g.reserved_words()), np.uint32)
    return dict(kinds=kinds, npos=npos, keyword_hash=kw, keyword_prefix=pre, keyword_prefix_bits=bits, reserved=reserved)


@functools.lru_cache(maxsize=4)
def program_tables(tokenizer, vocab_size: int) -> Tables:
    """The program grammar lifted to ``tokenizer``, as device arrays (cached per tokenizer)."""
    auto = g.program_automaton()
    tokens = token_bytes(tokenizer)[:vocab_size]
    table = lift(auto, tokens, MAX_EVENTS, MAX_TOKEN_BYTES)
    walk = _hash_walk(auto, table, tokens)
    pair = table.pair.copy()
    s_idx, c_idx = walk["pairs"]
    pair[s_idx[walk["drop"]], c_idx[walk["drop"]]] = -1
    column_of = np.full(vocab_size, -1, np.int32)
    column_of[table.columns] = np.arange(len(table.columns), dtype=np.int32)
    n_states = len(auto.edges)
    segment = np.zeros(n_states, np.int32)
    for s, cls in auto.segment.items():
        segment[s] = cls
    id_digits = np.full(n_states, -1, np.int32)
    for s, k in auto.id_digits.items():
        id_digits[s] = k
    raw = np.zeros((vocab_size, MAX_TOKEN_BYTES), np.int32)
    for i, t in enumerate(tokens):
        if t is not None and len(t) <= MAX_TOKEN_BYTES:
            raw[i, :len(t)] = np.frombuffer(t, np.uint8)
    funcs = _function_tables()
    host = Tables(
        columns=table.columns, column_of=column_of, pair=pair, next_state=table.next_state, events=table.events,
        snap_mul=walk["snap_mul"], snap_add=walk["snap_add"], end_mul=walk["end_mul"], end_add=walk["end_add"],
        name_bytes=walk["name_bytes"], name_reset=walk["name_reset"], def_bits=walk["def_bits"], token_bytes=raw,
        segment=segment, id_digits=id_digits, close=g.close_costs(auto), accept=table.accept,
        stop_ids=np.asarray(tokenizer.special.stop_ids, np.int32), **funcs)
    return Tables(*(jnp.asarray(x) for x in host))


def initial_rows(batch: int, room: Sequence[int] | None = None) -> Rows:
    """Rows at the program's start (nothing bound, no part); ``room[i]``: the most tokens row i
    may write, its stop token included (None: only the decode's own ``max_new_tokens``)."""
    regs = np.zeros((batch, N_REGS), np.int32)
    regs[:, FUNC] = -1
    left = np.full(batch, UNLIMITED, np.int32) if room is None else np.asarray(room, np.int32)
    return Rows(jnp.zeros((batch,), jnp.int32), jnp.asarray(regs), jnp.zeros((batch,), jnp.uint32),
                jnp.full((batch, BOUND_MAX), SENTINEL, jnp.uint32), jnp.full((batch, PREFIX_MAX), SENTINEL, jnp.uint32),
                jnp.zeros((batch, g.IDMAX), jnp.uint32), jnp.asarray(left))


def _left(rows: Rows, remaining: jax.Array) -> jax.Array:
    """[B, 1]: tokens left, this one included: the decode's count capped by the row's room."""
    return jnp.minimum(jnp.asarray(remaining, jnp.int32).reshape(-1), rows.left)[:, None]


def _member(table: jax.Array, query: jax.Array) -> jax.Array:
    """query [B, X] in the row's sorted table [B, T]."""
    idx = jax.vmap(lambda t, q: jnp.searchsorted(t, q))(table, query)
    found = jnp.take_along_axis(table, jnp.clip(idx, 0, table.shape[1] - 1), axis=1)
    return (found == query) & (query != np.uint32(SENTINEL))


def _digits(x: jax.Array) -> jax.Array:
    return 1 + (x >= 10) + (x >= 100)


def _run(tables: Tables, rows: Rows, pair: jax.Array, remaining: jax.Array) -> tuple[jax.Array, list[jax.Array]]:
    """Check and apply the events of the pairs ``pair [B, X]`` (-1: not writable); returns
    (ok [B, X], registers after, each [B, X]). ``remaining [B, 1]``: tokens left, this one included."""
    p = jnp.maximum(pair, 0)
    events = tables.events[p]
    h = rows.hash[:, None]
    r = [jnp.broadcast_to(rows.regs[:, i:i + 1], pair.shape) for i in range(N_REGS)]
    ok = pair >= 0
    fn = jnp.clip(r[FUNC], 0, tables.npos.shape[0] - 1)
    for e in range(events.shape[2]):
        code = events[..., e]
        kind, arg = code >> 8, code & 255
        name = h * tables.snap_mul[p, e] + tables.snap_add[p, e]
        fn = jnp.clip(r[FUNC], 0, tables.npos.shape[0] - 1)
        npos = tables.npos[fn]
        slot = jnp.minimum(r[POS], npos)
        pos_kinds = tables.kinds[fn, slot]
        cur_kinds = tables.kinds[fn, jnp.clip(r[CUR], 0, tables.kinds.shape[1] - 1)]
        bound = _member(rows.bound, name)
        positional = (r[KWPHASE] == 0) & (pos_kinds != 0)
        kw_match = (tables.keyword_hash[fn] == name[..., None])  # [B, X, K]
        kw_index = jnp.argmax(kw_match, axis=-1)
        kw_free = jnp.any(kw_match, axis=-1) & (((r[FILLED] >> kw_index) & 1) == 0)
        found = tables.reserved[jnp.clip(jnp.searchsorted(tables.reserved, name), 0, tables.reserved.shape[0] - 1)]
        reserved = found == name
        target = r[PARTS] + 1
        num = r[NUM] * 10 + arg
        tens = 10 ** jnp.clip(_digits(target) - _digits(num), 0, 2)
        checks = {
            g.POSVAL: positional & ((pos_kinds & arg) != 0),
            g.KWVAL: (cur_kinds & arg) != 0,
            g.KW_END: kw_free,
            g.REF_END: bound,
            g.REF_POS_END: bound & positional & ((pos_kinds & g.REF) != 0),
            g.DEF_END: ~reserved,
            g.DEF_ROOM: (r[NBOUND] < BOUND_MAX) & (r[NPREFIX] + g.IDMAX <= PREFIX_MAX),
            g.NEED_BOUND: r[NBOUND] > 0,
            g.PART_OPEN: (r[NBOUND] > 0) & (target <= 999),
            g.PDIGIT: (_digits(num) <= _digits(target)) & (target // tens == num),
            g.PID_END: r[NUM] == target,
        }
        for k, check in checks.items():
            ok = ok & ((kind != k) | check)
        advance_pos = (kind == g.POSVAL) | (kind == g.REF_POS_END)
        filled_pos = advance_pos & (r[POS] < npos)
        r[FILLED] = jnp.where(filled_pos, r[FILLED] | (1 << jnp.clip(r[POS], 0, 30)), r[FILLED])
        r[FILLED] = jnp.where(kind == g.KW_END, r[FILLED] | (1 << kw_index), r[FILLED])
        r[CUR] = jnp.where(kind == g.KW_END, kw_index, r[CUR])
        r[KWPHASE] = jnp.where(kind == g.KW_END, 1, r[KWPHASE])
        r[POS] = r[POS] + advance_pos
        opening = kind == g.CALL
        r[FUNC] = jnp.where(opening, arg, r[FUNC])
        for i in (POS, FILLED, KWPHASE):
            r[i] = jnp.where(opening, 0, r[i])
        r[NUM] = jnp.where(kind == g.PDIGIT, num, jnp.where(kind == g.PART_OPEN, 0, r[NUM]))
        r[PARTS] = r[PARTS] + (kind == g.PART_COMMIT)
        commit = kind == g.DEF_COMMIT
        r[NBOUND] = r[NBOUND] + commit
        r[NPREFIX] = r[NPREFIX] + jnp.where(commit, r[DEFLEN], 0)
    # The name in progress after the token: it must still lead somewhere.
    nxt = tables.next_state[p]
    segment = tables.segment[nxt]
    length = jnp.where(tables.name_reset[p], tables.name_bytes[p], r[IDLEN] + tables.name_bytes[p])
    r[IDLEN] = jnp.where(segment != g.SEG_NONE, length, 0)
    bits = tables.def_bits[p]
    count = jax.lax.population_count(bits & (DEF_START_BIT - 1))
    r[DEFLEN] = jnp.where(count > 0, jnp.where((bits & DEF_START_BIT) != 0, count, r[DEFLEN] + count), r[DEFLEN])
    name = h * tables.end_mul[p] + tables.end_add[p]
    fn = jnp.clip(r[FUNC], 0, tables.npos.shape[0] - 1)
    slot = jnp.minimum(r[POS], tables.npos[fn])
    ref_here = (r[KWPHASE] == 0) & ((tables.kinds[fn, slot] & g.REF) != 0)
    prefix_of_bound = _member(rows.prefixes, name)
    key = name ^ ((fn + 1).astype(jnp.uint32) * jnp.uint32(KEY_MIX))
    at = jnp.clip(jnp.searchsorted(tables.keyword_prefix, key), 0, tables.keyword_prefix.shape[0] - 1)
    kw_prefix = (tables.keyword_prefix[at] == key) & ((tables.keyword_prefix_bits[at] & ~r[FILLED]) != 0)
    leads = jnp.select([segment == g.SEG_REF, segment == g.SEG_ARG],
                       [prefix_of_bound, (prefix_of_bound & ref_here) | kw_prefix], True)
    ok = ok & leads & (r[IDLEN] <= g.IDMAX)
    # Room to finish.
    digits = tables.id_digits[nxt]
    cost = (tables.close[nxt, (r[NBOUND] > 0).astype(jnp.int32), (r[PARTS] > 0).astype(jnp.int32)]
            + jnp.where(segment != g.SEG_NONE, g.IDMAX - r[IDLEN], 0)
            + jnp.where(digits >= 0, _digits(r[PARTS] + 1) - jnp.maximum(digits, 1), 0))
    ok = ok & (cost <= remaining - 2)
    return ok, r


def allowed(tables: Tables, rows: Rows, remaining: jax.Array) -> jax.Array:
    """[B, V] bool: tokens each row may write now; ``remaining``: tokens left, this one included.
    Stop tokens where the program is complete (a line ended, a part written), or as a last resort
    where nothing else is allowed."""
    pair = tables.pair[rows.state]
    mask, _ = _run(tables, rows, pair, _left(rows, remaining))
    batch, vocab = mask.shape[0], tables.column_of.shape[0]
    stop = jnp.zeros((batch, vocab), bool).at[:, tables.stop_ids].set(True)
    may_stop = (tables.accept[rows.state] & (rows.regs[:, PARTS] > 0)) | ~jnp.any(mask, axis=1)
    full = jnp.zeros((batch, vocab), bool).at[:, tables.columns].set(mask)
    return full | (stop & may_stop[:, None])


def advance(tables: Tables, rows: Rows, token: jax.Array, remaining: jax.Array) -> Rows:
    """The rows after writing ``token`` [B] (a stop token leaves a row where it is)."""
    column = tables.column_of[token]
    pair = jnp.where(column >= 0, tables.pair[rows.state, jnp.maximum(column, 0)], -1)[:, None]
    _, r = _run(tables, rows, pair, _left(rows, remaining))
    written = pair[:, 0] >= 0
    p = jnp.maximum(pair[:, 0], 0)
    regs = jnp.where(written[:, None], jnp.stack([x[:, 0] for x in r], axis=-1), rows.regs)
    state = jnp.where(written, tables.next_state[p], rows.state)
    name = jnp.where(written, rows.hash * tables.end_mul[p] + tables.end_add[p], rows.hash)
    # A binding at this token's newline: the assigned name (before this token's bytes) and its prefixes.
    commit = written & jnp.any((tables.events[p] >> 8) == g.DEF_COMMIT, axis=1)
    deflen = rows.regs[:, DEFLEN]
    slots = jnp.arange(g.IDMAX)[None, :]

    def bind(tables_):
        bound, prefixes = tables_
        last = jnp.take_along_axis(rows.pending, jnp.clip(deflen - 1, 0, g.IDMAX - 1)[:, None], axis=1)[:, 0]
        at = jnp.clip(rows.regs[:, NBOUND], 0, BOUND_MAX - 1)
        bound = bound.at[jnp.arange(bound.shape[0]), at].set(jnp.where(commit, last, bound[jnp.arange(bound.shape[0]), at]))
        where = jnp.clip(rows.regs[:, NPREFIX][:, None] + slots, 0, PREFIX_MAX - 1)
        keep = commit[:, None] & (slots < deflen[:, None])
        old = jnp.take_along_axis(prefixes, where, axis=1)
        prefixes = prefixes.at[jnp.arange(prefixes.shape[0])[:, None], where].set(jnp.where(keep, rows.pending, old))
        return jnp.sort(bound, axis=1), jnp.sort(prefixes, axis=1)

    bound, prefixes = jax.lax.cond(jnp.any(commit), bind, lambda x: x, (rows.bound, rows.prefixes))
    # Prefix hashes of the name being assigned, byte by byte.
    bits = jnp.where(written, tables.def_bits[p], 0)
    raw = tables.token_bytes[jnp.clip(token, 0, tables.token_bytes.shape[0] - 1)]
    reset = (bits & DEF_START_BIT) != 0
    pending, length = rows.pending, jnp.where(bits != 0, deflen, rows.regs[:, DEFLEN])
    first = jnp.ones_like(written)
    for j in range(MAX_TOKEN_BYTES):
        on = ((bits >> j) & 1) == 1
        restart = on & first & reset
        length = jnp.where(restart, 0, length)
        prev = jnp.take_along_axis(pending, jnp.clip(length - 1, 0, g.IDMAX - 1)[:, None], axis=1)[:, 0]
        prev = jnp.where(length > 0, prev, jnp.uint32(g.HASH_START))
        value = prev * jnp.uint32(g.HASH_MUL) + (raw[:, j] + 1).astype(jnp.uint32)
        at = jnp.clip(length, 0, g.IDMAX - 1)
        pending = pending.at[jnp.arange(pending.shape[0]), at].set(jnp.where(on, value, pending[jnp.arange(pending.shape[0]), at]))
        length = length + on
        first = first & ~on
    return Rows(state, regs, name, bound, prefixes, pending, rows.left - 1)
