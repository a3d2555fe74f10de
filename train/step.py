"""One optimiser step: masked cross-entropy over micro-batches, gradients of the trainable
parameters only, clipped AdamW update. Jitted once with explicit shardings and with the state
it replaces donated.

The loss of a step is the mean over all scored tokens of the whole effective batch (not a mean
of per-micro-batch means), so splitting a batch into more micro-batches or over more devices
changes only float rounding.
"""

from __future__ import annotations

import math
from typing import Any, Callable

import flax.struct
import jax
import jax.numpy as jnp
import optax
from flax import nnx
from jax.sharding import Mesh, NamedSharding, PartitionSpec as P

from train.stochastic_rounding import apply_updates_rounded


# score(model, micro_batch) -> (sum of masked token NLL, number of correct argmax predictions)
Score = Callable[[nnx.Module, dict[str, jax.Array]], tuple[jax.Array, jax.Array]]


@flax.struct.dataclass
class TrainState:
    """What changes from step to step (the frozen parameters live outside it)."""

    step: jax.Array  # int32 scalar: optimiser steps taken
    params: Any  # nnx.State of the trainable parameters (master dtype)
    opt_state: Any
    rng: jax.Array  # uint32[2] raw key, split once per step


def cast_floats(tree: Any, dtype: jnp.dtype) -> Any:
    return jax.tree.map(lambda x: x.astype(dtype) if jnp.issubdtype(x.dtype, jnp.floating) else x, tree)


def _micro_shardings(batch_sharding: dict[str, NamedSharding]) -> dict[str, NamedSharding]:
    """Each batch array's layout without its leading accumulation axis: one micro-batch's rows
    keep the batch axes the run's rules table gave the whole batch (train/parallel.py)."""
    return {k: NamedSharding(s.mesh, P(*s.spec[1:])) for k, s in batch_sharding.items()}


def gathered_shardings(shardings: Any, row_axes: tuple[str, ...]) -> Any:
    """Each NamedSharding of `shardings` with the mesh axes that split the rows (FSDP's) taken
    out: the layout a weight has once gathered, still split over tensor-parallel axes."""
    def one(s: NamedSharding) -> NamedSharding:
        def keep(entry):
            names = tuple(a for a in ((entry,) if isinstance(entry, str) else entry or ()) if a not in row_axes)
            return names[0] if len(names) == 1 else (names or None)
        return NamedSharding(s.mesh, P(*(keep(e) for e in s.spec)))

    return jax.tree.map(one, shardings, is_leaf=lambda x: isinstance(x, NamedSharding))


