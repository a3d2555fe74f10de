"""Training the slots network (jax3dc.stage1_slots) on records' images and their parts.

Targets per record (``slot_targets``): each part's box from ``meta["boxes"]`` (the posed view's
boxes in the normalised frame, what the image shows), its kind from ``meta["part_names"]`` through
``jax3dc.stage1_slots.kinds`` (``other`` for a record without names) and its parent from the
record's target structure. A record with more parts than slots keeps the largest by box volume;
a kept part whose parent was dropped has no parent target.

Loss (DETR's set loss, in 3-D): slots and parts are paired one-to-one by the Hungarian algorithm
(scipy on the host, called from inside the jitted step) on a cost of box L1 + (1 - generalised
IoU) - the kind's probability - the exists probability; then exists BCE on every slot (an unpaired
slot's target is "no part", down-weighted by ``empty_weight`` as most slots are empty), and over
the paired slots box L1 + (1 - gIoU), kind cross-entropy and parent cross-entropy, whose label is
the slot paired with the part's parent, or "root". The set lives on the device and each step
gathers and augments its batch there, as train.stage1_net does.
"""

from __future__ import annotations

import json
import time
from dataclasses import dataclass
from typing import Callable, Mapping

import jax
import jax.numpy as jnp
import numpy as np
import optax
from flax import nnx
from scipy.optimize import linear_sum_assignment

from data_pipeline.record import Record
from jax3dc.stage1_slots.kinds import kind_index
from jax3dc.stage1_slots.model import SlotsNet
from train.stage1_net import augment

ROOT = -1  # a part's parent target when it is a root
UNKNOWN = -2  # a part whose parent was dropped (more parts than slots): no parent loss


@dataclass(frozen=True)
class SlotTargets:
    """Arrays of one set of records: images uint8 [N, S, S, 3] and per record up to K parts, padded."""

    images: np.ndarray
    boxes: np.ndarray  # [N, K, 6] float32: centre, extent (nu)
    kinds: np.ndarray  # [N, K] int32
    parents: np.ndarray  # [N, K] int32: index of the parent part in the same row, ROOT or UNKNOWN
    valid: np.ndarray  # [N, K] bool: a real part (not padding)

    def take(self, index: np.ndarray) -> "SlotTargets":
        return SlotTargets(*(getattr(self, f)[index] for f in self.__dataclass_fields__))

    def __len__(self) -> int:
        return len(self.images)


def slot_targets(record: Record, slots: int) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray, int]:
    """(boxes [K, 6], kinds [K], parents [K], valid [K], parts dropped) of one record; see the module
    docstring."""
    boxes = record.meta["boxes"]
    names = record.meta.get("part_names") or {}
    nodes = json.loads(record.target)["nodes"]
    volume = {pid: float(np.prod(b["extent"])) for pid, b in boxes.items()}
    kept = sorted(sorted(boxes, key=lambda pid: (-volume[pid], int(pid)))[:slots], key=int)
    row = {pid: i for i, pid in enumerate(kept)}
    out_boxes = np.zeros((slots, 6), np.float32)
    kinds = np.zeros(slots, np.int32)
    parents = np.full(slots, UNKNOWN, np.int32)
    valid = np.zeros(slots, bool)
    for i, pid in enumerate(kept):
        out_boxes[i] = [*boxes[pid]["centroid"], *boxes[pid]["extent"]]
        kinds[i] = kind_index(names.get(pid))
        parent = nodes.get(pid, {}).get("parent")
        parents[i] = ROOT if parent is None else row.get(str(parent), UNKNOWN)
        valid[i] = True
    return out_boxes, kinds, parents, valid, len(boxes) - len(kept)


def stack_targets(images: list[np.ndarray], rows: list[tuple]) -> SlotTargets:
    """SlotTargets of network images (uint8) and their ``slot_targets`` rows."""
    return SlotTargets(np.stack(images).astype(np.uint8), *(np.stack([r[k] for r in rows]) for k in range(4)))


