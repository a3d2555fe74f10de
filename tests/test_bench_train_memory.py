"""bench.train_memory counts, without allocating, the bytes a Trainer really holds."""

import jax

from bench.train_memory import state_bytes
from train.config import TrainConfig
from train.loop import Trainer


def _bytes(tree) -> int:
    return sum(x.size * x.dtype.itemsize for x in jax.tree.leaves(tree))


def test_counted_bytes_match_a_built_trainer(tmp_path):
    cfg = TrainConfig(init="tiny", data="synthetic", output_dir=str(tmp_path), seq_len=32, image_size=16,
                      batch_size=2, grad_accum=2, moments_dtype="bfloat16")
    counted = state_bytes(cfg)
    trainer = Trainer(cfg)
    n = sum(x.size for x in jax.tree.leaves(trainer.state.params))
    assert counted["trainable"] == _bytes(trainer.state.params) == 4 * n  # fp32 master
    assert counted["frozen"] == _bytes(trainer.model.frozen)
    assert counted["optimizer"] == _bytes(trainer.state.opt_state)
    assert 2 * 2 * n <= counted["optimizer"] < 2 * 2 * n + 64  # two bf16 moments and a few counters
    assert counted["grads"] == 4 * n + 4 * n  # float32 gradients and the float32 accumulation buffer
