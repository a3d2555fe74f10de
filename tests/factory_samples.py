"""Valid factory parameter records for tests, drawn as ``generate_object`` draws them but without
building any mesh (the factory writes its program; the writer is never finished)."""

from __future__ import annotations

from jax3dc.factories.registry import FACTORIES, seeded_draws
from jax3dc.factories.writer import Normalised, ProgramWriter
from jax3dc.parameters import Parameters


def sample_parameters(category: str, seed: int) -> Parameters:
    """The parameters ``generate_object(category, seed)`` uses."""
    draws = seeded_draws(category, seed)
    FACTORIES[category].build(ProgramWriter(), draws)
    return draws.parameters()


def build_normalised(category: str, seed: int) -> Normalised:
    """One factory's run as the writer finishes it: program, parts, structure and the relations
    the factory intended (``generate_object`` keeps only the relations extracted from the meshes)."""
    writer = ProgramWriter()
    FACTORIES[category].build(writer, seeded_draws(category, seed))
    return writer.finish()
