"""A byte-level BPE learned from our own prompts, targets and programs, with Qwen3's added tokens.

Why: a model trained from scratch does not need Qwen3's 151,669 ids. At hidden size 512 that
vocabulary is 77.7 M embedding parameters, most of the ``small`` preset, and every training
step computes logits over all of it, although our texts use few distinct strings (a fixed
prompt text, JSON keys, 3-decimal numbers, a program vocabulary). Learned on those texts, the
vocabulary stops growing at about 1,300 ids with no more tokens per text than Qwen3's;
bench/tokenizer.py measures tokens, parameters and training FLOPs of both.

What stays as in Qwen3, so that chat.encode_chat, generation and the model config work with
either tokenizer:
  * the 26 added tokens (same strings, same order, same special flags) right after the learned
    vocabulary, so ``<|image_pad|>`` is learned_size + 12 here as 151,643 + 12 is in Qwen3
    (tokenizer.expected_special_id); config_for_tokenizer carries the ids into the model config;
  * Qwen3's pre-tokenizer split (words, punctuation runs, each digit alone; optionally runs of
    up to ``digits`` digits, since our texts are mostly 3-decimal numbers) and the byte-level
    alphabet, so any text encodes and decodes back exactly.
Unlike Qwen3 there is no NFC normaliser: our texts are plain ASCII/UTF-8 and without it
decode(encode(x)) == x holds for every string, not only NFC ones.
"""

from __future__ import annotations

import dataclasses
import re
from typing import Iterable, Mapping, Sequence

import tokenizers
from tokenizers import AddedToken, Regex, decoders, models, pre_tokenizers, processors, trainers

from jax3dc.processing.chat import render_chat
from jax3dc.model.config import Qwen3VLConfig
from jax3dc.processing.tokenizer import Tokenizer

#: Qwen3's added tokens in id order, with their ``special`` flag (as in Qwen3's tokenizer.json).
QWEN_ADDED_TOKENS: tuple[tuple[str, bool], ...] = (
    ("<|endoftext|>", True), ("<|im_start|>", True), ("<|im_end|>", True),
    ("<|object_ref_start|>", True), ("<|object_ref_end|>", True), ("<|box_start|>", True),
    ("<|box_end|>", True), ("<|quad_start|>", True), ("<|quad_end|>", True),
    ("<|vision_start|>", True), ("<|vision_end|>", True), ("<|vision_pad|>", True),
    ("<|image_pad|>", True), ("<|video_pad|>", True),
    ("<tool_call>", False), ("</tool_call>", False), ("<|fim_prefix|>", False),
    ("<|fim_middle|>", False), ("<|fim_suffix|>", False), ("<|fim_pad|>", False),
    ("<|repo_name|>", False), ("<|file_sep|>", False), ("<tool_response>", False),
    ("</tool_response>", False), ("<think>", False), ("</think>", False),
)

#: Qwen3's pre-tokenizer split: contractions, letter runs (with one leading non-letter), single
#: digits ({digits}), punctuation runs (with trailing newlines), newline runs, spaces.
SPLIT_PATTERN = (
    r"(?i:'s|'t|'re|'ve|'m|'ll|'d)|[^\r\n\p{{L}}\p{{N}}]?\p{{L}}+|\p{{N}}{digits}| ?[^\s\p{{L}}\p{{N}}]+[\r\n]*"
    r"|\s*[\r\n]+|\s+(?!\S)|\s+"
)
QWEN_SPLIT_PATTERN = SPLIT_PATTERN.format(digits="")

#: Embedding rows are padded to a multiple of this (tensor-core and sharding friendly).
VOCAB_MULTIPLE = 128


_ADDED_SPLIT = re.compile("|".join(re.escape(content) for content, _ in QWEN_ADDED_TOKENS))


