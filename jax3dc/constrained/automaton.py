"""A character automaton with events, and its lifting to token tables that live on the device.

A grammar is written as a deterministic automaton over bytes whose edges may carry *events*
(small integer codes, e.g. "digit 3 of an id", "a node closes"). Events are where the grammar's
non-regular rules (ids of this prompt, no cycles, a joint count) are checked, against per-row
registers on the device (see ``jax3dc.constrained.structure``); the automaton itself holds only
what is regular.

``lift`` walks every token's bytes from every state once, on the host, and gives dense tables:
``pair[state, token]`` (an index into ``next_state`` / ``events``, -1 where the token cannot be
written), so a decode step needs one gather per row for its mask; nothing returns to the host.
Why not outlines-core / llguidance / xgrammar: the first compiles a regex into a token DFA, and
folding a prompt's part ids and joint count into a regex multiplies the states (measured with
outlines-core 0.2.14 on our BPE: 15,224 states for 8 parts and 3 joints, 140,008 for 12 and 4,
14 s to compile, acyclic parents not expressible at all); the other two compute each mask on the
CPU per token, a host round trip in every step of the jitted loop.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Iterable, Mapping, Sequence

import numpy as np

Events = tuple[int, ...]


@dataclass
class Automaton:
    """Deterministic byte automaton: ``edges[state][byte] = (target, events)``; ``accept``: states
    where the document is complete (only a stop token may follow)."""

    edges: list[dict[int, tuple[int, Events]]] = field(default_factory=lambda: [{}])
    accept: set[int] = field(default_factory=set)

    @property
    def start(self) -> int:
        return 0

    def new(self) -> int:
        self.edges.append({})
        return len(self.edges) - 1

    def edge(self, a: int, byte: int, b: int, events: Events = ()) -> None:
        """Add a -byte-> b; the same edge twice is fine, two different ones are a grammar bug."""
        old = self.edges[a].get(byte)
        if old is not None and old != (b, tuple(events)):
            raise ValueError(f"grammar is not deterministic at state {a}, byte {chr(byte)!r}: {old} vs {(b, events)}")
        self.edges[a][byte] = (b, tuple(events))

    def text(self, a: int, s: str, end: int | None = None, events: Mapping[int, Events] | None = None) -> int:
        """Spell ``s`` from ``a`` (reusing existing edges, so alternatives may share a prefix);
        ``end`` is the state the last byte goes to (a new one if None); ``events[i]`` rides on byte i."""
        data = s.encode()
        events = events or {}
        for i, byte in enumerate(data):
            ev = tuple(events.get(i, ()))
            last = i == len(data) - 1
            old = self.edges[a].get(byte)
            if last and end is not None:
                self.edge(a, byte, end, ev)
                a = end
            elif old is not None and old[1] == ev and not last:
                a = old[0]
            else:
                b = self.new()
                self.edge(a, byte, b, ev)
                a = b
        return a


def embed(auto: Automaton, entry: int, words: Iterable[tuple[str, int]], exits: Mapping[int, Mapping[int, tuple[int, Events]]],
          first_events: Events = (), byte_events: Mapping[int, Events] | None = None) -> None:
    """Add the finite language ``words`` (string, label) after ``entry``; a word with label L is
    followed by any edge of ``exits[L]`` (byte -> (target, events)).

    The trie of the words is minimised (states with the same label, exits and children are one),
    so e.g. every decimal number in [-9.999, 9.999] with 1 to 3 decimals takes a few dozen states.
    ``first_events`` ride on every first byte; ``byte_events[b]`` on every edge reading byte b.
    """
    byte_events = byte_events or {}
    trie: list[dict[int, int]] = [{}]
    label: list[int | None] = [None]
    for word, lab in words:
        node = 0
        for byte in word.encode():
            nxt = trie[node].get(byte)
            if nxt is None:
                trie.append({})
                label.append(None)
                nxt = trie[node][byte] = len(trie) - 1
            node = nxt
        if label[node] is not None and label[node] != lab:
            raise ValueError(f"word {word!r} has two labels")
        label[node] = lab
    # Minimise bottom up: a trie node's signature is its label and its children's classes.
    order = _postorder(trie)
    cls: dict[int, int] = {}
    signatures: dict[tuple, int] = {}
    for node in order:
        sig = (label[node], tuple(sorted((b, cls[c]) for b, c in trie[node].items())))
        cls[node] = signatures.setdefault(sig, len(signatures))
    states: dict[int, int] = {cls[0]: entry}
    done: set[int] = set()
    for node in reversed(order):  # root first
        c = cls[node]
        if c in done:
            continue
        done.add(c)
        here = states[c]
        for byte, child in trie[node].items():
            if cls[child] not in states:
                states[cls[child]] = auto.new()
            events = (first_events if node == 0 else ()) + tuple(byte_events.get(byte, ()))
            auto.edge(here, byte, states[cls[child]], events)
        if label[node] is not None:
            for byte, (target, events) in exits[label[node]].items():
                auto.edge(here, byte, target, events)


def _postorder(trie: list[dict[int, int]]) -> list[int]:
    out, stack = [], [(0, False)]
    while stack:
        node, expanded = stack.pop()
        if expanded:
            out.append(node)
            continue
        stack.append((node, True))
        stack.extend((c, False) for c in trie[node].values())
    return out


# ---- tokens ------------------------------------------------------------------------------------

def _byte_level_alphabet() -> dict[str, int]:
    """The byte-level BPE alphabet (GPT-2's, used by Qwen): each byte is shown as one printable
    character; printable Latin-1 bytes stand for themselves, the rest are shifted past 255."""
    shown = list(range(ord("!"), ord("~") + 1)) + list(range(ord("¡"), ord("¬") + 1)) + list(range(ord("®"), ord("ÿ") + 1))
    chars, extra = {}, 0
    for byte in range(256):
        if byte in shown:
            chars[chr(byte)] = byte
        else:
            chars[chr(256 + extra)] = byte
            extra += 1
    return chars


def token_bytes(tokenizer) -> list[bytes | None]:
    """The bytes each id writes, for every id of the model's vocabulary; None for added (special)
    tokens, which a grammar never writes (stop tokens are allowed separately)."""
    backend = tokenizer._backend
    alphabet = _byte_level_alphabet()
    added = set(backend.get_added_tokens_decoder())
    out: list[bytes | None] = []
    for i in range(backend.get_vocab_size(with_added_tokens=True)):
        piece = backend.id_to_token(i)
        if i in added or piece is None:
            out.append(None)
            continue
        try:
            out.append(bytes(alphabet[c] for c in piece))
        except KeyError:
            raise ValueError(f"token {i} ({piece!r}) is not byte-level BPE; constrained decoding needs a byte-level tokenizer") from None
    return out


@dataclass(frozen=True)
class TokenTable:
    """The automaton lifted to tokens (numpy; ``device_tables`` puts it on the device).

    Columns are the tokens that some state allows (``columns[c]`` is column c's token id; a large
    vocabulary such as Qwen's keeps a fraction of its ids). ``pair[s, c]``: -1 if token
    ``columns[c]`` cannot be written from state s, else an index p with ``next_state[p]`` the state
    after it and ``events[p]`` the events its bytes pass (0-padded).
    """

    columns: np.ndarray  # [U] int32
    pair: np.ndarray  # [S, U] int32
    next_state: np.ndarray  # [P] int32
    events: np.ndarray  # [P, E] int32
    accept: np.ndarray  # [S] bool
    passes: np.ndarray  # [P] bool: the token goes through one of ``lift``'s ``through`` states before its end


def lift(auto: Automaton, tokens: Sequence[bytes | None], max_events: int, max_token_bytes: int = 24,
         chunk: int = 16384, through: Iterable[int] = ()) -> TokenTable:
    """Walk every token from every state (vectorised over both); a token passing more than
    ``max_events`` events, or longer than ``max_token_bytes``, is not allowed there (shorter tokens
    always exist: every single byte is a token of a byte-level vocabulary). ``through``: states
    whose crossing inside a token is recorded (``TokenTable.passes``)."""
    n_states = len(auto.edges)
    marked = np.zeros(n_states + 1, bool)
    marked[list(through)] = True
    # Byte transition tables, state n_states is the dead state.
    dead = n_states
    step = np.full((n_states + 1, 256), dead, np.int32)
    step_events = np.zeros((n_states + 1, 256), np.int32)  # index into event_tuples
    event_tuples: list[Events] = [()]
    index_of: dict[Events, int] = {(): 0}
    for s, edges in enumerate(auto.edges):
        for byte, (t, ev) in edges.items():
            step[s, byte] = t
            step_events[s, byte] = index_of.setdefault(ev, len(event_tuples))
            if step_events[s, byte] == len(event_tuples):
                event_tuples.append(ev)
    tuple_len = np.asarray([len(e) for e in event_tuples], np.int32)
    tuple_codes = np.zeros((len(event_tuples), max(1, max(tuple_len))), np.int32)
    for i, ev in enumerate(event_tuples):
        tuple_codes[i, :len(ev)] = ev

    column_parts, pair_parts, next_parts, event_parts, pass_parts, count = [], [], [], [], [], 0
    sizes = np.asarray([len(t) if t is not None and 0 < len(t) <= max_token_bytes else 0 for t in tokens], np.int32)
    order = np.argsort(sizes, kind="stable")  # chunks of similar length walk few byte positions
    order = order[sizes[order] > 0]
    for lo in range(0, len(order), chunk):
        ids = order[lo:lo + chunk]
        lengths = sizes[ids]
        width = int(lengths.max())
        data = np.zeros((len(ids), width), np.int32)
        for j, i in enumerate(ids):
            data[j, :lengths[j]] = np.frombuffer(tokens[i], np.uint8)
        cur = np.broadcast_to(np.arange(n_states, dtype=np.int32)[:, None], (n_states, len(ids))).copy()
        evs = np.zeros((n_states, len(ids), max_events + 1), np.int32)  # last column: overflow, dropped
        used = np.zeros((n_states, len(ids)), np.int32)
        crossed = np.zeros((n_states, len(ids)), bool)
        for pos in range(width):
            active = pos < lengths  # [T]
            byte = data[:, pos]
            tup = np.where(active[None, :], step_events[cur, byte[None, :]], 0)
            cur = np.where(active[None, :], step[cur, byte[None, :]], cur)
            crossed |= (pos < lengths - 1)[None, :] & marked[cur]
            for e in range(tuple_codes.shape[1]):
                has = tuple_len[tup] > e
                slot = np.where(has, np.minimum(used, max_events), max_events)
                np.put_along_axis(evs, slot[..., None], np.where(has, tuple_codes[tup, e], 0)[..., None], -1)
                used = used + has
        valid = (cur != dead) & (used <= max_events)
        keep = np.nonzero(valid.any(axis=0))[0]
        valid, cur, evs, crossed = valid[:, keep], cur[:, keep], evs[:, keep], crossed[:, keep]
        s_idx, t_idx = np.nonzero(valid)
        pair = np.full(valid.shape, -1, np.int32)
        pair[s_idx, t_idx] = count + np.arange(len(s_idx), dtype=np.int32)
        column_parts.append(ids[keep])
        pair_parts.append(pair)
        next_parts.append(cur[s_idx, t_idx])
        event_parts.append(evs[s_idx, t_idx, :max_events])
        pass_parts.append(crossed[s_idx, t_idx])
        count += len(s_idx)
    accept = np.zeros(n_states, bool)
    accept[list(auto.accept)] = True
    columns = np.concatenate(column_parts).astype(np.int32)
    by_id = np.argsort(columns)  # columns in token order (pair indices are unchanged)
    return TokenTable(columns[by_id], np.concatenate(pair_parts, axis=1)[:, by_id],
                      np.concatenate(next_parts).astype(np.int32),
                      np.concatenate(event_parts).astype(np.int32).reshape(-1, max_events), accept,
                      np.concatenate(pass_parts))
