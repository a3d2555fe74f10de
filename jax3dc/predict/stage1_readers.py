"""Stage-1 readers: image I in, a factory parameter text out (``jax3dc.parameters``), whatever model writes it.

``--stage1 parameters --stage1-model DIR`` hands the folder to ``load_reader``, which picks the kind
of model by the marker file the folder holds (the first of ``READERS`` that matches): the image
network (``stage1_net.json``; the shipped one) before the language model's ``config.json``, the more
specific marker first. Another kind of model plugs in with one entry.
"""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path
from typing import Any, Callable

import numpy as np

from jax3dc.errors import InputFileError
from jax3dc.predict.models import parameters_model
from jax3dc.stage1_net import load_reader as load_image_network

Reader = Callable[[np.ndarray], str]
"""RGB uint8 image (H, W, 3) -> the one-line parameter text, e.g. ``stapler(length=0.31, ...)``."""


@dataclass(frozen=True)
class ReaderSettings:
    """What a reader may need from predict: a loaded language model is shared with stage 2 when both
    stages name one folder (``sampler`` loads each folder once), and the decoding flags."""

    sampler: Callable[[Path], Any]  # folder -> jax3dc.sampler.Sampler
    max_new_tokens: int
    constrained: bool


@dataclass(frozen=True)
class ReaderKind:
    """One kind of stage-1 model: the file its folder holds, what to call it, and how to load it."""

    marker: str
    description: str
    load: Callable[[Path, ReaderSettings], Reader]


def _language_model(folder: Path, settings: ReaderSettings) -> Reader:
    return parameters_model(settings.sampler(folder), settings.max_new_tokens, settings.constrained)


def _image_network(folder: Path, settings: ReaderSettings) -> Reader:
    return load_image_network(folder)


READERS: tuple[ReaderKind, ...] = (
    ReaderKind("stage1_net.json", "a stage-1 image network (jax3dc.stage1_net), as bench/stage1_net.py "
               "packages it", _image_network),
    ReaderKind("config.json", "a parameters language model: a Hugging Face folder, as the recipe "
               "bench/stage1_model.py packages it", _language_model),
)


def load_reader(folder: str | Path, settings: ReaderSettings) -> Reader:
    """The reader of the stage-1 model in ``folder``; a folder no kind recognises is an InputFileError
    listing the markers it looked for."""
    folder = Path(folder)
    if not folder.is_dir():
        raise InputFileError(folder, "stage-1 model folder not found (--stage1-model)")
    for kind in READERS:
        if (folder / kind.marker).is_file():
            return kind.load(folder, settings)
    wanted = "; ".join(f"{kind.marker} ({kind.description})" for kind in READERS)
    raise InputFileError(folder, f"not a stage-1 model folder: it holds none of {wanted}")
