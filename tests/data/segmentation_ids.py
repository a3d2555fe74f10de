"""Part ids of a rendered S: the tests' check that S holds only palette colours (the product
renders S and never reads it back)."""

from __future__ import annotations

import numpy as np

from jax3dc.palette import BACKGROUND_RGB


def decode_segmentation(seg_rgb: np.ndarray, palette: np.ndarray) -> np.ndarray:
    """Part ids [H,W] of an S image; raises ValueError on a colour that is neither background
    nor in the palette (S must never contain blended colours)."""
    flat = seg_rgb.reshape(-1, 3).astype(np.int64)
    code = (flat[:, 0] << 16) | (flat[:, 1] << 8) | flat[:, 2]
    table = {int((r << 16) | (g << 8) | b): i + 1 for i, (r, g, b) in enumerate(palette.astype(np.int64))}
    bg = (BACKGROUND_RGB[0] << 16) | (BACKGROUND_RGB[1] << 8) | BACKGROUND_RGB[2]
    table[int(bg)] = 0
    values, inverse = np.unique(code, return_inverse=True)
    missing = [v for v in values.tolist() if v not in table]
    if missing:
        raise ValueError(f"S holds {len(missing)} colours outside the palette, e.g. #{missing[0]:06x}")
    return np.array([table[v] for v in values.tolist()], dtype=np.int64)[inverse].reshape(seg_rgb.shape[:2])
