"""Plan and run a dataset build: objects → shard tasks (split by object) → shards, in parallel.

The plan depends only on the sources and the config: objects are assigned to train/val/test by
SHA-256 of their id (``split="hash"``) or all to the one split the config names, kept in source
order within a split, and cut into shards of a fixed number of objects. Workers (spawned
processes, each with its own GL context) build whole shards, so the bytes of a shard never
depend on the worker count.

An object whose loading or rendering raises is left out, not the build: its shard is written
with the other objects, and the manifest's ``skipped`` maps its id to the error (one line).
"""

from __future__ import annotations

import hashlib
import json
import multiprocessing
import sys
from dataclasses import asdict, dataclass
from functools import lru_cache
from pathlib import Path
from typing import Callable, Sequence

from tqdm import tqdm

from data_pipeline.augment import fuse_handles, merge_parts, split_part
from data_pipeline.compose import PartLibrary, composed_source
from data_pipeline.importers.object_ids import object_ids
from data_pipeline.importers.source import import_object
from data_pipeline.mirror import mirrored
from data_pipeline.samples import BUILD_APPEARANCES, SourceObject, derived_rng, factory_source, object_records, split_of
from data_pipeline.scenes import make_scene
from data_pipeline.shards import SHARD_SUFFIX, finished, load_manifest, save_manifest, write_shard
from jax3dc.errors import InputFileError, Jax3dcError, SetupError
from jax3dc.factories import FACTORIES, object_id


@dataclass(frozen=True)
class SourceSpec:
    """How to make one object: ``kind`` "factory" (category, seed), "import" (path), "scene"
    (seed = build seed, category = scene index as text) or "composed" (seed, path = part library)."""

    kind: str
    object_id: str
    category: str = ""
    seed: int = 0
    path: str = ""


@dataclass(frozen=True)
class ShardTask:
    name: str
    split: str
    sources: tuple[SourceSpec, ...]


@dataclass(frozen=True)
class BuildConfig:
    views: int
    seed: int
    size: int
    objects_per_shard: int
    augment: bool = False  # also one split and one merge variant per object (one view each)
    split: str = "hash"  # "hash": by SHA-256 of the object id; "train" / "val" / "test": every object there
    appearance: str = "plain"  # look of I: "plain" (one look), "varied" (lights, backdrop, colours, camera) or "mixed" (either, per view)
    mirror: bool = False  # also every view of each object's mirror image (data_pipeline.mirror)
    palette_per_view: bool = False  # S colours permuted per view, not per object: no colour set names an object
    fuse_handles: bool = False  # also every view of each object with its handles fused (data_pipeline.augment)


SPLIT_CHOICES = ("hash", "train", "val", "test")


def factory_sources(n: int, seed: int, categories: Sequence[str] | None = None) -> list[SourceSpec]:
    """``n`` factory objects cycling through ``categories`` (default: every factory, in registry
    order); object k of the build has seed ``seed * 1_000_000 + k``, so two builds with different
    seeds share no object. Naming categories lets a build add families a dataset lacks (new
    factories) without rendering every other family again."""
    categories = list(FACTORIES) if categories is None else list(categories)
    unknown = [c for c in categories if c not in FACTORIES]
    if unknown or not categories:
        raise Jax3dcError(f"unknown categories {', '.join(map(repr, unknown))}; known: {', '.join(FACTORIES)}"
                          if unknown else "no categories named")
    out = []
    for k in range(n):
        category, obj_seed = categories[k % len(categories)], seed * 1_000_000 + k
        out.append(SourceSpec("factory", object_id(category, obj_seed), category=category, seed=obj_seed))
    return out


def scene_sources(m: int, seed: int) -> list[SourceSpec]:
    return [SourceSpec("scene", f"scene_{seed:06d}_{k:06d}", category=str(k), seed=seed) for k in range(m)]


def composed_sources(n: int, seed: int, library: Path) -> list[SourceSpec]:
    """``n`` objects composed from the part library at ``library`` (``data_pipeline.compose``);
    object k has seed ``seed * 1_000_000 + k``, as factory objects do."""
    path = str(Path(library).resolve())
    return [SourceSpec("composed", f"composed_{seed:06d}_{k:06d}", seed=seed * 1_000_000 + k, path=path)
            for k in range(n)]


