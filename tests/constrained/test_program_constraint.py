"""Part-program constrained decoding (jax3dc.constrained.program): it accepts every program the
factories write, refuses what SPEC §6 forbids, and a randomly initialised model decoding under it
always writes a program that parses."""

from __future__ import annotations

import dataclasses

import jax
import jax.numpy as jnp
import numpy as np
import pytest
from flax import nnx

from jax3dc.constrained import program_constraint
from jax3dc.constrained.program import advance, allowed, initial_rows, program_tables
from jax3dc.model.config import Qwen3VLConfig
from jax3dc.generate import GenerationConfig
from jax3dc.model.qwen3_vl import Qwen3VL
from jax3dc.processing.tokenizer import load_tokenizer
from jax3dc.program.interpreter import parse_program
from jax3dc.release import MODEL_DIR
from tests.generation import generate

OK = ("mat1 = material('Wood', 'oak')\n"
      "box1 = box((1, 0.5, 0.25), center=(0, 0, 0.125))\n"
      "leg_2 = cylinder(radius=0.05, depth=0.5, center=(0.4, 0, -0.25), axis='z', segments=16)\n"
      "body_1 = difference(box1, leg_2)\n"
      "part(1, 'body', body_1, material=mat1)\n"
      "part(2, 'leg', leg_2)\n")


def _factory_programs(seeds: int) -> list[tuple[str, str]]:
    from jax3dc.factories.registry import FACTORIES, generate_object

    return [(f"{c}/{s}", generate_object(c, s).program_text) for c in FACTORIES for s in range(seeds)]


@jax.jit
def _accepted(tables, rows, ids, real, budget):
    """[B, n] bool: whether the grammar takes each token of each row (padding counts as taken)."""
    batch = jnp.arange(ids.shape[0])

    def step(rows, x):
        i, token, is_real = x
        left = budget - i
        ok = allowed(tables, rows, left)[batch, token] | ~is_real
        return advance(tables, rows, token, left), ok

    _, ok = jax.lax.scan(step, rows, (jnp.arange(ids.shape[1]), ids.T, real.T))
    return ok.T


def _first_refused(tokenizer, vocab: int, texts: list[str], budget: int = 8192) -> list[int | None]:
    """Feed each text and a stop token, all texts as rows of one scanned loop (no host round trip
    per token; lengths padded to a multiple of 256, so few compiles); per text, the index of the
    first token the grammar refuses, else None."""
    seqs = [tokenizer.encode(t) + [tokenizer.special.im_end] for t in texts]
    n = -(-max(map(len, seqs)) // 256) * 256
    ids = np.zeros((len(seqs), n), np.int32)
    real = np.zeros((len(seqs), n), bool)
    for b, seq in enumerate(seqs):
        ids[b, :len(seq)], real[b, :len(seq)] = seq, True
    budgets = np.full((len(seqs),), budget, np.int32)
    ok = np.asarray(_accepted(program_tables(tokenizer, vocab), initial_rows(len(seqs)), ids, real, budgets))
    return [None if row.all() else int(np.argmin(row)) for row in ok]


def _walk(tokenizer, vocab: int, text: str) -> int | None:
    return _first_refused(tokenizer, vocab, [text])[0]


@pytest.mark.parametrize("tokenizer_dir", [MODEL_DIR, pytest.param(None, marks=pytest.mark.slow)], ids=["release-bpe", "qwen3"])
def test_grammar_accepts_every_factory_program(tokenizer_dir) -> None:
    tokenizer = load_tokenizer(tokenizer_dir)
    vocab = 1408 if tokenizer_dir is not None else 151936
    # Qwen3's 151,936-token vocabulary makes each step ~100x dearer on a CPU (8 programs took ~6 of a
    # 2-core suite's minutes): two categories; the shipped BPE walks every category's programs
    programs = _factory_programs(2) if tokenizer_dir is not None else _factory_programs(1)[::20]
    first = _first_refused(tokenizer, vocab, [text for _, text in programs])
    refused = [key for (key, _), at in zip(programs, first) if at is not None]
    assert not refused, refused
    assert _walk(tokenizer, vocab, OK) is None


@pytest.mark.parametrize("bad", [
    OK.replace("box((1", "cuboid((1"),  # unknown function
    OK.replace("box1 = box(", "import box\nbox1 = box("),  # import
    OK.replace("radius=0.05", "radius=0.05, height=1"),  # unknown keyword
    OK.replace("segments=16)", "segments=16, radius=1)"),  # a keyword given twice
    OK.replace("difference(box1, leg_2)", "difference(box1, leg_3)"),  # a name never bound
    OK.replace("difference(box1, leg_2)", "difference(box1, box1x)"),  # a longer, unbound name
    OK.replace("body_1 = difference(box1, leg_2)", "body_1 = difference(body_1, leg_2)"),  # bound only after its line
    OK.replace("radius=0.05", "radius=0.05 * 2"),  # not a literal
    OK.replace("radius=0.05", "radius=leg_2.radius"),  # attribute access
    OK.replace("leg_2 = cylinder", "__leg = cylinder"),  # dunder name
    OK.replace("leg_2 = cylinder", "box = cylinder"),  # a predefined name assigned
    OK.replace("part(2, 'leg'", "part(3, 'leg'"),  # ids not 1, 2, ...
    OK.replace("part(1, 'body', body_1, material=mat1)\n", ""),  # part 2 before part 1
    OK.replace("axis='z'", "axis=z"),  # the axis as an unbound name
    OK.replace("center=(0, 0, 0.125)", "center=mat1"),  # a name where a sequence must be
    "box1 = box(1)\n",  # no part: the program may not stop
])
def test_grammar_refuses_what_the_language_forbids(bad: str) -> None:
    assert _walk(load_tokenizer(MODEL_DIR), 1408, bad) is not None, bad


def test_random_tiny_model_always_writes_programs_that_parse() -> None:
    """Sampled at temperature 1 from random weights (nothing steers it but the mask), every row
    stops within its budget with a program that parses."""
    tokenizer = load_tokenizer(MODEL_DIR)
    config = dataclasses.replace(Qwen3VLConfig.tiny(vocab_size=1408), image_token_id=1297, video_token_id=1298,
                                 vision_start_token_id=1294, vision_end_token_id=1295)
    model = Qwen3VL(config, rngs=nnx.Rngs(5))
    rows = 16
    prompt = tokenizer.encode("Write a part program.")
    input_ids = np.asarray([prompt] * rows, np.int32)
    out = generate(model, input_ids, np.ones_like(input_ids), config=GenerationConfig(
        max_new_tokens=400, temperature=1.0, stop_ids=tokenizer.special.stop_ids, pad_id=tokenizer.special.endoftext),
        key=jax.random.key(11), constraint=program_constraint(tokenizer, 1408, rows))
    tokens, lengths = np.asarray(out.tokens), np.asarray(out.lengths)
    for r in range(rows):
        assert int(tokens[r, lengths[r] - 1]) in tokenizer.special.stop_ids, f"row {r} did not finish"
        text = tokenizer.decode(tokens[r, :lengths[r]].tolist())
        tree = parse_program(text)
        assert any(getattr(s.value, "func", None) is not None and s.value.func.id == "part" for s in tree.body), text