def corners(boxes: jax.Array) -> tuple[jax.Array, jax.Array]:
    """(lo, hi) of centre-extent boxes [..., 6]."""
    centre, half = boxes[..., :3], jnp.abs(boxes[..., 3:]) / 2.0
    return centre - half, centre + half


def giou(a: jax.Array, b: jax.Array) -> jax.Array:
    """Generalised IoU of axis-aligned 3-D boxes (centre, extent) [..., 6], broadcast: IoU minus the
    share of the smallest enclosing box that neither fills. In [-1, 1]."""
    a_lo, a_hi = corners(a)
    b_lo, b_hi = corners(b)
    inter = jnp.prod(jnp.clip(jnp.minimum(a_hi, b_hi) - jnp.maximum(a_lo, b_lo), 0.0), axis=-1)
    union = jnp.prod(a_hi - a_lo, axis=-1) + jnp.prod(b_hi - b_lo, axis=-1) - inter
    enclosing = jnp.prod(jnp.maximum(a_hi, b_hi) - jnp.minimum(a_lo, b_lo), axis=-1)
    eps = 1e-9
    return inter / (union + eps) - (enclosing - union) / (enclosing + eps)


@dataclass(frozen=True)
class SlotsTrainConfig:
    steps: int = 20000
    batch: int = 128
    lr: float = 5e-4
    warmup: int = 500
    weight_decay: float = 1e-4
    box_weight: float = 5.0  # box L1
    giou_weight: float = 2.0
    kind_weight: float = 1.0
    exists_weight: float = 1.0
    parent_weight: float = 1.0
    empty_weight: float = 0.25  # weight of an empty slot's exists loss
    shift: int = 6  # pixels of random translation
    time_limit_s: float = 3600.0
    log_every: int = 100
    seed: int = 0


def _assign(cost: np.ndarray) -> np.ndarray:
    """Target row of each slot [B, K] from costs [B, K slots, K targets] (square: every slot gets a row)."""
    out = np.empty(cost.shape[:2], np.int32)
    for b, c in enumerate(np.asarray(cost, np.float64)):
        rows, cols = linear_sum_assignment(np.nan_to_num(c, nan=1e6, posinf=1e6, neginf=-1e6))
        out[b, rows] = cols
    return out


def match(outputs: tuple, batch: Mapping[str, jax.Array], config: SlotsTrainConfig) -> jax.Array:
    """The Hungarian pairing [B, K] (target row of each slot) of the module docstring; padding rows
    cost nothing, so they take the slots no part wants."""
    exists, boxes, kinds, _ = (jax.lax.stop_gradient(x) for x in outputs)
    pred, target = boxes[:, :, None], batch["boxes"][:, None]
    kind_p = jnp.take_along_axis(jax.nn.softmax(kinds, -1)[:, :, None, :],
                                 batch["kinds"][:, None, :, None], axis=-1)[..., 0]
    cost = (config.box_weight * jnp.abs(pred - target).sum(-1) + config.giou_weight * (1.0 - giou(pred, target))
            - config.kind_weight * kind_p - config.exists_weight * jax.nn.sigmoid(exists)[:, :, None])
    cost = jnp.where(batch["valid"][:, None, :], cost, 0.0)
    shape = jax.ShapeDtypeStruct(cost.shape[:2], jnp.int32)
    return jax.pure_callback(_assign, shape, cost, vmap_method="sequential")