@lru_cache(maxsize=4)
def part_library(path: str) -> PartLibrary:
    """The library of ``path``, listed once per process (a build composes thousands of objects from it)."""
    return PartLibrary.open(path)


def import_sources(paths: list[Path]) -> list[SourceSpec]:
    """One spec per path; ids are unique in the import (see ``importers.object_ids``)."""
    ids = object_ids(paths)
    return [SourceSpec("import", object_id, path=str(Path(p).resolve())) for p, object_id in zip(paths, ids)]


def plan_shards(sources: list[SourceSpec], objects_per_shard: int, split: str = "hash") -> list[ShardTask]:
    """Shard tasks per split; ``split`` "hash" assigns each object by its id, a split name puts
    every object in that split."""
    if split not in SPLIT_CHOICES:
        raise ValueError(f"split must be one of {', '.join(SPLIT_CHOICES)}, not {split!r}")

    def split_of_source(s: SourceSpec) -> str:
        return split_of(s.object_id) if split == "hash" else split

    tasks = []
    for split_name in ("train", "val", "test"):
        members = [s for s in sources if split_of_source(s) == split_name]
        for i in range(0, len(members), objects_per_shard):
            chunk = tuple(members[i:i + objects_per_shard])
            tasks.append(ShardTask(f"{split_name}-{i // objects_per_shard:05d}{SHARD_SUFFIX}", split_name, chunk))
    return tasks


def load_source(spec: SourceSpec) -> SourceObject:
    if spec.kind == "factory":
        return factory_source(spec.category, spec.seed)
    if spec.kind == "composed":
        return composed_source(spec.seed, part_library(spec.path), spec.object_id)
    obj = import_object(Path(spec.path))
    return SourceObject(str(obj.meta.get("category", "imported")), spec.object_id, obj.structure, obj.parts,
                        float(obj.meta.get("scale", 1.0)), warnings=tuple(obj.meta.get("warnings", ())))


def load_sources(spec: SourceSpec) -> list[SourceObject]:
    """The objects one spec renders: a scene gives its part- and object-level versions."""
    if spec.kind == "scene":
        return make_scene(spec.seed, int(spec.category))
    return [load_source(spec)]


def config_doc(config: BuildConfig) -> dict:
    """The config as a manifest records it: ``appearance`` only when it is not "plain", so a plain
    build writes (and resumes) the manifest of builds made before the option existed."""
    if config.appearance not in BUILD_APPEARANCES:
        raise ValueError(f"appearance must be one of {', '.join(BUILD_APPEARANCES)}, not {config.appearance!r}")
    doc = asdict(config)
    if doc.get("appearance") == "plain":
        del doc["appearance"]
    for flag in ("mirror", "palette_per_view", "fuse_handles"):  # absent when off: the manifests of older builds still match
        if not doc.get(flag):
            doc.pop(flag, None)
    return doc


def spec_records(spec: SourceSpec, split: str, config: BuildConfig):
    """The records of one source: its views, with ``config.mirror`` every view of its mirror image,
    with ``config.fuse_handles`` every view of it with its handles fused into the parts they sit on,
    and with ``config.augment`` its split and merge variants (one view each)."""
    objects = load_sources(spec)
    for warning in objects[0].warnings:  # printed by the worker that built the object: once per build
        tqdm.write(f"warning: {spec.object_id}: {warning}", file=sys.stderr)

    def records(obj: SourceObject, views: int):
        return object_records(obj, views, config.seed, config.size, split=split, appearance=config.appearance,
                              palette_per_view=config.palette_per_view)

    for obj in objects:
        yield from records(obj, config.views)
    if spec.kind == "scene":
        return
    if config.mirror:
        yield from records(mirrored(objects[0]), config.views)
    if config.fuse_handles and (fused := fuse_handles(objects[0])) is not None:
        yield from records(fused, config.views)
    if config.augment:
        rng = derived_rng(config.seed, "augment", objects[0].object_id)
        for variant in (split_part(objects[0], rng), merge_parts(objects[0], rng)):
            if variant is not None:
                yield from records(variant, 1)


def error_line(error: BaseException) -> str:
    """``error`` on one line: its type and message, line breaks (MuJoCo's "Element name ...") joined."""
    message = " ".join(str(error).split())
    return f"{type(error).__name__}: {message}" if message else type(error).__name__


