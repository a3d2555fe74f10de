"""A training run from start (or from its latest checkpoint) to the exported model.

    state <- latest checkpoint of output_dir, else fresh (preset weights or HF checkpoint)
    repeat until `steps`: next batch -> jitted step -> loss finite? -> log / validate / save
    final checkpoint, then the model as an HF directory in output_dir/hf

A non-finite loss stops the run before anything from that step is saved, so the latest
checkpoint on disk is the last good one; the error message names it.
"""

from __future__ import annotations

import math
import os
import time
from dataclasses import dataclass
from typing import Callable, Iterator

import jax
import jax.numpy as jnp
import numpy as np
import optax
from jax.experimental import multihost_utils
from jax.sharding import Mesh

from jax3dc import sharding
from jax3dc.compilation import CompileClock
from jax3dc.errors import Jax3dcError
from train import model_state
from train.batch import check_batch
from train.checkpoint import RunCheckpoints
from train.config import TrainConfig, sharding_rules, to_json, validate
from train.data import make_loader, run_pivot_frame, run_processor, run_tokenizer
from train.metrics_log import FlopsModel, MetricsLog, peak_flops, peak_memory_gib, plot_losses
from train.optimizer import build_optimizer, learning_rate
from train.parallel import batch_axes, batch_sharding, build_mesh, global_batch, replicated, to_host
from train.step import TrainState, make_eval_step, make_train_step


class NonFiniteLossError(Jax3dcError):
    """The loss became NaN or infinite; the run stopped without saving that step."""


@dataclass
class RunResult:
    final_step: int
    last_loss: float
    best_val_loss: float | None
    output_dir: str


def attention_backend(setting: str) -> str | None:
    """jax.nn.dot_product_attention's implementation: cuDNN's fused kernel on GPUs (jax's own
    default is plain XLA, which writes every [heads, L, L] score matrix to memory), else XLA."""
    if setting == "auto":
        return "cudnn" if jax.default_backend() == "gpu" else None
    return None if setting == "xla" else setting


def opt_state_shardings(tx: optax.GradientTransformation, params, params_sharding, mesh: Mesh):
    """Moments are placed like their parameters; counters and the like are replicated."""
    shapes = jax.eval_shape(tx.init, params)
    return optax.tree_map_params(tx, lambda _, s: s, shapes, params_sharding,
                                 transform_non_params=lambda _: replicated(mesh))


