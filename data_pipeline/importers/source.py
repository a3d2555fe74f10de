"""Finding the source file of an object and importing it."""

from __future__ import annotations

import json
from pathlib import Path

from data_pipeline.importers.assemble import ImportedObject, assemble
from data_pipeline.importers.frames import FRONTS
from data_pipeline.importers.limits import ImportLimits
from data_pipeline.importers.mjcf import read_mjcf
from data_pipeline.importers.output import is_converted, read_imported
from data_pipeline.importers.safe_xml import parse_xml
from data_pipeline.importers.urdf import read_urdf
from jax3dc.errors import InputFileError

URDF_SCALE_NOTE = (
    "URDF lengths taken as metres; PartNet-Mobility meshes are in arbitrary units, so this scale "
    "is only nominal for them"
)
MJCF_SCALE_NOTE = "MJCF lengths are metres"
MAX_META_BYTES = 1 << 20
"""PartNet-Mobility's meta.json is a few hundred bytes; a larger one is not read."""


def _format_of(path: Path) -> str:
    """"urdf" or "mjcf", from the root element (suffixes are ambiguous: URDFs are XML too)."""
    tag = parse_xml(path).tag
    formats = {"robot": "urdf", "mujoco": "mjcf"}
    if tag not in formats:
        raise InputFileError(path, f"neither a URDF (<robot>) nor an MJCF (<mujoco>) file: root is <{tag}>")
    return formats[tag]


def find_source(path: Path) -> tuple[Path, str]:
    """The URDF / MJCF file of ``path`` (a file or an object directory) and its format."""
    path = Path(path)
    if path.is_file():
        return path, _format_of(path)
    if not path.is_dir():
        raise InputFileError(path, "no such file or directory")
    if (path / "mobility.urdf").is_file():
        return path / "mobility.urdf", "urdf"
    candidates = sorted(path.glob("*.urdf")) + sorted(path.glob("*.xml")) + sorted(path.glob("*.mjcf"))
    found, refused = [], []
    for candidate in candidates:
        try:
            found.append((candidate, _format_of(candidate)))
        except InputFileError as e:
            refused.append(e)
    if not found and len(refused) == 1:
        raise refused[0]  # the one candidate's own reason (malformed, DOCTYPE...) says more than "none found"
    if len(found) != 1:
        names = ", ".join(p.name for p, _ in found) or "none"
        raise InputFileError(path, f"expected one URDF or MJCF file in the directory, found {names}")
    return found[0]


def _object_info(source: Path) -> dict:
    """Object id (the PartNet-Mobility folder name, else the file stem) and category (from
    PartNet-Mobility's meta.json ``model_cat`` where present)."""
    folder = source.parent
    info = {"category": "", "object_id": folder.name if source.name == "mobility.urdf" else source.stem}
    meta = folder / "meta.json"
    if meta.is_file():
        try:
            data = json.loads(meta.read_text()) if meta.stat().st_size <= MAX_META_BYTES else {}
        except (ValueError, OSError, RecursionError):  # only the category is read from it: a broken file loses that
            data = {}
        if isinstance(data, dict):
            info["category"] = str(data.get("model_cat", ""))
    return info


def default_front(source: Path) -> str:
    """PartNet-Mobility objects face -X once their root joint has made them Z-up (their drawers
    open and doors swing towards -X); other sources are assumed to follow SPEC (-Y)."""
    return "-x" if source.name == "mobility.urdf" else "-y"


def import_object(
    path: Path, metres_per_unit: float | None = None, front: str | None = None, progress: bool = False,
    limits: ImportLimits = ImportLimits(), bounds_only: bool = False,
) -> ImportedObject:
    """Import one object.

    ``metres_per_unit`` overrides the unit of the source's lengths; ``front`` (one of
    ``FRONTS``) overrides the direction the source object faces (see :func:`default_front`);
    ``limits`` caps what the files may make us load and keeps mesh paths inside the object's folder.
    ``bounds_only`` (URDF; an MJCF is always read in full) makes every mesh file its bounding box:
    structure, joints and part boxes without the surfaces, for fast checks over a whole dataset.
    A folder that ``jax3dc data convert`` wrote is read back as it is: its frame and units are
    already the project's, so ``metres_per_unit`` and ``front`` cannot apply to it.
    """
    if is_converted(Path(path)):
        if metres_per_unit is not None or front is not None:
            raise InputFileError(Path(path), "a converted object is already in the normalised frame: "
                                 "its front and units cannot be set again")
        return read_imported(Path(path))
    source, fmt = find_source(Path(path))
    if front is not None and front not in FRONTS:
        raise InputFileError(source, f"front must be one of {FRONTS}, got {front!r}")
    tree = read_urdf(source, progress, limits, bounds_only) if fmt == "urdf" else read_mjcf(source, progress, limits)
    note = URDF_SCALE_NOTE if fmt == "urdf" else MJCF_SCALE_NOTE
    if metres_per_unit is not None:
        if not metres_per_unit > 0:
            raise InputFileError(source, f"metres per unit must be positive, got {metres_per_unit}")
        note = f"source lengths scaled by {metres_per_unit} m per unit, as given by the user"
    return assemble(tree, metres_per_unit or 1.0, note, front or default_front(source), _object_info(source))
