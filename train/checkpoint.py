"""Run checkpoints with orbax: trainable parameters, optimiser state, step and RNG (one pytree),
the frozen parameters, every process's loader position and the validation loss, saved together.

Saves are asynchronous (training goes on while arrays are written). The last ``keep_last``
checkpoints are kept, plus the one with the lowest validation loss. Restoring takes an
abstract target carrying the CURRENT mesh's shardings, so a run saved on one mesh resumes on
another (orbax reads each shard it needs). A checkpoint that was still being written when the
process died is never listed, so resume always starts from a complete one.

Each process reads its own slice of the data, so each has its own loader position; orbax
writes JSON items from process 0 only, so the positions are gathered there and saved as one
list, and each process takes its own back on restore.
"""

from __future__ import annotations

import json
import os
from typing import Any

import jax
import numpy as np
import orbax.checkpoint as ocp
from jax.experimental import multihost_utils
from orbax.checkpoint import checkpoint_managers as policies

from jax3dc.errors import Jax3dcError


class CheckpointError(Jax3dcError):
    """A checkpoint that cannot continue this run (e.g. loader positions of another process count)."""


def _all_processes(state: dict) -> list[dict]:
    """Every process's loader state, in process order (a collective: all processes call it)."""
    if jax.process_count() == 1:
        return [state]

    data = np.frombuffer(json.dumps(state, sort_keys=True).encode(), np.uint8)
    longest = int(np.max(multihost_utils.process_allgather(np.asarray(data.size, np.int64))))
    padded = np.zeros(longest, np.uint8)
    padded[:data.size] = data
    rows = multihost_utils.process_allgather(padded)  # [processes, longest]
    return [json.loads(bytes(r).rstrip(b"\0")) for r in rows]


def _own(states: list[dict], where: str) -> dict:
    """This process's loader state from the saved list."""
    if len(states) == jax.process_count():
        return states[jax.process_index()]
    if all(s == states[0] for s in states):  # position-only state (e.g. synthetic data): any count
        return states[0]
    raise CheckpointError(f"{where} holds the loader positions of {len(states)} processes; this run "
                          f"has {jax.process_count()}. Resume with {len(states)} processes.")


def _abstract(tree: Any, shardings: Any) -> Any:
    """ShapeDtypeStructs with the target shardings (what orbax restores into)."""
    return jax.tree.map(lambda x, s: jax.ShapeDtypeStruct(x.shape, x.dtype, sharding=s), tree, shardings)


class RunCheckpoints:
    """The checkpoints of one run directory."""

    def __init__(self, directory: str, keep_last: int):
        self.directory = os.path.abspath(directory)
        keep = policies.AnyPreservationPolicy([
            policies.LatestN(n=keep_last),
            policies.BestN(get_metric_fn=lambda m: m["val_loss"], reverse=True, n=1,
                           keep_checkpoints_without_metrics=False),
        ])
        options = ocp.CheckpointManagerOptions(preservation_policy=keep, enable_async_checkpointing=True,
                                               create=True)
        self.manager = ocp.CheckpointManager(self.directory, options=options,
                                             item_names=("state", "frozen", "loader", "meta"))

    def latest_step(self) -> int | None:
        return self.manager.latest_step()

    def best_step(self) -> int | None:
        return self.manager.best_step()

    def all_steps(self) -> list[int]:
        return list(self.manager.all_steps())

    def save(self, step: int, state: Any, frozen: Any, loader_state: dict, meta: dict,
             val_loss: float | None = None) -> None:
        """Start writing step `step`; returns while the write goes on in the background."""
        metrics = {"val_loss": float(val_loss)} if val_loss is not None else None
        loaders = {"processes": _all_processes(loader_state)}
        items = dict(state=ocp.args.StandardSave(state), loader=ocp.args.JsonSave(loaders),
                     meta=ocp.args.JsonSave(meta))
        if jax.tree.leaves(frozen):  # nothing frozen (training everything): orbax refuses empty trees
            items["frozen"] = ocp.args.StandardSave(frozen)
        self.manager.save(step, args=ocp.args.Composite(**items), metrics=metrics, force=True)

    def restore(self, step: int, state_like: Any, state_shardings: Any, frozen_like: Any,
                frozen_shardings: Any) -> tuple[Any, Any, dict, dict]:
        """(state, frozen, this process's loader_state, meta) of `step`, placed with the given
        shardings."""
        items = dict(state=ocp.args.StandardRestore(_abstract(state_like, state_shardings)),
                     loader=ocp.args.JsonRestore(), meta=ocp.args.JsonRestore())
        if jax.tree.leaves(frozen_like):
            items["frozen"] = ocp.args.StandardRestore(_abstract(frozen_like, frozen_shardings))
        out = self.manager.restore(step, args=ocp.args.Composite(**items))
        loader_state = _own(out["loader"]["processes"], f"checkpoint {step} in {self.directory}")
        return out["state"], out["frozen"] if "frozen" in items else frozen_like, loader_state, out["meta"]

    def wait(self) -> None:
        """Block until every started save is on disk."""
        self.manager.wait_until_finished()

    def close(self) -> None:
        self.manager.wait_until_finished()
        self.manager.close()
