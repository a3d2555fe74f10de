"""The "photo" look: a varied render carried through what a camera and a file do to a picture.

A user's photo is never a clean render: it is exposed and white-balanced by the camera, a little
out of focus, noisy, vignetted, shrunk and JPEG-compressed on its way to us. Renders have none of
this, so a model trained on them alone can take a clean image as the sign of the procedural domain
(the varied and plain looks already taught one such sign, see the model card). ``degrade`` applies
each of these effects with its own odds and strength, drawn from the view's generator, to I only:
S and the target are untouched, since the geometry of the view does not change.
"""

from __future__ import annotations

import io

import numpy as np
from PIL import Image
from scipy.ndimage import gaussian_filter

EXPOSURE_STOPS = (-0.7, 0.5)  # multiplies linear light by 2**stops
WHITE_BALANCE = 0.12  # per-channel gain in 1 ± this
BLUR_SIGMA = (0.4, 1.6)  # px at 224 px, scaled with the image side: defocus and slight shake
NOISE_SIGMA = (1.5, 9.0)  # of 255: read noise; shot noise grows with brightness on top of it
VIGNETTE = (0.1, 0.45)  # fraction of brightness lost in the corners
RESCALE = (0.4, 0.8)  # shrunk to this fraction of its side and back: a phone photo resized
JPEG_QUALITY = (25, 90)
ODDS = {"exposure": 0.8, "blur": 0.6, "noise": 0.7, "vignette": 0.4, "rescale": 0.35, "jpeg": 0.85}


def degrade(rgb: np.ndarray, rng: np.random.Generator) -> np.ndarray:
    """``rgb`` (H, W, 3) uint8 as a camera and a photo's way to us would leave it; the same
    generator state gives the same bytes. The numbers of every effect are drawn before any applies,
    so that which effects apply does not shift the others' numbers."""
    if rgb.ndim != 3 or rgb.shape[2] != 3 or rgb.dtype != np.uint8:
        raise ValueError(f"degrade expects an (H, W, 3) uint8 image, got {rgb.shape} {rgb.dtype}")
    applies = {name: rng.random() < p for name, p in ODDS.items()}
    stops, gains = rng.uniform(*EXPOSURE_STOPS), rng.uniform(1 - WHITE_BALANCE, 1 + WHITE_BALANCE, 3)
    sigma, noise = rng.uniform(*BLUR_SIGMA) * rgb.shape[0] / 224.0, rng.uniform(*NOISE_SIGMA)
    corner, fraction, quality = rng.uniform(*VIGNETTE), rng.uniform(*RESCALE), int(rng.integers(*JPEG_QUALITY))
    linear = (rgb.astype(np.float64) / 255.0) ** 2.2
    if applies["exposure"]:
        linear = linear * 2.0 ** stops * gains
    if applies["vignette"]:
        h, w = rgb.shape[:2]
        y, x = np.mgrid[0:h, 0:w]
        r2 = ((x - (w - 1) / 2) / (w / 2)) ** 2 + ((y - (h - 1) / 2) / (h / 2)) ** 2
        linear = linear * (1.0 - corner * np.clip(r2 / 2.0, 0.0, 1.0))[..., None]
    image = np.clip(linear, 0.0, 1.0) ** (1 / 2.2) * 255.0
    if applies["blur"]:
        image = gaussian_filter(image, sigma=(sigma, sigma, 0))
    if applies["noise"]:
        shot = np.sqrt(np.clip(image, 0.0, 255.0) / 255.0) * noise
        image = image + rng.normal(size=image.shape) * (noise * 0.5 + shot)
    out = np.clip(np.rint(image), 0, 255).astype(np.uint8)
    if applies["rescale"]:
        h, w = out.shape[:2]
        small = Image.fromarray(out).resize((max(8, round(w * fraction)), max(8, round(h * fraction))), Image.BILINEAR)
        out = np.asarray(small.resize((w, h), Image.BILINEAR))
    if applies["jpeg"]:
        buf = io.BytesIO()
        Image.fromarray(out).save(buf, format="JPEG", quality=quality)
        out = np.asarray(Image.open(io.BytesIO(buf.getvalue())).convert("RGB"))
    return np.ascontiguousarray(out, dtype=np.uint8)
