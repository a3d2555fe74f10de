"""The factory registry: category + seed (or category + parameters) -> program, structure, parts.

`generate_object(category, seed)` draws the factory's parameters from a generator seeded by the
pair and records them (`GeneratedObject.parameters`); `run_parameters(parameters)` runs the same
factory from such a record alone into the same object. So the record is a complete description
of the object: the stage-1 target (jax3dc.parameters).
"""

from __future__ import annotations

import zlib
from dataclasses import dataclass
from typing import Callable

import numpy as np
import trimesh

from jax3dc.factories import appliances, devices, furniture, household, mechanisms, shelves, small_objects, storage
from jax3dc.factories.writer import Normalised, ProgramWriter
from jax3dc.errors import Jax3dcError
from jax3dc.mounted import MOUNTED_CATEGORIES
from jax3dc.parameters import Draws, ParameterError, Parameters, Schema
from jax3dc.structure.schema import Structure

Build = Callable[[ProgramWriter, Draws], None]


@dataclass(frozen=True)
class Factory:
    """A parametric object family: `build` reads the parameters of `schema` from its Draws."""

    category: str
    build: Build
    schema: Schema
    instance_heavy: bool = False
    mounted: bool = False  # fixed to a wall, counter or floor in use: it need not stand free (physics gravity test)


@dataclass
class GeneratedObject:
    category: str
    object_id: str
    program_text: str
    structure: Structure
    parts: dict[int, trimesh.Trimesh]
    scale_m_per_nu: float
    names: dict[int, str]
    parameters: Parameters


_BUILDS: dict[str, tuple[Build, Schema]] = {
    "cabinet": (storage.cabinet, storage.CABINET),
    "drawer_chest": (storage.drawer_chest, storage.DRAWER_CHEST),
    "wardrobe": (storage.wardrobe, storage.WARDROBE),
    "kitchen_unit": (storage.kitchen_unit, storage.KITCHEN_UNIT),
    "nightstand": (storage.nightstand, storage.NIGHTSTAND),
    "safe": (storage.safe, storage.SAFE),
    "refrigerator": (appliances.refrigerator, appliances.REFRIGERATOR),
    "oven": (appliances.oven, appliances.OVEN),
    "microwave": (appliances.microwave, appliances.MICROWAVE),
    "dishwasher": (appliances.dishwasher, appliances.DISHWASHER),
    "washing_machine": (appliances.washing_machine, appliances.WASHING_MACHINE),
    "storage_box": (household.storage_box, household.STORAGE_BOX),
    "laptop": (household.laptop, household.LAPTOP),
    "toilet": (household.toilet, household.TOILET),
    "trash_can": (household.trash_can, household.TRASH_CAN),
    "door": (household.door, household.DOOR),
    "window": (household.window, household.WINDOW),
    "faucet": (household.faucet, household.FAUCET),
    "lamp": (household.lamp, household.LAMP),
    "suitcase": (household.suitcase, household.SUITCASE),
    "table": (furniture.table, furniture.TABLE),
    "chair": (furniture.chair, furniture.CHAIR),
    "stool": (furniture.stool, furniture.STOOL),
    "office_chair": (furniture.office_chair, furniture.OFFICE_CHAIR),
    "sofa": (furniture.sofa, furniture.SOFA),
    "bed": (furniture.bed, furniture.BED),
    "desk": (furniture.desk, furniture.DESK),
    "kitchen_pot": (small_objects.kitchen_pot, small_objects.KITCHEN_POT),
    "kettle": (small_objects.kettle, small_objects.KETTLE),
    "bucket": (small_objects.bucket, small_objects.BUCKET),
    "eyeglasses": (small_objects.eyeglasses, small_objects.EYEGLASSES),
    "globe": (small_objects.globe, small_objects.GLOBE),
    "desk_fan": (small_objects.desk_fan, small_objects.DESK_FAN),
    "printer": (small_objects.printer, small_objects.PRINTER),
    "toaster": (small_objects.toaster, small_objects.TOASTER),
    "stapler": (small_objects.stapler, small_objects.STAPLER),
    **devices.BUILDS,
    **mechanisms.BUILDS,
}
_SHELVES: dict[str, tuple[Build, Schema]] = {
    "cell_shelf": (shelves.cell_shelf, shelves.CELL_SHELF),
    "large_shelf": (shelves.large_shelf, shelves.LARGE_SHELF),
    "simple_bookcase": (shelves.simple_bookcase, shelves.SIMPLE_BOOKCASE),
    "triangle_shelf": (shelves.triangle_shelf, shelves.TRIANGLE_SHELF),
}

FACTORIES: dict[str, Factory] = {  # mounted: fixed in place in use (jax3dc.mounted)
    **{name: Factory(name, build, schema, mounted=name in MOUNTED_CATEGORIES) for name, (build, schema) in _BUILDS.items()},
    **{name: Factory(name, build, schema, instance_heavy=True) for name, (build, schema) in _SHELVES.items()},
}
SCHEMAS: dict[str, Schema] = {name: f.schema for name, f in FACTORIES.items()}  # the stage-1 target's vocabulary


def object_id(category: str, seed: int) -> str:
    return f"{category}_{seed:06d}"


def seeded_draws(category: str, seed: int) -> Draws:
    """The parameter source of (category, seed): a generator seeded by the pair, recording."""
    if category not in FACTORIES:
        raise Jax3dcError(f"unknown category {category!r}; known: {', '.join(sorted(FACTORIES))}")
    if isinstance(seed, bool) or not isinstance(seed, (int, np.integer)) or seed < 0:
        raise Jax3dcError(f"seed must be a non-negative integer, got {seed!r}")
    rng = np.random.default_rng([int(seed), zlib.crc32(category.encode("utf-8"))])
    return Draws.seeded(FACTORIES[category].schema, rng)


def _run(category: str, draws: Draws) -> Normalised:
    writer = ProgramWriter()
    FACTORIES[category].build(writer, draws)
    return writer.finish()


def _generated(out: Normalised, category: str, object_id_: str, parameters: Parameters) -> GeneratedObject:
    return GeneratedObject(
        category=category,
        object_id=object_id_,
        program_text=out.program_text,
        structure=out.structure,
        parts=out.result.parts,
        scale_m_per_nu=out.scale_m_per_nu,
        names=out.result.names,
        parameters=parameters,
    )


def generate_object(category: str, seed: int) -> GeneratedObject:
    """Builds one object deterministically: the same (category, seed) gives identical output."""
    draws = seeded_draws(category, seed)
    out = _run(category, draws)
    return _generated(out, category, object_id(category, int(seed)), draws.parameters())


def run_parameters(parameters: Parameters, object_id_: str | None = None) -> GeneratedObject:
    """Runs the factory of `parameters.category` from the record alone (the stage-1 runner): any
    record that fits the category's schema runs; one that does not raises ParameterError."""
    if parameters.category not in FACTORIES:
        raise ParameterError("category", f"unknown category {parameters.category!r}")
    draws = Draws.given(FACTORIES[parameters.category].schema, parameters)
    out = _run(parameters.category, draws)
    return _generated(out, parameters.category, object_id_ or f"{parameters.category}_parameters", draws.parameters())
