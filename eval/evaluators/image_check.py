"""The "no object found" check of ``predict`` (jax3dc.predict.stage1.check_object_image) against real data: it must
accept every render and refuse blank and noise images.

Run: python3 -m eval.evaluate image_check --data DIR [DIR ...]

Each DIR is a dataset of ``jax3dc data build`` / ``data import`` (any appearance, size, split);
every record's image I goes through the check. Prints, per folder and over all, the images
refused (there should be none), the lowest foreground coverage and smooth share with the record
they belong to, then the same figures for synthetic blank and noise images of 32 to 640 px
(each must be refused), against the module's thresholds.
"""

from __future__ import annotations

import argparse
import io
from collections.abc import Sequence
from pathlib import Path

import numpy as np
from PIL import Image

from data_pipeline.shards import read_dataset
from jax3dc.errors import InputFileError
from jax3dc.predict.stage1 import MIN_COVERAGE, MIN_SMOOTH, check_object_image, foreground_coverage, smooth_share

SIZES = (32, 64, 224, 640)


def synthetic(size: int, rng: np.random.Generator) -> dict[str, np.ndarray]:
    """Images with nothing in them: flat colours and noise."""
    grey = rng.integers(0, 256, (size, size, 1), dtype=np.uint8)
    return {"white": np.full((size, size, 3), 255, np.uint8), "black": np.zeros((size, size, 3), np.uint8),
            "uniform noise": rng.integers(0, 256, (size, size, 3), dtype=np.uint8),
            "grey noise": np.repeat(grey, 3, axis=-1),
            "gaussian noise 40": np.clip(128 + 40 * rng.standard_normal((size, size, 3)), 0, 255).astype(np.uint8),
            "gaussian noise 20": np.clip(128 + 20 * rng.standard_normal((size, size, 3)), 0, 255).astype(np.uint8)}


def refused(rgb: np.ndarray) -> str | None:
    try:
        check_object_image(rgb, "image")
    except InputFileError as e:
        return e.message
    return None


def main(argv: Sequence[str] | None = None) -> None:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--data", nargs="+", required=True, metavar="DIR")
    args = parser.parse_args(argv)
    rows = []
    for folder in args.data:
        before = len(rows)
        for record in read_dataset(Path(folder)):
            rgb = np.asarray(Image.open(io.BytesIO(record.image_png)).convert("RGB"))
            rows.append((foreground_coverage(rgb), smooth_share(rgb), refused(rgb), f"{folder}:{record.key}"))
        mine = rows[before:]
        print(f"{folder}: {len(mine)} images, {sum(r[2] is not None for r in mine)} refused")
    coverage, smooth = min(rows, key=lambda r: r[0]), min(rows, key=lambda r: r[1])
    print(f"all: {len(rows)} images, {sum(r[2] is not None for r in rows)} refused; lowest coverage "
          f"{100 * coverage[0]:.2f} % ({coverage[3]}; refused below {100 * MIN_COVERAGE:.2f} %), lowest smooth share "
          f"{100 * smooth[1]:.1f} % ({smooth[3]}; refused below {100 * MIN_SMOOTH:.0f} %)")
    for row in rows:
        if row[2] is not None:
            print(f"  refused {row[3]}: {row[2]}")
    rng = np.random.default_rng(0)
    for size in SIZES:
        for name, rgb in synthetic(size, rng).items():
            why = refused(rgb)
            print(f"{size:>4} px {name:<18} coverage {100 * foreground_coverage(rgb):6.2f} %  smooth "
                  f"{100 * smooth_share(rgb):5.1f} %  {'refused: ' + why if why else 'ACCEPTED'}")


if __name__ == "__main__":
    main()
