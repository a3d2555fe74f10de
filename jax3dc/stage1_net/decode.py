"""The network's outputs for one image -> a parameter record that fits its schema, always.

The category is the arg-max of its logits; each of its ``Number`` values is clipped to [0, 1],
mapped onto [lo, hi] and rounded to the schema's decimals (then clipped again, so rounding never
leaves the range); each discrete value is the arg-max over that entry's real classes only. Any
outputs (an untrained network's, NaNs included) give a record the schema accepts, so the text
always parses and the factory always runs it.
"""

from __future__ import annotations

from typing import Mapping

import numpy as np

from jax3dc.parameters import DECIMALS, Count, Number, Parameters, Schema, format_parameters
from jax3dc.stage1_net.layout import OutputLayout, Slot, classes


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
