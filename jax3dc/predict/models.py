"""The models at inference, on in-memory images: text in, text out, through the one sampler.

``predict`` has an image from disk and an S it rendered; it hands them (as PNG bytes, lossless) to
``jax3dc.sampler.Sampler.generate_batch``, the decode that ``eval run`` uses for records, one
prompt at a time. Each model becomes a plain callable (prompt text -> generated text), which is
also the seam tests use to stand in for a model (``generate_structure`` of
:class:`jax3dc.predict.pipeline.PredictConfig`, ``generate_program`` of its stage-1 config).
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Callable

import numpy as np

from jax3dc.constrained.parameters import longest_text
from jax3dc.decoding import DecodeOptions
from jax3dc.factories.registry import SCHEMAS
from jax3dc.render import png_bytes
from jax3dc.sampler import Sampler

TextModel = Callable[[str], str]
"""Prompt text -> the model's raw output text (a structure JSON or a part program)."""

IMAGE_KEY = "the input image"  # what a decode error about predict's one prompt names


@dataclass(frozen=True)
class ImageExample:
    """One prediction's images and prompt, shaped as the sampler's ``Example`` (a dataset record is one too)."""

    image_png: bytes
    seg_png: bytes  # b"" for the code and parameters tasks: I alone
    prompt: str
    key: str = IMAGE_KEY


def generate_texts(sampler: Sampler, example: ImageExample, task: str, max_new_tokens: int,
                   options: DecodeOptions = DecodeOptions()) -> list[tuple[str, float]]:
    """The model's replies (without the end-of-turn token) and their log-likelihoods: one prompt,
    ``options.candidates`` rows of one decode, the first greedy, the others sampled."""
    samples = sampler.generate_batch([sampler.prompt(example, task)], 1, max_new_tokens, bucket=1, options=options)[0]
    return [(s.reply, s.logprob) for s in samples]


def structure_model(sampler: Sampler, image_png: bytes, seg_png: bytes, max_new_tokens: int,
                    options: DecodeOptions = DecodeOptions()) -> TextModel:
    """Stage 2 (f_str): reads (I, S, prompt) and writes the structure JSON (the first answer, greedy;
    under the structure grammar of the prompt unless ``options.constrained``
    is off; joints grounded in the legend's boxes with ``options.grounding``)."""
    return lambda prompt: generate_texts(sampler, ImageExample(image_png, seg_png, prompt), "structure",
                                         max_new_tokens, options)[0][0]


def structure_candidates(sampler: Sampler, image_png: bytes, seg_png: bytes, max_new_tokens: int,
                         options: DecodeOptions) -> Callable[[str], list[tuple[str, float]]]:
    """Stage 2 with ``options.candidates`` answers per prompt (text, log-likelihood), the first greedy."""
    return lambda prompt: generate_texts(sampler, ImageExample(image_png, seg_png, prompt), "structure",
                                         max_new_tokens, options)


def code_model(sampler: Sampler, image_png: bytes, max_new_tokens: int, constrained: bool = True) -> TextModel:
    """Stage 1, code backend: reads I and the fixed code prompt and writes a part program (greedy;
    under the part-program grammar unless ``constrained`` is off)."""
    return lambda prompt: generate_texts(sampler, ImageExample(image_png, b"", prompt), "code", max_new_tokens,
                                         DecodeOptions(constrained=constrained))[0][0]


def parameters_model(sampler: Sampler, max_new_tokens: int, constrained: bool = True) -> Callable[[np.ndarray], str]:
    """Stage 1, parameters backend: reads I (RGB uint8) and the fixed parameters prompt and writes a
    factory's category and parameters (greedy; under the parameter grammar of the factories'
    schemas unless ``constrained`` is off). The budget is at most one token per byte of the longest
    text the schemas allow, and the stop token."""
    budget = min(max_new_tokens, longest_text(SCHEMAS) + 1)
    options = DecodeOptions(constrained=constrained, schemas=SCHEMAS)
    return lambda rgb: generate_texts(sampler, ImageExample(png_bytes(rgb), b"", ""), "parameters", budget,
                                      options)[0][0]
