"""The convex-piece cache on the commands a user runs: seconds with the cache (each part mesh
decomposed once per process) against without it (``CACHE_ENTRIES = 0``: every export and check
decomposes again), in the same run, for a few factory objects.

python3 -m bench.convex_cache [--categories cabinet bucket faucet oven] [--seed 0] [--repeats 2]

Every run starts from an empty cache, as a new process does (the disk cache under it is off,
``JAX3DC_PIECE_CACHE=''``: both columns are this process's own work); the first object's commands run once
untimed first (imports and first calls). Per object and command it prints the
best of ``--repeats`` seconds uncached and cached and their ratio (uncached / cached):
  export mjcf      ``jax3dc export --format mjcf`` (one decomposition either way)
  export 3         ``jax3dc export`` to urdf, usd and mjcf in turn, in one process
  predict          ``jax3dc.predict.predict`` from a parts folder, the object's own structure standing
                   in for the structure model: exports, physics check, report
The last lines sum each command over the objects. Copied into a checkout from before the cache
(0c25652), the script times that code as it was: both columns are then its uncached path.
"""

from __future__ import annotations

import argparse
import contextlib
import io
import os
import tempfile
import time
from collections.abc import Callable
from pathlib import Path

os.environ.setdefault("MUJOCO_GL", "egl")
os.environ["JAX3DC_PIECE_CACHE"] = ""

from PIL import Image  # noqa: E402

from jax3dc.factories import generate_object  # noqa: E402
from jax3dc.factories.registry import FACTORIES  # noqa: E402
import jax3dc.geometry.convex_pieces as cp  # noqa: E402
from jax3dc.predict import PredictConfig, predict  # noqa: E402
from jax3dc.predict.stage1 import Stage1Config  # noqa: E402
from jax3dc.cli import main as cli  # noqa: E402
from jax3dc.geometry.parts import part_boxes, save_parts  # noqa: E402
from jax3dc.structure import canonicalize, to_json  # noqa: E402

COMMANDS = ("export mjcf", "export 3", "predict")


def _seconds(run: Callable[[], None], cached: bool, repeats: int) -> float:
    """Best of ``repeats`` runs from an empty cache; uncached runs keep nothing in it."""
    entries = getattr(cp, "CACHE_ENTRIES", None)  # None: code from before the cache
    clear = getattr(cp, "clear_cache", lambda: None)
    if entries is not None:
        cp.CACHE_ENTRIES = entries if cached else 0
    try:
        best = float("inf")
        for _ in range(repeats):
            clear()
            start = time.perf_counter()
            with contextlib.redirect_stdout(io.StringIO()):  # export's "wrote ..." lines
                run()
            best = min(best, time.perf_counter() - start)
        return best
    finally:
        if entries is not None:
            cp.CACHE_ENTRIES = entries
        clear()


def _commands(category: str, seed: int, folder: Path) -> dict[str, Callable[[], None]]:
    obj = generate_object(category, seed)
    save_parts(obj.parts, folder / "parts")
    structure = to_json(canonicalize(obj.structure, part_boxes(obj.parts)))
    (folder / "structure.json").write_text(structure)
    image = folder / "image.png"  # the stand-in structure model does not look at it
    Image.new("RGB", (96, 96), "white").save(image)

    def export(*formats: str) -> Callable[[], None]:
        def run() -> None:
            for fmt in formats:
                assert cli(["export", str(folder / "structure.json"), "--parts", str(folder / "parts"), "--format",
                            fmt, "--out", str(folder / "export"), "--scale", str(obj.scale_m_per_nu)]) == 0
        return run

    def run_predict() -> None:
        config = PredictConfig(Stage1Config(f"parts:{folder / 'parts'}"), generate_structure=lambda prompt: structure,
                               scale=obj.scale_m_per_nu, mounted=FACTORIES[category].mounted)
        predict(image, config, folder / "predict")

    return {"export mjcf": export("mjcf"), "export 3": export("urdf", "usd", "mjcf"), "predict": run_predict}


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--categories", nargs="+", default=["cabinet", "bucket", "faucet", "oven"])
    ap.add_argument("--seed", type=int, default=0)
    ap.add_argument("--repeats", type=int, default=2)
    args = ap.parse_args(argv)
    totals = {c: [0.0, 0.0] for c in COMMANDS}
    print(f"{'object':<12} {'command':<12} {'uncached s':>10} {'cached s':>9} {'ratio':>6}")
    with tempfile.TemporaryDirectory() as tmp:
        for i, category in enumerate(args.categories):
            commands = _commands(category, args.seed, Path(tmp) / category)
            if i == 0:
                for run in commands.values():
                    _seconds(run, False, 1)
            for name, run in commands.items():
                uncached, cached = (_seconds(run, flag, args.repeats) for flag in (False, True))
                totals[name][0] += uncached
                totals[name][1] += cached
                print(f"{category:<12} {name:<12} {uncached:>10.2f} {cached:>9.2f} {uncached / cached:>6.2f}", flush=True)
    for name, (uncached, cached) in totals.items():
        print(f"{'all':<12} {name:<12} {uncached:>10.2f} {cached:>9.2f} {uncached / cached:>6.2f}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
