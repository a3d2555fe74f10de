"""Whether image I can hold an object for stage 1 to read, decided from its pixels before any model runs.

A stage-1 model asked about a blank or a noise image still answers (its grammar makes sure the
answer runs), so the object it invents would go all the way to the exports. Three refusals, each
one error line, in this order:
* too small: fewer than ``MIN_SIDE`` pixels on a side, less than one merged vision token of the
  models (16 px patches, 2 x 2 merged);
* noise: almost no pixel has a smooth 3 x 3 neighbourhood. Renders are mostly smooth (sky, floor,
  the faces of parts), i.i.d. noise nowhere;
* blank: almost nothing differs from the background colour (the median of the border), measured on
  the image shrunk to at most ``COVERAGE_SIDE`` px so that sensor or JPEG noise does not count.

The thresholds leave a wide margin on the data (``python3 -m bench.image_check --data DIR ...``):
over 10,140 renders, none refused (procedural objects in the plain look on black at 32, 64 and 448
px and in varied looks with sky, floor and textures at 32 to 224 px, varied scenes, and the
PartNet-Mobility fixtures on black at 224 px), the lowest foreground coverage is 1.3 % (a knife)
and the lowest smooth share 60 % (a stool on a checker floor); uniform (colour or grey) and
Gaussian noise images of 32 to 640 px have a smooth share of at most 5.3 %.
"""

from __future__ import annotations

import numpy as np
from PIL import Image
from scipy.ndimage import maximum_filter, minimum_filter

from jax3dc.errors import InputFileError

MIN_SIDE = 32  # px
COVERAGE_SIDE = 64  # px: the longer side of the image the foreground is measured on
FOREGROUND_STEP = 0.04  # a pixel differs from the background by more than this in some channel (0..1)
MIN_COVERAGE = 0.002  # share of the shrunk image that must differ from the background
SMOOTH_RANGE = 0.2  # a pixel is smooth when its 3 x 3 neighbourhood spans at most this in every channel
MIN_SMOOTH = 0.2  # share of smooth pixels below which the image is noise


def foreground_coverage(rgb: np.ndarray) -> float:
    """Share of the image (shrunk to at most COVERAGE_SIDE px) that differs from the border's median colour."""
    image = Image.fromarray(rgb)
    factor = -(-max(image.size) // COVERAGE_SIDE)
    small = np.asarray(image.reduce(factor) if factor > 1 else image, np.float32) / 255.0
    border = np.concatenate([small[0], small[-1], small[:, 0], small[:, -1]])
    background = np.median(border, axis=0)
    return float((np.abs(small - background).max(axis=-1) > FOREGROUND_STEP).mean())


def smooth_share(rgb: np.ndarray) -> float:
    """Share of pixels whose 3 x 3 neighbourhood spans at most SMOOTH_RANGE in every channel."""
    x = rgb.astype(np.float32) / 255.0
    span = maximum_filter(x, size=(3, 3, 1)) - minimum_filter(x, size=(3, 3, 1))
    return float((span.max(axis=-1) <= SMOOTH_RANGE).mean())


def check_object_image(rgb: np.ndarray, where: str) -> None:
    """Raises InputFileError naming ``where`` when the RGB uint8 image (H, W, 3) is too small, blank or noise."""
    height, width = rgb.shape[:2]
    if min(height, width) < MIN_SIDE:
        raise InputFileError(where, f"the image is {width}x{height} px, too small for stage 1 to read: it needs "
                                    f"at least {MIN_SIDE} px on each side")
    smooth = smooth_share(rgb)
    if smooth < MIN_SMOOTH:
        raise InputFileError(where, f"no object found: the image is noise (only {100 * smooth:.1f} % of its "
                                    "pixels lie in a smooth neighbourhood)")
    coverage = foreground_coverage(rgb)
    if coverage < MIN_COVERAGE:
        raise InputFileError(where, f"no object found: the image is one flat colour ({100 * coverage:.1f} % of it "
                                    "differs from the background)")
