"""Segmentation colours (SPEC §3): a fixed base palette, permuted per object.

The base palette is a literal table so that the colours of every record ever written stay the
same on any machine and numpy version; ``farthest_point_palette()`` is the code that produced it
(tests regenerate it and check the table and its guarantees). It is the greedy farthest-point
selection in CIELAB (ΔE76) over an 18-level sRGB grid, started from the background and skipping
grid colours within BACKGROUND_MARGIN_DELTA_E of it: 128 colours, every pair at least
MIN_PAIR_DELTA_E apart and each at least MIN_BACKGROUND_DELTA_E from the black background.
128 rather than 64 so that part-level scenes with many parts still get one colour per part.

Each object sees the whole palette in its own order, taken from SHA-256 of
``category + "/" + object_id`` (never Python's ``hash``, which changes per process), so the same
object always gets the same colours and a colour says nothing about a part's role across objects.
"""

from __future__ import annotations

import hashlib

import numpy as np

from jax3dc.errors import StructureError

BACKGROUND_RGB: tuple[int, int, int] = (0, 0, 0)

PALETTE_SIZE = 128
GRID_LEVELS = 18
BACKGROUND_MARGIN_DELTA_E = 30.0
MIN_PAIR_DELTA_E = 18.0  # guaranteed by the table (measured 18.37)
MIN_BACKGROUND_DELTA_E = 30.0  # guaranteed by the table (measured 31.2)

_BASE_HEX = (
    "00ff00", "0000ff", "ff0000", "00ffff", "ffa5ff", "ffd20f", "006900", "0f0069",
    "c3785a", "0078b4", "ff0078", "ff1eff", "d2ffa5", "f0f0ff", "69003c", "5a78ff",
    "2d8778", "96d200", "00ff96", "ff870f", "a50096", "877800", "960000", "4b2d00",
    "a57896", "ffd287", "690fc3", "002d00", "2d2d5a", "69d2ff", "969669", "3cc387",
    "ff87a5", "ff5a5a", "1eb42d", "784ba5", "4b4b4b", "96a5ff", "d269ff", "a5e1c3",
    "ff00b4", "ffc3b4", "f0ff00", "b41e4b", "78a52d", "a55a00", "5a0000", "f0f069",
    "c35aa5", "7896a5", "d2960f", "78ff5a", "a500ff", "ffffd2", "004bff", "ffc3f0",
    "874b4b", "4b692d", "0f5ab4", "ff965a", "c30078", "4b0f5a", "e14b0f", "00ffd2",
    "003cb4", "b4b45a", "004b69", "78e178", "4bc3c3", "b4b4e1", "ff69e1", "b4b400",
    "c3c3b4", "690f96", "1e874b", "7869a5", "b487ff", "00a5ff", "004b3c", "96ff00",
    "b400d2", "c3ff78", "693c5a", "c3964b", "ff003c", "873c1e", "967869", "695a1e",
    "ff8778", "875af0", "0096b4", "ffd25a", "3c000f", "00003c", "96ffc3", "87b478",
    "ff5aa5", "000096", "870069", "a53c69", "a5d2e1", "c34b3c", "002d78", "00a54b",
    "a54bc3", "1e00d2", "3c3c1e", "a5ffff", "2d002d", "697869", "e1004b", "00d200",
    "c396d2", "d2b4c3", "5a5a78", "c36978", "e12dd2", "5a780f", "ffb487", "ffb45a",
    "3c87f0", "e1e196", "5ae1c3", "f05a78", "e1fff0", "874b87", "d2b487", "005a2d",
)

BASE_PALETTE: np.ndarray = np.array([[int(h[k:k + 2], 16) for k in (0, 2, 4)] for h in _BASE_HEX], dtype=np.uint8)
BASE_PALETTE.setflags(write=False)

