"""Training the stage-1 image network (jax3dc.stage1_net) on records' images and parameter texts.

Targets per record: the category index; each of its Number values normalised to [0, 1] of the
entry's range; each discrete value's class. Loss: cross-entropy of the category, plus, over the
true category's values only, the mean cross-entropy of the discrete values and a weighted
smooth-L1 of the numbers (other categories' outputs get no gradient); with ``box_weight``, also
the numbers' error measured in the parts' boxes (train.stage1_box_metric: sqrt(dᵀ M d) per record,
so an error that moves no box costs nothing and one that moves a thin part costs much). Images are
shifted by a few pixels and their brightness jittered each step, which the small build needs
against overfitting. The set is put on the device once and each jitted step gathers and augments
its own batch there (on a GPU the host would otherwise be the bottleneck); optax AdamW with warm-up
and cosine decay, bounded by steps and wall time.
"""

from __future__ import annotations

import time
from dataclasses import dataclass
from typing import Callable, Mapping, Sequence

import jax
import jax.numpy as jnp
import numpy as np
import optax
from flax import nnx

from jax3dc.parameters import Count, Schema, parse_parameters
from jax3dc.stage1_net.folder import normalised_number
from jax3dc.stage1_net.layout import OutputLayout
from jax3dc.stage1_net.model import Stage1Net, forward


@dataclass(frozen=True)
class Targets:
    """Arrays of one set of records: images uint8 [B, S, S, 3] and the targets described above."""

    images: np.ndarray
    category: np.ndarray  # [B] int32
    numbers: np.ndarray  # [B, N] float32 in [0, 1]
    number_mask: np.ndarray  # [B, N] bool: the record's category owns the value
    discrete: np.ndarray  # [B, D] int32 class index
    discrete_mask: np.ndarray  # [B, D] bool
    metric_index: np.ndarray  # [B, K] int32: head index of each number the box metric covers, -1 past them
    metric: np.ndarray  # [B, K, K] float32: the box metric (zero where none was computed)

    def take(self, index: np.ndarray) -> "Targets":
        return Targets(*(getattr(self, f)[index] for f in self.__dataclass_fields__))

    def __len__(self) -> int:
        return len(self.category)


def targets(images: Sequence[np.ndarray], texts: Sequence[str], layout: OutputLayout,
            schemas: Mapping[str, Schema], box: tuple[np.ndarray, np.ndarray] | None = None) -> Targets:
    """The arrays of records given as network images (uint8) and parameter texts; ``box`` is
    (index, metric) of train.stage1_box_metric.box_metrics for the same records, or none."""
    n = len(texts)
    nn, nd = max(len(layout.numbers), 1), max(len(layout.discrete), 1)
    index, metric = box if box is not None else (np.full((n, 1), -1, np.int32), np.zeros((n, 1, 1), np.float32))
    if len(index) != n or len(metric) != n:
        raise ValueError(f"box metrics for {len(index)} records, but {n} texts")
    out = Targets(np.stack(images).astype(np.uint8), np.zeros(n, np.int32), np.zeros((n, nn), np.float32),
                  np.zeros((n, nn), bool), np.zeros((n, nd), np.int32), np.zeros((n, nd), bool),
                  np.asarray(index, np.int32), np.asarray(metric, np.float32))
    index = {c: i for i, c in enumerate(layout.categories)}
    for i, text in enumerate(texts):
        params = parse_parameters(text, schemas)
        out.category[i] = index[params.category]
        for s in layout.numbers:
            if s.category == params.category:
                value = params[s.spec.name] if s.slot is None else params[s.spec.name][s.slot]
                out.numbers[i, s.index] = normalised_number(s.spec, value)
                out.number_mask[i, s.index] = True
        for s in layout.discrete:
            if s.category == params.category:
                value = params[s.spec.name] if s.slot is None else params[s.spec.name][s.slot]
                out.discrete[i, s.index] = value - s.spec.lo if isinstance(s.spec, Count) else value
                out.discrete_mask[i, s.index] = True
    return out


