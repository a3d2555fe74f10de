"""Adam with its moments stored in bf16 (train/adam_moments.py) against optax's float32 Adam, and
the rounding that keeps the stored moments unbiased."""

import jax
import jax.numpy as jnp
import numpy as np
import optax
import pytest

from train.adam_moments import scale_by_adam_stored_in
from train.config import ConfigError, TrainConfig, apply_overrides, validate
from train.optimizer import build_optimizer

B1, B2, EPS = 0.9, 0.999, 1e-8


def _grads(step: int) -> dict[str, jax.Array]:
    rng = np.random.default_rng(step)
    return {"w": jnp.asarray(rng.normal(size=(64, 32)) * 10.0 ** rng.uniform(-4, 1, (64, 32)), jnp.float32),
            "b": jnp.asarray(rng.normal(size=(32,)), jnp.float32)}


def _numpy_adam(grads: list[dict[str, np.ndarray]]) -> list[dict[str, np.ndarray]]:
    """Adam's scaled update of each step, in float64 (Kingma & Ba, algorithm 1)."""
    mu = {k: np.zeros_like(v, np.float64) for k, v in grads[0].items()}
    nu = {k: np.zeros_like(v, np.float64) for k, v in grads[0].items()}
    out = []
    for t, g in enumerate(grads, start=1):
        step = {}
        for k, v in g.items():
            mu[k] = B1 * mu[k] + (1 - B1) * v
            nu[k] = B2 * nu[k] + (1 - B2) * v.astype(np.float64) ** 2
            step[k] = mu[k] / (1 - B1 ** t) / (np.sqrt(nu[k] / (1 - B2 ** t)) + EPS)
        out.append(step)
    return out


def _run(tx: optax.GradientTransformation, steps: int) -> tuple[list[dict], optax.OptState]:
    params = jax.tree.map(jnp.zeros_like, _grads(0))
    state, updates = tx.init(params), []
    update = jax.jit(tx.update)
    for t in range(steps):
        u, state = update(_grads(t), state, params)
        updates.append(u)
    return updates, state


def test_float32_storage_is_optax_adam_and_numpy_adam():
    ours, _ = _run(scale_by_adam_stored_in("float32", B1, B2, EPS), 3)
    theirs, _ = _run(optax.scale_by_adam(B1, B2, EPS), 3)
    want = _numpy_adam([jax.tree.map(np.asarray, _grads(t)) for t in range(3)])
    for o, t, w in zip(ours, theirs, want):
        for k in w:
            np.testing.assert_allclose(o[k], t[k], rtol=1e-6, atol=1e-7)
            np.testing.assert_allclose(o[k], w[k], rtol=1e-5, atol=1e-6)


def test_bfloat16_moments_are_bf16_and_update_within_bf16_of_float32():
    (first, *_, last), state = _run(scale_by_adam_stored_in("bfloat16", B1, B2, EPS), 4)
    want = _numpy_adam([jax.tree.map(np.asarray, _grads(t)) for t in range(4)])
    assert {x.dtype for x in jax.tree.leaves((state.mu, state.nu))} == {jnp.dtype(jnp.bfloat16)}
    assert int(state.count) == 4
    for k in want[0]:
        assert first[k].dtype == jnp.float32
        # step 1 reads float32 moments back: exact up to float32; later steps read rounded ones
        np.testing.assert_allclose(first[k], want[0][k], rtol=1e-5, atol=1e-6)
        # later steps read moments rounded to bf16 (steps of 2^-8..2^-7 of their size); Adam's
        # step is O(1) per element, so the bound is absolute too, for a mu that nearly cancels
        np.testing.assert_allclose(last[k], want[3][k], rtol=2.0 ** -7, atol=2.0 ** -7)


def test_bf16_second_moment_follows_a_falling_gradient_scale():
    """The case round-to-nearest fails (module docstring): nu must decay when gradients shrink."""
    tx = scale_by_adam_stored_in("bfloat16", B1, B2, EPS)
    ref = optax.scale_by_adam(B1, B2, EPS)
    p = {"w": jnp.zeros((4096,), jnp.float32)}

    def body(carry, scale):
        ours, theirs = carry
        g = {"w": jnp.full((4096,), scale)}
        return (tx.update(g, ours)[1], ref.update(g, theirs)[1]), None

    scales = jnp.where(jnp.arange(2000) < 1000, 1.0, 0.1 ** 0.5)  # g^2: 1 then 0.1
    (ours, theirs), _ = jax.jit(lambda s: jax.lax.scan(body, (tx.init(p), ref.init(p)), s))(scales)
    want = float(theirs.nu["w"].mean())  # ~0.30
    assert abs(float(ours.nu["w"].astype(jnp.float32).mean()) / want - 1) < 0.02


def test_default_optimizer_keeps_optax_adamw_state_layout_and_updates():
    cfg = TrainConfig(weight_decay=0.1, warmup_steps=0, steps=10, lr=1e-3)
    params = {"w": jnp.ones((4, 3)), "b": jnp.ones((3,))}
    ours = build_optimizer(cfg)
    adamw = optax.chain(optax.clip_by_global_norm(cfg.clip_norm),
                        optax.adamw(optax.constant_schedule(cfg.lr), b1=cfg.b1, b2=cfg.b2, eps=cfg.eps,
                                    weight_decay=cfg.weight_decay, mask=lambda p: jax.tree.map(lambda x: x.ndim >= 2, p)))
    s_ours, s_theirs = ours.init(params), adamw.init(params)
    assert jax.tree.structure(s_ours) == jax.tree.structure(s_theirs)
    g = jax.tree.map(lambda x: 0.3 * x, params)
    u_ours, _ = ours.update(g, s_ours, params)
    u_theirs, _ = adamw.update(g, s_theirs, params)
    jax.tree.map(lambda a, b: np.testing.assert_allclose(a, b, rtol=1e-6), u_ours, u_theirs)
    bf16 = build_optimizer(apply_overrides(cfg, ["moments_dtype=bfloat16"]))
    assert jax.tree.structure(bf16.init(params)) == jax.tree.structure(s_ours)


def test_moments_dtype_is_checked():
    cfg = TrainConfig(data="synthetic")
    assert apply_overrides(cfg, ["moments_dtype=bfloat16"]).moments_dtype == "bfloat16"
    validate(apply_overrides(cfg, ["moments_dtype=bfloat16"]))
    with pytest.raises(ConfigError, match="moments_dtype 'float16'"):
        validate(apply_overrides(cfg, ["moments_dtype=float16"]))
