"""A stage-1 network folder, ``stage1_net.json`` (config and schemas) beside ``model.safetensors``,
and the reader it gives: image -> the network's outputs -> a parameter text that fits its schema.

The JSON marker holds everything decoding needs (the categories and each entry's kind and range),
so a folder is read without the factories. Weights are float16 (the network is small and its
activations are normalised; float16 halves the shipped bytes). Loading is strict: a missing,
unexpected or misshapen tensor raises InputFileError naming the file and the tensor.

Decoding always gives a record its schema accepts: the category is the arg-max of its logits; each
of its ``Number`` values is clipped to [0, 1], mapped onto [lo, hi] and rounded to the schema's
decimals (then clipped again, so rounding never leaves the range); each discrete value is the
arg-max over that entry's real classes only. Any outputs (an untrained network's, NaNs included)
give a record the schema accepts, so the text always parses and the factory always runs it.
"""

from __future__ import annotations

import json
from dataclasses import dataclass
from pathlib import Path
from typing import Callable, Mapping

import numpy as np
from flax import nnx

from jax3dc.errors import InputFileError, Jax3dcError
from jax3dc.nnx_weights import load_params, save_params
from jax3dc.parameters import DECIMALS, Count, Number, Parameters, Schema, format_parameters
from jax3dc.stage1_net.image import network_image
from jax3dc.stage1_net.layout import OutputLayout, Slot, classes, schemas_from_json, schemas_to_json
from jax3dc.stage1_net.model import Stage1Net, Stage1NetConfig, forward

MARKER = "stage1_net.json"
WEIGHTS = "model.safetensors"
FORMAT = "jax3dc-stage1-net/1"


def _number(slot: Slot, value: float) -> float:
    spec = slot.spec
    share = float(np.clip(np.nan_to_num(value, nan=0.5), 0.0, 1.0))
    return float(min(max(round(spec.lo + share * (spec.hi - spec.lo), DECIMALS), spec.lo), spec.hi))


def _discrete(slot: Slot, logits: np.ndarray) -> int:
    real = np.nan_to_num(np.asarray(logits[:classes(slot.spec)], np.float64), nan=-np.inf)
    index = int(np.argmax(real)) if np.isfinite(real).any() else 0
    return slot.spec.lo + index if isinstance(slot.spec, Count) else index


def decode_parameters(layout: OutputLayout, schemas: Mapping[str, Schema], category_logits: np.ndarray,
                      numbers: np.ndarray, discrete_logits: np.ndarray) -> Parameters:
    """One image's record from its outputs ([C], [N], [D, K]); see the module docstring."""
    logits = np.nan_to_num(np.asarray(category_logits, np.float64), nan=-np.inf)
    category = layout.categories[int(np.argmax(logits)) if np.isfinite(logits).any() else 0]
    schema = schemas[category]
    values: dict[str, list] = {spec.name: [] for spec in schema.specs}
    for slot in layout.numbers:
        if slot.category == category:
            values[slot.spec.name].append(_number(slot, numbers[slot.index]))
    for slot in layout.discrete:
        if slot.category == category:
            values[slot.spec.name].append(_discrete(slot, discrete_logits[slot.index]))
    record = {spec.name: tuple(values[spec.name]) if spec.slots else values[spec.name][0] for spec in schema.specs}
    return schema.check(Parameters(category, record))


def decode_text(layout: OutputLayout, schemas: Mapping[str, Schema], category_logits: np.ndarray,
                numbers: np.ndarray, discrete_logits: np.ndarray) -> str:
    """The record's one-line text (jax3dc.parameters.format_parameters)."""
    params = decode_parameters(layout, schemas, category_logits, numbers, discrete_logits)
    return format_parameters(params, schemas[params.category])


def normalised_number(spec: Number, value: float) -> float:
    """A Number's training target: 0 at lo, 1 at hi (the inverse of decoding's mapping)."""
    return 0.0 if spec.hi == spec.lo else (float(value) - spec.lo) / (spec.hi - spec.lo)



@dataclass(frozen=True)
class Stage1Network:
    """A loaded network with what decoding needs."""

    model: Stage1Net
    schemas: dict[str, Schema]
    layout: OutputLayout

    def read(self, images: np.ndarray) -> list[str]:
        """Parameter texts of a batch of network images ([B, size, size, 3] floats in [0, 1])."""
        cat, num, disc = (np.asarray(x) for x in forward(self.model, images))
        return [decode_text(self.layout, self.schemas, cat[i], num[i], disc[i]) for i in range(len(images))]


def save_network(folder: str | Path, model: Stage1Net, schemas: Mapping[str, Schema], notes: dict | None = None) -> Path:
    """Writes the folder (created if needed); ``notes`` (e.g. the training recipe) go into the marker."""
    folder = Path(folder)
    folder.mkdir(parents=True, exist_ok=True)
    save_params(model, folder / WEIGHTS)
    marker = {"format": FORMAT, "config": model.config.to_json(), "schemas": schemas_to_json(schemas),
              "weights": WEIGHTS, **({"notes": notes} if notes else {})}
    (folder / MARKER).write_text(json.dumps(marker, indent=1) + "\n", encoding="utf-8")
    return folder


def _read_marker(folder: Path) -> dict:
    path = folder / MARKER
    if not folder.is_dir():
        raise InputFileError(str(folder), "not a folder (expected a stage-1 network folder holding " + MARKER + ")")
    if not path.is_file():
        raise InputFileError(str(path), "missing: not a stage-1 network folder")
    try:
        marker = json.loads(path.read_text(encoding="utf-8"))
    except (ValueError, UnicodeDecodeError) as e:
        raise InputFileError(str(path), f"not valid JSON ({e})") from None
    if not isinstance(marker, dict) or marker.get("format") != FORMAT:
        raise InputFileError(str(path), f"format is not {FORMAT!r}")
    return marker


def load_network(folder: str | Path) -> Stage1Network:
    """The network a ``save_network`` folder holds; see the module docstring for the errors."""
    folder = Path(folder)
    marker = _read_marker(folder)
    marker_path = str(folder / MARKER)
    try:
        schemas = schemas_from_json(marker["schemas"])
        config = Stage1NetConfig.from_json(marker["config"])
    except (KeyError, TypeError, ValueError, Jax3dcError) as e:
        raise InputFileError(marker_path, f"bad config or schemas ({e})") from None
    layout = OutputLayout.of(schemas)
    if Stage1NetConfig.for_layout(layout, image_size=config.image_size, widths=config.widths,
                                  reduced=config.reduced, hidden=config.hidden, blocks=config.blocks) != config:
        raise InputFileError(marker_path, "the config's head sizes do not match its schemas")
    weights = folder / str(marker.get("weights", WEIGHTS))
    model = load_params(nnx.eval_shape(lambda: Stage1Net(config, nnx.Rngs(0))), weights)
    return Stage1Network(model, schemas, layout)


def load_reader(folder: str | Path) -> Callable[[np.ndarray], str]:
    """A function from an RGB uint8 image (any size, HxWx3) to the parameter text of its object;
    a bad image raises ImageInputError (jax3dc.stage1_net.image)."""
    network = load_network(folder)
    size = network.model.config.image_size

    def read(image: np.ndarray) -> str:
        return network.read(network_image(image, size)[None])[0]

    return read
