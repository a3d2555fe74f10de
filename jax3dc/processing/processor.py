"""Qwen3-VL image preprocessing in numpy: image -> flattened patches + (t, h, w) grid.

Reproduces the PIL backend of ``transformers``' Qwen2-VL image processor (the class
``AutoImageProcessor`` picks for ``qwen3_vl`` when torchvision is absent, and the one pinned in
our parity tests). The torchvision ("fast") backend resizes with its own antialiased bicubic
kernel and differs from PIL by a few grey levels, so the two HF backends do not agree exactly
with each other; we follow PIL because training and inference both run through this module and
PIL is available everywhere.

Steps, as in HF: composite transparency onto white and convert to RGB; ``smart_resize`` to
multiples of ``patch_size * merge_size`` inside the pixel budget; bicubic resize with PIL on
uint8; rescale by 1/255 (float64, then float32); normalise with the mean/std; repeat each frame
``temporal_patch_size`` times; flatten patches so that the four patches of one merged token are
consecutive (order gh, gw, mh, mw; features C, T, ph, pw).
"""

from __future__ import annotations

import json
import math
import os
from dataclasses import dataclass
from typing import Sequence, Union

import numpy as np
from PIL import Image, UnidentifiedImageError

from jax3dc.errors import InputFileError

ImageLike = Union[str, os.PathLike, Image.Image, np.ndarray]

MAX_ASPECT_RATIO = 200  # HF rejects images more elongated than this
MIN_IMAGE_SIDE = 32
"""px: the shortest image side the project reads or renders, one merged vision token of the models
(16 px patches, 2 x 2 merged): ``predict``'s image check, the stage-1 network's reader and
``data build --size`` hold to it, so a render the build writes is one that ``predict`` accepts."""


@dataclass(frozen=True)
class ImageProcessorConfig:
    """Settings of ``preprocessor_config.json``; defaults are the released Qwen3-VL ones."""

    patch_size: int = 16
    temporal_patch_size: int = 2
    merge_size: int = 2
    min_pixels: int = 256 * 256  # HF "size.shortest_edge"
    max_pixels: int = 4096 * 4096  # HF "size.longest_edge"
    image_mean: tuple[float, float, float] = (0.5, 0.5, 0.5)
    image_std: tuple[float, float, float] = (0.5, 0.5, 0.5)

    @property
    def factor(self) -> int:
        """Side lengths are multiples of this so patches merge evenly."""
        return self.patch_size * self.merge_size

    @classmethod
    def qwen3_vl(cls) -> "ImageProcessorConfig":
        return cls()

    @classmethod
    def from_pretrained(cls, checkpoint_dir: str | os.PathLike) -> "ImageProcessorConfig":
        """Read ``preprocessor_config.json`` of a Hugging Face checkpoint directory."""
        path = os.path.join(checkpoint_dir, "preprocessor_config.json")
        try:
            with open(path, encoding="utf-8") as f:
                raw = json.load(f)
        except (OSError, json.JSONDecodeError) as err:
            raise InputFileError(path, f"cannot read image processor config: {err}") from err
        size = raw.get("size") or {}
        default = cls()
        return cls(
            patch_size=int(raw.get("patch_size", default.patch_size)),
            temporal_patch_size=int(raw.get("temporal_patch_size", default.temporal_patch_size)),
            merge_size=int(raw.get("merge_size", default.merge_size)),
            min_pixels=int(size.get("shortest_edge", raw.get("min_pixels", default.min_pixels))),
            max_pixels=int(size.get("longest_edge", raw.get("max_pixels", default.max_pixels))),
            image_mean=tuple(float(v) for v in raw.get("image_mean", default.image_mean)),
            image_std=tuple(float(v) for v in raw.get("image_std", default.image_std)),
        )

    def save_pretrained(self, checkpoint_dir: str | os.PathLike) -> str:
        """Write ``preprocessor_config.json`` in the layout of the released Qwen3-VL checkpoints."""
        path = os.path.join(checkpoint_dir, "preprocessor_config.json")
        doc = {
            "size": {"longest_edge": self.max_pixels, "shortest_edge": self.min_pixels},
            "patch_size": self.patch_size,
            "temporal_patch_size": self.temporal_patch_size,
            "merge_size": self.merge_size,
            "image_mean": list(self.image_mean),
            "image_std": list(self.image_std),
            "do_rescale": True,
            "rescale_factor": 1.0 / 255.0,
            "do_normalize": True,
            "do_convert_rgb": True,
            "resample": int(Image.Resampling.BICUBIC),
            "image_processor_type": "Qwen2VLImageProcessor",
            "processor_class": "Qwen3VLProcessor",
        }
        os.makedirs(checkpoint_dir, exist_ok=True)
        with open(path, "w", encoding="utf-8") as f:
            json.dump(doc, f, indent=2)
        return path


