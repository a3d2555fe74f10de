"""Parameter-text constrained decoding (jax3dc.constrained.parameters): it accepts every record's
text, refuses what does not fit a schema, and a randomly initialised model decoding under it always
writes a text that parses and runs into an object."""

from __future__ import annotations

import dataclasses

import jax
import jax.numpy as jnp
import numpy as np
from flax import nnx

from jax3dc.constrained import parameters_constraint
from jax3dc.constrained.parameters import advance, allowed, initial_rows, longest_text, parameters_tables
from jax3dc.factories.registry import SCHEMAS, run_parameters
from jax3dc.generate import GenerationConfig
from jax3dc.model.config import Qwen3VLConfig
from jax3dc.model.qwen3_vl import Qwen3VL
from jax3dc.parameters import format_parameters, parse_parameters
from jax3dc.processing.tokenizer import load_tokenizer
from jax3dc.release import MODEL_DIR
from tests.factory_samples import sample_parameters
from tests.generation import generate

VOCAB = 1408


@jax.jit
def _accepted(tables, rows, ids, real, budget):
    batch = jnp.arange(ids.shape[0])

    def step(rows, x):
        i, token, is_real = x
        left = budget - i
        ok = allowed(tables, rows, left)[batch, token] | ~is_real
        return advance(tables, rows, token, left), ok

    _, ok = jax.lax.scan(step, rows, (jnp.arange(ids.shape[1]), ids.T, real.T))
    return ok.T


def _first_refused(texts: list[str], budget: int = 1024) -> list[int | None]:
    """Feed each text and a stop token as rows of one scanned loop; per text, the index of the
    first token the grammar refuses, else None."""
    tokenizer = load_tokenizer(MODEL_DIR)
    seqs = [tokenizer.encode(t) + [tokenizer.special.im_end] for t in texts]
    n = -(-max(map(len, seqs)) // 128) * 128
    ids = np.zeros((len(seqs), n), np.int32)
    real = np.zeros((len(seqs), n), bool)
    for b, seq in enumerate(seqs):
        ids[b, :len(seq)], real[b, :len(seq)] = seq, True
    tables = parameters_tables(SCHEMAS, tokenizer, VOCAB)
    ok = np.asarray(_accepted(tables, initial_rows(len(seqs)), ids, real, np.full((len(seqs),), budget, np.int32)))
    return [None if row.all() else int(np.argmin(row)) for row in ok]


def test_grammar_accepts_every_categorys_records() -> None:
    texts = [format_parameters(sample_parameters(c, s), SCHEMAS[c]) for c in sorted(SCHEMAS) for s in range(3)]
    first = _first_refused(texts)
    assert all(at is None for at in first), [t for t, at in zip(texts, first) if at is not None]


GOOD = format_parameters(sample_parameters("stapler", 0), SCHEMAS["stapler"])


BAD = [
    GOOD.replace("stapler(", "staplers("),  # not a category
    GOOD.replace("length=", "width="),  # entries out of order
    GOOD.replace("length=0.", "length=9."),  # out of range
    GOOD.replace(", metal=", ", metal=7, metal="),  # an entry twice
    GOOD.replace("stapler(length", "stapler( length"),  # another spelling
    GOOD[:-1] + ", extra=1)",  # an entry the schema lacks
    GOOD[:-1],  # never closed: the stop token is refused
    "cabinet(width=0.5)",  # entries missing
]


def test_grammar_refuses_what_no_schema_allows() -> None:
    first = _first_refused(BAD)
    assert all(at is not None for at in first), [bad for bad, at in zip(BAD, first) if at is None]


def test_longest_text_bounds_every_record() -> None:
    longest = longest_text(SCHEMAS)
    assert all(len(format_parameters(sample_parameters(c, s), SCHEMAS[c])) <= longest
               for c in SCHEMAS for s in range(3))
    assert longest < 400


def test_random_tiny_model_always_writes_texts_that_run() -> None:
    """Sampled at temperature 1 from random weights, every row stops within its budget with a text
    that parses and runs into an object, even when the budget is tight."""
    tokenizer = load_tokenizer(MODEL_DIR)
    config = dataclasses.replace(Qwen3VLConfig.tiny(vocab_size=VOCAB), image_token_id=1297, video_token_id=1298,
                                 vision_start_token_id=1294, vision_end_token_id=1295)
    model = Qwen3VL(config, rngs=nnx.Rngs(3))
    rows = 12
    prompt = tokenizer.encode("Write its parameters.")
    input_ids = np.asarray([prompt] * rows, np.int32)
    for budget in (longest_text(SCHEMAS) + 1, 90):
        out = generate(model, input_ids, np.ones_like(input_ids), config=GenerationConfig(
            max_new_tokens=budget, temperature=1.0, stop_ids=tokenizer.special.stop_ids,
            pad_id=tokenizer.special.endoftext), key=jax.random.key(budget),
            constraint=parameters_constraint(SCHEMAS, tokenizer, VOCAB, rows))
        tokens, lengths = np.asarray(out.tokens), np.asarray(out.lengths)
        categories = set()
        for r in range(rows):
            assert int(tokens[r, lengths[r] - 1]) in tokenizer.special.stop_ids, f"row {r} did not finish"
            params = parse_parameters(tokenizer.decode(tokens[r, :lengths[r] - 1].tolist()), SCHEMAS)
            categories.add(params.category)
            assert len(run_parameters(params).parts) >= 2
        assert len(categories) > 1
