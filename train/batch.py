"""The batch protocol between a data loader and the trainer, and a synthetic loader for tests.

A loader is an iterator of batches with ``get_state() -> dict`` and ``set_state(dict)``
(the same two methods as a grain ``DatasetIterator``), so a checkpoint can hold the loader's
position and a resumed run sees exactly the batches it would have seen. The state must be
JSON-serialisable.

Each process's loader yields only ITS rows of the global batch (``rows = global_batch /
process_count``); the trainer assembles the global array from every process's rows. A batch
is a dict of numpy arrays, leading axis = rows:

    input_ids       int32 [rows, L]   token ids, image placeholders included
    attention_mask  int32 [rows, L]   optional: 1 for real tokens, 0 for padding (absent = no
                                      padding, which lets the causal flash-attention kernel run)
    labels          int32 [rows, L]   the target AT each position (already shifted: the token
                                      that should follow position t), any value where masked
    loss_mask       float32 [rows, L] 1 where the position's prediction is scored (answer tokens)
    pixel_values    float32 [rows, P, D]  optional: each row's images, P patches in all of
                                      D = 3 * temporal_patch * patch**2 values (HF layout)
    image_grid_thw  int32 [rows, 3] or [rows, k, 3]  optional, with pixel_values: the (t, h, w)
                                      patch grid of each of the row's 1 or k images
    position_ids    int32 [rows, 3, L] optional: multimodal RoPE ids (t, h, w); computed from
                                      input_ids and image_grid_thw when absent
    segment_ids     int32 [rows, L]   optional: packed rows (data_pipeline/packing.py) number
                                      their examples 1.. (0 = padding); attention stays inside
                                      an example. Needs position_ids (restarting per example).

Rows of a batch all share one image size so that shapes are static under jit; a loader
buckets by size (or resizes) to keep it so. The trainer splits the rows into micro-batches
for gradient accumulation, so ``rows`` must be a multiple of the accumulation count.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Iterator, Mapping, Protocol

import numpy as np

from jax3dc.errors import Jax3dcError

TOKEN_KEYS = ("input_ids", "labels", "loss_mask")
OPTIONAL_TOKEN_KEYS = ("attention_mask",)
IMAGE_KEYS = ("pixel_values", "image_grid_thw")


class BatchError(Jax3dcError):
    """A batch that does not follow the protocol (missing key, wrong shape or dtype)."""


class Loader(Protocol):
    """What the trainer needs from a data loader."""

    def __iter__(self) -> Iterator[dict[str, np.ndarray]]: ...

    def __next__(self) -> dict[str, np.ndarray]: ...

    def get_state(self) -> dict: ...

    def set_state(self, state: Mapping) -> None: ...


def check_batch(batch: Mapping[str, np.ndarray], rows: int, seq_len: int) -> None:
    """Raise BatchError naming the first key whose presence or shape breaks the protocol."""
    for key in TOKEN_KEYS:
        if key not in batch:
            raise BatchError(f"batch has no {key!r} (keys: {sorted(batch)})")
        if batch[key].shape != (rows, seq_len):
            raise BatchError(f"batch[{key!r}] has shape {batch[key].shape}, expected {(rows, seq_len)}")
    for key in OPTIONAL_TOKEN_KEYS:
        if key in batch and batch[key].shape != (rows, seq_len):
            raise BatchError(f"batch[{key!r}] has shape {batch[key].shape}, expected {(rows, seq_len)}")
    if "segment_ids" in batch:
        if batch["segment_ids"].shape != (rows, seq_len):
            raise BatchError(f"batch['segment_ids'] has shape {batch['segment_ids'].shape}, expected {(rows, seq_len)}")
        if "position_ids" not in batch:
            raise BatchError("batch has segment_ids (packed rows) but no position_ids")
    if "position_ids" in batch and batch["position_ids"].shape != (rows, 3, seq_len):
        raise BatchError(f"batch['position_ids'] has shape {batch['position_ids'].shape}, "
                         f"expected {(rows, 3, seq_len)}")
    has = [k in batch for k in IMAGE_KEYS]
    if any(has) and not all(has):
        raise BatchError("batch must carry both pixel_values and image_grid_thw, or neither")
    if all(has):
        pv, thw = batch["pixel_values"], batch["image_grid_thw"]
        if pv.ndim != 3 or pv.shape[0] != rows:
            raise BatchError(f"batch['pixel_values'] has shape {pv.shape}, expected (rows={rows}, P, D)")
        if thw.shape[0] != rows or thw.shape[-1] != 3 or thw.ndim not in (2, 3):
            raise BatchError(f"batch['image_grid_thw'] has shape {thw.shape}, expected (rows={rows}, [k,] 3)")
        patches = np.prod(thw, axis=-1).reshape(rows, -1).sum(axis=1)
        if not np.all(patches == pv.shape[1]):
            raise BatchError(f"image grids give {patches.tolist()} patches per row, pixel_values has P={pv.shape[1]}")


@dataclass(frozen=True)
class ImageLayout:
    """Where an image sits in a synthetic sequence: token ids and its patch geometry."""

    vision_start_id: int
    image_token_id: int
    vision_end_id: int
    grid_hw: tuple[int, int]  # patches per side
    merge: int  # spatial merge: image tokens = h * w / merge**2
    patch_dim: int

    @property
    def patches(self) -> int:
        return self.grid_hw[0] * self.grid_hw[1]

    @property
    def tokens(self) -> int:
        return self.patches // (self.merge * self.merge)


class SyntheticBatches:
    """Deterministic, learnable batches: each row counts upward by a random stride mod vocab.

    Row ``r`` of global step ``i`` depends only on (seed, i, r), so a process that owns rows
    ``[p * rows, (p + 1) * rows)`` sees the same data whatever the number of processes, and
    the state is just the next step index.
    """

    def __init__(self, *, vocab: int, seq_len: int, global_rows: int, seed: int = 0,
                 image: ImageLayout | None = None, process_index: int = 0, process_count: int = 1,
                 text_vocab: int | None = None, padding: bool = True):
        if global_rows % process_count:
            raise BatchError(f"global batch {global_rows} is not divisible by {process_count} processes")
        self.vocab = vocab
        self.text_vocab = min(text_vocab or vocab, vocab)
        self.seq_len = seq_len
        self.rows = global_rows // process_count
        self.first_row = process_index * self.rows
        self.seed = seed
        self.image = image
        self.padding = padding  # rows end in up to L/8 padding tokens; False: no attention_mask
        self.step = 0
        if image is not None and image.tokens + 2 >= seq_len:
            raise BatchError(f"sequence length {seq_len} leaves no room after {image.tokens} image tokens")

    def __iter__(self) -> "SyntheticBatches":
        return self

    def __next__(self) -> dict[str, np.ndarray]:
        rows = [self._row(self.step, self.first_row + k) for k in range(self.rows)]
        self.step += 1
        return {key: np.stack([r[key] for r in rows]) for key in rows[0]}

    def get_state(self) -> dict:
        return {"step": self.step, "seed": self.seed}

    def set_state(self, state: Mapping) -> None:
        if int(state["seed"]) != self.seed:
            raise BatchError(f"loader state has seed {state['seed']}, this loader {self.seed}")
        self.step = int(state["step"])

    def _row(self, step: int, row: int) -> dict[str, np.ndarray]:
        rng = np.random.default_rng([self.seed, step, row])
        L = self.seq_len
        start, stride = rng.integers(0, self.text_vocab), rng.integers(1, 7)
        ids = ((start + stride * np.arange(L)) % self.text_vocab).astype(np.int32)
        n_pad = int(rng.integers(0, L // 8 + 1)) if self.padding else 0
        attention = np.ones(L, np.int32)
        if n_pad:
            attention[L - n_pad:] = 0
            ids[L - n_pad:] = 0
        out = {}
        prompt_end = 0
        if self.image is not None:
            im = self.image
            ids[0] = im.vision_start_id
            ids[1:1 + im.tokens] = im.image_token_id
            ids[1 + im.tokens] = im.vision_end_id
            prompt_end = im.tokens + 2
            out["pixel_values"] = rng.standard_normal((im.patches, im.patch_dim), dtype=np.float32)
            out["image_grid_thw"] = np.array([1, *im.grid_hw], np.int32)
        labels = np.zeros(L, np.int32)
        labels[:-1] = ids[1:]
        loss_mask = np.zeros(L, np.float32)
        first = max(prompt_end - 1, 0)
        loss_mask[first:L - 1] = attention[first + 1:]
        out.update(input_ids=ids, labels=labels, loss_mask=loss_mask)
        if self.padding:
            out["attention_mask"] = attention
        return out
