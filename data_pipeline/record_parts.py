"""The part meshes of a data record, rebuilt by the code that made the record.

A record carries its structure, boxes and (factory objects) its part program, but no meshes, and
the verdict needs meshes posed as in the record's view. They are rebuilt along the data build's own
path rather than a second implementation of it: ``load_sources`` (a factory object from its
category and seed, a scene from the build seed and its index, an import from its source folder),
the split / merge augmentation replayed with the build's generator, then the view's pose
(``move_joint`` by the recorded joint and θ). The result must match the record's boxes, so a
factory or importer changed since the build is an error, not silently different meshes.
"""

from __future__ import annotations

import re
from pathlib import Path
from typing import Mapping

import numpy as np
import trimesh

from data_pipeline.augment import merge_parts, split_part
from data_pipeline.build import SourceSpec, load_sources
from data_pipeline.mirror import AUGMENTATION as MIRROR, mirrored
from data_pipeline.record import Record
from data_pipeline.samples import SourceObject, derived_rng
from data_pipeline.views import move_joint
from jax3dc.errors import Jax3dcError
from jax3dc.factories import FACTORIES, object_id as factory_object_id
from jax3dc.geometry.parts import part_boxes
from jax3dc.mounted import is_mounted
from jax3dc.structure import boxes_from_dict

# meta["theta"] is rounded to 4 decimals, so a re-posed part may sit up to ~1e-4 nu off; boxes
# themselves are written to 6 decimals
BOX_TOL_NU = 1e-3
_SCENE_ID = re.compile(r"scene_(\d+)_(\d+)")


def record_parts(record: Record, sources: Mapping[str, Path] | None = None
                 ) -> tuple[dict[int, trimesh.Trimesh], float, bool]:
    """(part meshes in the record's view, nu, ids = the record's part ids; metres per nu; mounted).

    ``sources`` maps the object id of imported records (the source folder's name) to that folder;
    factory and scene records need none. Raises Jax3dcError naming the record key when the parts
    cannot be rebuilt or do not match the record's boxes.
    """
    meta = record.meta
    source = _source_object(record, sources or {})
    if meta.get("augmentation"):
        source = _augmented(source, record)
    moved = meta.get("moved_joint")
    parts = source.parts
    if moved is not None:
        parts = move_joint(source.structure, source.parts, int(moved), float(meta["theta"])).parts
    _check_boxes(parts, record)
    return parts, float(meta["scale_m_per_nu"]), is_mounted(str(meta.get("category", "")))


def _source_spec(record: Record, sources: Mapping[str, Path]) -> SourceSpec:
    """How the build made the record's object, from its meta (see ``data_pipeline.build``)."""
    category, object_id = record.meta.get("category"), record.meta.get("object_id")
    if object_id in sources:
        folder = Path(sources[object_id])
        if not folder.is_dir():
            raise Jax3dcError(f"record {record.key}: source folder {folder} of {object_id} does not exist")
        return SourceSpec("import", object_id, path=str(folder.resolve()))
    if category == "scene" and (match := _SCENE_ID.fullmatch(str(object_id))):
        return SourceSpec("scene", object_id, category=str(int(match.group(2))), seed=int(match.group(1)))
    if category in FACTORIES:
        seed = str(object_id).removeprefix(f"{category}_")
        if seed.isdigit() and factory_object_id(category, int(seed)) == object_id:
            return SourceSpec("factory", object_id, category=category, seed=int(seed))
    raise Jax3dcError(f"record {record.key}: cannot rebuild its parts: object {object_id!r} (category "
                      f"{category!r}) is neither a factory object nor a scene, and no source folder was given for it")


def _source_object(record: Record, sources: Mapping[str, Path]) -> SourceObject:
    spec = _source_spec(record, sources)
    granularity = record.meta.get("granularity", "part")
    try:
        objects = load_sources(spec)
    except Jax3dcError as error:
        raise Jax3dcError(f"record {record.key}: cannot rebuild its object: {error}") from error
    found = [obj for obj in objects if obj.granularity == granularity]
    if not found:
        raise Jax3dcError(f"record {record.key}: its source has no {granularity!r} granularity")
    return found[0]


def _augmented(source: SourceObject, record: Record) -> SourceObject:
    """The mirror image, or the split or merge variant the build made, replayed with the build's
    generator (both are drawn from it in that order, as in ``data_pipeline.build.spec_records``)."""
    if record.meta["augmentation"] == MIRROR:
        return mirrored(source)
    rng = derived_rng(record.meta["seed"], "augment", source.object_id)
    for variant in (split_part(source, rng), merge_parts(source, rng)):
        if variant is not None and variant.augmentation == record.meta["augmentation"]:
            return variant
    raise Jax3dcError(f"record {record.key}: replaying the build's augmentation does not give "
                      f"{record.meta['augmentation']!r}")


def _check_boxes(parts: dict[int, trimesh.Trimesh], record: Record) -> None:
    want = boxes_from_dict(record.meta["boxes"])
    have = part_boxes(parts)
    if set(have) != set(want):
        raise Jax3dcError(f"record {record.key}: rebuilt parts {sorted(have)} are not the record's parts {sorted(want)}")
    for part, box in want.items():
        off = max(np.max(np.abs(np.subtract(have[part].centroid, box.centroid))),
                  np.max(np.abs(np.subtract(have[part].extent, box.extent))))
        if off > BOX_TOL_NU:
            raise Jax3dcError(f"record {record.key}: rebuilt part {part} is {off:.4f} nu off the record's box "
                              "(the factory or importer changed since the build?)")
