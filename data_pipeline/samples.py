"""One object (parts + structure) → its training records (SPEC §4), one per view.

Occluded parts: the legend and the target always list every part of the object (their boxes come
from the stage-1 parts, which exist whether or not a camera sees them); a part no pixel of S
shows is listed in ``meta["hidden_parts"]``. So the regions of S are exactly the parts minus the
hidden ones, and ids still mean the same part in S, legend and target.

Part names: ``meta["part_names"]`` maps part id -> the source's semantic name (a factory's
``freezer_door``, PartNet-Mobility's ``rotation_door``, a composed object's part), for the parts
that have one; the slots network's kind targets read it (``jax3dc.stage1_slots.kinds``). Records
built before it existed have none, and their parts count as kind ``other``.
"""

from __future__ import annotations

import hashlib
from dataclasses import dataclass, replace

import numpy as np
import trimesh

from data_pipeline.photo import degrade
from data_pipeline.record import Record
from data_pipeline.views import sample_view_pose
from jax3dc.factories import generate_object
from jax3dc.factories.registry import SCHEMAS
from jax3dc.render import (APPEARANCES, PartRenderer, paint_segmentation, part_rgba, png_bytes, sample_appearance,
                           sample_camera, sample_lighting, sample_view_lighting, vary_camera)
from jax3dc.geometry.parts import part_boxes
from jax3dc.palette import object_palette
from jax3dc.parameters import format_parameters
from jax3dc.prompt import build_prompt
from jax3dc.relations import with_extracted_relations
from jax3dc.structure import Structure, boxes_to_dict, canonicalize, to_json

SPLITS = (("train", 0.90), ("val", 0.95), ("test", 1.0))
BUILD_APPEARANCES = (*APPEARANCES, "photo", "mixed", "all")  # the renderer's looks, a degraded varied one, two per-view mixes
VARIED_LOOKS = ("varied", "photo")  # rendered by the varied renderer and camera


@dataclass(frozen=True)
class SourceObject:
    """What every source (factory, importer, scene, augmentation) hands to the renderer."""

    category: str
    object_id: str
    structure: Structure
    parts: dict[int, trimesh.Trimesh]
    scale_m_per_nu: float
    program: str | None = None
    parameters: str | None = None  # the factory's parameter text, when the parts are its own
    granularity: str = "part"
    augmentation: str | None = None
    warnings: tuple[str, ...] = ()  # what an importer dropped or guessed; `data import` prints them once


def normalised(structure: Structure, parts: dict[int, trimesh.Trimesh]) -> tuple[Structure, dict[int, trimesh.Trimesh], float]:
    """An object built in metres put in the normalised frame (bounding box centred, largest extent
    1), with its pivots moved and its slide ranges scaled alike; also the metres per unit. Sources
    that assemble objects from pieces (scenes, composed objects) end with it, as factories do."""
    lo = np.min([m.bounds[0] for m in parts.values()], axis=0)
    hi = np.max([m.bounds[1] for m in parts.values()], axis=0)
    centre, size = (lo + hi) / 2.0, float((hi - lo).max())
    out = {p: trimesh.Trimesh((m.vertices - centre) / size, m.faces, process=False) for p, m in parts.items()}
    nodes = {}
    for pid, n in structure.nodes.items():
        j = n.joint
        if j is not None:
            scale = size if j.type == "slide" else 1.0
            j = replace(j, pivot=tuple(float(v) for v in (np.asarray(j.pivot) - centre) / size),
                        range=(j.range[0] / scale, j.range[1] / scale))
        nodes[pid] = replace(n, joint=j)
    return replace(structure, nodes=nodes), out, size


def split_of(object_id: str) -> str:
    """train / val / test from SHA-256 of the object id: every view of an object lands together."""
    u = int.from_bytes(hashlib.sha256(object_id.encode("utf-8")).digest()[:8], "big") / 2.0**64
    return next(name for name, upper in SPLITS if u < upper)


def factory_source(category: str, seed: int) -> SourceObject:
    """Factory object ``category`` of ``seed`` as a source (data builds and scenes both take them)."""
    g = generate_object(category, seed)
    return SourceObject(g.category, g.object_id, g.structure, g.parts, g.scale_m_per_nu, g.program_text,
                        parameters=format_parameters(g.parameters, SCHEMAS[g.category]))


def derived_rng(*keys: object) -> np.random.Generator:
    """A numpy generator seeded from SHA-256 of the keys (stable across processes and runs)."""
    digest = hashlib.sha256("/".join(str(k) for k in keys).encode("utf-8")).digest()
    return np.random.default_rng(int.from_bytes(digest[:16], "big"))


