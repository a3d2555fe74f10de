"""A factory's parameter record describes its object completely: run from the record alone, every
category gives the object of the seeded path, and any record that fits the schema runs."""

import numpy as np
import pytest

from jax3dc.factories import FACTORIES, generate_object
from jax3dc.factories.registry import SCHEMAS, run_parameters, seeded_draws
from jax3dc.factories.writer import ProgramWriter
from jax3dc.parameters import (Chance, Choice, Count, Draws, Number, ParameterError, Parameters, Schema,
                               format_parameters, parse_parameters)
from jax3dc.structure import to_json
from tests.factory_samples import sample_parameters

CATEGORIES = sorted(FACTORIES)


@pytest.mark.parametrize("category", CATEGORIES)
def test_the_record_alone_rebuilds_the_seeded_object(category):
    for seed in (0, 1, 2):
        seeded = generate_object(category, seed)
        assert sample_parameters(category, seed) == seeded.parameters
        text = format_parameters(seeded.parameters, SCHEMAS[category])
        rebuilt = run_parameters(parse_parameters(text, SCHEMAS), seeded.object_id)
        assert rebuilt.program_text == seeded.program_text
        assert to_json(rebuilt.structure) == to_json(seeded.structure)
        assert rebuilt.names == seeded.names and rebuilt.scale_m_per_nu == seeded.scale_m_per_nu
        assert sorted(rebuilt.parts) == sorted(seeded.parts)
        for pid, mesh in seeded.parts.items():
            np.testing.assert_array_equal(rebuilt.parts[pid].vertices, mesh.vertices)
            np.testing.assert_array_equal(rebuilt.parts[pid].faces, mesh.faces)
        assert rebuilt.parameters == seeded.parameters


def test_every_schema_entry_is_read_by_some_seed():
    """No entry is dead weight in the target: each is read by some branch within 60 seeds."""
    for category, factory in FACTORIES.items():
        read = set()
        for seed in range(60):
            draws = seeded_draws(category, seed)
            factory.build(ProgramWriter(), draws)
            read |= draws.read
        assert read == {s.name for s in factory.schema.specs}, category


def _uniform(spec, rng):
    if isinstance(spec, Number):
        return round(float(rng.uniform(spec.lo, spec.hi)), 3)
    if isinstance(spec, Count):
        return int(rng.integers(spec.lo, spec.hi + 1))
    if isinstance(spec, Chance):
        return int(rng.random() < 0.5)
    return int(rng.integers(len(spec.options)))


def test_any_record_that_fits_the_schema_runs():
    """What a model may write under the grammar (any in-range values, unread entries included)."""
    rng = np.random.default_rng(7)
    for category, schema in sorted(SCHEMAS.items()):
        for _ in range(2):
            values = {s.name: tuple(_uniform(s, rng) for _ in range(s.slots)) if s.slots else _uniform(s, rng)
                      for s in schema.specs}
            obj = run_parameters(Parameters(category, values))
            assert sorted(obj.parts) == list(range(1, len(obj.parts) + 1)) and len(obj.parts) >= 2


def test_text_round_trips_and_is_one_line():
    for category in CATEGORIES:
        params = sample_parameters(category, 5)
        text = format_parameters(params, SCHEMAS[category])
        assert "\n" not in text and text.startswith(f"{category}(")
        assert parse_parameters(text, SCHEMAS) == params
        assert format_parameters(parse_parameters(text, SCHEMAS), SCHEMAS[category]) == text


SMALL = Schema("thing", (Number("width", 0.4, 1.0), Count("rows", 1, 3), Chance("lid", 0.5),
                         Choice("wood", ("oak", "pine")), Count("books", 2, 6, slots=2)))


def test_text_form_of_a_small_schema():
    params = Parameters("thing", {"width": 0.5, "rows": 2, "lid": 1, "wood": 1, "books": (3, 2)})
    assert format_parameters(params, SMALL) == "thing(width=0.5, rows=2, lid=1, wood=1, books=(3, 2))"


@pytest.mark.parametrize("text, where", [
    ("thing(width=1.2, rows=2, lid=1, wood=1, books=(3, 2))", "thing.width"),  # out of range
    ("thing(width=0.5001, rows=2, lid=1, wood=1, books=(3, 2))", "thing.width"),  # 4 decimals
    ("thing(width=0.5, rows=2.0, lid=1, wood=1, books=(3, 2))", "thing.rows"),  # a count as a float
    ("thing(width=0.5, rows=2, lid=2, wood=1, books=(3, 2))", "thing.lid"),
    ("thing(width=0.5, rows=2, lid=1, wood=5, books=(3, 2))", "thing.wood"),
    ("thing(width=0.5, rows=2, lid=1, wood=1, books=(3, 9))", "thing.books[1]"),
    ("thing(rows=2, width=0.5, lid=1, wood=1, books=(3, 2))", "thing.width"),  # order
    ("thing(width=0.5, rows=2, lid=1, wood=1, books=(3,))", "column"),  # a slot missing
    ("thing(width=0.5, rows=2, lid=1, wood=1, books=(3, 2))) x", "column"),  # trailing text
    ("thing(width=0.5, rows=2", "end"),  # cut short
    ("lamp(width=0.5)", "category"),  # not in these schemas
    ("thing(width=__import__('os'))", "column"),  # never evaluated
])
def test_bad_text_names_the_entry(text, where):
    with pytest.raises(ParameterError) as e:
        parse_parameters(text, {"thing": SMALL})
    assert e.value.where.startswith(where), str(e.value)


def test_draws_refuse_a_second_read_and_a_wrong_kind():
    draws = Draws.seeded(SMALL, np.random.default_rng(0))
    draws.number("width")
    with pytest.raises(ParameterError, match="read twice"):
        draws.number("width")
    with pytest.raises(ParameterError, match="read as Number"):
        draws.number("rows")
    with pytest.raises(ParameterError, match="slot"):
        draws.count("books")
    with pytest.raises(ParameterError, match="not a parameter"):
        draws.chance("door")


def test_unread_entries_keep_their_defaults():
    draws = Draws.seeded(SMALL, np.random.default_rng(0))
    draws.count("books", 1)
    params = draws.parameters()
    assert params["width"] == 0.4 and params["rows"] == 1 and params["lid"] == 0 and params["wood"] == 0
    assert params["books"][0] == 2 and 2 <= params["books"][1] <= 6


def test_run_parameters_refuses_a_record_of_the_wrong_shape():
    params = sample_parameters("cabinet", 0)
    with pytest.raises(ParameterError, match="cabinet.width"):
        run_parameters(Parameters("cabinet", {**params.values, "width": 3.0}))
    with pytest.raises(ParameterError, match="unknown category"):
        run_parameters(Parameters("spaceship", dict(params.values)))
