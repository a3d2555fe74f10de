"""``jax3dc predict`` writes the viewer beside its report, and ``jax3dc view`` on its folder
writes the same page again (from object.glb, physics.json, image.png and seg.png)."""

from __future__ import annotations

import json

from jax3dc.predict import PredictConfig, predict
from jax3dc.predict.stage1 import Stage1Config
from jax3dc.cli import main
from jax3dc.geometry.parts import part_boxes
from jax3dc.structure import canonicalize, to_json
from test_viewer_sources import page_data
from viewer_cases import cabinet, png


def test_predict_writes_a_viewer_that_view_rewrites(tmp_path) -> None:
    structure, parts = cabinet()
    (tmp_path / "parts").mkdir()
    for pid, mesh in parts.items():
        mesh.export(tmp_path / "parts" / f"{pid}.obj")
    (tmp_path / "photo.png").write_bytes(png((90, 160, 60)))
    target = to_json(canonicalize(structure, part_boxes(parts)))
    listed = []
    config = PredictConfig(Stage1Config(f"parts:{tmp_path / 'parts'}"), generate_structure=lambda prompt: target)
    result = predict(tmp_path / "photo.png", config, tmp_path / "out", on_output=lambda name, path: listed.append(name))
    page = result.out / "viewer.html"
    assert "viewer" in listed and "image" in listed and page.is_file()
    data = page_data(page)
    verdict = json.loads((result.out / "physics.json").read_text())
    assert (data["verdict"]["ok"], data["verdict"]["joints"]) == (verdict["ok"], verdict["joints"])
    assert sorted(p["id"] for p in data["parts"] if p["joint"]) == sorted(result.structure.joints())
    assert [i["caption"] for i in data["images"]] == ["image I", "segmentation S"]
    first = page.read_text()
    page.unlink()
    assert main(["view", str(result.out), "--no-open"]) == 0
    assert page.read_text() == first