def object_records(obj: SourceObject, views: int, seed: int, size: int, split: str | None = None,
                   appearance: str = "plain", palette_per_view: bool = False) -> list[Record]:
    """``views`` records of ``obj``: view 0 at rest, later views each with one joint moved.
    ``meta["split"]`` is ``split``, else ``split_of(obj.object_id)``.

    ``appearance`` "plain": today's look, byte for byte. "varied": lights, sky, floor, part colours,
    textures, camera distance and field of view drawn from their own generators, derived from the
    object's keys plus "appearance" (per object) and the view number (per view); the poses,
    azimuth and elevation come from the object's generator exactly as in "plain", so S of a
    varied view equals the plain S of the same pose and camera. "mixed": each view plain or
    varied with equal odds (its own generator), so that every source is seen in both looks and the
    look cannot tell a model which domain (factory or real) an object comes from; a plain view of
    a mixed build is byte for byte the plain build's, a varied one the varied build's. "photo": the
    varied view through a camera's and a file's degradations (``data_pipeline.photo``), I only.
    "all": each view plain, varied or photo with equal odds.

    ``palette_per_view``: each view's S and legend take the palette of its own key (a training
    augmentation: colours then name no object, so a model cannot recall an answer by them)."""
    if appearance not in BUILD_APPEARANCES:
        raise ValueError(f"appearance must be one of {', '.join(BUILD_APPEARANCES)}, not {appearance!r}")
    keys = (seed, obj.category, obj.object_id, obj.augmentation or "")
    rng = derived_rng(*keys)
    palette = object_palette(obj.category, obj.object_id)
    rgba, lighting = part_rgba(obj.structure, rng), sample_lighting(rng)  # drawn in both looks: same poses after
    looks = view_looks(keys, views, appearance)
    look = sample_appearance(obj.structure, derived_rng(*keys, "appearance")) if set(looks) & set(VARIED_LOOKS) else None
    renderers: dict[bool, PartRenderer] = {}  # plain or varied, made on first use: a mixed object may need both
    try:
        records = []
        for view in range(views):
            varied = looks[view] in VARIED_LOOKS
            if varied not in renderers:
                renderers[varied] = PartRenderer(obj.parts, rgba, lighting, size, look if varied else None)
            renderer = renderers[varied]
            posed = sample_view_pose(obj.structure, obj.parts, view, rng)
            lo = np.min([m.bounds[0] for m in posed.parts.values()], axis=0)
            hi = np.max([m.bounds[1] for m in posed.parts.values()], axis=0)
            radius = float(np.linalg.norm(hi - lo)) / 2.0
            camera = sample_camera(rng, centre=(lo + hi) / 2.0, radius=radius)
            view_lighting = None
            if varied:
                view_rng = derived_rng(*keys, "appearance", view)
                camera = vary_camera(camera, radius, view_rng)
                view_lighting = sample_view_lighting(view_rng)
            rgb, ids = renderer.render(posed.poses, camera, view_lighting)
            if looks[view] == "photo":
                rgb = degrade(rgb, derived_rng(*keys, "photo", view))
            boxes = part_boxes(posed.parts)
            structure = canonicalize(with_extracted_relations(posed.structure, posed.parts), boxes)
            visible = set(np.unique(ids).tolist()) - {0}
            tail = [t for t in (obj.augmentation, None if obj.granularity == "part" else obj.granularity) if t]
            key = "/".join([obj.category, obj.object_id, str(view), *tail])
            view_palette = object_palette(obj.category, key) if palette_per_view else palette
            meta = {
                "category": obj.category, "object_id": obj.object_id, "seed": seed, "view": view,
                "split": split or split_of(obj.object_id), "granularity": obj.granularity,
                "scale_m_per_nu": obj.scale_m_per_nu, "camera": camera.to_dict(),
                "boxes": boxes_to_dict(boxes), "augmentation": obj.augmentation,
                "moved_joint": posed.moved_joint, "theta": round(posed.theta, 4),
                "hidden_parts": sorted(set(obj.parts) - visible), "size": size,
            }
            names = {str(pid): node.name for pid, node in sorted(structure.nodes.items()) if node.name}
            if names:  # the parts' semantic names (stage 1's kinds); absent where the source names none
                meta["part_names"] = names
            if appearance != "plain":
                meta["appearance"] = looks[view]
            if palette_per_view:
                meta["palette_key"] = key
            records.append(Record(
                key=key, image_png=png_bytes(rgb), seg_png=png_bytes(paint_segmentation(ids, view_palette)),
                prompt=build_prompt(boxes, view_palette, len(structure.joints()) or None),
                target=to_json(structure), program=obj.program,
                parameters=obj.parameters, meta=meta))
        return records
    finally:
        for renderer in renderers.values():
            renderer.close()


def view_looks(keys: tuple, views: int, appearance: str) -> list[str]:
    """The look of each view; "mixed" draws plain or varied and "all" plain, varied or photo, each
    with equal odds, from the object's keys and the view number alone, so a view's look never
    depends on how many views are made (and a mixed build's views stay what they were before
    "all" existed)."""
    if appearance == "mixed":
        return ["varied" if derived_rng(*keys, "look", view).random() < 0.5 else "plain" for view in range(views)]
    if appearance == "all":
        return [("plain", "varied", "photo")[int(derived_rng(*keys, "look", view).random() * 3)] for view in range(views)]
    return [appearance] * views
