"""Where each category's parameter entries sit in the network's outputs, and the schemas as JSON.

The network has three heads (jax3dc.stage1_net.model): category logits, one regression output per
``Number`` value, and one padded group of class logits per ``Count`` / ``Chance`` / ``Choice``
value. ``OutputLayout`` gives every (category, entry, slot) its place in those heads, so a
category's outputs are read (and its losses masked) by index. The schemas travel with the weights
in ``stage1_net.json`` (``schemas_to_json`` / ``schemas_from_json``), so decoding needs nothing
outside the core: the factories that own the schemas stay where they are.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any, Mapping

import numpy as np

from jax3dc.parameters import Chance, Choice, Count, Number, ParameterError, Schema, Spec


def classes(spec: Spec) -> int:
    """How many values a discrete entry takes (a Number has none)."""
    if isinstance(spec, Count):
        return spec.hi - spec.lo + 1
    if isinstance(spec, Chance):
        return 2
    if isinstance(spec, Choice):
        return len(spec.options)
    raise TypeError(f"{spec.name} is a Number, not a discrete entry")


@dataclass(frozen=True)
class Slot:
    """One value of one entry: its category, entry, slot (None without slots) and head index."""

    category: str
    spec: Spec
    slot: int | None
    index: int


@dataclass(frozen=True)
class OutputLayout:
    """The head indices of every value of every category, in category and schema order."""

    categories: tuple[str, ...]
    numbers: tuple[Slot, ...]
    discrete: tuple[Slot, ...]
    max_classes: int

    @classmethod
    def of(cls, schemas: Mapping[str, Schema]) -> "OutputLayout":
        if not schemas:
            raise ValueError("a stage-1 network needs at least one category schema")
        numbers: list[Slot] = []
        discrete: list[Slot] = []
        for category, schema in schemas.items():
            for spec in schema.specs:
                target = numbers if isinstance(spec, Number) else discrete
                for slot in range(spec.slots) if spec.slots else (None,):
                    target.append(Slot(category, spec, slot, len(target)))
        widest = max((classes(s.spec) for s in discrete), default=1)
        return cls(tuple(schemas), tuple(numbers), tuple(discrete), widest)

    def class_mask(self) -> np.ndarray:
        """[discrete, max_classes] booleans: which padded logits are real classes."""
        mask = np.zeros((max(len(self.discrete), 1), self.max_classes), bool)
        for s in self.discrete:
            mask[s.index, :classes(s.spec)] = True
        return mask

    def category_masks(self) -> tuple[np.ndarray, np.ndarray]:
        """[categories, numbers] and [categories, discrete] booleans: the values each category owns."""
        index = {c: i for i, c in enumerate(self.categories)}
        numbers = np.zeros((len(self.categories), max(len(self.numbers), 1)), bool)
        discrete = np.zeros((len(self.categories), max(len(self.discrete), 1)), bool)
        for s in self.numbers:
            numbers[index[s.category], s.index] = True
        for s in self.discrete:
            discrete[index[s.category], s.index] = True
        return numbers, discrete


def _spec_to_json(spec: Spec) -> dict[str, Any]:
    base = {"name": spec.name, "slots": spec.slots}
    if isinstance(spec, Number):
        return {"kind": "number", "lo": spec.lo, "hi": spec.hi, **base}
    if isinstance(spec, Count):
        return {"kind": "count", "lo": spec.lo, "hi": spec.hi, **base}
    if isinstance(spec, Chance):
        return {"kind": "chance", "p": spec.p, **base}
    return {"kind": "choice", "options": list(spec.options), **base}


def schemas_to_json(schemas: Mapping[str, Schema]) -> dict[str, list[dict[str, Any]]]:
    return {category: [_spec_to_json(s) for s in schema.specs] for category, schema in schemas.items()}


def _spec_from_json(entry: Any, where: str) -> Spec:
    try:
        kind, name, slots = entry["kind"], str(entry["name"]), int(entry.get("slots", 0))
        if kind == "number":
            return Number(name, float(entry["lo"]), float(entry["hi"]), slots)
        if kind == "count":
            return Count(name, int(entry["lo"]), int(entry["hi"]), slots)
        if kind == "chance":
            return Chance(name, float(entry["p"]), slots)
        if kind == "choice":
            return Choice(name, tuple(str(o) for o in entry["options"]), slots)
    except (KeyError, TypeError, ValueError) as e:
        raise ParameterError(where, f"entry is not a schema entry ({type(e).__name__}: {e})") from None
    raise ParameterError(where, f"unknown entry kind {kind!r}")


def schemas_from_json(data: Any) -> dict[str, Schema]:
    """The schemas ``schemas_to_json`` wrote; raises ParameterError naming the entry that is wrong."""
    if not isinstance(data, dict) or not data:
        raise ParameterError("schemas", "expected a non-empty object of category -> entries")
    schemas = {}
    for category, entries in data.items():
        if not isinstance(entries, list):
            raise ParameterError(f"schemas.{category}", "expected a list of entries")
        specs = tuple(_spec_from_json(e, f"schemas.{category}[{i}]") for i, e in enumerate(entries))
        try:
            schemas[category] = Schema(category, specs)
        except ValueError as e:
            raise ParameterError(f"schemas.{category}", str(e)) from None
    return schemas
