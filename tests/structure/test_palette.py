"""Palette: colours far apart in CIELAB and from the background, stable per-object permutations."""

import hashlib

import numpy as np
import pytest

from jax3dc.errors import StructureError
from jax3dc.palette import (
    BACKGROUND_RGB,
    BASE_PALETTE,
    MIN_BACKGROUND_DELTA_E,
    MIN_PAIR_DELTA_E,
    PALETTE_SIZE,
    farthest_point_palette,
    hex_colour,
    object_palette,
    object_permutation,
    part_colour,
    srgb_to_lab,
)


def test_lab_conversion_reference_values():
    # CIELAB (D65) of sRGB primaries and white, as tabulated (e.g. by Bruce Lindbloom's calculator)
    want = {(255, 255, 255): (100.0, 0.0, 0.0), (0, 0, 0): (0.0, 0.0, 0.0),
            (255, 0, 0): (53.24, 80.09, 67.20), (0, 255, 0): (87.73, -86.18, 83.18), (0, 0, 255): (32.30, 79.19, -107.86)}
    for rgb, lab in want.items():
        np.testing.assert_allclose(srgb_to_lab(np.array(rgb)), lab, atol=0.02)
    # lightness follows the grey ramp monotonically
    grey = srgb_to_lab(np.array([[v, v, v] for v in range(0, 256, 15)]))
    assert np.all(np.diff(grey[:, 0]) > 0) and np.allclose(grey[:, 1:], 0, atol=1e-3)


def test_base_palette_is_large_distinct_and_far_from_the_background():
    assert BASE_PALETTE.shape == (PALETTE_SIZE, 3) and PALETTE_SIZE >= 64 and BASE_PALETTE.dtype == np.uint8
    assert len({tuple(c) for c in BASE_PALETTE.tolist()}) == PALETTE_SIZE
    lab = srgb_to_lab(BASE_PALETTE)
    d = np.linalg.norm(lab[:, None] - lab[None], axis=-1)
    d[np.eye(PALETTE_SIZE, dtype=bool)] = np.inf
    assert d.min() >= MIN_PAIR_DELTA_E
    assert np.linalg.norm(lab - srgb_to_lab(np.array(BACKGROUND_RGB)), axis=1).min() >= MIN_BACKGROUND_DELTA_E
    assert not BASE_PALETTE.flags.writeable


def test_table_is_what_the_generator_makes_and_beats_a_random_choice():
    np.testing.assert_array_equal(farthest_point_palette(), BASE_PALETTE)
    # a random sample of the same grid is far worse: the greedy spread is doing real work
    rng = np.random.default_rng(0)
    sample = rng.integers(0, 256, size=(PALETTE_SIZE, 3))
    lab = srgb_to_lab(sample)
    d = np.linalg.norm(lab[:, None] - lab[None], axis=-1)
    d[np.eye(PALETTE_SIZE, dtype=bool)] = np.inf
    assert d.min() < MIN_PAIR_DELTA_E / 2


def test_object_palette_is_a_deterministic_permutation_from_sha256():
    p = object_palette("cabinet", "seed_3")
    assert p.shape == BASE_PALETTE.shape
    assert sorted(map(tuple, p.tolist())) == sorted(map(tuple, BASE_PALETTE.tolist()))
    np.testing.assert_array_equal(p, object_palette("cabinet", "seed_3"))
    # the order follows SHA-256 keys of the seed, recomputed here independently
    seed = hashlib.sha256(b"cabinet/seed_3").digest()
    keys = [hashlib.sha256(seed + i.to_bytes(4, "big")).digest() for i in range(PALETTE_SIZE)]
    assert object_permutation("cabinet", "seed_3").tolist() == sorted(range(PALETTE_SIZE), key=keys.__getitem__)
    # category and id are joined with "/": ("a/b", "c") and ("a", "b/c") are the same object seed
    np.testing.assert_array_equal(object_palette("a/b", "c"), object_palette("a", "b/c"))


def test_objects_get_different_orders_and_first_colours_spread_out():
    firsts = [tuple(object_palette("chair", str(i))[0]) for i in range(400)]
    assert len(set(firsts)) > PALETTE_SIZE * 0.8  # part 1's colour says nothing about the part
    assert not np.array_equal(object_palette("chair", "1"), object_palette("chair", "2"))
    assert not np.array_equal(object_palette("chair", "1"), object_palette("table", "1"))


def test_stable_in_a_fresh_interpreter():
    # Python's hash() is salted per process; the palette order must not be
    import subprocess
    import sys

    code = "from jax3dc.palette import object_palette; print(object_palette('lamp', 'x7')[:5].tolist())"
    outs = {subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True,
                           env={"PYTHONHASHSEED": str(seed), "PATH": ""}, cwd=str(_repo_root())).stdout
            for seed in (1, 2)}
    assert len(outs) == 1 and outs.pop().strip() == str(object_palette("lamp", "x7")[:5].tolist())


def _repo_root():
    from pathlib import Path
    return Path(__file__).resolve().parents[2]


def test_part_colour_and_hex():
    p = object_palette("door", "a")
    assert part_colour(p, 1) == tuple(int(v) for v in p[0])
    assert part_colour(p, PALETTE_SIZE) == tuple(int(v) for v in p[-1])
    for bad in (0, -1, PALETTE_SIZE + 1):
        with pytest.raises(StructureError) as info:
            part_colour(p, bad)
        assert info.value.rule == "palette_size"
    assert hex_colour((58, 123, 213)) == "#3a7bd5"
    assert hex_colour(np.array([0, 255, 16], dtype=np.uint8)) == "#00ff10"
    # hex text parses back to the colour
    for c in BASE_PALETTE[:10]:
        h = hex_colour(c)
        assert tuple(int(h[k:k + 2], 16) for k in (1, 3, 5)) == tuple(int(v) for v in c)
