"""The two models at inference, on in-memory images (no Record): text in, text out.

``eval.generation.Generator`` loads a checkpoint and generates for records read from shards;
``predict`` has an image from disk and an S it rendered, so this module feeds those straight to the
same jitted prefill + decode. Each model becomes a plain callable (prompt text -> generated
text), which is also the seam tests use to stand in for a model (``generate_structure`` /
``generate_program`` of :func:`eval.predict.pipeline.predict`).
"""

from __future__ import annotations

from typing import TYPE_CHECKING, Callable, Sequence

import numpy as np
from PIL import Image

from jax3dc.prompt import chat_messages, code_messages

if TYPE_CHECKING:
    from eval.generation import Generator

TextModel = Callable[[str], str]
"""Prompt text -> the model's raw output text (a structure JSON or a part program)."""

DEFAULT_MAX_NEW_TOKENS = 2048


def generate_text(generator: "Generator", images: Sequence[Image.Image], messages: list[dict],
                  max_new_tokens: int) -> str:
    """The model's reply (greedy, without the end-of-turn token) to one chat whose image items are
    ``images``, in order."""
    from jax3dc.model.chat import encode_chat
    from jax3dc.model.generate import GenerationConfig, decode, prefill  # jax: imported only to generate
    from jax3dc.model.processor import preprocess_images

    processed = preprocess_images(list(images), generator.processor)
    chat = encode_chat(generator.tokenizer, messages, processed.image_grid_thw,
                       generator.config.vision.spatial_merge_size, add_generation_prompt=True)
    ids = chat.input_ids[None, :]
    window = int(np.prod(processed.image_grid_thw, axis=1).max())
    prefilled = prefill(generator.model, ids, np.ones_like(ids), processed.pixel_values, processed.image_grid_thw,
                        max_new_tokens, vision_window=window)
    special = generator.tokenizer.special
    config = GenerationConfig(max_new_tokens=max_new_tokens, stop_ids=special.stop_ids, pad_id=special.endoftext)
    out = decode(generator.model, prefilled, config)
    tokens = np.asarray(out.tokens)[0, :int(np.asarray(out.lengths)[0])].tolist()
    if tokens and tokens[-1] in special.stop_ids:
        tokens = tokens[:-1]  # the end-of-turn marker is not part of the reply (a program would not parse)
    return generator.tokenizer.decode(tokens)


def structure_model(generator: "Generator", image: Image.Image, seg: Image.Image, max_new_tokens: int) -> TextModel:
    """Stage 2 (f_str): reads (I, S, prompt) and writes the structure JSON."""
    return lambda prompt: generate_text(generator, [image, seg], chat_messages(prompt), max_new_tokens)


def code_model(generator: "Generator", image: Image.Image, max_new_tokens: int) -> TextModel:
    """Stage 1, code backend: reads I and the fixed code prompt and writes a part program."""
    return lambda prompt: generate_text(generator, [image], code_messages(), max_new_tokens)
