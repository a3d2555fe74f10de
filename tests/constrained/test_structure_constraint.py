"""Structure-grammar constrained decoding (jax3dc.constrained): it accepts what the canonical
writer writes, and a randomly initialised model decoding under it always writes a document that
parses and validates against its prompt's part ids and joint count."""

from __future__ import annotations

import dataclasses
import json

import jax
import numpy as np
import pytest
from flax import nnx

from jax3dc.constrained import prompt_counts, structure_constraint
from jax3dc.constrained.structure import advance, allowed, initial_rows, structure_tables
from jax3dc.errors import StructureError
from jax3dc.model.config import Qwen3VLConfig
from jax3dc.generate import GenerationConfig
from jax3dc.model.qwen3_vl import Qwen3VL
from jax3dc.processing.tokenizer import load_tokenizer
from jax3dc.release import MODEL_DIR
from jax3dc.structure import parse_structure, to_json
from tests.generation import generate


def _prompt(n: int, joints: int | None) -> str:
    legend = "\n".join(f"{i}: #{i * 40503 % 0xFFFFFF:06x} | 0.000 0.000 0.000 | 0.500 0.500 0.500" for i in range(1, n + 1))
    return "Parts (id: colour | centroid | extent):\n" + legend + ("" if joints is None else f"\nJoints: {joints}")


def _factory_targets() -> list[str]:
    from jax3dc.factories import generate_object

    out = []
    for category, seed in [("cabinet", 0), ("drawer_chest", 1), ("laptop", 2), ("globe", 3), ("cell_shelf", 4), ("oven", 5)]:
        out.append(to_json(generate_object(category, seed).structure))
    return out


def _walk(tokenizer, vocab: int, text: str, n: int, joints: int) -> int | None:
    """Feed ``text`` token by token; the index of the first token the grammar refuses, else None."""
    tables = structure_tables(tokenizer, vocab)
    rows = initial_rows([n], [joints])
    ids = tokenizer.encode(text) + [tokenizer.special.im_end]
    step_mask, step_rows = jax.jit(allowed), jax.jit(advance)
    for i, token in enumerate(ids):
        left = np.asarray([4096 - i])
        if not bool(step_mask(tables, rows, left)[0, token]):
            return i
        rows = step_rows(tables, rows, np.asarray([token]), left)
    return None


@pytest.mark.parametrize("tokenizer_dir", [MODEL_DIR, pytest.param(None, marks=pytest.mark.slow)], ids=["release-bpe", "qwen3"])
def test_grammar_accepts_the_canonical_writer(tokenizer_dir) -> None:
    tokenizer = load_tokenizer(tokenizer_dir)
    vocab = 1408 if tokenizer_dir is not None else 151936
    for text in _factory_targets()[: 6 if tokenizer_dir is not None else 2]:
        doc = json.loads(text)
        n, joints = len(doc["nodes"]), sum("joint" in v for v in doc["nodes"].values())
        assert _walk(tokenizer, vocab, text, n, joints) is None, text


def test_grammar_refuses_wrong_ids_cycles_and_joint_counts() -> None:
    tokenizer = load_tokenizer(MODEL_DIR)
    ok = ('{"materials":{"0":{"family":"Wood","desc":"oak"}},"nodes":{"1":{"parent":null,"material":0},'
          '"2":{"parent":1,"material":0,"joint":{"type":"hinge","axis":[0.0,0.0,1.0],"pivot":[0.1,0.0,0.0],'
          '"range":[0.0,1.571]}}},"relations":[]}')
    assert _walk(tokenizer, 1408, ok, 2, 1) is None
    assert _walk(tokenizer, 1408, ok, 2, -1) is None
    for bad, n, joints in [
        (ok, 3, 1),  # a part of the legend is missing
        (ok, 2, 0),  # one joint more than the prompt's count
        (ok.replace(',"joint":{"type":"hinge","axis":[0.0,0.0,1.0],"pivot":[0.1,0.0,0.0],"range":[0.0,1.571]}', ''),
         2, 1),  # one joint less
        (ok.replace('"2":{"parent":1', '"3":{"parent":1'), 3, 1),  # ids out of order
        (ok.replace('"parent":null', '"parent":2'), 2, 1),  # 1 -> 2 -> 1: a cycle
        (ok.replace('"parent":null', '"parent":1'), 2, 1),  # its own parent
        (ok.replace('"material":0,"joint"', '"material":1,"joint"'), 2, 1),  # material 1 is not defined
        (ok.replace('[0.0,0.0,1.0]', '[0.0,0.0,0.0]'), 2, 1),  # zero axis
        (ok.replace('[0.0,1.571]', '[0.5,1.571]'), 2, 1),  # range not around the pose shown
        (ok.replace('[0.0,1.571]', '[0.0,7.0]'), 2, 1),  # hinge beyond 2 pi
        (ok.replace('"relations":[]', '"relations":[{"type":"instance","a":1,"b":1}]'), 2, 1),
    ]:
        assert _walk(tokenizer, 1408, bad, n, joints) is not None, bad