class Trainer:
    """Holds the mesh, model, optimiser, jitted steps and checkpoints of one run."""

    def __init__(self, cfg: TrainConfig, attention_impl: str | None = None):
        validate(cfg)
        self.cfg = cfg
        attention_impl = attention_impl or attention_backend(cfg.attention)
        self.mesh = build_mesh(cfg.mesh)
        self.rules = sharding_rules(cfg)
        real_data = cfg.data != "synthetic"
        self.tokenizer = run_tokenizer(cfg) if real_data else None  # synthetic ids need none
        self.model = model_state.create(cfg, self.mesh, attention_impl, self.tokenizer if real_data else None)
        self.processor = run_processor(cfg, self.model.config)
        self.tx = build_optimizer(cfg)
        self.schedule = learning_rate(cfg)
        rep = replicated(self.mesh)
        opt_sh = opt_state_shardings(self.tx, self.model.trainable, self.model.trainable_sharding, self.mesh)
        opt_state = jax.jit(self.tx.init, out_shardings=opt_sh)(self.model.trainable)
        rng = jax.device_put(jax.random.key_data(jax.random.key(cfg.seed)), rep)
        self.state = TrainState(step=jax.device_put(jnp.zeros((), jnp.int32), rep),
                                params=self.model.trainable, opt_state=opt_state, rng=rng)
        self.state_sharding = TrainState(step=rep, params=self.model.trainable_sharding,
                                         opt_state=opt_sh, rng=rep)
        self.model.trainable = None  # owned by self.state from here on (donated each step)
        self.accum = cfg.grad_accum
        self._train_step = self._eval_step = None

    # ------------------------------------------------------------------ steps
    def _batch_shardings(self, batch: dict) -> dict:
        return {k: batch_sharding(self.mesh, v.ndim, leading_accum=True, rules=self.rules) for k, v in batch.items()}

    def train_step(self, batch: dict) -> dict:
        """One optimiser step on this process's rows `batch`; returns device metrics."""
        check_batch(batch, self.cfg.batch_size // jax.process_count(), self.cfg.seq_len)
        g = global_batch(batch, self.mesh, self.accum, self.rules)
        if self._train_step is None:
            compute, _ = model_state.dtypes(self.cfg)
            self._train_step = make_train_step(
                self.model.graphdef, model_state.score, self.tx, self.schedule, compute, self.mesh,
                self.state_sharding, self.model.frozen_sharding, self._batch_shardings(g),
                stochastic_rounding=self.cfg.stochastic_rounding,
                gather_over=batch_axes(self.mesh, self.rules) if self.cfg.weight_gather == "step" else ())
        # the mesh activates the model's activation constraints; the rules reach them and the loss
        with jax.set_mesh(self.mesh), sharding.use_rules(self.rules):
            self.state, metrics = self._train_step(self.state, self.model.frozen, g)
        return metrics

    def validate(self, loader: Iterator, batches: int) -> float:
        """Mean token NLL over `batches` batches of `loader`."""
        nll = scored = 0.0
        for _ in range(batches):
            g = global_batch(next(loader), self.mesh, self.accum, self.rules)
            if self._eval_step is None:
                compute, _ = model_state.dtypes(self.cfg)
                self._eval_step = make_eval_step(
                    self.model.graphdef, model_state.score, compute, self.mesh, self.state_sharding,
                    self.model.frozen_sharding, self._batch_shardings(g))
            with jax.set_mesh(self.mesh), sharding.use_rules(self.rules):
                n, _, s = self._eval_step(self.state.params, self.model.frozen, g)
            nll += float(to_host(n))
            scored += float(to_host(s))
        return nll / max(scored, 1.0)

    # ------------------------------------------------------------------ checkpoints
    def restore(self, ckpt: RunCheckpoints, step: int) -> tuple[dict, dict]:
        state, frozen, loader_state, meta = ckpt.restore(step, self.state, self.state_sharding,
                                                         self.model.frozen, self.model.frozen_sharding)
        self.state, self.model.frozen = state, frozen
        return loader_state, meta

    def save(self, ckpt: RunCheckpoints, loader, val_loss: float | None, best_val: float | None) -> None:
        step = int(to_host(self.state.step))
        ckpt.save(step, self.state, self.model.frozen, loader.get_state(),
                  {"step": step, "val_loss": val_loss, "best_val_loss": best_val}, val_loss=val_loss)

    def export(self, directory: str) -> None:
        """Every process calls this: the export gathers each tensor collectively; process 0 writes."""
        self.model.trainable = self.state.params
        model_state.export_hf(self.model, directory, self.tokenizer, self.processor,
                               run_pivot_frame(self.cfg))
        self.model.trainable = None

    def flops_model(self) -> FlopsModel:
        patches = (self.cfg.image_size // self.model.config.vision.patch_size) ** 2 if self.cfg.image_size else 0
        frozen = self.model.frozen  # the vision tower's frozen part runs forward only
        vision = model_state.count_params(frozen["visual"]) if "visual" in frozen else 0
        return FlopsModel.from_model_config(self.model.config, vision_params=vision,
                                            patches_per_image=patches, weight_grads=not self.cfg.lora_rank)


def run(cfg: TrainConfig, on_step: Callable[[int, dict], None] | None = None,
        attention_impl: str | None = None) -> RunResult:
    """Train per `cfg`, resuming from output_dir's latest checkpoint if there is one.

    `on_step(step, metrics)` is called after every step with host floats (for tools and tests).
    """
    validate(cfg)  # before output_dir exists: a run that cannot start leaves nothing behind
    out = cfg.output_dir
    lead = jax.process_index() == 0
    if lead:
        os.makedirs(out, exist_ok=True)
        with open(os.path.join(out, "config.json"), "w") as f:
            f.write(to_json(cfg))
    trainer = Trainer(cfg, attention_impl)
    loader = make_loader(cfg, trainer.model.config, "train", trainer.tokenizer, trainer.processor)
    if cfg.eval_batches:  # a validation split without records must stop the run now, not after training
        _check_val_data(cfg, trainer)
    ckpt = RunCheckpoints(os.path.join(out, "checkpoints"), cfg.keep_last)
    start = ckpt.latest_step() or 0
    log = MetricsLog(out, total_steps=cfg.steps, first_step=start, enabled=lead)
    best_val = None
    if start:
        loader_state, meta = trainer.restore(ckpt, start)
        loader.set_state(loader_state)
        best_val = meta.get("best_val_loss")
        log.message(f"resumed from step {start} ({ckpt.directory})")
    flops = trainer.flops_model()
    peak = peak_flops(jax.devices()[0].device_kind)
    tokens_per_step = cfg.batch_size * cfg.seq_len
    last_loss = math.nan
    timer, timed_steps, wait_s, save_s = None, 0, 0.0, 0.0
    deadline = time.monotonic() + 60 * cfg.time_limit_min if cfg.time_limit_min else None
    step = start
    clock = CompileClock()
    started = time.perf_counter()
    try:
        for step in range(start + 1, cfg.steps + 1):
            waited = time.perf_counter()
            batch = next(loader)
            wait_s += time.perf_counter() - waited
            metrics = trainer.train_step(batch)
            last = step == cfg.steps or _out_of_time(deadline)
            saving = step % cfg.save_every == 0 or last
            validating = bool(cfg.eval_batches) and (step % cfg.eval_every == 0 or last)
            logging = step % cfg.log_every == 0 or last
            first = timer is None
            # Metrics stay on the device between log steps, so the host dispatches the next steps
            # while this one runs; they are read back to log, before a checkpoint (a non-finite loss
            # is never saved), on the compiling first step, and every step when a caller watches.
            values: dict[str, float] = {}
            if logging or saving or validating or first or on_step is not None:
                values = {k: float(to_host(v)) for k, v in metrics.items()}
                if not math.isfinite(values["loss"]):
                    ckpt.wait()
                    good = ckpt.latest_step()
                    raise NonFiniteLossError(
                        f"loss is {values['loss']} at step {step} (read back every {cfg.log_every} steps, so it may "
                        f"have turned non-finite a few steps before); stopped without saving it. Last good checkpoint: "
                        f"{'step %d in %s' % (good, ckpt.directory) if good else 'none'}")
                last_loss = values["loss"]
            if first:  # the first step compiles: log its time and where it went, and time the rest from its end
                values["compile_s"] = time.perf_counter() - started - wait_s
                values.update(clock.elapsed())  # trace_s, lower_s, xla_s, compiles, cache_hits
                timer, wait_s, logging = time.perf_counter(), 0.0, True
            else:
                timed_steps += 1
            if logging:
                if timed_steps:
                    dt = (time.perf_counter() - timer) / timed_steps
                    values["tokens_per_s"] = tokens_per_step / dt
                    values["data_wait_frac"] = wait_s / (dt * timed_steps)  # > 0.1: the loader limits the run
                    if peak:
                        values["mfu"] = flops.step_flops(cfg.batch_size, cfg.seq_len) / dt / (peak * jax.device_count())
                    timer, timed_steps = time.perf_counter(), 0
                memory = peak_memory_gib(jax.local_devices())
                if memory is not None:
                    values["peak_mem_gib"] = memory
                if save_s:
                    values["save_s"] = save_s
                wait_s = save_s = 0.0
                values.update({f"skipped_{k}": float(v) for k, v in getattr(loader, "skipped", {}).items()})
                log.write(step, values)
            val_loss = None
            if validating:
                val_loss = trainer.validate(make_loader(cfg, trainer.model.config, "val", trainer.tokenizer, trainer.processor), cfg.eval_batches)
                best_val = val_loss if best_val is None else min(best_val, val_loss)
                log.write(step, {"loss": val_loss}, kind="val")
            if saving:  # asynchronous: save_s is how long the run waited (the copy off the device)
                saved = time.perf_counter()
                trainer.save(ckpt, loader, val_loss, best_val)
                save_s += time.perf_counter() - saved
            log.advance()
            if on_step is not None:
                on_step(step, values)
            if last:
                break
        ckpt.wait()
        if step < cfg.steps:
            log.message(f"time limit of {cfg.time_limit_min} min reached: stopped at step {step} of {cfg.steps}")
        if cfg.export_hf and step > start:
            trainer.export(os.path.join(out, "hf"))
    finally:
        ckpt.close()
        log.close()
    if lead and step > start:
        plot_losses(out)
    return RunResult(step, last_loss, best_val, out)


def _check_val_data(cfg: TrainConfig, trainer: Trainer) -> None:
    """Reads one validation batch; the loader's error is re-raised with how to go on without."""
    from data_pipeline.loader import LoaderError  # lazy: as in train.data.make_loader (0.06 s)

    try:
        next(make_loader(cfg, trainer.model.config, "val", trainer.tokenizer, trainer.processor))
    except LoaderError as e:
        raise LoaderError(f"validation data: {e}. Give it with --set val_data=DIR, or train without "
                          "validation with --set eval_batches=0") from None


def _out_of_time(deadline: float | None) -> bool:
    """Whether the run's time is up; every process takes process 0's answer so all stop together."""
    if deadline is None:
        return False
    late = time.monotonic() > deadline
    if jax.process_count() > 1:
        late = bool(multihost_utils.broadcast_one_to_all(np.asarray(late)))
    return late