def chat_segments(messages: Sequence[Mapping]) -> list[str]:
    """The texts between added tokens of a conversation as encode_chat renders it (``user\\n``
    + prompt, ``assistant\\n`` + answer, the ``\\n`` between turns): what a BPE should be trained
    on, since added tokens are matched before the learned vocabulary ever sees the text."""
    images = sum(1 for m in messages if not isinstance(m["content"], str)
                 for item in m["content"]
                 if item.get("type") == "image" or "image" in item or "image_url" in item)
    text, _ = render_chat(messages, [0] * images)
    return [piece for piece in _ADDED_SPLIT.split(text) if piece]


def _empty_byte_level_bpe(digits: int) -> tokenizers.Tokenizer:
    pattern = QWEN_SPLIT_PATTERN if digits == 1 else SPLIT_PATTERN.format(digits=f"{{1,{digits}}}")
    backend = tokenizers.Tokenizer(models.BPE())
    backend.pre_tokenizer = pre_tokenizers.Sequence([
        pre_tokenizers.Split(Regex(pattern), behavior="isolated", invert=False),
        pre_tokenizers.ByteLevel(add_prefix_space=False, trim_offsets=False, use_regex=False),
    ])
    backend.post_processor = processors.ByteLevel(add_prefix_space=False, trim_offsets=False, use_regex=False)
    backend.decoder = decoders.ByteLevel(add_prefix_space=False, trim_offsets=False, use_regex=False)
    return backend


def train_bpe(texts: Iterable[str], vocab_size: int, min_frequency: int = 2, digits: int = 1) -> Tokenizer:
    """A byte-level BPE of at most ``vocab_size`` ids in all (learned + the 26 added tokens).

    The learned part is the 256 byte symbols plus merges of pairs seen at least
    ``min_frequency`` times; it stops early when no such pair is left, so a small corpus gives
    fewer ids than asked. ``digits``: the longest run of digits one token may cover (Qwen3: 1;
    3 makes "0.082" three tokens instead of five). The same texts give the same tokenizer
    (training breaks count ties by the pair's ids, never by hash order).
    """
    if vocab_size < 256 + len(QWEN_ADDED_TOKENS):
        raise ValueError(f"vocab_size {vocab_size} is below the 256 byte symbols + {len(QWEN_ADDED_TOKENS)} "
                         "added tokens")
    if digits < 1:
        raise ValueError(f"digits must be >= 1, got {digits}")
    backend = _empty_byte_level_bpe(digits)
    trainer = trainers.BpeTrainer(
        vocab_size=vocab_size - len(QWEN_ADDED_TOKENS), min_frequency=min_frequency,
        initial_alphabet=pre_tokenizers.ByteLevel.alphabet(), special_tokens=[], show_progress=False)
    backend.train_from_iterator(texts, trainer)
    learned = backend.get_vocab_size(with_added_tokens=False)
    for index, (content, special) in enumerate(QWEN_ADDED_TOKENS):
        # One at a time: each must get the next id even where add_tokens would reorder a batch.
        token = AddedToken(content, special=special, normalized=False, lstrip=False, rstrip=False,
                           single_word=False)
        (backend.add_special_tokens if special else backend.add_tokens)([token])
        if backend.token_to_id(content) != learned + index:
            raise RuntimeError(f"added token {content} got id {backend.token_to_id(content)}, not {learned + index}")
    return Tokenizer(backend, f"<byte-level BPE: {learned} learned ids, digit runs of <= {digits}>")


def config_for_tokenizer(config: Qwen3VLConfig, tokenizer: Tokenizer) -> Qwen3VLConfig:
    """``config`` with an embedding table sized to ``tokenizer`` (rounded up to a multiple of
    VOCAB_MULTIPLE) and the tokenizer's ids of the vision tokens."""
    special = tokenizer.special
    vocab = -(-tokenizer.vocab_size // VOCAB_MULTIPLE) * VOCAB_MULTIPLE
    return dataclasses.replace(
        config, text=dataclasses.replace(config.text, vocab_size=vocab),
        image_token_id=special.image_pad, video_token_id=tokenizer.token_id("<|video_pad|>"),
        vision_start_token_id=special.vision_start, vision_end_token_id=special.vision_end)
