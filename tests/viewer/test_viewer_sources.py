"""``jax3dc view``: which object a path means, the page it writes, and one-line errors."""

from __future__ import annotations

import json
import re
from pathlib import Path

import pytest
import trimesh

from jax3dc.cli import main
from jax3dc.export.gltf import gltf_bytes
from jax3dc.structure import to_json
from jax3dc.viewer.page import ASSETS_DIR
from viewer_cases import MARKUP_NAME, REASON, WARNING, cabinet, png, verdict

VENDOR = Path(__file__).resolve().parents[2] / "jax3dc" / "viewer" / "static" / "vendor"


def page_data(page: Path) -> dict:
    text = page.read_text(encoding="utf-8")
    found = re.search(r'<script id="jax3dc-data" type="application/json">(.*?)</script>', text, re.S)
    return json.loads(found.group(1))


def export_folder(folder: Path) -> Path:
    structure, parts = cabinet()
    folder.mkdir()
    (folder / "object.glb").write_bytes(gltf_bytes(structure, parts, 0.5))
    (folder / "physics.json").write_text(json.dumps(verdict().to_json()))
    (folder / "image.png").write_bytes(png((200, 60, 40)))
    return folder


def test_folder_with_glb_gives_page_with_verdict_and_neighbours(tmp_path: Path, capsys) -> None:
    folder = export_folder(tmp_path / "pred")
    assert main(["view", str(folder), "--no-open"]) == 0
    page = folder / "viewer.html"
    assert f"wrote {page}" in capsys.readouterr().out
    data = page_data(page)
    assert [p["id"] for p in data["parts"]] == [1, 2, 3, 4, 5]
    by_id = {p["id"]: p for p in data["parts"]}
    assert by_id[5]["parent"] == 4 and by_id[1]["parent"] is None
    assert by_id[4]["joint"]["range"] == pytest.approx([0.0, 0.2]) and by_id[4]["joint"]["range_unit"] == "m"
    assert by_id[2]["name"] == MARKUP_NAME and "<img" not in page.read_text().split("jax3dc-data")[1]
    assert data["verdict"]["joints"]["2"]["ok"] is False and data["scale_m_per_nu"] == 0.5
    assert data["verdict"]["joints"] == {"2": {"ok": False, "reasons": [REASON], "warnings": []},
                                         "3": {"ok": True, "reasons": [], "warnings": [WARNING]},
                                         "4": {"ok": True, "reasons": [], "warnings": []}}
    assert [i["caption"] for i in data["images"]] == ["image I"]  # no seg.png there
    assert data["relations"] == [{"type": "symmetric", "a": 2, "b": 3, "plane": "yz"}]
    for name in ("three.bundle.min.js", "viewer.js", "viewer.css", "LICENSE-three.txt"):
        assert (folder / ASSETS_DIR / name).is_file(), name


def test_structure_with_parts_is_exported_for_the_page(tmp_path: Path) -> None:
    structure, parts = cabinet()
    (tmp_path / "parts").mkdir()
    for pid, mesh in parts.items():
        mesh.export(tmp_path / "parts" / f"{pid}.obj")
    (tmp_path / "o.json").write_text(to_json(structure))
    assert main(["view", str(tmp_path / "o.json"), "--parts", str(tmp_path / "parts"), "--scale", "2",
                 "--out", str(tmp_path / "v" / "page.html"), "--no-open"]) == 0
    data = page_data(tmp_path / "v" / "page.html")
    assert {p["id"]: p["joint"]["range"][1] for p in data["parts"] if p["joint"]} == pytest.approx({2: 0.0, 3: 1.571, 4: 0.8})
    assert data["verdict"] is None


def test_vendored_bundle_is_the_one_recorded(tmp_path: Path) -> None:
    import hashlib

    recorded = json.loads((VENDOR / "VENDORED.json").read_text())["three.bundle.min.js"]
    assert hashlib.sha256((VENDOR / "three.bundle.min.js").read_bytes()).hexdigest() == recorded["sha256"]
    assert recorded["npm"]["three"] == "0.187.0"
    assert "MIT License" in (VENDOR / "LICENSE-three.txt").read_text()


@pytest.mark.parametrize("case, message", [
    ("missing", "not found"),
    ("two_glbs", "several .glb files (a.glb, b.glb): name one of them"),
    ("foreign_glb", "no node carries a part_id extra"),
    ("bad_verdict", "physics.json: not JSON"),
    ("reasons_only", "physics.json: not a physics verdict (KeyError: 'findings')"),
    ("empty", "no .glb file and no structure.json with parts/"),
])
def test_bad_inputs_are_one_line_errors(tmp_path: Path, capsys, case: str, message: str) -> None:
    folder = tmp_path / "f"
    if case == "two_glbs":
        export_folder(folder)
        (folder / "object.glb").rename(folder / "a.glb")
        (folder / "b.glb").write_bytes((folder / "a.glb").read_bytes())
    elif case == "foreign_glb":
        folder.mkdir()
        trimesh.Scene([trimesh.creation.box()]).export(folder / "x.glb")
    elif case == "bad_verdict":
        export_folder(folder)
        (folder / "physics.json").write_text("{nope")
    elif case == "reasons_only":  # a verdict without its findings cannot be typed again
        export_folder(folder)
        (folder / "physics.json").write_text(json.dumps({k: v for k, v in verdict().to_json().items() if k != "findings"}))
    elif case == "empty":
        folder.mkdir()
    assert main(["view", str(folder), "--no-open"]) == 1
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and err.startswith("jax3dc view: error: ") and message in err, err