@dataclass(frozen=True)
class ProcessedImages:
    """Patches of one or more images, concatenated, and each image's (t, h, w) patch grid."""

    pixel_values: np.ndarray  # [sum(t*h*w), C * temporal_patch_size * patch_size**2] float32
    image_grid_thw: np.ndarray  # [num_images, 3] int64



def image_token_counts(image_grid_thw: np.ndarray | Sequence[Sequence[int]], merge_size: int) -> list[int]:
    """Pad tokens per image: the merger turns merge_size x merge_size patches into one token."""
    return [int(np.prod(grid)) // merge_size**2 for grid in np.asarray(image_grid_thw).reshape(-1, 3)]


def smart_resize(height: int, width: int, factor: int, min_pixels: int, max_pixels: int) -> tuple[int, int]:
    """Target size: multiples of ``factor``, area within [min_pixels, max_pixels], aspect kept.

    Same rounding as HF (round to nearest multiple, then floor/ceil after rescaling by sqrt of
    the area ratio) so that the token count matches the original model's exactly.
    """
    if max(height, width) / min(height, width) > MAX_ASPECT_RATIO:
        raise ValueError(f"aspect ratio {max(height, width) / min(height, width):.1f} exceeds {MAX_ASPECT_RATIO}")
    h_bar = round(height / factor) * factor
    w_bar = round(width / factor) * factor
    if h_bar * w_bar > max_pixels:
        beta = math.sqrt((height * width) / max_pixels)
        h_bar = max(factor, math.floor(height / beta / factor) * factor)
        w_bar = max(factor, math.floor(width / beta / factor) * factor)
    elif h_bar * w_bar < min_pixels:
        beta = math.sqrt(min_pixels / (height * width))
        h_bar = math.ceil(height * beta / factor) * factor
        w_bar = math.ceil(width * beta / factor) * factor
    return h_bar, w_bar


MAX_IMAGE_PIXELS = 40_000_000
"""Largest image decoded (about 6300 x 6300): the model sees at most a few megapixels, and a 12000 x
12000 image costs 432 MB as RGB before it is shrunk. Checked from the header, before decoding."""


def load_image(path: str | os.PathLike, max_pixels: int = MAX_IMAGE_PIXELS) -> Image.Image:
    """Open and fully decode an image file; a missing, corrupt or non-image file, or one of more
    than ``max_pixels`` pixels, is an InputFileError."""
    pil_cap = Image.MAX_IMAGE_PIXELS
    try:
        Image.MAX_IMAGE_PIXELS = None  # our own cap below, which a user can raise, says it in one line
        try:
            image = Image.open(path)
        finally:
            Image.MAX_IMAGE_PIXELS = pil_cap
        with image:
            if image.width * image.height > max_pixels:
                raise InputFileError(str(path), f"image of {image.width} x {image.height} pixels; the cap is "
                                                f"{max_pixels} pixels (raise it with --max-image-pixels)")
            image.load()
            return image.copy()
    except FileNotFoundError as err:
        raise InputFileError(str(path), "image file not found") from err
    except UnidentifiedImageError as err:
        raise InputFileError(str(path), "not an image file (format not recognised)") from err
    except Image.DecompressionBombError as err:
        raise InputFileError(str(path), f"image too large: {err}") from err
    except (OSError, SyntaxError, ValueError) as err:
        # Truncated / corrupt data surfaces as OSError ("image file is truncated") or SyntaxError.
        raise InputFileError(str(path), f"corrupt image data: {err}") from err


def to_rgb(image: Image.Image) -> Image.Image:
    """RGB copy of ``image``; transparent pixels are composited onto white, as HF does."""
    if "A" in image.getbands() or image.info.get("transparency") is not None:
        rgba = image.convert("RGBA")
        white = Image.new("RGBA", rgba.size, (255, 255, 255, 255))
        return Image.alpha_composite(white, rgba).convert("RGB")
    return image.convert("RGB")


def _as_pil(image: ImageLike) -> tuple[Image.Image, str]:
    if isinstance(image, Image.Image):
        return image, "<image>"
    if isinstance(image, np.ndarray):
        if image.dtype != np.uint8 or image.ndim not in (2, 3) or (image.ndim == 3 and image.shape[2] not in (1, 3, 4)):
            raise InputFileError(
                "<array>", f"expected uint8 HxW, HxWx1, HxWx3 or HxWx4 array, got {image.dtype} {image.shape}")
        arr = image[..., 0] if image.ndim == 3 and image.shape[2] == 1 else image
        return Image.fromarray(arr), "<array>"
    return load_image(image), str(image)


def patchify(image: np.ndarray, config: ImageProcessorConfig) -> tuple[np.ndarray, tuple[int, int, int]]:
    """[C, H, W] float32 -> ([gh*gw, C*T*P*P], (1, gh, gw)); a merged token's patches stay adjacent."""
    p, m, t = config.patch_size, config.merge_size, config.temporal_patch_size
    channels, height, width = image.shape
    gh, gw = height // p, width // p
    x = image.reshape(channels, gh // m, m, p, gw // m, m, p)
    x = x.transpose(1, 4, 2, 5, 0, 3, 6)  # (gh/m, gw/m, mh, mw, C, ph, pw)
    x = np.broadcast_to(x[:, :, :, :, :, None], (*x.shape[:5], t, p, p))  # one frame repeated t times
    return np.ascontiguousarray(x).reshape(gh * gw, channels * t * p * p), (1, gh, gw)


def preprocess_image(image: ImageLike, config: ImageProcessorConfig = ImageProcessorConfig()) -> ProcessedImages:
    """One image (path, PIL image or uint8 array) -> its patches and grid."""
    pil, source = _as_pil(image)
    rgb = to_rgb(pil)
    try:
        height, width = smart_resize(rgb.height, rgb.width, config.factor, config.min_pixels, config.max_pixels)
    except ValueError as err:
        raise InputFileError(source, str(err)) from err
    resized = np.asarray(rgb.resize((width, height), resample=Image.Resampling.BICUBIC))
    chw = resized.transpose(2, 0, 1)
    scaled = (chw.astype(np.float64) * (1.0 / 255.0)).astype(np.float32)
    mean = np.asarray(config.image_mean, dtype=np.float32)[:, None, None]
    std = np.asarray(config.image_std, dtype=np.float32)[:, None, None]
    normalised = (scaled - mean) / std
    patches, grid = patchify(normalised, config)
    return ProcessedImages(patches, np.asarray([grid], dtype=np.int64))


def preprocess_images(
    images: Sequence[ImageLike], config: ImageProcessorConfig = ImageProcessorConfig()
) -> ProcessedImages:
    """Several images, in prompt order, concatenated the way the vision tower consumes them."""
    if not images:
        raise ValueError("preprocess_images needs at least one image")
    parts = [preprocess_image(im, config) for im in images]
    return ProcessedImages(
        np.concatenate([p.pixel_values for p in parts], axis=0),
        np.concatenate([p.image_grid_thw for p in parts], axis=0),
    )
