"""`jax3dc demo` command."""

from __future__ import annotations

import argparse
from pathlib import Path


def register(subparsers: argparse._SubParsersAction) -> None:
    p = subparsers.add_parser(
        "demo", help="run the whole pipeline on a small embedded default (CPU, minutes)",
        description="Build a small procedural dataset, score the reference and the no-training "
                    "baselines, export one object to every format, train a tiny model briefly on the "
                    "CPU, evaluate it on held-out records and predict one held-out image end to end. "
                    "summary.json lists every stage with its outputs.")
    p.add_argument("--out", default="demo_out", help="output folder (default: demo_out)")
    p.add_argument("--size", choices=("tiny", "default"), default="default",
                   help="tiny: a few minutes (used by the tests); default: about 7 minutes plus the build")
    p.add_argument("--seed", type=int, default=0, help="dataset seed")
    p.set_defaults(func=_run)


def _run(args: argparse.Namespace) -> int:
    from eval.demo import run_demo

    run_demo(Path(args.out), args.size, args.seed)
    return 0