# sRGB (D65) -> CIE XYZ (IEC 61966-2-1) and the D65 reference white, for CIELAB.
_SRGB_TO_XYZ = np.array([
    [0.4124564, 0.3575761, 0.1804375],
    [0.2126729, 0.7151522, 0.0721750],
    [0.0193339, 0.1191920, 0.9503041],
])
_D65_WHITE = np.array([0.95047, 1.0, 1.08883])


def srgb_to_lab(rgb: np.ndarray) -> np.ndarray:
    """CIELAB (D65) of 8-bit sRGB colours [..., 3]."""
    c = np.asarray(rgb, dtype=np.float64) / 255.0
    linear = np.where(c <= 0.04045, c / 12.92, ((c + 0.055) / 1.055) ** 2.4)
    t = (linear @ _SRGB_TO_XYZ.T) / _D65_WHITE
    delta = 6.0 / 29.0
    f = np.where(t > delta**3, np.cbrt(t), t / (3 * delta * delta) + 4.0 / 29.0)
    return np.stack([116.0 * f[..., 1] - 16.0, 500.0 * (f[..., 0] - f[..., 1]), 200.0 * (f[..., 1] - f[..., 2])], -1)


def farthest_point_palette(
    size: int = PALETTE_SIZE,
    background: tuple[int, int, int] = BACKGROUND_RGB,
    levels: int = GRID_LEVELS,
    margin: float = BACKGROUND_MARGIN_DELTA_E,
) -> np.ndarray:
    """Greedy farthest-point colours in CIELAB over an sRGB grid (how BASE_PALETTE was made).

    Each step takes the grid colour farthest (ΔE76) from the background and every colour chosen so
    far; colours within ``margin`` of the background are never candidates.
    """
    axis = np.round(np.linspace(0, 255, levels)).astype(np.int64)
    grid = np.stack(np.meshgrid(axis, axis, axis, indexing="ij"), -1).reshape(-1, 3)
    lab = srgb_to_lab(grid)
    to_background = np.linalg.norm(lab - srgb_to_lab(np.array(background)), axis=1)
    keep = to_background >= margin
    grid, lab, nearest = grid[keep], lab[keep], to_background[keep]
    chosen = []
    for _ in range(size):
        k = int(np.argmax(nearest))
        chosen.append(k)
        nearest = np.minimum(nearest, np.linalg.norm(lab - lab[k], axis=1))
    return grid[chosen].astype(np.uint8)


def object_permutation(category: str, object_id: str, size: int = PALETTE_SIZE) -> np.ndarray:
    """The palette order of one object: indices sorted by SHA-256 keys derived from its seed.

    Sorting by hash keys (instead of a numpy generator, whose streams may change between
    versions) keeps the order fixed forever.
    """
    seed = hashlib.sha256(f"{category}/{object_id}".encode("utf-8")).digest()
    keys = [hashlib.sha256(seed + i.to_bytes(4, "big")).digest() for i in range(size)]
    return np.array(sorted(range(size), key=keys.__getitem__), dtype=np.int64)


def object_palette(category: str, object_id: str) -> np.ndarray:
    """The base palette [K, 3] uint8 in this object's order; part id p gets row p - 1."""
    return BASE_PALETTE[object_permutation(category, object_id)]


def part_colour(palette: np.ndarray, part_id: int) -> tuple[int, int, int]:
    """Colour of part ``part_id`` (1-based) in an object's palette."""
    if not 1 <= part_id <= len(palette):
        raise StructureError("palette_size", f"part {part_id}",
                             f"part ids must lie in 1..{len(palette)} (one palette colour per part)")
    r, g, b = (int(v) for v in palette[part_id - 1])
    return (r, g, b)


def hex_colour(rgb: tuple[int, int, int] | np.ndarray) -> str:
    """``#rrggbb`` text of an 8-bit colour, as written in the prompt legend."""
    r, g, b = (int(v) for v in rgb)
    return f"#{r:02x}{g:02x}{b:02x}"
