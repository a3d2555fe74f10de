"""Training rows from tokenised examples: several examples packed into one fixed-length row.

A packed row keeps its examples apart exactly as if each were alone in its own row:

* ``segment_ids`` number the examples 1..k (0 = padding); the model attends only within a
  segment (block-diagonal causal mask);
* ``position_ids`` restart for every example (the multimodal RoPE ids of the example alone);
* labels are shifted inside each example, so an example's last token never predicts the next
  example's first token;
* images fill a row's slots in order (``pack * images_per_example`` per row, all of one size),
  so rows may mix examples of one image (code task) and two (structure task); the model places
  a row's image features in the order of its image tokens (``images_per_row``), so unused
  trailing slots (zero pixels) are computed by the frozen vision tower but never read.

So the loss of a packed batch equals the loss of the same examples unpacked.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Sequence

import ml_dtypes
import numpy as np

from jax3dc.processing.chat import IGNORE_INDEX


@dataclass(frozen=True)
class Example:
    """One tokenised conversation with its images (HF layout, one grid row per image)."""

    key: str
    input_ids: np.ndarray  # [n] int32
    labels: np.ndarray  # [n] int32, unshifted; IGNORE_INDEX where not scored
    pixel_values: np.ndarray  # [patches of all images, D] float32
    image_grid_thw: np.ndarray  # [images, 3] int64

    def __len__(self) -> int:
        return int(self.input_ids.shape[0])


def rope_positions(input_ids: np.ndarray, image_grid_thw: np.ndarray, image_token_id: int,
                   merge: int) -> np.ndarray:
    """Multimodal RoPE ids [3, n] of one example alone (no padding), the numpy twin of
    jax3dc.model.rope.get_rope_index: text advances all three ids by one; a run of image
    tokens is one image at (t, row, col) offsets from the counter, which then jumps by
    max(h, w) merged patches."""
    n = len(input_ids)
    pos = np.empty((3, n), np.int64)
    is_img = input_ids == image_token_id
    counter, i, image = 0, 0, 0
    while i < n:
        if not is_img[i]:
            pos[:, i] = counter
            counter += 1
            i += 1
            continue
        j = i
        while j < n and is_img[j]:
            j += 1
        if image >= len(image_grid_thw):
            raise ValueError(f"more image-token runs than images ({len(image_grid_thw)})")
        _, h, w = (int(v) for v in image_grid_thw[image])
        gh, gw = h // merge, w // merge
        k = np.arange(j - i)
        plane = max(gh * gw, 1)
        pos[0, i:j] = counter + k // plane
        pos[1, i:j] = counter + (k % plane) // max(gw, 1)
        pos[2, i:j] = counter + k % max(gw, 1)
        counter += max(gh, gw)
        image += 1
        i = j
    if image != len(image_grid_thw):
        raise ValueError(f"{len(image_grid_thw)} images but {image} image-token runs")
    return pos.astype(np.int32)


def pixel_dtype(name: str) -> np.dtype:
    return np.dtype(ml_dtypes.bfloat16) if name == "bfloat16" else np.dtype(name)


@dataclass(frozen=True)
class RowLayout:
    """Static shapes of one packed row."""

    seq_len: int
    pack: int  # examples per row at most
    images_per_example: int  # the most images one example may bring (slots are sized for it)
    grid: tuple[int, int, int]  # (t, h, w) patch grid of every image
    patch_dim: int
    pad_id: int
    image_token_id: int
    merge: int
    pixel_dtype: str = "float32"  # bfloat16 halves what workers send when the model computes in it

    @property
    def patches_per_image(self) -> int:
        return int(np.prod(self.grid))

    @property
    def slots(self) -> int:
        return self.pack * self.images_per_example


def pack_row(examples: Sequence[Example], layout: RowLayout) -> dict[str, np.ndarray]:
    """One row of the batch protocol (train/batch.py) holding ``examples`` back to back
    (none: a padding row, which scores nothing)."""
    if len(examples) > layout.pack:
        raise ValueError(f"a row holds at most {layout.pack} examples, got {len(examples)}")
    L = layout.seq_len
    ids = np.full(L, layout.pad_id, np.int32)
    labels = np.zeros(L, np.int32)
    loss_mask = np.zeros(L, np.float32)
    segments = np.zeros(L, np.int32)
    positions = np.zeros((3, L), np.int32)
    pixels = np.zeros((layout.slots * layout.patches_per_image, layout.patch_dim), pixel_dtype(layout.pixel_dtype))
    offset = slot = 0
    for s, ex in enumerate(examples):
        n = len(ex)
        if offset + n > L:
            raise ValueError(f"examples need {offset + n} tokens, the row has {L}")
        if ex.image_grid_thw.shape[0] > layout.images_per_example:
            raise ValueError(f"{ex.key}: {ex.image_grid_thw.shape[0]} images, rows hold at most "
                             f"{layout.images_per_example} per example")
        if (ex.image_grid_thw != np.asarray(layout.grid)).any():
            raise ValueError(f"{ex.key}: image grids {ex.image_grid_thw.tolist()}, rows expect {list(layout.grid)}")
        span = slice(offset, offset + n)
        ids[span] = ex.input_ids
        labels[offset:offset + n - 1] = ex.input_ids[1:]
        loss_mask[offset:offset + n - 1] = ex.labels[1:] != IGNORE_INDEX
        segments[span] = s + 1
        positions[:, span] = rope_positions(ex.input_ids, ex.image_grid_thw, layout.image_token_id, layout.merge)
        first = slot * layout.patches_per_image
        pixels[first:first + ex.pixel_values.shape[0]] = ex.pixel_values
        slot += ex.image_grid_thw.shape[0]
        offset += n
    grids = np.tile(np.asarray(layout.grid, np.int32), (layout.slots, 1))  # unused slots: zero pixels, never placed
    return {"input_ids": ids, "labels": labels, "loss_mask": loss_mask, "segment_ids": segments,
            "attention_mask": (segments > 0).astype(np.int32), "position_ids": positions,
            "pixel_values": pixels, "image_grid_thw": grids}
