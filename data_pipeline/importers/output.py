"""Writing an imported object as the files of one converted object directory.

Layout: ``structure.json`` (canonical O), ``parts/<id>.obj`` (normalised frame), ``boxes.json``
(per-part boxes) and ``meta.json`` (scale, source, part names, warnings).
"""

from __future__ import annotations

import json
import re
from pathlib import Path

from data_pipeline.importers.assemble import ImportedObject
from jax3dc.errors import InputFileError
from jax3dc.geometry.parts import save_parts
from jax3dc.structure import save_boxes, to_json

_PART_FILE = re.compile(r"^\d+\.(obj|stl|ply|glb)$")


def write_imported(obj: ImportedObject, out_dir: Path) -> None:
    """Write ``obj`` under ``out_dir``; part files left from an earlier conversion are replaced."""
    out_dir = Path(out_dir)
    try:
        out_dir.mkdir(parents=True, exist_ok=True)
        parts_dir = out_dir / "parts"
        if parts_dir.is_dir():
            for stale in parts_dir.iterdir():
                if _PART_FILE.match(stale.name):
                    stale.unlink()
        save_parts(obj.parts, parts_dir)
        (out_dir / "structure.json").write_text(to_json(obj.structure) + "\n")
        save_boxes(obj.boxes, out_dir / "boxes.json")
        (out_dir / "meta.json").write_text(json.dumps(obj.meta, indent=1) + "\n")
    except OSError as e:
        raise InputFileError(out_dir, f"cannot write the converted object: {e.strerror or e}") from None
