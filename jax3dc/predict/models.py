"""The two models at inference, on in-memory images (no Record): text in, text out.

``jax3dc.sampler.Generator`` loads a checkpoint and generates for records read from shards;
``predict`` has an image from disk and an S it rendered, so this module feeds those straight to the
same jitted prefill + decode. Each model becomes a plain callable (prompt text -> generated
text), which is also the seam tests use to stand in for a model (``generate_structure`` /
``generate_program`` of :func:`jax3dc.predict.pipeline.predict`).
"""

from __future__ import annotations

from typing import TYPE_CHECKING, Callable, Sequence

import numpy as np
from PIL import Image

from jax3dc.prompt import chat_messages, code_messages

if TYPE_CHECKING:
    from jax3dc.sampler import Generator

TextModel = Callable[[str], str]
"""Prompt text -> the model's raw output text (a structure JSON or a part program)."""

DEFAULT_MAX_NEW_TOKENS = 2048


def generate_texts(generator: "Generator", images: Sequence[Image.Image], messages: list[dict], max_new_tokens: int,
                   grammar_prompt: str | None = None, candidates: int = 1, temperature: float = 0.8,
                   top_p: float = 0.95, seed: int = 0, program_grammar: bool = False) -> list[tuple[str, float]]:
    """The model's replies (without the end-of-turn token) and their log-likelihoods to one chat
    whose image items are ``images``, in order: ``candidates`` rows of one decode, the first greedy,
    the others sampled; under the structure grammar of ``grammar_prompt`` when it is given, or
    the part-program grammar with ``program_grammar``."""
    import jax

    from jax3dc.constrained import program_constraint, structure_constraint
    from jax3dc.processing.chat import encode_chat
    from jax3dc.generate import GenerationConfig, decode, prefill, repeat_rows  # jax: imported only to generate
    from jax3dc.processing.processor import preprocess_images

    processed = preprocess_images(list(images), generator.processor)
    chat = encode_chat(generator.tokenizer, messages, processed.image_grid_thw,
                       generator.config.vision.spatial_merge_size, add_generation_prompt=True)
    ids = chat.input_ids[None, :]
    window = int(np.prod(processed.image_grid_thw, axis=1).max())
    prefilled = prefill(generator.model, ids, np.ones_like(ids), processed.pixel_values, processed.image_grid_thw,
                        max_new_tokens, vision_window=window)
    special = generator.tokenizer.special
    sampled = candidates > 1
    if sampled:
        prefilled = repeat_rows(prefilled, candidates)
    config = GenerationConfig(max_new_tokens=max_new_tokens, stop_ids=special.stop_ids, pad_id=special.endoftext,
                              temperature=temperature if sampled else 0.0, top_p=top_p if sampled else 1.0)
    vocab = generator.config.text.vocab_size
    constraint = None
    if grammar_prompt is not None:
        constraint = structure_constraint(generator.tokenizer, vocab, [grammar_prompt] * candidates)
    elif program_grammar:
        constraint = program_constraint(generator.tokenizer, vocab, candidates)
    greedy = np.arange(candidates) == 0 if sampled else None
    out = decode(generator.model, prefilled, config, jax.random.key(seed), greedy, constraint)
    replies = []
    for row in range(candidates):
        tokens = np.asarray(out.tokens)[row, :int(np.asarray(out.lengths)[row])].tolist()
        if tokens and tokens[-1] in special.stop_ids:
            tokens = tokens[:-1]  # the end-of-turn marker is not part of the reply (a program would not parse)
        replies.append((generator.tokenizer.decode(tokens), float(np.asarray(out.logprobs)[row])))
    return replies


def generate_text(generator: "Generator", images: Sequence[Image.Image], messages: list[dict],
                  max_new_tokens: int) -> str:
    """The model's greedy, unconstrained reply (the code model's part program)."""
    return generate_texts(generator, images, messages, max_new_tokens)[0][0]


def structure_model(generator: "Generator", image: Image.Image, seg: Image.Image, max_new_tokens: int,
                    constrained: bool = True) -> TextModel:
    """Stage 2 (f_str): reads (I, S, prompt) and writes the structure JSON (greedy; under the
    structure grammar of the prompt unless ``constrained`` is off)."""
    return lambda prompt: generate_texts(generator, [image, seg], chat_messages(prompt), max_new_tokens,
                                         prompt if constrained else None)[0][0]


def structure_candidates(generator: "Generator", image: Image.Image, seg: Image.Image, max_new_tokens: int,
                         candidates: int, constrained: bool = True) -> Callable[[str], list[tuple[str, float]]]:
    """Stage 2 with ``candidates`` answers per prompt (text, log-likelihood), the first greedy."""
    return lambda prompt: generate_texts(generator, [image, seg], chat_messages(prompt), max_new_tokens,
                                         prompt if constrained else None, candidates)


def code_model(generator: "Generator", image: Image.Image, max_new_tokens: int, constrained: bool = True) -> TextModel:
    """Stage 1, code backend: reads I and the fixed code prompt and writes a part program (greedy;
    under the part-program grammar unless ``constrained`` is off)."""
    return lambda prompt: generate_texts(generator, [image], code_messages(), max_new_tokens,
                                         program_grammar=constrained)[0][0]
