"""The trainer's view of the device mesh: mesh from the config, shardings for state and batches.

Parameter placement comes from each parameter's logical axis names mapped through the run's
rules table (jax3dc/sharding.py, set by TrainConfig.sharding_rules); this module adds the
trainer's side from the same table: the batch layout (rows over the ``batch`` rule's mesh axes)
and assembling each process's rows into global arrays.
"""

from __future__ import annotations

from typing import Any

import jax
import numpy as np
from jax.sharding import Mesh, NamedSharding, PartitionSpec as P

from jax3dc import sharding
from train.config import ConfigError, MeshConfig


def build_mesh(cfg: MeshConfig, devices: list | None = None) -> Mesh:
    """A mesh over all (global) devices with axes (data, fsdp, tensor)."""
    try:
        return sharding.make_mesh(cfg.data, cfg.fsdp, cfg.tensor, devices=devices)
    except ValueError as e:
        raise ConfigError(f"mesh (data, fsdp, tensor) = ({cfg.data}, {cfg.fsdp}, {cfg.tensor}): {e}") from None


def state_shardings(state: Any, mesh: Mesh, rules: sharding.Rules) -> Any:
    """NamedSharding for every variable of an nnx State, from its logical axes and the run's
    rules table (axes that do not divide a dimension are left replicated, with a warning)."""
    return sharding.state_shardings(state, mesh, rules)


def replicated(mesh: Mesh) -> NamedSharding:
    return NamedSharding(mesh, P())


def batch_axes(mesh: Mesh, rules: sharding.Rules) -> tuple[str, ...]:
    """The mesh axes batch rows are split over: the ``batch`` rule's (data x fsdp by default)."""
    return sharding.mesh_axes("batch", dict(mesh.shape), rules)


def batch_sharding(mesh: Mesh, ndim: int, leading_accum: bool, rules: sharding.Rules) -> NamedSharding:
    """Rows over the batch axes; with an accumulation axis in front, that axis is not split."""
    lead = (None,) if leading_accum else ()
    return NamedSharding(mesh, P(*lead, batch_axes(mesh, rules) or None, *([None] * (ndim - 1 - len(lead)))))


def global_batch(local: dict[str, np.ndarray], mesh: Mesh, accum: int, rules: sharding.Rules) -> dict[str, jax.Array]:
    """Assemble each process's rows into global arrays of shape [accum, rows/accum, ...].

    Every process passes its own rows (in loader order); process p's rows become rows
    [p * r, (p + 1) * r) of every micro-batch.
    """
    out = {}
    n_proc = jax.process_count()
    for key, value in local.items():
        rows = value.shape[0]
        if rows % accum:
            raise ConfigError(f"{rows} local rows do not split into {accum} micro-batches")
        shaped = value.reshape(accum, rows // accum, *value.shape[1:])
        global_shape = (accum, rows // accum * n_proc, *value.shape[1:])
        axes = batch_axes(mesh, rules)
        split = int(np.prod([mesh.shape[a] for a in axes]))
        if global_shape[1] % split:
            raise ConfigError(f"micro-batch of {global_shape[1]} rows does not split over "
                              f"{' x '.join(axes)} = {split} devices; raise batch_size or lower grad_accum")
        layout = batch_sharding(mesh, shaped.ndim, leading_accum=True, rules=rules)
        out[key] = jax.make_array_from_process_local_data(layout, shaped, global_shape)
    return out


def to_host(x: jax.Array) -> np.ndarray:
    """Value of a replicated array on this host (works when other hosts hold shards too)."""
    if x.is_fully_addressable:
        return np.asarray(x)
    return np.asarray(x.addressable_data(0))
