"""Writing the viewer page: ``<name>.html`` with the object's data in it, and a ``viewer_files/``
folder beside it with the page's script, style and the vendored three.js (with its licences).

The data (GLB, images, verdict) sit in the page as JSON, so it works from a file URL, where a
browser refuses to fetch other files, as well as from ``jax3dc view --serve``. Several pages in
one folder share one ``viewer_files/``.
"""

from __future__ import annotations

import base64
import html
import json
import shutil
from dataclasses import dataclass
from importlib import resources
from pathlib import Path
from string import Template
from typing import Any

from jax3dc.errors import InputFileError
from jax3dc.physics.findings import Verdict
from jax3dc.viewer.model import viewer_model

ASSETS_DIR = "viewer_files"
# shipped files the page loads (static/ and static/vendor/ of this package), copied into ASSETS_DIR
ASSETS = ("viewer.js", "viewer.css", "vendor/three.bundle.min.js", "vendor/LICENSE-three.txt",
          "vendor/LICENSE-esbuild.txt", "vendor/VENDORED.json")


@dataclass(frozen=True)
class ViewerInputs:
    """One object's page: its GLB (``jax3dc.export.gltf``), physics verdict and the PNG bytes of I
    and S, each optional but the GLB."""

    glb: bytes
    title: str
    where: str  # names the GLB's origin in errors
    verdict: Verdict | None = None
    image_png: bytes | None = None
    seg_png: bytes | None = None


def _data_uri(png: bytes | None) -> str | None:
    return None if png is None else "data:image/png;base64," + base64.b64encode(png).decode("ascii")


def page_data(inputs: ViewerInputs) -> dict[str, Any]:
    """Everything the page's script reads (see viewer.js)."""
    model = viewer_model(inputs.glb, inputs.where)
    verdict = None
    if inputs.verdict is not None:  # the verdict JSON's reasons, without the findings the page does not read
        data = inputs.verdict.to_json()
        verdict = {"ok": data["ok"], "joints": data["joints"], "checks": {k: v for k, v in data["checks"].items() if v}}
    return {
        "title": inputs.title,
        "glb": base64.b64encode(inputs.glb).decode("ascii"),
        "parts": model.parts,
        "relations": model.relations,
        "scale_m_per_nu": model.scale_m_per_nu,
        "verdict": verdict,
        "images": [{"caption": caption, "src": src} for caption, src in
                   (("image I", _data_uri(inputs.image_png)), ("segmentation S", _data_uri(inputs.seg_png))) if src],
    }


def _script_json(value: Any) -> str:
    """JSON safe inside a <script> element: no '<' can close it or open a comment."""
    return json.dumps(value, separators=(",", ":")).replace("<", "\\u003c")


def copy_assets(folder: Path) -> None:
    """The page's shipped files into ``folder`` (skipped when an identical copy is there)."""
    static = resources.files("jax3dc.viewer") / "static"
    folder.mkdir(parents=True, exist_ok=True)
    for name in ASSETS:
        target = folder / Path(name).name
        source = static / name
        with resources.as_file(source) as src:
            if not (target.is_file() and target.stat().st_size == src.stat().st_size
                    and target.read_bytes() == src.read_bytes()):
                shutil.copyfile(src, target)


def write_viewer(inputs: ViewerInputs, path: str | Path) -> Path:
    """Writes the page at ``path`` and its files into ``viewer_files/`` beside it; returns ``path``."""
    path = Path(path)
    template = Template((resources.files("jax3dc.viewer") / "static" / "viewer.html").read_text(encoding="utf-8"))
    page = template.substitute(title=html.escape(inputs.title), assets=ASSETS_DIR, data=_script_json(page_data(inputs)))
    try:
        path.parent.mkdir(parents=True, exist_ok=True)
        copy_assets(path.parent / ASSETS_DIR)
        path.write_text(page, encoding="utf-8")
    except OSError as e:
        raise InputFileError(path, f"cannot write the viewer: {e.strerror or e}") from None
    return path
