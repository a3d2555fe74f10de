"""`jax3dc predict` on several images: one folder each, named safely from the file names, an
index.html whose every link works, the models loaded once, and a second run that only does what
the first left undone (and shows an edited folder as it is now). The stand-in structure model is
the object's own target, as elsewhere."""

from __future__ import annotations

import json
from html.parser import HTMLParser
from pathlib import Path
from urllib.parse import unquote

import pytest
from PIL import Image

from jax3dc.cli import main
from jax3dc.edits.folder import edit_folder
from jax3dc.predict import PredictConfig
from jax3dc.predict.batch import DONE_FILE, batch_images, folder_name, folder_names, predict_batch
from jax3dc.predict.gallery import ERROR, FAILS, GALLERY_FILE, PASSES
from jax3dc.predict.stage1 import Stage1Config
from predict_cases import CAMERA, target_json, write_glb, write_image

MARKUP = '<b onclick="alert(1)">x'  # a file name with markup (no "/": a file name cannot hold one)


class Links(HTMLParser):
    """Every href and src of a page, and its text."""

    def __init__(self):
        super().__init__()
        self.urls: list[str] = []
        self.text: list[str] = []

    def handle_starttag(self, tag, attrs):
        self.urls += [value for name, value in attrs if name in ("href", "src")]

    def handle_data(self, data):
        self.text.append(data)


def gallery(out: Path) -> Links:
    page = Links()
    page.feed((out / GALLERY_FILE).read_text(encoding="utf-8"))
    return page


def test_folder_names_are_safe_and_unique():
    assert folder_name("../../etc/passwd.png") == "passwd"
    assert folder_name("..\\..\\x.png") == "x"
    assert folder_name("<script>alert(1)</script>.png") == "script"  # an upload's name: its last component
    assert folder_name(f"{MARKUP}.png") == "b_onclick_alert_1_x"
    assert folder_name("..png") == folder_name("....") == folder_name("") == "image"
    assert folder_name(".hidden.jpg") == "hidden" and folder_name("a b&c.tar.png") == "a_b_c.tar"
    assert len(folder_name("x" * 500 + ".png")) == 64
    names = folder_names([Path("a.png"), Path("A.jpg"), Path("a.webp"), Path("index.html.png")])
    assert names == ["a", "A-2", "a-3", "index.html-2"]


@pytest.fixture
def inputs(tmp_path):
    folder = tmp_path / "photos"
    folder.mkdir()
    for name in ("cabinet.png", f"{MARKUP}.png", "second.jpg"):
        write_image(folder / name)
    (folder / "broken.png").write_bytes(b"not an image")
    (folder / "notes.txt").write_text("not an image file name: skipped")
    return folder, write_glb(tmp_path / "object.glb")


def test_a_batch_writes_a_folder_per_image_and_a_gallery_and_resumes(inputs, tmp_path):
    folder, glb = inputs
    asked = []
    config = PredictConfig(Stage1Config(f"mesh:{glb}"), generate_structure=lambda p: asked.append(p) or target_json(),
                           camera=CAMERA)
    out = tmp_path / "out"
    images = batch_images([folder])
    assert [p.name for p in images] == [f"{MARKUP}.png", "broken.png", "cabinet.png", "second.jpg"]
    items = predict_batch(images, config, out)
    assert [i.folder.name for i in items] == ["b_onclick_alert_1_x", "broken", "cabinet", "second"]
    assert [i.card.state for i in items] == [PASSES, ERROR, PASSES, PASSES] and len(asked) == 3
    assert sorted(p.name for p in out.iterdir()) == ["b_onclick_alert_1_x", "broken", "cabinet", "index.html", "second"]
    assert not (out / "broken" / DONE_FILE).exists()  # a failure is tried again next time

    page = gallery(out)
    assert MARKUP not in (out / GALLERY_FILE).read_text() and any(MARKUP in t for t in page.text)
    targets = {unquote(url) for url in page.urls}
    assert {f"{name}/viewer.html" for name in ("cabinet", "second", "b_onclick_alert_1_x")} <= targets
    for url in targets:  # relative, inside the batch folder, and there
        assert not url.startswith(("/", "http", "file:")) and ".." not in url
        assert (out / url).is_file(), url

    (out / "second" / DONE_FILE).unlink()  # as if the run had been killed while predicting it
    with Image.open(folder / "cabinet.png") as image:  # and cabinet.png replaced by another picture
        image.rotate(90).save(folder / "cabinet.png")
    edit_folder(out / "b_onclick_alert_1_x", {"part": 3, "ops": [{"op": "set_line", "value": "edge +x +y"}]})
    again = predict_batch(batch_images([folder]), config, out)
    assert [i.skipped for i in again] == [True, False, False, False] and len(asked) == 5
    assert set(json.loads((out / "second" / DONE_FILE).read_text())) == {"image", "image_sha256"}
    assert [i.card.state for i in again] == [FAILS, ERROR, PASSES, PASSES]  # the edited door now fails


def test_the_command_loads_the_models_once_and_keeps_one_image_in_out(inputs, tmp_path, monkeypatch, capsys):
    from jax3dc.predict import pipeline
    from jax3dc.sampler import Sampler

    loads = []
    monkeypatch.setattr(Sampler, "load", classmethod(lambda cls, folder, dtype: loads.append(folder) or object()))
    monkeypatch.setattr(pipeline, "structure_model", lambda *args: lambda prompt: target_json())
    folder, glb = inputs
    images = [str(folder / "cabinet.png"), str(folder / "second.jpg")]
    out = tmp_path / "batch"
    assert main(["predict", *images, "--stage1", f"mesh:{glb}", "--out", str(out)]) == 0
    assert len(loads) == 1  # one structure model for both images
    printed = capsys.readouterr().out
    assert f"2 images, 0 failed; see {out / GALLERY_FILE}" in printed
    assert (out / "cabinet" / "viewer.html").is_file() and (out / "second" / DONE_FILE).is_file()
    assert main(["predict", images[0], "--stage1", f"mesh:{glb}", "--out", str(tmp_path / "one")]) == 0
    assert (tmp_path / "one" / "structure.json").is_file() and not (tmp_path / "one" / GALLERY_FILE).exists()
    assert main(["predict", str(folder), "--stage1", f"mesh:{glb}", "--out", str(out)]) == 1  # broken.png fails
    printed = capsys.readouterr().out
    assert "cabinet.png -> " in printed and "skipped (done before)" in printed and "4 images, 1 failed" in printed

