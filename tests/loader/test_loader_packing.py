"""Packed rows: RoPE ids, labels and the loss are those of each example alone."""

from __future__ import annotations

import jax
import jax.numpy as jnp
import numpy as np
import pytest
from flax import nnx

from data_pipeline.examples import ExampleEncoder
from data_pipeline.packing import RowLayout, pack_row, rope_positions
from jax3dc.processing.chat import IGNORE_INDEX
from jax3dc.model.qwen3_vl import Qwen3VL
from jax3dc.model.rope import get_rope_index
from jax3dc.processing.tokenizer import load_tokenizer
from tests.loader.loader_fixtures import CATEGORIES, record, tiny_config, tiny_processor


@pytest.fixture(scope="module")
def setup():
    cfg, tok = tiny_config(), load_tokenizer()
    encoder = ExampleEncoder(tok, tiny_processor(), cfg.vision.spatial_merge_size)
    examples = [encoder.encode(record(c, s)) for s, c in enumerate(CATEGORIES[:3])]
    return cfg, tok, encoder, examples


@pytest.fixture(scope="module")
def code_examples(setup):
    """Code-task examples (image I alone -> part program) of two records."""
    cfg, tok, _, _ = setup
    encoder = ExampleEncoder(tok, tiny_processor(), cfg.vision.spatial_merge_size, task="code")
    return [encoder.encode(record(c, s)) for s, c in enumerate(CATEGORIES[3:5])]


def layout_for(cfg, tok, seq_len: int, pack: int) -> RowLayout:
    return RowLayout(seq_len=seq_len, pack=pack, images_per_example=2, grid=(1, 8, 8),
                     patch_dim=cfg.vision.patch_dim, pad_id=tok.special.endoftext,
                     image_token_id=cfg.image_token_id, merge=cfg.vision.spatial_merge_size)


def test_rope_positions_match_the_model(setup) -> None:
    cfg, _, _, examples = setup
    for ex in examples:
        ours = rope_positions(ex.input_ids, ex.image_grid_thw, cfg.image_token_id, 2)
        ref, _ = get_rope_index(jnp.asarray(ex.input_ids)[None], jnp.asarray(ex.image_grid_thw),
                                cfg.image_token_id, 2)
        np.testing.assert_array_equal(ours, np.asarray(ref)[:, 0])


def test_labels_cover_exactly_the_answer(setup) -> None:
    cfg, tok, _, examples = setup
    ex = examples[0]
    rec = record(CATEGORIES[0], 0)
    row = pack_row([ex], layout_for(cfg, tok, len(ex) + 5, 1))
    scored = row["labels"][row["loss_mask"] > 0]
    assert tok.decode(scored, skip_special_tokens=False) == rec.target + "<|im_end|>"
    assert row["loss_mask"][len(ex) - 1:].sum() == 0  # nothing predicted past the example


def token_nll(model: Qwen3VL, rows: list[dict]) -> list[np.ndarray]:
    """Per-token NLL of the scored positions of each row."""
    batch = {k: np.stack([r[k] for r in rows]) for k in rows[0]}
    per_row = batch["image_grid_thw"].shape[1]
    hidden = model(jnp.asarray(batch["input_ids"]), attention_mask=jnp.asarray(batch["attention_mask"]),
                   pixel_values=jnp.asarray(batch["pixel_values"].reshape(-1, batch["pixel_values"].shape[-1])),
                   image_grid_thw=jnp.asarray(batch["image_grid_thw"].reshape(-1, 3)),
                   position_ids=jnp.asarray(batch["position_ids"].transpose(1, 0, 2)),
                   segment_ids=jnp.asarray(batch["segment_ids"]), images_per_row=per_row,
                   vision_window=64, return_hidden=True)
    out = []
    for b in range(len(rows)):
        where = np.nonzero(batch["loss_mask"][b])[0]
        logits = model.logits(hidden[b, where])
        logz = jax.nn.logsumexp(logits, axis=-1)
        picked = jnp.take_along_axis(logits, jnp.asarray(batch["labels"][b, where])[:, None], axis=-1)[:, 0]
        out.append(np.asarray(logz - picked))
    return out


def test_packed_loss_equals_unpacked(setup, code_examples) -> None:
    """Per-token NLL of every example is the same in one packed row and in rows of its own, in a
    row that mixes code examples (one image) with structure examples (two). (A structure-only row
    checked the same ~50 s over again: its examples are a subset of this row's kinds.)"""
    cfg, tok, _, examples = setup
    # one-image examples first, between and last: image slots are filled in order
    examples = [code_examples[0], examples[0], code_examples[1], examples[1]]
    model = Qwen3VL(cfg, rngs=nnx.Rngs(3))
    total = sum(len(e) for e in examples)
    packed = pack_row(examples, layout_for(cfg, tok, total + 7, len(examples)))
    alone = [pack_row([e], layout_for(cfg, tok, max(len(e) for e in examples), 1)) for e in examples]
    (packed_nll,) = token_nll(model, [packed])
    alone_nll = np.concatenate(token_nll(model, alone))
    assert packed_nll.shape == alone_nll.shape and packed_nll.size > 100
    np.testing.assert_allclose(packed_nll, alone_nll, rtol=2e-5, atol=2e-5)
    # and the packing is not vacuous: without segments, later examples would see earlier ones
    leaky = dict(packed)
    leaky["segment_ids"] = (packed["segment_ids"] > 0).astype(np.int32)
    assert not np.allclose(token_nll(model, [leaky])[0], alone_nll, atol=1e-3)


def test_unused_image_slots_are_ignored(setup) -> None:
    cfg, tok, _, examples = setup
    layout = layout_for(cfg, tok, 4096, 4)
    row = pack_row(examples[:2], layout)
    assert row["pixel_values"].shape[0] == 8 * 64 and not row["pixel_values"][4 * 64:].any()
    assert (row["image_grid_thw"] == [1, 8, 8]).all()
    with pytest.raises(ValueError, match="at most 4"):
        pack_row(examples * 2, layout)
    ignored = examples[0].labels == IGNORE_INDEX
    assert ignored.any() and not ignored.all()