def build_shard(task: ShardTask, out_dir: str, config: BuildConfig) -> tuple[str, int, str, dict[str, str]]:
    """Render every object of ``task`` and write its shard; returns (name, records, sha256, skipped).

    An object whose loading or rendering raises is left out whole (none of its records are
    written) and ``skipped`` maps its id to :func:`error_line` of the error, a plain string, so it
    crosses the worker pool whatever the error was. A SetupError (the machine, not the object:
    no OpenGL) still stops the build."""
    skipped: dict[str, str] = {}

    def records():
        for spec in task.sources:
            try:
                made = list(spec_records(spec, task.split, config))
            except SetupError:
                raise
            except Exception as error:  # noqa: BLE001  (any failure of one object: leave it out)
                skipped[spec.object_id] = error_line(error)
                continue
            yield from made

    count, sha = write_shard(Path(out_dir) / task.name, records())
    return task.name, count, sha, skipped


def _build_star(args: tuple) -> tuple[str, int, str, dict[str, str]]:
    return build_shard(*args)


def describe_source(spec: SourceSpec) -> str:
    """Where an object comes from, for a warning: the imported path, or the factory / scene seed."""
    if spec.kind == "import":
        return spec.path
    return f"{spec.kind} {spec.category} seed {spec.seed}"


def _comparable(manifest: dict, wanted: dict) -> dict:
    """The manifest's fields of ``wanted``; a config written before ``split`` existed was "hash"."""
    have = {k: manifest.get(k) for k in wanted}
    if isinstance(have["config"], dict) and "split" not in have["config"]:
        have["config"] = dict(have["config"], split="hash")
    return have


def run_build(out_dir: Path, sources: list[SourceSpec], config: BuildConfig, workers: int,
              progress: bool = True, on_shard: Callable[[str], None] | None = None) -> dict:
    """Build (or finish) the dataset in ``out_dir``; returns the final manifest. Objects that
    failed to load or render are in ``manifest["skipped"]`` (id → error) and each got a warning
    line on stderr."""
    out_dir.mkdir(parents=True, exist_ok=True)
    tasks = plan_shards(sources, config.objects_per_shard, config.split)
    source_text = json.dumps([asdict(s) for s in sources], sort_keys=True).encode("utf-8")
    wanted = {"config": config_doc(config), "sources": len(sources),
              "sources_sha256": hashlib.sha256(source_text).hexdigest()}  # a digest keeps the manifest small
    manifest = load_manifest(out_dir)
    if manifest is None:
        manifest = dict(wanted, shards={}, complete=False)
    elif _comparable(manifest, wanted) != wanted:
        raise InputFileError(out_dir, "holds a build with other settings or sources; use a new --out directory")
    todo = [t for t in tasks if not finished(out_dir, manifest, t.name)]
    skipped = manifest.setdefault("skipped", {})
    for t in todo:
        manifest["shards"].pop(t.name, None)
        for spec in t.sources:
            skipped.pop(spec.object_id, None)
    bar = tqdm(total=len(tasks), initial=len(tasks) - len(todo), unit="shard", disable=not progress)
    jobs = [(t, str(out_dir), config) for t in todo]
    split_of_task = {t.name: t.split for t in tasks}
    source_of = {s.object_id: s for t in tasks for s in t.sources}

    def done(result: tuple[str, int, str, dict[str, str]]) -> None:
        name, count, sha, skipped_here = result
        for object_id, message in skipped_here.items():
            tqdm.write(f"warning: skipped {object_id} ({describe_source(source_of[object_id])}): {message}",
                       file=sys.stderr)
        skipped.update(skipped_here)
        manifest["shards"][name] = {"records": count, "sha256": sha, "split": split_of_task[name]}
        save_manifest(out_dir, manifest)
        bar.update(1)
        if on_shard is not None:
            on_shard(name)

    if workers <= 1 or len(jobs) <= 1:
        for job in jobs:
            done(build_shard(*job))
    else:
        with multiprocessing.get_context("spawn").Pool(workers) as pool:
            for result in pool.imap_unordered(_build_star, jobs):
                done(result)
    bar.close()
    manifest["complete"] = True
    save_manifest(out_dir, manifest)
    return manifest
