"""What ``jax3dc view`` shows, from what it is pointed at: a predict output folder or an export
folder (its one ``.glb``), a GLB file, or a structure JSON with ``--parts`` (the GLB made here,
as ``jax3dc export --format gltf`` would). ``physics.json``, ``image.png`` and ``seg.png`` beside
the object are shown when they are there (predict writes all three).
"""

from __future__ import annotations

import json
from pathlib import Path

from jax3dc.errors import InputFileError
from jax3dc.export.cli import _scale_from_meta  # the scale rule of `jax3dc export`
from jax3dc.export.gltf import gltf_bytes
from jax3dc.geometry.parts import load_parts
from jax3dc.physics.findings import Verdict
from jax3dc.structure import parse_structure
from jax3dc.viewer.page import ViewerInputs

PAGE_NAME = "viewer.html"


def _bytes_if_there(path: Path) -> bytes | None:
    try:
        return path.read_bytes() if path.is_file() else None
    except OSError as e:
        raise InputFileError(path, f"cannot read: {e.strerror or e}") from None


def read_verdict(path: Path) -> Verdict | None:
    """physics.json (``Verdict.to_json``) typed again, if it exists; malformed is an input error."""
    raw = _bytes_if_there(path)
    if raw is None:
        return None
    try:
        data = json.loads(raw.decode("utf-8"))
    except (UnicodeDecodeError, ValueError) as e:
        raise InputFileError(path, f"not JSON: {e}") from None
    try:
        return Verdict.from_json(data)
    except (AttributeError, KeyError, TypeError, ValueError) as e:
        raise InputFileError(path, f'not a physics verdict ({type(e).__name__}: {e}): expected '
                                   '{"ok", "joints": {part id: ...}, "checks", "findings"}') from None


def _structure_glb(structure_path: Path, parts_dir: Path, scale: float | None) -> bytes:
    try:
        text = structure_path.read_text(encoding="utf-8")
    except (OSError, UnicodeDecodeError) as e:
        raise InputFileError(structure_path, f"cannot read the structure: {getattr(e, 'strerror', None) or e}") from None
    parts = load_parts(parts_dir)
    structure = parse_structure(text, part_ids=parts.keys())
    return gltf_bytes(structure, parts, scale or _scale_from_meta(structure_path) or 1.0)


def _with_neighbours(glb: bytes, folder: Path, title: str, where: str) -> ViewerInputs:
    return ViewerInputs(glb, title, where, read_verdict(folder / "physics.json"),
                        _bytes_if_there(folder / "image.png"), _bytes_if_there(folder / "seg.png"))


def view_inputs(path: str | Path, parts: str | Path | None = None, scale: float | None = None
                ) -> tuple[ViewerInputs, Path]:
    """The page's inputs and where the page goes by default (beside the object)."""
    path = Path(path)
    if parts is not None:
        glb = _structure_glb(path, Path(parts), scale)
        return _with_neighbours(glb, path.parent, path.stem, str(path)), path.with_name(f"{path.stem}_viewer.html")
    if path.is_file():
        if path.suffix.lower() != ".glb":
            raise InputFileError(path, "expected a folder, a .glb file, or a structure .json with --parts DIR")
        return (_with_neighbours(path.read_bytes(), path.parent, path.stem, str(path)),
                path.with_name(f"{path.stem}_viewer.html"))
    if not path.is_dir():
        raise InputFileError(path, "not found")
    glbs = sorted(path.glob("*.glb"))
    if len(glbs) > 1:
        raise InputFileError(path, f"several .glb files ({', '.join(p.name for p in glbs)}): name one of them")
    title = path.resolve().name
    if glbs:
        return _with_neighbours(glbs[0].read_bytes(), path, title, str(glbs[0])), path / PAGE_NAME
    if (path / "structure.json").is_file() and (path / "parts").is_dir():
        glb = _structure_glb(path / "structure.json", path / "parts", scale)
        return _with_neighbours(glb, path, title, str(path / "structure.json")), path / PAGE_NAME
    raise InputFileError(path, "no .glb file and no structure.json with parts/: not a predict or export folder")
