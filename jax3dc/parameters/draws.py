"""Where a factory reads its parameters: drawn from a seeded generator, or given by a record.

A factory asks for each parameter by name (``p.number("width")``); the schema says its kind and
range. Drawn, each kind makes exactly one generator call (``Number``: ``uniform`` rounded to
DECIMALS; ``Count``: ``integers(lo, hi + 1)``; ``Chance``: ``random() < p``; ``Choice``:
``integers(len(options))``), in the order the factory asks, and the value is recorded; given,
the value is read from the record. So a factory run on ``Draws.seeded`` and then on
``Draws.given(draws.parameters())`` takes the same branches with the same numbers.
"""

from __future__ import annotations

import numpy as np

from jax3dc.parameters.schema import DECIMALS, Chance, Choice, Count, Number, ParameterError, Parameters, Schema, Spec


class Draws:
    """A factory's parameter source; see the module docstring. Each (name, slot) is read once:
    a second read is a factory bug (two draws sharing a name), reported as such."""

    def __init__(self, schema: Schema, rng: np.random.Generator | None = None, given: Parameters | None = None):
        if (rng is None) == (given is None):
            raise ValueError("Draws needs exactly one of a generator and given parameters")
        self.schema = schema
        self._rng = rng
        self._given = schema.check(given) if given is not None else None
        self._drawn: dict[str, dict[int, float | int]] = {}

    @classmethod
    def seeded(cls, schema: Schema, rng: np.random.Generator) -> "Draws":
        return cls(schema, rng=rng)

    @classmethod
    def given(cls, schema: Schema, params: Parameters) -> "Draws":
        return cls(schema, given=params)

    def _read(self, name: str, slot: int | None, kind: type) -> float | int:
        spec = self.schema.spec(name)
        where = f"{self.schema.category}.{name}" + (f"[{slot}]" if slot is not None else "")
        if not isinstance(spec, kind):
            raise ParameterError(where, f"read as {kind.__name__}, declared {type(spec).__name__}")
        if (slot is None) != (spec.slots == 0) or (slot is not None and not 0 <= slot < spec.slots):
            raise ParameterError(where, f"slot {slot!r} does not fit {spec.slots} slots")
        seen = self._drawn.setdefault(name, {})
        key = slot if slot is not None else 0
        if key in seen:
            raise ParameterError(where, "read twice (two draws share one name)")
        if self._given is not None:
            value = self._given[name][slot] if slot is not None else self._given[name]
        else:
            value = _draw(spec, self._rng)
        seen[key] = value
        return value

    def number(self, name: str, slot: int | None = None) -> float:
        return float(self._read(name, slot, Number))

    def count(self, name: str, slot: int | None = None) -> int:
        return int(self._read(name, slot, Count))

    def chance(self, name: str, slot: int | None = None) -> bool:
        return bool(self._read(name, slot, Chance))

    def choice(self, name: str, slot: int | None = None) -> str:
        spec = self.schema.spec(name)
        index = int(self._read(name, slot, Choice))
        return spec.options[index]

    @property
    def read(self) -> frozenset[str]:
        """The entries this run has read (the rest keep their defaults in ``parameters()``)."""
        return frozenset(self._drawn)

    def parameters(self) -> Parameters:
        """The record of this run: every value read, defaults for entries never read."""
        values = self.schema.defaults()
        for spec in self.schema.specs:
            seen = self._drawn.get(spec.name, {})
            if spec.slots:
                values[spec.name] = tuple(seen.get(i, spec.default()) for i in range(spec.slots))
            elif seen:
                values[spec.name] = seen[0]
        return self.schema.check(Parameters(self.schema.category, values))


def _draw(spec: Spec, rng: np.random.Generator) -> float | int:
    if isinstance(spec, Number):
        return round(float(rng.uniform(spec.lo, spec.hi)), DECIMALS)
    if isinstance(spec, Count):
        return int(rng.integers(spec.lo, spec.hi + 1))
    if isinstance(spec, Chance):
        return int(rng.random() < spec.p)
    return int(rng.integers(len(spec.options)))
