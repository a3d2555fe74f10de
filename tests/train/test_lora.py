"""LoRA on the tiny model: fresh adapters change nothing, merging equals the adapted model, a
LoRA run trains only the adapters, resumes from its checkpoint, and exports a plain HF model that
transformers loads with the same logits."""

from __future__ import annotations

import dataclasses

import jax
import jax.numpy as jnp
import numpy as np
import pytest
from flax import nnx

from jax3dc.model import Qwen3VLConfig, load_pretrained
from jax3dc.model.lora import LoraSpec, add_lora, merge_lora
from jax3dc.model.params import to_hf
from jax3dc.model.safetensors_io import iter_tensors
from train.checkpoint import RunCheckpoints
from train.config import ConfigError, TrainConfig, validate
from train.loop import Trainer, make_loader
from train.optimizer import path_name

IDS = np.random.default_rng(0).integers(0, 100, (2, 11))  # text tokens of the tiny vocabulary
# Text only: every M-RoPE section's position is the token's index (get_rope_index's answer,
# given here because computing it op by op takes seconds).
POSITIONS = np.broadcast_to(np.arange(IDS.shape[1]), (3, *IDS.shape))


def logits(model: nnx.Module) -> np.ndarray:
    """Op by op, not jitted: with the adapter terms in the program XLA fuses the model's other
    ops differently, which moves the base logits by an ulp, so "exactly" could not be tested."""
    with jax.default_matmul_precision("highest"):
        return np.asarray(model(jnp.asarray(IDS, jnp.int32), position_ids=jnp.asarray(POSITIONS, jnp.int32)))


@pytest.fixture(scope="module")
def hf_base(tmp_path_factory):
    """A random tiny Qwen3-VL saved by transformers: the base model of every test here (loading it
    compiles nothing, unlike initialising one)."""
    import torch
    import transformers

    d = {k: v for k, v in Qwen3VLConfig.tiny().to_hf_dict().items() if k not in ("architectures", "model_type", "dtype")}
    torch.manual_seed(0)
    path = tmp_path_factory.mktemp("base")
    transformers.Qwen3VLForConditionalGeneration(transformers.Qwen3VLConfig(**d)).save_pretrained(path)
    return path


def test_fresh_adapters_leave_logits_exactly_and_merging_equals_the_adapters(hf_base):
    base, _ = load_pretrained(hf_base)
    adapted = add_lora(nnx.clone(base), LoraSpec(rank=4, alpha=8.0), rngs=nnx.Rngs(1))
    adapters = nnx.state(adapted, nnx.LoRAParam)
    assert len(jax.tree.leaves(adapters)) == 2 * 7 * 3  # A and B on 7 projections of 3 layers
    reference = logits(base)
    np.testing.assert_array_equal(logits(adapted), reference)  # B = 0: exactly the base model

    rng = np.random.default_rng(2)
    nnx.update(adapted, jax.tree.map(lambda x: jnp.asarray(0.3 * rng.standard_normal(x.shape), x.dtype), adapters))
    with_adapters = logits(adapted)
    merged = merge_lora(adapted)
    assert not jax.tree.leaves(nnx.state(merged, nnx.LoRAParam))
    assert nnx.graphdef(merged) == nnx.graphdef(base)  # the plain architecture again
    assert np.abs(with_adapters - reference).max() > 0.1  # the adapters matter...
    np.testing.assert_allclose(logits(merged), with_adapters, rtol=1e-5, atol=1e-5)  # ...and merge exactly


def test_lora_settings_are_checked():
    good = TrainConfig(init="tiny", data="synthetic", lora_rank=4)
    validate(good)
    for bad in (dict(lora_rank=-1), dict(lora_targets=("q_proj", "qkv")), dict(lora_targets=())):
        with pytest.raises(ConfigError, match="lora|LoRA"):
            validate(dataclasses.replace(good, **bad))


def _flat(state: nnx.State) -> dict[str, np.ndarray]:
    return {path_name(p): np.asarray(v.get_value()) for p, v in nnx.to_flat_state(state)}


def test_lora_run_trains_only_adapters_resumes_and_exports_a_plain_model(hf_base, tmp_path):
    import torch
    import transformers

    cfg = TrainConfig(init=str(hf_base), data="synthetic", output_dir=str(tmp_path), seq_len=32, image_size=0,
                      batch_size=2, grad_accum=1, steps=6, warmup_steps=0, lr=1e-2, compute_dtype="float32",
                      remat="none", lora_rank=4, lora_alpha=8.0)
    trainer = Trainer(cfg)
    adapters0, frozen0 = _flat(trainer.state.params), _flat(trainer.model.frozen)
    assert adapters0 and all(k.endswith(("/lora_a", "/lora_b")) for k in adapters0)
    assert all(not v.any() for k, v in adapters0.items() if "lora_b" in k)  # B starts at zero
    assert any(k.endswith("q_proj/kernel") for k in frozen0)

    loader = make_loader(cfg, trainer.model.config, "train")
    batch = next(loader)
    ckpt = RunCheckpoints(str(tmp_path / "checkpoints"), keep_last=2)
    losses = []
    for step in range(1, 5):
        losses.append(float(trainer.train_step(batch)["loss"]))
        if step == 2:
            trainer.save(ckpt, loader, None, None)
    assert losses[-1] < losses[0] - 0.05, losses
    adapters = _flat(trainer.state.params)
    assert all(not np.array_equal(adapters[k], adapters0[k]) for k in adapters0)  # every adapter moved
    for k, v in _flat(trainer.model.frozen).items():
        np.testing.assert_array_equal(v, frozen0[k], err_msg=k)  # the base is bit-identical

    ckpt.wait()
    trainer.restore(ckpt, 2)  # back to step 2: the same two steps again give the same losses
    ckpt.close()
    assert [float(trainer.train_step(batch)["loss"]) for _ in range(2)] == losses[2:]
    for k, v in _flat(trainer.state.params).items():
        np.testing.assert_array_equal(v, adapters[k], err_msg=k)

    trainer.export(str(tmp_path / "hf"))
    exported = dict(iter_tensors(tmp_path / "hf"))
    layer = "language_model/layers/1/self_attn/q_proj"
    w, a, b = frozen0[f"{layer}/kernel"], adapters[f"{layer}/lora_a"], adapters[f"{layer}/lora_b"]
    want = to_hf(w + cfg.lora_alpha / cfg.lora_rank * np.tensordot(a, b, axes=1), "linear", 1, trainer.model.config)
    got = exported["model.language_model.layers.1.self_attn.q_proj.weight"]
    assert np.abs(got - to_hf(w, "linear", 1, trainer.model.config)).max() > 1e-3  # not the base weight
    np.testing.assert_allclose(got, want, rtol=1e-6, atol=1e-7)
    assert not any("lora" in name for name in exported)

    hf = transformers.Qwen3VLForConditionalGeneration.from_pretrained(tmp_path / "hf", dtype=torch.float32).eval()
    with torch.no_grad():
        theirs = hf(input_ids=torch.tensor(IDS)).logits.numpy()
    ours = logits(nnx.merge(trainer.model.graphdef, trainer.state.params, trainer.model.frozen))  # unmerged
    assert np.abs(ours - theirs).max() / np.abs(ours).max() < 1e-5
