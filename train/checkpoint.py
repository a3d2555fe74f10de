"""Run checkpoints with orbax: trainable parameters, optimiser state, step and RNG (one pytree),
the frozen parameters, the loader's position and the validation loss, saved together.

Saves are asynchronous (training goes on while arrays are written). The last ``keep_last``
checkpoints are kept, plus the one with the lowest validation loss. Restoring takes an
abstract target carrying the CURRENT mesh's shardings, so a run saved on one mesh resumes on
another (orbax reads each shard it needs). A checkpoint that was still being written when the
process died is never listed, so resume always starts from a complete one.
"""

from __future__ import annotations

import os
from typing import Any

import jax
import orbax.checkpoint as ocp
from orbax.checkpoint import checkpoint_managers as policies


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
        items = dict(state=ocp.args.StandardSave(state), loader=ocp.args.JsonSave(loader_state),
                     meta=ocp.args.JsonSave(meta))
        if jax.tree.leaves(frozen):  # nothing frozen (training everything): orbax refuses empty trees
            items["frozen"] = ocp.args.StandardSave(frozen)
        self.manager.save(step, args=ocp.args.Composite(**items), metrics=metrics, force=True)

    def restore(self, step: int, state_like: Any, state_shardings: Any, frozen_like: Any,
                frozen_shardings: Any) -> tuple[Any, Any, dict, dict]:
        """(state, frozen, loader_state, meta) of `step`, placed with the given shardings."""
        items = dict(state=ocp.args.StandardRestore(_abstract(state_like, state_shardings)),
                     loader=ocp.args.JsonRestore(), meta=ocp.args.JsonRestore())
        if jax.tree.leaves(frozen_like):
            items["frozen"] = ocp.args.StandardRestore(_abstract(frozen_like, frozen_shardings))
        out = self.manager.restore(step, args=ocp.args.Composite(**items))
        return out["state"], out["frozen"] if "frozen" in items else frozen_like, out["loader"], out["meta"]

    def wait(self) -> None:
        """Block until every started save is on disk."""
        self.manager.wait_until_finished()

    def close(self) -> None:
        self.manager.wait_until_finished()
        self.manager.close()
