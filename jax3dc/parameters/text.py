"""The one-line text of a parameter record, as a model writes it:

    cabinet(width=0.812, depth=0.4, height=1.1, wood=2, shelves=3, bins=(0, 1, 0))

The category, then every entry of its schema in schema order as ``name=value``; numbers with at
most DECIMALS decimals and no trailing zeros, integers for counts, 0/1 for chances, option indices
for choices, a parenthesised list for entries with slots. One spelling per record, so the text is
a training target and the grammar (``jax3dc.constrained.parameters``) can fix every byte but the
values. Parsing is a strict scanner, never ``eval``.
"""

from __future__ import annotations

import re
from typing import Mapping

from jax3dc.parameters.schema import DECIMALS, Number, ParameterError, Parameters, Schema, Value


def format_number(value: float) -> str:
    text = f"{value:.{DECIMALS}f}".rstrip("0").rstrip(".")
    return "0" if text in ("-0", "") else text


def _value(value, is_number: bool) -> str:
    if isinstance(value, tuple):
        return "(" + ", ".join(_value(v, is_number) for v in value) + ")"
    return format_number(value) if is_number else str(int(value))


def format_parameters(params: Parameters, schema: Schema) -> str:
    """The record's text; the record is checked against ``schema`` first."""
    params = schema.check(params)
    body = ", ".join(f"{s.name}={_value(params[s.name], isinstance(s, Number))}" for s in schema.specs)
    return f"{schema.category}({body})"


_TOKEN = re.compile(r"\s*(?:(?P<name>[a-z_][a-z0-9_]*)|(?P<number>-?\d+(?:\.\d+)?)|(?P<punct>[(),=]))")


def _scan(text: str) -> list[tuple[str, str, int]]:
    out, pos = [], 0
    text = text.rstrip()
    while pos < len(text):
        m = _TOKEN.match(text, pos)
        if m is None or m.end() == pos:
            raise ParameterError(f"column {pos + 1}", f"unexpected {text[pos:pos + 12]!r}")
        kind = m.lastgroup
        out.append((kind, m.group(kind), pos + 1))
        pos = m.end()
    return out


def parse_parameters(text: str, schemas: Mapping[str, Schema]) -> Parameters:
    """The record a text describes, checked against its category's schema; raises
    ParameterError naming the column or entry that does not fit."""
    tokens = _scan(text)
    at = 0

    def take(kind: str, value: str | None = None) -> str:
        nonlocal at
        if at >= len(tokens):
            raise ParameterError("end", f"the text ends where {value or kind} is expected")
        k, v, col = tokens[at]
        if k != kind or (value is not None and v != value):
            raise ParameterError(f"column {col}", f"expected {value or kind}, got {v!r}")
        at += 1
        return v

    def number() -> float | int:
        v = take("number")
        return float(v) if "." in v else int(v)

    category = take("name")
    if category not in schemas:
        raise ParameterError("category", f"unknown category {category!r}")
    schema = schemas[category]
    take("punct", "(")
    values: dict[str, Value] = {}
    for i, spec in enumerate(schema.specs):
        if i:
            take("punct", ",")
        name = take("name")
        if name != spec.name:
            raise ParameterError(f"{category}.{spec.name}", f"expected entry {spec.name!r}, got {name!r}")
        take("punct", "=")
        if spec.slots:
            take("punct", "(")
            items = []
            for j in range(spec.slots):
                if j:
                    take("punct", ",")
                items.append(number())
            take("punct", ")")
            values[name] = tuple(float(v) if isinstance(spec, Number) else v for v in items)
        else:
            v = number()
            values[name] = float(v) if isinstance(spec, Number) else v
    take("punct", ")")
    if at != len(tokens):
        raise ParameterError(f"column {tokens[at][2]}", "text continues after the closing parenthesis")
    return schema.check(Parameters(category, values))
