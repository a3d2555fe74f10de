"""The grain pipeline from ArrayRecord shards to training batches (the protocol of train/batch.py).

    shards of each dataset -> this process's slice -> shuffle (new order every epoch) -> repeat
      -> weighted mixture of the datasets -> decode PNGs + image preprocessing + chat tokens
      -> length policy -> packing into rows -> batches        (in `workers` processes)
      -> this process's batch; the trainer makes global device arrays of every process's rows

Deterministic for a seed: the same batches in the same order whatever the machine, and the
iterator state (grain's state plus the skip counters) is JSON, saved with the training
checkpoint, so a resumed run sees exactly the batches it would have seen.

Nothing is cut: an example longer than a row is skipped and counted (``too_long``), as is a
record that cannot be decoded (``corrupt``), has no part program for the code task
(``no_program``) or no factory parameters for the parameters task (``no_parameters``); the first
of each kind is logged with its key.
"""

from __future__ import annotations

import logging
from collections import Counter
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any, Iterator, Mapping, Sequence

import grain
import numpy as np
from absl import flags

from data_pipeline.examples import IMAGES_PER_TASK, TASKS, ExampleEncoder, UnusableRecord
from data_pipeline.packing import Example, RowLayout, pack_row
from data_pipeline.record import CorruptRecordError, decode_record
from data_pipeline.shards import shard_paths
from jax3dc.errors import Jax3dcError
from jax3dc.model.config import Qwen3VLConfig
from jax3dc.processing.processor import ImageProcessorConfig, smart_resize
from jax3dc.processing.tokenizer import Tokenizer
from jax3dc.structure.box_frame import PivotFrame

log = logging.getLogger(__name__)

SKIP_REASONS = ("corrupt", "too_long", "no_program", "no_parameters", "other_split")


class LoaderError(Jax3dcError):
    """The loader cannot be built as configured (no shards, bad weights, unknown task)."""


@dataclass(frozen=True)
class LoaderConfig:
    """What the loader reads and how it shapes batches."""

    sources: tuple[str, ...]  # dataset folders (or shard files)
    seq_len: int
    rows: int  # rows per batch on THIS process
    split: str = "train"
    task: str = "structure"
    tasks: tuple[str, ...] = ()  # one per source (the same folder may appear under both); empty: `task` for all
    weights: tuple[float, ...] = ()  # one per source; empty: equal
    pack: int = 6  # examples per row at most (1: no packing, one padded example per row)
    pixel_dtype: str = "float32"  # float32 (exact) or bfloat16 (half the bytes; for bf16 models)
    image_size: int = 0  # square side I and S are resized to (0: as stored, must agree)
    seed: int = 0
    shuffle: bool = True
    workers: int = 0  # grain worker processes (0: decode in this process)
    worker_buffer: int = 2  # batches each worker prepares ahead
    process_index: int = 0
    process_count: int = 1
    pivot_frame: PivotFrame = PivotFrame()  # how structure targets write joint pivots
    score_placeholder_materials: bool = False  # see ExampleEncoder


@dataclass(frozen=True)
class Skipped:
    key: str
    reason: str
    message: str


@dataclass
class _Decode:
    """Record bytes -> Example or Skipped (a bad record must not stop training)."""

    encoder: ExampleEncoder
    split: str

    def __call__(self, blob: bytes) -> Example | Skipped:
        try:
            record = decode_record(blob)
        except CorruptRecordError as e:
            return Skipped("?", "corrupt", str(e))
        if record.meta.get("split", self.split) != self.split:
            return Skipped(record.key, "other_split", "")
        try:
            return self.encoder.encode(record)
        except UnusableRecord as e:
            return Skipped(record.key, e.reason, str(e))


class _PackedBatches(grain.IterDataset):
    """Examples -> (batch, skip counts since the previous batch)."""

    def __init__(self, parent: grain.IterDataset, layout: RowLayout, rows: int, dry_limit: int, what: str):
        super().__init__(parent)
        self.layout, self.rows, self.dry_limit, self.what = layout, rows, dry_limit, what

    def __iter__(self) -> "_PackedBatchIterator":
        return _PackedBatchIterator(self._parent.__iter__(), self.layout, self.rows, self.dry_limit, self.what)


