"""Command-line options that several benchmarks share, declared once.

The model benches (decode, model step, train step, train command, train scaling) take the same
workload options and append their figures the same way; declaring each option here keeps its
name, type, default and meaning alike across scripts. Each bench still owns its parser and its
own options. Only argparse and json are imported, so a bench can parse its flags (and set XLA
flags from them) before jax loads.
"""

from __future__ import annotations

import argparse
import json
from collections.abc import Iterable

DEFAULT_PRESET = "qwen3_vl_4b"
DEFAULT_IMAGE = 448  # pixels per side: the 4B layout's one image per row
ATTENTION_IMPLS = ("xla", "cudnn")


def bench_parser(description: str | None) -> argparse.ArgumentParser:
    """A parser whose --help prints the description as written, so usage examples keep their lines."""
    return argparse.ArgumentParser(description=description, formatter_class=argparse.RawDescriptionHelpFormatter)


def add_preset(parser: argparse.ArgumentParser, choices: Iterable[str] | None = None,
               help: str = "Qwen3VLConfig preset name") -> None:
    parser.add_argument("--preset", default=DEFAULT_PRESET, choices=None if choices is None else list(choices),
                        help=help)


def add_seq(parser: argparse.ArgumentParser, default: int, flag: str = "--seq") -> None:
    parser.add_argument(flag, type=int, default=default, help="tokens per training row")


def add_batch(parser: argparse.ArgumentParser, default: int) -> None:
    parser.add_argument("--batch", type=int, default=default, help="rows per training step")


def add_image(parser: argparse.ArgumentParser) -> None:
    parser.add_argument("--image", type=int, default=DEFAULT_IMAGE, help="image side in pixels (one image per row)")


def add_attention_impl(parser: argparse.ArgumentParser, default: str) -> None:
    """`--impl`: the attention kernel of the model benches that build Qwen3VL directly."""
    parser.add_argument("--impl", default=default, choices=list(ATTENTION_IMPLS), help="attention implementation")


def add_json_lines(parser: argparse.ArgumentParser, flag: str = "--json") -> None:
    """Where a bench appends its figures, one JSON object a line, so repeated runs add up to a history."""
    parser.add_argument(flag, help="also append the figures as JSON lines to this file")


def append_json_lines(path: str | None, rows: Iterable[dict]) -> None:
    """Append `rows` to `path` (nothing when no path was given)."""
    if not path:
        return
    with open(path, "a", encoding="utf-8") as f:
        for row in rows:
            f.write(json.dumps(row) + "\n")
