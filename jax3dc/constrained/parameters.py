"""Parameter-text masks on the device: which tokens each row may write next, and the step.

The grammar (``parameters_grammar``) is a finite automaton without events, so a row's state is
one integer and a mask is one gather of the lifted table. Termination: a token is allowed only
while the bytes still needed to close the text after it (``close``, one token per byte at worst)
plus a stop token fit the tokens left; a stop token only where the text is complete (or, as a last
resort, where nothing else fits). So for any logits a row ends in a complete, parseable record
whenever the budget holds the category's longest text (``longest_text``); below that, a category
too long for the room left is never started.
"""

from __future__ import annotations

import functools
from typing import Mapping, NamedTuple

import jax
import jax.numpy as jnp
import numpy as np

from jax3dc.constrained.automaton import lift, token_bytes
from jax3dc.constrained.parameters_grammar import _pieces, close_costs, parameters_automaton, value_words
from jax3dc.parameters import Schema

MAX_TOKEN_BYTES = 24


class Tables(NamedTuple):
    """The lifted parameter grammar on the device."""

    columns: jax.Array  # [U] int32: token id of each column
    column_of: jax.Array  # [V] int32: column of each token id, -1 if none
    pair: jax.Array  # [S, U] int32: index into next_state, -1 where the token cannot be written
    next_state: jax.Array  # [P] int32
    close: jax.Array  # [S] int32: bytes to a complete text
    accept: jax.Array  # [S] bool
    stop_ids: jax.Array  # [2] int32


class Rows(NamedTuple):
    """Per-row grammar state: the automaton state alone."""

    state: jax.Array  # [B] int32


def _candidate_tokens(auto, tokens: list[bytes | None]) -> list[bytes | None]:
    """Tokens that could be written somewhere: every byte pair inside one follows an edge pair of
    the automaton (exact: a written token walks such edges). Cuts Qwen's 151k ids to ~18k before
    the lift, which walks every kept token from every state."""
    follows = {(b1, b2) for edges in auto.edges for b1, (t, _) in edges.items() for b2 in auto.edges[t]}
    alphabet = {b for edges in auto.edges for b in edges}
    return [t if t is not None and t[0] in alphabet and all(p in follows for p in zip(t, t[1:])) else None
            for t in tokens]


def _key(schemas: Mapping[str, Schema]) -> tuple:
    return tuple(sorted(schemas.items()))


@functools.lru_cache(maxsize=4)
def _tables(schema_key: tuple, tokenizer, vocab_size: int) -> Tables:
    auto = parameters_automaton(dict(schema_key))
    tokens = _candidate_tokens(auto, token_bytes(tokenizer)[:vocab_size])
    table = lift(auto, tokens, 1, MAX_TOKEN_BYTES)
    column_of = np.full(vocab_size, -1, np.int32)
    column_of[table.columns] = np.arange(len(table.columns), dtype=np.int32)
    host = (table.columns, column_of, table.pair, table.next_state, close_costs(auto), table.accept,
            np.asarray(tokenizer.special.stop_ids, np.int32))
    return Tables(*(jnp.asarray(x) for x in host))


def parameters_tables(schemas: Mapping[str, Schema], tokenizer, vocab_size: int) -> Tables:
    """The grammar of ``schemas`` lifted to ``tokenizer``, as device arrays (cached per schemas and
    tokenizer: Qwen3's vocabulary takes about a minute on two CPU cores, the project's BPE seconds)."""
    return _tables(_key(schemas), tokenizer, vocab_size)


def longest_text(schemas: Mapping[str, Schema]) -> int:
    """Bytes of the longest text any record of ``schemas`` can have: a token budget this large
    never cuts a row short."""
    longest = 0
    for schema in schemas.values():
        pieces = _pieces(schema)
        longest = max(longest, sum(len(p) if isinstance(p, str) else max(map(len, value_words(p))) for p in pieces))
    return longest


def initial_rows(batch: int) -> Rows:
    return Rows(jnp.zeros((batch,), jnp.int32))


def _fits(tables: Tables, pair: jax.Array, remaining: jax.Array) -> jax.Array:
    """pair [B, X] writable and its close cost, plus a stop, within ``remaining - 1`` tokens."""
    after = tables.close[tables.next_state[jnp.maximum(pair, 0)]]
    return (pair >= 0) & (after + 1 <= remaining - 1)


def allowed(tables: Tables, rows: Rows, remaining: jax.Array) -> jax.Array:
    """[B, V] bool: tokens each row may write now; ``remaining``: tokens left, this one included."""
    pair = tables.pair[rows.state]
    left = jnp.broadcast_to(jnp.asarray(remaining, jnp.int32).reshape(-1, 1), pair.shape[:1] + (1,))
    mask = _fits(tables, pair, left)
    batch, vocab = mask.shape[0], tables.column_of.shape[0]
    full = jnp.zeros((batch, vocab), bool).at[:, tables.columns].set(mask)
    may_stop = tables.accept[rows.state] | ~jnp.any(mask, axis=1)
    stop = jnp.zeros((batch, vocab), bool).at[:, tables.stop_ids].set(True)
    return full | (stop & may_stop[:, None])


def advance(tables: Tables, rows: Rows, token: jax.Array, remaining: jax.Array) -> Rows:
    """The rows after writing ``token`` [B] (a stop or pad token leaves a row where it is)."""
    del remaining  # the state alone decides; kept for the decode loop's common signature
    column = tables.column_of[token]
    pair = jnp.where(column >= 0, tables.pair[rows.state, jnp.maximum(column, 0)], -1)
    state = jnp.where(pair >= 0, tables.next_state[jnp.maximum(pair, 0)], rows.state)
    return Rows(state)
