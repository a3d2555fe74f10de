"""The trainer's view of the device mesh: mesh from the config, shardings for state and batches.

Parameter placement comes from each parameter's logical axis names mapped through the one
rules table in jax3dc/sharding.py; this module adds the trainer's side: the batch layout (rows
over data x fsdp) and assembling each process's rows into global arrays.
"""

from __future__ import annotations

from typing import Any

import jax
import numpy as np
from jax.sharding import Mesh, NamedSharding, PartitionSpec as P

from jax3dc import sharding
from train.config import ConfigError, MeshConfig

BATCH_AXES = ("data", "fsdp")  # batch rows are split over both: fsdp is data parallel for activations


def build_mesh(cfg: MeshConfig, devices: list | None = None) -> Mesh:
    """A mesh over all (global) devices with axes (data, fsdp, tensor)."""
    try:
        return sharding.make_mesh(cfg.data, cfg.fsdp, cfg.tensor, devices=devices)
    except ValueError as e:
        raise ConfigError(f"mesh (data, fsdp, tensor) = ({cfg.data}, {cfg.fsdp}, {cfg.tensor}): {e}") from None


def state_shardings(state: Any, mesh: Mesh) -> Any:
    """NamedSharding for every variable of an nnx State, from its logical axes and the one
    rules table (axes that do not divide a dimension are left replicated)."""
    return sharding.state_shardings(state, mesh, sharding.LOGICAL_RULES)


def replicated(mesh: Mesh) -> NamedSharding:
    return NamedSharding(mesh, P())


def batch_sharding(mesh: Mesh, ndim: int, leading_accum: bool) -> NamedSharding:
    """Rows over (data, fsdp); with an accumulation axis in front, that axis is not split."""
    lead = (None,) if leading_accum else ()
    return NamedSharding(mesh, P(*lead, BATCH_AXES, *([None] * (ndim - 1 - len(lead)))))


def global_batch(local: dict[str, np.ndarray], mesh: Mesh, accum: int) -> dict[str, jax.Array]:
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
        split = mesh.shape["data"] * mesh.shape["fsdp"]
        if global_shape[1] % split:
            raise ConfigError(f"micro-batch of {global_shape[1]} rows does not split over "
                              f"data x fsdp = {split} devices; raise batch_size or lower grad_accum")
        sharding = batch_sharding(mesh, shaped.ndim, leading_accum=True)
        out[key] = jax.make_array_from_process_local_data(sharding, shaped, global_shape)
    return out


def to_host(x: jax.Array) -> np.ndarray:
    """Value of a replicated array on this host (works when other hosts hold shards too)."""
    if x.is_fully_addressable:
        return np.asarray(x)
    return np.asarray(x.addressable_data(0))