def test_prompt_counts_reads_the_legend_and_joint_line() -> None:
    assert prompt_counts(_prompt(4, 2)) == (4, 2)
    assert prompt_counts(_prompt(3, None)) == (3, -1)
    with pytest.raises(StructureError, match="not 1..3"):
        prompt_counts(_prompt(3, None).replace("\n2:", "\n7:"))
    with pytest.raises(StructureError, match="no part legend"):
        prompt_counts("Write the structure.")


def test_a_prompt_the_grammar_cannot_take_is_an_error_naming_it() -> None:
    tokenizer = load_tokenizer(MODEL_DIR)
    with pytest.raises(StructureError, match=r"cabinet/7/0: 130 parts: the structure grammar takes at most 127"):
        structure_constraint(tokenizer, 1408, [_prompt(2, 1), _prompt(130, None)], ["box/1/0", "cabinet/7/0"])
    with pytest.raises(StructureError, match=r"box/1/0: the prompt has no part legend"):
        structure_constraint(tokenizer, 1408, ["Write the structure."], ["box/1/0"])


def test_random_tiny_model_always_writes_valid_structures() -> None:
    """Sampled at temperature 1 from random weights (the hardest case for a grammar: nothing
    steers it but the mask), every row parses, has exactly its prompt's part ids and, where the
    prompt gives one, its joint count."""
    tokenizer = load_tokenizer(MODEL_DIR)
    config = dataclasses.replace(Qwen3VLConfig.tiny(vocab_size=1408), image_token_id=1297, video_token_id=1298,
                                 vision_start_token_id=1294, vision_end_token_id=1295)
    model = Qwen3VL(config, rngs=nnx.Rngs(3))
    cases = [(1, None), (2, 1), (3, None), (3, 0), (4, 2), (4, 3), (5, 3), (6, None), (8, 4), (10, 9)] * 2
    prompts = [_prompt(n, j) for n, j in cases]
    ids = [tokenizer.encode(p) for p in prompts]
    width = max(len(x) for x in ids)
    input_ids = np.full((len(ids), width), tokenizer.special.endoftext, np.int32)
    mask = np.zeros_like(input_ids)
    for r, x in enumerate(ids):
        input_ids[r, width - len(x):], mask[r, width - len(x):] = x, 1
    out = generate(model, input_ids, mask, config=GenerationConfig(max_new_tokens=1200, temperature=1.0,
                   stop_ids=tokenizer.special.stop_ids, pad_id=tokenizer.special.endoftext),
                   key=jax.random.key(7), constraint=structure_constraint(tokenizer, 1408, prompts))
    tokens, lengths = np.asarray(out.tokens), np.asarray(out.lengths)
    assert np.all(np.isfinite(np.asarray(out.logprobs)))
    for r, (n, joints) in enumerate(cases):
        assert int(tokens[r, lengths[r] - 1]) in tokenizer.special.stop_ids, f"row {r} did not finish"
        text = tokenizer.decode(tokens[r, :lengths[r]].tolist())
        structure = parse_structure(text, part_ids=list(range(1, n + 1)))
        assert sorted(structure.nodes) == list(range(1, n + 1))
        if joints is not None:
            assert len(structure.joints()) == joints, text
