"""`jax3dc demo` command."""

from __future__ import annotations

import argparse
from pathlib import Path


def register(subparsers: argparse._SubParsersAction) -> None:
    p = subparsers.add_parser(
        "demo", help="run the whole pipeline on a small embedded default (CPU, minutes)",
        description="Build a small procedural dataset, score the reference and the no-training "
                    "baselines on its test split, and export one held-out object to every format. "
                    "Stages not available yet are reported as skipped, with the reason.")
    p.add_argument("--out", default="demo_out", help="output folder (default: demo_out)")
    p.add_argument("--size", choices=("tiny", "default"), default="default",
                   help="tiny: about a minute (used by the tests); default: a few minutes")
    p.add_argument("--seed", type=int, default=0, help="dataset seed")
    p.set_defaults(func=_run)


def _run(args: argparse.Namespace) -> int:
    from eval.demo import run_demo

    run_demo(Path(args.out), args.size, args.seed)
    return 0
