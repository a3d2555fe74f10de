"""Parameter schemas (one per factory category) and the records they type.

Four kinds of entry, each with its own sampling rule (``Draws``) and value type:

* ``Number``: uniform in [lo, hi], rounded to DECIMALS decimals (a length in metres, an angle in
  degrees): a float;
* ``Count``: an integer in [lo, hi] (both inclusive);
* ``Chance``: a yes/no with probability ``p`` of yes: 0 or 1;
* ``Choice``: one of ``options`` (a finish, a style): the option's index.

An entry with ``slots`` > 0 holds that many values (e.g. books per shelf), indexed by the factory.
A record holds every entry of its schema, in schema order: entries a branch of the factory never
read keep their default (``lo``, 0), so every category has one fixed shape, which keeps the text
and its grammar regular.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Mapping, Union

from jax3dc.errors import Jax3dcError

DECIMALS = 3
Value = Union[float, int, tuple]


class ParameterError(Jax3dcError):
    """A parameter record (or its text) does not fit its schema; ``where`` names the entry."""

    def __init__(self, where: str, message: str):
        self.where = where
        self.message = message
        super().__init__(f"{where}: {message}" if where else message)

    def __reduce__(self):
        return type(self), (self.where, self.message)


@dataclass(frozen=True)
class Number:
    name: str
    lo: float
    hi: float
    slots: int = 0

    def default(self) -> float:
        return float(self.lo)

    def check(self, value, where: str) -> float:
        if isinstance(value, bool) or not isinstance(value, (int, float)) or not math.isfinite(value):
            raise ParameterError(where, f"expected a number, got {value!r}")
        value = float(value)
        if round(value, DECIMALS) != value:
            raise ParameterError(where, f"{value!r} has more than {DECIMALS} decimals")
        if not self.lo <= value <= self.hi:
            raise ParameterError(where, f"{value!r} is outside [{self.lo}, {self.hi}]")
        return value


@dataclass(frozen=True)
class Count:
    name: str
    lo: int
    hi: int
    slots: int = 0

    def default(self) -> int:
        return int(self.lo)

    def check(self, value, where: str) -> int:
        if isinstance(value, bool) or not isinstance(value, int):
            raise ParameterError(where, f"expected an integer, got {value!r}")
        if not self.lo <= value <= self.hi:
            raise ParameterError(where, f"{value!r} is outside {self.lo}..{self.hi}")
        return int(value)


@dataclass(frozen=True)
class Chance:
    name: str
    p: float
    slots: int = 0

    def default(self) -> int:
        return 0

    def check(self, value, where: str) -> int:
        if isinstance(value, bool) or value not in (0, 1) or not isinstance(value, int):
            raise ParameterError(where, f"expected 0 or 1, got {value!r}")
        return int(value)


@dataclass(frozen=True)
class Choice:
    name: str
    options: tuple[str, ...]
    slots: int = 0

    def default(self) -> int:
        return 0

    def check(self, value, where: str) -> int:
        if isinstance(value, bool) or not isinstance(value, int):
            raise ParameterError(where, f"expected an option index, got {value!r}")
        if not 0 <= value < len(self.options):
            raise ParameterError(where, f"option {value!r} is outside 0..{len(self.options) - 1}")
        return int(value)


Spec = Union[Number, Count, Chance, Choice]


@dataclass(frozen=True)
class Parameters:
    """One object's parameters: its category and a value per schema entry, in schema order
    (a tuple for entries with slots). Plain numbers only, so a record is its own JSON."""

    category: str
    values: Mapping[str, Value]

    def __getitem__(self, name: str) -> Value:
        return self.values[name]

    def to_dict(self) -> dict:
        return {"category": self.category,
                "values": {k: list(v) if isinstance(v, tuple) else v for k, v in self.values.items()}}


@dataclass(frozen=True)
class Schema:
    """A category's parameters in the order the factory first reads them."""

    category: str
    specs: tuple[Spec, ...]

    def __post_init__(self):
        names = [s.name for s in self.specs]
        if len(set(names)) != len(names):
            raise ValueError(f"schema {self.category!r} names an entry twice: {names}")

    def spec(self, name: str) -> Spec:
        for s in self.specs:
            if s.name == name:
                return s
        raise ParameterError(f"{self.category}.{name}", "not a parameter of this category")

    def defaults(self) -> dict[str, Value]:
        return {s.name: (s.default(),) * s.slots if s.slots else s.default() for s in self.specs}

    def check(self, params: Parameters) -> Parameters:
        """``params`` with its values checked against this schema (types, ranges, order, slots);
        raises ParameterError naming the first entry that does not fit."""
        if params.category != self.category:
            raise ParameterError("category", f"{params.category!r} is not {self.category!r}")
        given = list(params.values)
        expected = [s.name for s in self.specs]
        if given != expected:
            missing = [n for n in expected if n not in params.values]
            extra = [n for n in given if n not in expected]
            what = f"missing {missing}" if missing else f"unknown {extra}" if extra else "out of order"
            raise ParameterError(self.category, f"entries {what}; expected {', '.join(expected)}")
        values: dict[str, Value] = {}
        for s in self.specs:
            where = f"{self.category}.{s.name}"
            value = params.values[s.name]
            if s.slots:
                if not isinstance(value, (tuple, list)) or len(value) != s.slots:
                    raise ParameterError(where, f"expected {s.slots} values, got {value!r}")
                values[s.name] = tuple(s.check(v, f"{where}[{i}]") for i, v in enumerate(value))
            else:
                values[s.name] = s.check(value, where)
        return Parameters(self.category, values)