def make_train_step(graphdef: nnx.GraphDef, score: Score, tx: optax.GradientTransformation,
                    schedule: optax.Schedule, compute_dtype: jnp.dtype, mesh: Mesh,
                    state_sharding: Any, frozen_sharding: Any, batch_sharding: Any,
                    stochastic_rounding: bool = False, gather_over: tuple[str, ...] = ()) -> Callable:
    """jit(step)(state, frozen, batch) -> (state, metrics). `batch` arrays are [accum, rows, ...].
    With `stochastic_rounding`, bf16 weights take their updates rounded stochastically, with a
    key split from the state's RNG (train/stochastic_rounding.py).

    With `gather_over` (the mesh axes the rows are split over, FSDP's), the weights are cast to
    the compute dtype and gathered over those axes once per step, before the micro-batches; every
    micro-batch (forward, rematerialised forward, backward) reads that copy, and its gradient is
    reduce-scattered back to the master layout in float32. Without it each micro-batch gathers
    the sharded weights itself (XLA does so in its forward pass and again in the rematerialised
    one), which costs collectives per micro-batch but no gathered copy in memory. With one device
    over those axes both are the same program (no copy is made)."""
    micro_spec = _micro_shardings(batch_sharding)
    gather_once = math.prod(mesh.shape[a] for a in gather_over) > 1  # on one device: nothing to gather
    if gather_once:
        params_gathered = gathered_shardings(state_sharding.params, gather_over)
        frozen_gathered = gathered_shardings(frozen_sharding, gather_over)

    def loss_sum(params, frozen, micro, n_scored):
        model = nnx.merge(graphdef, cast_floats(params, compute_dtype), cast_floats(frozen, compute_dtype))
        nll, correct = score(model, micro)
        return nll / n_scored, (nll, correct)

    grad_fn = jax.grad(loss_sum, has_aux=True)

    def step(state: TrainState, frozen, batch):
        n_scored = jnp.maximum(jnp.sum(batch["loss_mask"].astype(jnp.float32)), 1.0)
        params = state.params
        if gather_once:
            params = jax.lax.with_sharding_constraint(cast_floats(params, compute_dtype), params_gathered)
            frozen = jax.lax.with_sharding_constraint(cast_floats(frozen, compute_dtype), frozen_gathered)

        def micro_grads(micro):
            micro = {k: jax.lax.with_sharding_constraint(v, micro_spec[k]) for k, v in micro.items()}
            g, aux = grad_fn(params, frozen, micro, n_scored)
            if gather_once:  # back to the master layout, summed in float32
                g = jax.lax.with_sharding_constraint(cast_floats(g, jnp.float32), state_sharding.params)
            return g, aux

        def micro_step(carry, micro):
            grads, nll, correct = carry
            g, (m_nll, m_correct) = micro_grads(micro)
            grads = jax.tree.map(lambda a, b: a + b.astype(a.dtype), grads, g)
            return (grads, nll + m_nll, correct + m_correct), None

        if jax.tree.leaves(batch)[0].shape[0] == 1:  # no accumulation: no float32 gradient buffer
            grads, (nll, correct) = micro_grads({k: v[0] for k, v in batch.items()})
        else:
            zeros = jax.tree.map(lambda p: jnp.zeros(p.shape, jnp.float32), state.params)
            init = (zeros, jnp.zeros((), jnp.float32), jnp.zeros((), jnp.float32))
            (grads, nll, correct), _ = jax.lax.scan(micro_step, init, batch)
        grad_norm = optax.tree.norm(grads)
        grads = jax.tree.map(lambda g, p: g.astype(p.dtype), grads, state.params)
        updates, opt_state = tx.update(grads, state.opt_state, state.params)
        rng, round_key = jax.random.split(state.rng)
        if stochastic_rounding:
            params = apply_updates_rounded(state.params, updates, round_key)
        else:
            params = optax.apply_updates(state.params, updates)
        metrics = {"loss": nll / n_scored, "accuracy": correct / n_scored, "grad_norm": grad_norm,
                   "lr": schedule(state.step), "scored_tokens": n_scored}
        new = TrainState(step=state.step + 1, params=params, opt_state=opt_state, rng=rng)
        return new, metrics

    rep = NamedSharding(mesh, P())
    return jax.jit(step, in_shardings=(state_sharding, frozen_sharding, batch_sharding),
                   out_shardings=(state_sharding, rep), donate_argnums=(0,))


def make_eval_step(graphdef: nnx.GraphDef, score: Score, compute_dtype: jnp.dtype, mesh: Mesh,
                   state_sharding: Any, frozen_sharding: Any, batch_sharding: Any) -> Callable:
    """jit(eval)(params, frozen, batch) -> (nll sum, correct sum, scored tokens) over all micro-batches."""
    micro_spec = _micro_shardings(batch_sharding)

    def evaluate(params, frozen, batch):
        def body(carry, micro):
            micro = {k: jax.lax.with_sharding_constraint(v, micro_spec[k]) for k, v in micro.items()}
            model = nnx.merge(graphdef, cast_floats(params, compute_dtype), cast_floats(frozen, compute_dtype))
            nll, correct = score(model, micro)
            return (carry[0] + nll, carry[1] + correct), None

        zero = jnp.zeros((), jnp.float32)
        (nll, correct), _ = jax.lax.scan(body, (zero, zero), batch)
        return nll, correct, jnp.sum(batch["loss_mask"].astype(jnp.float32))

    rep = NamedSharding(mesh, P())
    return jax.jit(evaluate, in_shardings=(state_sharding.params, frozen_sharding, batch_sharding),
                   out_shardings=rep)