class _PackedBatchIterator(grain.DatasetIterator):
    """Greedy, in-order packing. An example that does not fit the last row of a batch opens the
    next batch; the state then points just before it (the parent's state taken before pulling
    it), so a restored iterator reads it again instead of needing it stored.

    The records repeat forever, so a split with no usable record would be read forever: after
    ``dry_limit`` skipped records in a row (more than a full pass) it raises LoaderError."""

    def __init__(self, parent: grain.DatasetIterator, layout: RowLayout, rows: int, dry_limit: int, what: str):
        super().__init__(parent)
        self.layout, self.rows, self.dry_limit, self.what = layout, rows, dry_limit, what
        self._carry: Example | None = None
        self._carry_state: dict | None = None
        self._dry: Counter = Counter()  # skipped records since the last usable one

    def _pull(self) -> tuple[Example | Skipped, dict | None]:
        if self._carry is not None:
            item, state = self._carry, self._carry_state
            self._carry = self._carry_state = None
            return item, state
        state = self._parent.get_state()
        return next(self._parent), state

    def __next__(self) -> tuple[dict[str, np.ndarray], dict[str, int]]:
        L, pack = self.layout.seq_len, self.layout.pack
        rows: list[list[Example]] = []
        current: list[Example] = []
        used = 0
        skipped: Counter = Counter()
        while len(rows) < self.rows:
            try:
                item, state = self._pull()
            except StopIteration:
                if not rows and not current:
                    raise
                break
            if isinstance(item, Skipped) or len(item) > L:
                reason = item.reason if isinstance(item, Skipped) else "too_long"
                skipped[reason] += 1
                self._dry[reason] += 1
                if sum(self._dry.values()) > self.dry_limit:
                    counts = ", ".join(f"{n} {r}" for r, n in sorted(self._dry.items()))
                    raise LoaderError(f"{self.what}: no usable record in more than a full pass over them ({counts})")
                continue
            self._dry.clear()
            if current and (used + len(item) > L or len(current) == pack):
                rows.append(current)
                current, used = [], 0
                if len(rows) == self.rows:
                    self._carry, self._carry_state = item, state
                    break
            current.append(item)
            used += len(item)
        if current and len(rows) < self.rows:
            rows.append(current)
        while len(rows) < self.rows:  # only at the end of a finite pass: padding rows
            rows.append([])
        packed = [pack_row(r, self.layout) for r in rows]
        batch = {k: np.stack([p[k] for p in packed]) for k in packed[0]}
        return batch, dict(skipped)

    def get_state(self) -> dict[str, Any]:
        return self._carry_state if self._carry is not None else self._parent.get_state()

    def set_state(self, state: dict[str, Any]) -> None:
        self._parent.set_state(state)
        self._carry = self._carry_state = None


