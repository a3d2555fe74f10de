"""Two training steps of the real tiny model: vision tower untouched, decoder moved."""

import jax
import numpy as np
import pytest

from train.config import TrainConfig
from train.loop import Trainer, make_loader


@pytest.mark.slow
def test_frozen_vision_bit_identical_and_decoder_updated(tmp_path):
    cfg = TrainConfig(init="tiny", data="synthetic", output_dir=str(tmp_path), seq_len=32, image_size=16, batch_size=2,
                      grad_accum=2, steps=4, warmup_steps=0, lr=1e-2, compute_dtype="float32")
    trainer = Trainer(cfg)
    frozen0 = [np.asarray(x) for x in jax.tree.leaves(trainer.model.frozen)]
    train0 = [np.asarray(x) for x in jax.tree.leaves(trainer.state.params)]
    loader = make_loader(cfg, trainer.model.config, "train")
    losses = [float(trainer.train_step(next(loader))["loss"]) for _ in range(2)]
    assert all(np.isfinite(losses))
    for a, b in zip(frozen0, jax.tree.leaves(trainer.model.frozen)):
        np.testing.assert_array_equal(a, np.asarray(b))
    moved = [not np.array_equal(a, np.asarray(b)) for a, b in zip(train0, jax.tree.leaves(trainer.state.params))]
    assert all(moved)
    assert len(jax.tree.leaves(trainer.state.opt_state)) > 0
