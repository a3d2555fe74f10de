"""Small devices of PartNet-Mobility's categories that had no factory (filled in by the next commits)."""

from __future__ import annotations

from typing import Callable

from jax3dc.factories.writer import ProgramWriter
from jax3dc.parameters import Draws, Schema

BUILDS: dict[str, tuple[Callable[[ProgramWriter, Draws], None], Schema]] = {}
