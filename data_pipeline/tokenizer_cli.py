"""``jax3dc data tokenizer``: learn a byte-level BPE (jax3dc.processing.bpe) from datasets' texts."""

from __future__ import annotations

import argparse
from pathlib import Path
from typing import Iterable, Iterator

from tqdm import tqdm

from data_pipeline.shards import load_manifest, read_dataset
from jax3dc.errors import InputFileError
from jax3dc.processing.bpe import QWEN_ADDED_TOKENS, chat_segments, train_bpe
from jax3dc.prompt import chat_messages, code_messages, parameters_messages

DESCRIPTION = """\
Train a byte-level BPE tokenizer on the prompts, target JSON and part programs of built datasets
(`jax3dc data build` / `import` output), with the same 26 added tokens as Qwen3 (<|im_start|>,
<|image_pad|>, ...) placed right after the learned vocabulary, so it works with the chat format
and the model unchanged. Written to --out: tokenizer.json and tokenizer_config.json (loadable by
jax3dc and by transformers' AutoTokenizer). Train a model with it:
`jax3dc train --set tokenizer=DIR ...`.

Texts are taken as the model sees them: the structure conversation (prompt, target) and, for
records with a program, the code conversation (CODE_PROMPT, program), and for records with factory
parameters, the parameters conversation (PARAMETERS_PROMPT, parameters). Only the train split is
used unless --split says otherwise; bench/tokenizer.py compares vocabulary sizes with Qwen3's.

example:  jax3dc data tokenizer --data data/train --vocab-size 4096 --out tokenizers/bpe4k
"""


def record_texts(records: Iterable, split: str) -> Iterator[str]:
    """Chat segments of every record in ``split`` ("all": every record)."""
    for record in records:
        if split != "all" and record.meta.get("split") != split:
            continue
        yield from chat_segments(chat_messages(record.prompt, record.target))
        if record.program:
            yield from chat_segments(code_messages(record.program))
        if record.parameters:
            yield from chat_segments(parameters_messages(record.parameters))


def register(subparsers: argparse._SubParsersAction) -> None:
    parser = subparsers.add_parser("tokenizer", help="train a byte-level BPE tokenizer on datasets' texts",
                                   description=DESCRIPTION, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--data", metavar="DIR", type=Path, action="append", required=True,
                        help="dataset directory (repeat for several)")
    parser.add_argument("--vocab-size", type=int, required=True,
                        help="ids in all, learned + 26 added (e.g. 4096); fewer if the texts run out of pairs")
    parser.add_argument("--out", metavar="DIR", type=Path, required=True, help="output directory")
    parser.add_argument("--split", choices=("train", "val", "test", "all"), default="train",
                        help="records to learn from (default train)")
    parser.add_argument("--min-frequency", type=int, default=2,
                        help="merge only pairs seen at least this often (default 2)")
    parser.add_argument("--digits", type=int, default=1,
                        help="longest run of digits one token may cover (default 1, as Qwen3; 3 shortens "
                        "3-decimal numbers, see bench/tokenizer.py)")
    parser.add_argument("--quiet", action="store_true", help="no progress bar and no summary")
    parser.set_defaults(func=run_tokenizer_command)


def run_tokenizer_command(args: argparse.Namespace) -> int:
    if args.vocab_size < 256 + len(QWEN_ADDED_TOKENS) or args.min_frequency < 1 or args.digits < 1:
        raise SystemExit(f"--vocab-size must be >= {256 + len(QWEN_ADDED_TOKENS)}, --min-frequency and "
                         "--digits >= 1")
    total = 0
    for directory in args.data:
        manifest = load_manifest(directory)
        if manifest is None:
            raise InputFileError(directory, "no manifest.json: not a dataset written by `jax3dc data build`")
        total += sum(s["records"] for s in manifest["shards"].values())
    records = (r for directory in args.data for r in read_dataset(directory))
    progress = tqdm(records, total=total, unit="record", disable=args.quiet)
    texts = list(record_texts(progress, args.split))
    if not texts:
        raise InputFileError(args.data[0], f"no records in split {args.split!r}")
    tokenizer = train_bpe(texts, args.vocab_size, args.min_frequency, args.digits)
    tokenizer.save_pretrained(args.out)
    if not args.quiet:
        print(f"{tokenizer.vocab_size} ids ({tokenizer.vocab_size - len(QWEN_ADDED_TOKENS)} learned + "
              f"{len(QWEN_ADDED_TOKENS)} added) -> {args.out / 'tokenizer.json'}")
    return 0
