"""Object parameters: a category and its factory's parameter vector, the stage-1 target.

A procedural factory is a function of a few named draws (a width, a drawer count, a wood). Its
``Schema`` lists them in order with their ranges; a ``Parameters`` record holds one value per
entry; ``Draws`` is what a factory reads them from, either drawn from a seeded generator (and
recorded) or given by a record, so the factory runs from the record alone into the same object.
``format_parameters`` / ``parse_parameters`` are the record's one-line text (what a model writes);
``jax3dc.constrained.parameters`` decodes it under a grammar built from the schemas.

The schemas and builds themselves live with the factories (``jax3dc.factories``), whose
``run_parameters`` turns a record into the object (``docs/stage1_parameters.md``).
"""

from jax3dc.parameters.draws import Draws
from jax3dc.parameters.schema import (
    DECIMALS,
    Chance,
    Choice,
    Count,
    Number,
    ParameterError,
    Parameters,
    Schema,
    Spec,
)
from jax3dc.parameters.text import format_number, format_parameters, parse_parameters

__all__ = [
    "DECIMALS", "Chance", "Choice", "Count", "Draws", "Number", "ParameterError", "Parameters", "Schema", "Spec",
    "format_number", "format_parameters", "parse_parameters",
]
