"""The factory registry and `generate_object`: category + seed -> program, structure, parts."""

from __future__ import annotations

import zlib
from dataclasses import dataclass
from typing import Callable

import numpy as np
import trimesh

from data_pipeline.factories import appliances, furniture, household, shelves, small_objects, storage
from data_pipeline.factories.writer import Normalised, ProgramWriter
from jax3dc.errors import Jax3dcError
from jax3dc.mounted import MOUNTED_CATEGORIES
from jax3dc.structure.schema import Structure

Build = Callable[[ProgramWriter, np.random.Generator], None]


@dataclass(frozen=True)
class Factory:
    """A parametric object family: `build` draws its parameters from the generator."""

    category: str
    build: Build
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


_BUILDS: dict[str, Build] = {
    "cabinet": storage.cabinet,
    "drawer_chest": storage.drawer_chest,
    "wardrobe": storage.wardrobe,
    "kitchen_unit": storage.kitchen_unit,
    "nightstand": storage.nightstand,
    "safe": storage.safe,
    "refrigerator": appliances.refrigerator,
    "oven": appliances.oven,
    "microwave": appliances.microwave,
    "dishwasher": appliances.dishwasher,
    "washing_machine": appliances.washing_machine,
    "storage_box": household.storage_box,
    "laptop": household.laptop,
    "toilet": household.toilet,
    "trash_can": household.trash_can,
    "door": household.door,
    "window": household.window,
    "faucet": household.faucet,
    "lamp": household.lamp,
    "suitcase": household.suitcase,
    "table": furniture.table,
    "chair": furniture.chair,
    "stool": furniture.stool,
    "office_chair": furniture.office_chair,
    "sofa": furniture.sofa,
    "bed": furniture.bed,
    "desk": furniture.desk,
    "kitchen_pot": small_objects.kitchen_pot,
    "kettle": small_objects.kettle,
    "bucket": small_objects.bucket,
    "eyeglasses": small_objects.eyeglasses,
    "globe": small_objects.globe,
    "desk_fan": small_objects.desk_fan,
    "printer": small_objects.printer,
    "toaster": small_objects.toaster,
    "stapler": small_objects.stapler,
}
_SHELVES: dict[str, Build] = {
    "cell_shelf": shelves.cell_shelf,
    "large_shelf": shelves.large_shelf,
    "simple_bookcase": shelves.simple_bookcase,
    "triangle_shelf": shelves.triangle_shelf,
}

FACTORIES: dict[str, Factory] = {  # mounted: fixed in place in use (jax3dc.mounted)
    **{name: Factory(name, build, mounted=name in MOUNTED_CATEGORIES) for name, build in _BUILDS.items()},
    **{name: Factory(name, build, instance_heavy=True) for name, build in _SHELVES.items()},
}


def object_id(category: str, seed: int) -> str:
    return f"{category}_{seed:06d}"


def build_normalised(category: str, seed: int) -> Normalised:
    """Runs one factory: program, parts, structure and the relations the factory intended."""
    if category not in FACTORIES:
        raise Jax3dcError(f"unknown category {category!r}; known: {', '.join(sorted(FACTORIES))}")
    if isinstance(seed, bool) or not isinstance(seed, (int, np.integer)) or seed < 0:
        raise Jax3dcError(f"seed must be a non-negative integer, got {seed!r}")
    rng = np.random.default_rng([int(seed), zlib.crc32(category.encode("utf-8"))])
    writer = ProgramWriter()
    FACTORIES[category].build(writer, rng)
    return writer.finish()


def generate_object(category: str, seed: int) -> GeneratedObject:
    """Builds one object deterministically: the same (category, seed) gives identical output."""
    out = build_normalised(category, seed)
    return GeneratedObject(
        category=category,
        object_id=object_id(category, int(seed)),
        program_text=out.program_text,
        structure=out.structure,
        parts=out.result.parts,
        scale_m_per_nu=out.scale_m_per_nu,
        names=out.result.names,
    )