def row_layout(cfg: LoaderConfig, model: Qwen3VLConfig, tokenizer: Tokenizer,
               processor: ImageProcessorConfig) -> RowLayout:
    if not cfg.image_size:
        raise LoaderError("image_size must be set: rows hold images of one fixed size")
    if processor.patch_size != model.vision.patch_size or processor.merge_size != model.vision.spatial_merge_size:
        raise LoaderError(f"image processor (patch {processor.patch_size}, merge {processor.merge_size}) does not "
                          f"match the model (patch {model.vision.patch_size}, merge {model.vision.spatial_merge_size})")
    special = tokenizer.special
    for name, ours, model_id in (("<|image_pad|>", special.image_pad, model.image_token_id),
                                 ("<|vision_start|>", special.vision_start, model.vision_start_token_id),
                                 ("<|vision_end|>", special.vision_end, model.vision_end_token_id)):
        if ours != model_id:
            raise LoaderError(f"tokenizer {tokenizer.source} has {name} = {ours}, the model expects {model_id}")
    h, w = smart_resize(cfg.image_size, cfg.image_size, processor.factor, processor.min_pixels, processor.max_pixels)
    images = max(IMAGES_PER_TASK[t] for t in source_tasks(cfg))
    return RowLayout(seq_len=cfg.seq_len, pack=cfg.pack, images_per_example=images,
                     grid=(1, h // processor.patch_size, w // processor.patch_size), patch_dim=model.vision.patch_dim,
                     pad_id=tokenizer.special.endoftext, image_token_id=model.image_token_id,
                     merge=model.vision.spatial_merge_size, pixel_dtype=cfg.pixel_dtype)


def source_tasks(cfg: LoaderConfig) -> tuple[str, ...]:
    """The task of each source: ``cfg.tasks`` when given (one per source), else ``cfg.task`` for all."""
    tasks = cfg.tasks or (cfg.task,) * len(cfg.sources)
    if len(tasks) != len(cfg.sources):
        raise LoaderError(f"{len(tasks)} tasks for {len(cfg.sources)} sources")
    unknown = [t for t in tasks if t not in TASKS]
    if unknown:
        raise LoaderError(f"task {unknown[0]!r}: expected one of {TASKS}")
    return tuple(tasks)


def _source(path_list: Sequence[Path], cfg: LoaderConfig) -> tuple[grain.MapDataset, int]:
    """This process's records of one dataset, repeated forever, and how many there are."""
    ds = grain.MapDataset.source(grain.sources.ArrayRecordDataSource([str(p) for p in path_list]))
    if len(ds) < cfg.process_count:
        raise LoaderError(f"{len(ds)} records cannot be shared by {cfg.process_count} processes")
    ds = ds[cfg.process_index::cfg.process_count]  # disjoint slices that together cover the data
    if cfg.shuffle:
        ds = ds.shuffle(seed=cfg.seed)
    return ds.repeat(None), len(ds)


def _full_pass(lengths: Sequence[int], weights: Sequence[float]) -> int:
    """Draws from the mixture after which every source (``lengths`` records each) has been read
    through at least once, twice over for the mixture's rounding: a bound on skips in a row."""
    weights = list(weights) or [1.0] * len(lengths)
    total = sum(weights)
    return 2 * max(int(np.ceil(n * total / w)) for n, w in zip(lengths, weights) if w > 0) + 16


def build_dataset(cfg: LoaderConfig, model: Qwen3VLConfig, tokenizer: Tokenizer,
                  processor: ImageProcessorConfig) -> grain.IterDataset:
    """The whole pipeline as a grain IterDataset of (batch, skip counts)."""
    if not cfg.sources:
        raise LoaderError("no data sources given")
    tasks = source_tasks(cfg)
    if cfg.weights and len(cfg.weights) != len(cfg.sources):
        raise LoaderError(f"{len(cfg.weights)} weights for {len(cfg.sources)} sources")
    if cfg.weights and min(cfg.weights) <= 0:  # grain's mix refuses a zero proportion
        bad = next(s for s, w in zip(cfg.sources, cfg.weights) if w <= 0)
        raise LoaderError(f"mixture weights {cfg.weights} must all be > 0 ({bad} has "
                          f"{cfg.weights[cfg.sources.index(bad)]:g}; leave a source out of data= instead of weighting it 0)")
    if not 0 <= cfg.process_index < cfg.process_count:
        raise LoaderError(f"process {cfg.process_index} of {cfg.process_count}")
    layout = row_layout(cfg, model, tokenizer, processor)
    sources, lengths = zip(*(_source(shard_paths([s], cfg.split), cfg) for s in cfg.sources))
    decoded = [ds.map(_Decode(ExampleEncoder(tokenizer, processor, layout.merge, task, cfg.image_size, cfg.pivot_frame,
                                                    cfg.score_placeholder_materials), cfg.split))
               for ds, task in zip(sources, tasks)]
    examples = decoded[0] if len(decoded) == 1 else grain.MapDataset.mix(decoded, list(cfg.weights) or None)
    named = ", ".join(s if len(set(tasks)) == 1 else f"{s} ({t})" for s, t in zip(cfg.sources, tasks))
    what = f"split {cfg.split!r} ({'+'.join(dict.fromkeys(tasks))} task) of {named} ({sum(lengths)} records)"
    batches = _PackedBatches(examples.to_iter_dataset(), layout, cfg.rows, _full_pass(lengths, cfg.weights), what)
    if cfg.workers > 0:
        if not flags.FLAGS.is_parsed():  # grain workers read absl flags; unparsed flags make them fail
            flags.FLAGS.mark_as_parsed()
        batches = batches.mp_prefetch(grain.MultiprocessingOptions(
            num_workers=cfg.workers, per_worker_buffer_size=cfg.worker_buffer))
    return batches


@dataclass
class ShardLoader:
    """The trainer's loader (train/batch.py protocol) over a grain pipeline, with skip totals."""

    iterator: grain.DatasetIterator
    skipped: Counter = field(default_factory=Counter)

    @classmethod
    def create(cls, cfg: LoaderConfig, model: Qwen3VLConfig, tokenizer: Tokenizer,
               processor: ImageProcessorConfig) -> "ShardLoader":
        return cls(iter(build_dataset(cfg, model, tokenizer, processor)))

    def __iter__(self) -> Iterator[dict[str, np.ndarray]]:
        return self

    def __next__(self) -> dict[str, np.ndarray]:
        batch, skipped = next(self.iterator)
        for reason, n in skipped.items():
            if reason != "other_split" and not self.skipped[reason]:
                log.warning("skipping %s records (first of them in this run; totals in loader stats)", reason)
            self.skipped[reason] += n
        return batch

    def get_state(self) -> dict:
        return {"grain": self.iterator.get_state(), "skipped": dict(self.skipped)}

    def set_state(self, state: Mapping) -> None:
        self.iterator.set_state(state["grain"])
        self.skipped = Counter(state.get("skipped", {}))
