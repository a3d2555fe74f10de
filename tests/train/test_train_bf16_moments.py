"""The tiny model trained with bf16 moments under fp32 master weights learns like fp32 moments,
holds its moments in bf16 on the mesh, and resumes them from a checkpoint."""

import dataclasses

import jax
import jax.numpy as jnp
import numpy as np
import pytest

from train.checkpoint import RunCheckpoints
from train.config import TrainConfig
from train.loop import Trainer, make_loader

STEPS = 30


def _moments(trainer: Trainer) -> list[jax.Array]:
    adam = trainer.state.opt_state[1][0]  # chain(clip, chain(adam, decay, lr))
    return jax.tree.leaves((adam.mu, adam.nu))


def _train(cfg: TrainConfig, steps: int, ckpt: RunCheckpoints | None = None, save_at: int = 0) -> tuple[Trainer, list[float]]:
    trainer = Trainer(cfg)
    loader = make_loader(cfg, trainer.model.config, "train")
    losses = []
    for step in range(1, steps + 1):
        losses.append(float(trainer.train_step(next(loader))["loss"]))
        if step == save_at:
            trainer.save(ckpt, loader, None, None)
    return trainer, losses


@pytest.mark.slow
def test_bf16_moments_learn_like_fp32_and_resume(tmp_path):
    cfg = TrainConfig(init="tiny", data="synthetic", output_dir=str(tmp_path), seq_len=32, image_size=0, batch_size=4,
                      grad_accum=1, steps=STEPS, warmup_steps=3, lr=1e-2, compute_dtype="float32", remat="none")
    _, fp32 = _train(cfg, STEPS)
    ckpt = RunCheckpoints(str(tmp_path / "checkpoints"), keep_last=2)
    bf16_cfg = dataclasses.replace(cfg, moments_dtype="bfloat16")
    trainer, bf16 = _train(bf16_cfg, STEPS, ckpt, save_at=STEPS - 2)

    assert bf16[-1] < 0.8 * bf16[0], bf16  # it learns: the comparison below is not between two flat curves
    assert abs(bf16[-1] / fp32[-1] - 1) < 0.05, (fp32[-1], bf16[-1])
    moments = _moments(trainer)
    assert moments and {m.dtype for m in moments} == {jnp.dtype(jnp.bfloat16)}
    params = jax.tree.leaves(trainer.state.params)
    assert {p.dtype for p in params} == {jnp.dtype(jnp.float32)}  # fp32 master
    assert [m.sharding for m in moments] == [p.sharding for p in params] * 2  # mu, then nu, like their weights

    ckpt.wait()
    final = [np.asarray(m) for m in moments]
    trainer.restore(ckpt, STEPS - 2)
    ckpt.close()
    assert {m.dtype for m in _moments(trainer)} == {jnp.dtype(jnp.bfloat16)}
    loader = make_loader(bf16_cfg, trainer.model.config, "train")
    loader.set_state({"step": STEPS - 2, "seed": 0})
    assert [float(trainer.train_step(next(loader))["loss"]) for _ in range(2)] == bf16[-2:]
    for a, b in zip(final, _moments(trainer)):  # the same rounding bits after the resume
        np.testing.assert_array_equal(a, np.asarray(b))