@dataclass(frozen=True)
class TrainConfig:
    steps: int = 3000
    batch: int = 64
    lr: float = 2e-3
    warmup: int = 100
    weight_decay: float = 1e-4
    number_weight: float = 4.0
    box_weight: float = 0.0  # weight of the numbers' box-metric loss (needs Targets with metrics)
    discrete_weight: float = 1.0  # weight of the discrete values' cross-entropy
    shift: int = 6  # pixels of random translation
    time_limit_s: float = 600.0
    log_every: int = 100
    seed: int = 0


def augment(images: jax.Array, key: jax.Array, shift: int) -> jax.Array:
    """uint8 images [B, S, S, 3] -> floats in [0, 1], each shifted by up to ``shift`` px (edges
    repeated) and its brightness, contrast and colour balance jittered a little. Runs inside the
    jitted step, so an accelerator never waits on the host for its batch."""
    b, s = images.shape[:2]
    k_shift, k_gain, k_colour, k_contrast = jax.random.split(key, 4)
    x = images.astype(jnp.float32) / 255.0
    padded = jnp.pad(x, ((0, 0), (shift, shift), (shift, shift), (0, 0)), mode="edge")
    offsets = jax.random.randint(k_shift, (b, 2), 0, 2 * shift + 1)
    out = jax.vmap(lambda im, o: jax.lax.dynamic_slice(im, (o[0], o[1], 0), (s, s, 3)))(padded, offsets)
    gain = (jax.random.uniform(k_gain, (b, 1, 1, 1), minval=0.8, maxval=1.2)
            * jax.random.uniform(k_colour, (b, 1, 1, 3), minval=0.93, maxval=1.07))
    mean = out.mean(axis=(1, 2, 3), keepdims=True)
    contrast = jax.random.uniform(k_contrast, (b, 1, 1, 1), minval=0.8, maxval=1.2)
    return jnp.clip((out - mean) * contrast + mean * gain, 0.0, 1.0)


def box_loss(numbers: jax.Array, batch: dict) -> jax.Array:
    """Mean over the batch's records that have a metric of sqrt(dᵀ M d): the relative box error the
    number error d causes, to first order (train.stage1_box_metric)."""
    index = batch["metric_index"]
    valid = index >= 0
    d = jnp.take_along_axis(numbers - batch["numbers"], jnp.maximum(index, 0), axis=1) * valid
    q = jnp.einsum("bk,bkl,bl->b", d, batch["metric"], d)
    has = valid.any(axis=-1).astype(jnp.float32)
    return ((jnp.sqrt(jnp.maximum(q, 0.0) + 1e-4) - 1e-2) * has).sum() / jnp.maximum(has.sum(), 1.0)


def _loss(model: Stage1Net, batch: dict, class_mask: jax.Array, number_weight: float,
          box_weight: float = 0.0, discrete_weight: float = 1.0) -> tuple[jax.Array, dict]:
    category, numbers, discrete = model(batch["images"])
    ce_cat = optax.softmax_cross_entropy_with_integer_labels(category, batch["category"]).mean()
    logits = jnp.where(class_mask[None], discrete, -1e9)
    ce = optax.softmax_cross_entropy_with_integer_labels(logits, batch["discrete"])
    dmask = batch["discrete_mask"].astype(jnp.float32)
    ce_disc = (ce * dmask).sum() / jnp.maximum(dmask.sum(), 1.0)
    nmask = batch["number_mask"].astype(jnp.float32)
    err = optax.huber_loss(numbers, batch["numbers"], delta=0.1) / 0.1
    l_num = (err * nmask).sum() / jnp.maximum(nmask.sum(), 1.0)
    loss = ce_cat + discrete_weight * ce_disc + number_weight * l_num
    metrics = {"category_ce": ce_cat, "discrete_ce": ce_disc, "number_l1": l_num}
    if box_weight > 0.0:
        metrics["box"] = box_loss(numbers, batch)
        loss = loss + box_weight * metrics["box"]
    return loss, {"loss": loss, **metrics}


