"""Image I as the network reads it: any RGB uint8 image -> a square float image of the trained size.

A non-square image is padded to a square with its border's median colour (the object stays
centred, as in the renders it was trained on), then resized with antialiasing. Training and the
reader both go through ``network_image``, so they see the same pixels.
"""

from __future__ import annotations

import numpy as np
from PIL import Image

from jax3dc.errors import Jax3dcError
from jax3dc.processing.processor import MIN_IMAGE_SIDE

MIN_SPREAD = 2.0  # pixel standard deviation (0..255) below which an image shows nothing to read


class ImageInputError(Jax3dcError):
    """An image the stage-1 network cannot read (wrong type, shape or size)."""


def check_image(image: object) -> np.ndarray:
    """``image`` if it is an RGB uint8 array of at least MIN_IMAGE_SIDE px a side that is not one flat
    colour (a blank image has no object to read); else ImageInputError."""
    if not isinstance(image, np.ndarray):
        raise ImageInputError(f"stage-1 image: expected a numpy array, got {type(image).__name__}")
    if image.ndim != 3 or image.shape[2] != 3:
        raise ImageInputError(f"stage-1 image: expected shape (height, width, 3) RGB, got {image.shape}")
    if image.dtype != np.uint8:
        raise ImageInputError(f"stage-1 image: expected uint8 pixels, got {image.dtype}")
    if min(image.shape[:2]) < MIN_IMAGE_SIDE:
        raise ImageInputError(f"stage-1 image: {image.shape[1]}x{image.shape[0]} px is too small "
                              f"(at least {MIN_IMAGE_SIDE} px a side)")
    if float(image.std()) < MIN_SPREAD:
        raise ImageInputError("stage-1 image: one flat colour, no object to read")
    return image


def network_image(image: np.ndarray, size: int) -> np.ndarray:
    """[size, size, 3] float32 in [0, 1]; see the module docstring."""
    image = check_image(image)
    h, w = image.shape[:2]
    if h != w:
        border = np.concatenate([image[0], image[-1], image[:, 0], image[:, -1]])
        side = max(h, w)
        square = np.empty((side, side, 3), np.uint8)
        square[:] = np.median(border, axis=0).astype(np.uint8)
        top, left = (side - h) // 2, (side - w) // 2
        square[top:top + h, left:left + w] = image
        image = square
    if image.shape[0] != size:
        image = np.asarray(Image.fromarray(image).resize((size, size), Image.Resampling.BILINEAR, reducing_gap=None))
    return image.astype(np.float32) / 255.0