def slots_loss(model: SlotsNet, batch: Mapping[str, jax.Array], config: SlotsTrainConfig) -> tuple[jax.Array, dict]:
    """The set loss of the module docstring and its parts."""
    outputs = model(batch["images"])
    exists, boxes, kinds, parents = outputs
    k = exists.shape[1]
    target_of_slot = match(outputs, batch, config)  # [B, K]
    slot_of_target = jnp.argsort(target_of_slot, axis=-1)  # the inverse permutation
    take = lambda a: jnp.take_along_axis(a, target_of_slot if a.ndim == 2 else target_of_slot[..., None], axis=1)
    paired = take(batch["valid"]).astype(jnp.float32)
    n = jnp.maximum(paired.sum(), 1.0)
    bce = optax.sigmoid_binary_cross_entropy(exists, paired)
    weight = paired + config.empty_weight * (1.0 - paired)
    l_exists = (bce * weight).sum() / weight.sum()
    t_boxes = take(batch["boxes"])
    l_box = (jnp.abs(boxes - t_boxes).sum(-1) * paired).sum() / n
    l_giou = ((1.0 - giou(boxes, t_boxes)) * paired).sum() / n
    l_kind = (optax.softmax_cross_entropy_with_integer_labels(kinds, take(batch["kinds"])) * paired).sum() / n
    parent_row = take(batch["parents"])
    label = jnp.where(parent_row == ROOT, k, jnp.take_along_axis(slot_of_target, jnp.maximum(parent_row, 0), axis=1))
    has_parent = paired * (parent_row != UNKNOWN)
    l_parent = ((optax.softmax_cross_entropy_with_integer_labels(parents, label) * has_parent).sum()
                / jnp.maximum(has_parent.sum(), 1.0))
    loss = (config.exists_weight * l_exists + config.box_weight * l_box + config.giou_weight * l_giou
            + config.kind_weight * l_kind + config.parent_weight * l_parent)
    return loss, {"loss": loss, "exists": l_exists, "box_l1": l_box, "giou": l_giou, "kind": l_kind,
                  "parent": l_parent}


def train(model: SlotsNet, data: SlotTargets, config: SlotsTrainConfig,
          on_log: Callable[[dict], None] = print) -> list[dict]:
    """Trains ``model`` in place; returns the logged rows (step, seconds, steps/s, losses)."""
    schedule = optax.warmup_cosine_decay_schedule(0.0, config.lr, min(config.warmup, config.steps // 2),
                                                  max(config.steps, 1), end_value=0.02 * config.lr)
    optimizer = nnx.Optimizer(model, optax.chain(optax.clip_by_global_norm(1.0),
                                                 optax.adamw(schedule, weight_decay=config.weight_decay)),
                              wrt=nnx.Param)
    arrays = {f: jnp.asarray(getattr(data, f)) for f in data.__dataclass_fields__}

    @nnx.jit(donate_argnums=(0, 1))
    def step(model: SlotsNet, optimizer: nnx.Optimizer, arrays: dict, index: jax.Array, key: jax.Array) -> dict:
        batch = {f: a[index] for f, a in arrays.items()}
        batch["images"] = augment(batch["images"], key, config.shift)
        grads, metrics = nnx.grad(slots_loss, has_aux=True)(model, batch, config)
        optimizer.update(model, grads)
        return metrics

    rng = np.random.default_rng(config.seed)
    keys = jax.random.split(jax.random.key(config.seed), config.steps)
    rows, running, start, last = [], [], time.perf_counter(), (0, 0.0)
    order, at = rng.permutation(len(data)), 0
    batch = min(config.batch, len(data))
    for i in range(1, config.steps + 1):
        if at + batch > len(order):
            order, at = rng.permutation(len(data)), 0
        index = jnp.asarray(order[at:at + batch], jnp.int32)
        at += batch
        running.append(step(model, optimizer, arrays, index, keys[i - 1]))
        elapsed = time.perf_counter() - start
        if i % config.log_every == 0 or i == config.steps or elapsed > config.time_limit_s:
            means = {k: round(float(np.mean([float(m[k]) for m in running])), 4) for k in running[0]}
            rate = (i - last[0]) / max(elapsed - last[1], 1e-9)
            row = {"step": i, "seconds": round(elapsed, 1), "steps_per_s": round(rate, 2), **means}
            rows.append(row)
            on_log(row)
            running, last = [], (i, elapsed)
        if elapsed > config.time_limit_s:
            break
    return rows