def learning_rate(config: TrainConfig, step: int, progress: float) -> float:
    """Linear warm-up over ``config.warmup`` steps, then a cosine to 2 % of the peak over the run's
    progress: the larger of the share of steps done and the share of the time limit used, so a run
    that its time limit ends still finishes its decay instead of stopping at a high rate."""
    warmup = min(config.warmup, config.steps // 2)
    if step <= warmup:
        return config.lr * step / max(warmup, 1)
    cosine = 0.5 * (1.0 + np.cos(np.pi * min(max(progress, 0.0), 1.0)))
    return config.lr * (0.02 + 0.98 * cosine)


def train(model: Stage1Net, data: Targets, layout: OutputLayout, config: TrainConfig,
          on_log: Callable[[dict], None] = print) -> list[dict]:
    """Trains ``model`` in place; returns the logged rows (step, seconds, losses)."""
    optimizer = nnx.Optimizer(model, optax.inject_hyperparams(optax.adamw)(learning_rate=config.lr,
                              weight_decay=config.weight_decay), wrt=nnx.Param)
    class_mask = jnp.asarray(layout.class_mask())

    # the whole set lives on the device once (an argument, not a constant baked into the program);
    # a step gathers its batch by index there
    arrays = {f: jnp.asarray(getattr(data, f)) for f in data.__dataclass_fields__}

    @nnx.jit(donate_argnums=(0, 1))
    def step(model: Stage1Net, optimizer: nnx.Optimizer, arrays: dict, index: jax.Array, key: jax.Array,
             lr: jax.Array) -> dict:
        batch = {f: a[index] for f, a in arrays.items()}
        batch["images"] = augment(batch["images"], key, config.shift)
        grads, metrics = nnx.grad(_loss, has_aux=True)(model, batch, class_mask, config.number_weight,
                                                        config.box_weight, config.discrete_weight)
        optimizer.opt_state.hyperparams["learning_rate"][...] = lr
        optimizer.update(model, grads)
        return metrics

    rng = np.random.default_rng(config.seed)
    keys = jax.random.split(jax.random.key(config.seed), config.steps)
    rows, running, start = [], [], time.perf_counter()
    order, at = rng.permutation(len(data)), 0
    for i in range(1, config.steps + 1):
        if at + config.batch > len(order):
            order, at = rng.permutation(len(data)), 0
        index = jnp.asarray(order[at:at + config.batch], jnp.int32)
        at += config.batch
        elapsed = time.perf_counter() - start
        lr = learning_rate(config, i, max(i / config.steps, elapsed / config.time_limit_s))
        running.append(step(model, optimizer, arrays, index, keys[i - 1], jnp.float32(lr)))
        if i % config.log_every == 0 or i == config.steps or elapsed > config.time_limit_s:
            row = {"step": i, "seconds": round(elapsed, 1), "lr": round(float(lr), 6),
                   **{k: round(float(np.mean([float(m[k]) for m in running])), 4) for k in running[0]}}
            rows.append(row)
            on_log(row)
            running = []
        if elapsed > config.time_limit_s:
            break
    return rows


def accuracy(model: Stage1Net, data: Targets, layout: OutputLayout, batch: int = 128) -> dict:
    """Quick held-out scores without running any factory: category accuracy, the discrete values'
    accuracy and the numbers' mean absolute error (share of the range), both on the true category."""
    cats, disc_ok, num_err = [], [], []
    class_mask = layout.class_mask()
    for lo in range(0, len(data), batch):
        part = data.take(np.arange(lo, min(lo + batch, len(data))))
        category, numbers, discrete = (np.asarray(x) for x in forward(model, part.images.astype(np.float32) / 255.0))
        cats.append(category.argmax(-1) == part.category)
        pred = np.where(class_mask[None], discrete, -np.inf).argmax(-1)
        disc_ok.append((pred == part.discrete)[part.discrete_mask])
        num_err.append(np.abs(np.clip(numbers, 0, 1) - part.numbers)[part.number_mask])
    return {"category": float(np.concatenate(cats).mean()), "discrete": float(np.concatenate(disc_ok).mean()),
            "number_mae": float(np.concatenate(num_err).mean())}
