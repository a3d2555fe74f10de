"""The gallery of a batch prediction (`jax3dc predict IMG IMG --out DIR`: DIR/index.html) in the real
headless Chromium: every image is shown, and every viewer link opens a working viewer from the
file URL, with no console error and no request leaving the folder."""

from __future__ import annotations

import pytest

from browser_page import Page
from jax3dc.predict import PredictConfig
from jax3dc.predict.batch import predict_batch
from jax3dc.predict.gallery import GALLERY_FILE
from jax3dc.predict.stage1 import Stage1Config
from tests.predict.predict_cases import CAMERA, target_json, write_glb, write_image


@pytest.fixture(scope="module")
def batch(tmp_path_factory):
    root = tmp_path_factory.mktemp("gallery")
    config = PredictConfig(Stage1Config(f"mesh:{write_glb(root / 'object.glb')}"),
                           generate_structure=lambda prompt: target_json(), camera=CAMERA)
    images = [write_image(root / "kitchen cabinet.png"), write_image(root / "<i>second.png")]
    predict_batch(images, config, root / "out")
    return root / "out"


def test_every_viewer_link_of_the_gallery_opens_a_working_viewer(browser, batch):
    gallery = browser.new_page()
    errors = []
    gallery.on("pageerror", lambda e: errors.append(str(e)))
    gallery.goto((batch / GALLERY_FILE).resolve().as_uri())
    assert gallery.locator("figure img").count() == 2
    assert all(gallery.locator("figure img").nth(k).evaluate("img => img.naturalWidth > 0") for k in range(2))
    assert gallery.locator("figcaption b").all_inner_texts() == ["kitchen cabinet.png", "<i>second.png"]
    links = gallery.locator("figcaption a", has_text="viewer")
    urls = [links.nth(k).evaluate("a => a.href") for k in range(links.count())]
    assert len(urls) == 2 and errors == []
    for url in urls:
        assert url.startswith(batch.resolve().as_uri() + "/")
        viewer = Page(browser, url)
        assert viewer.errors == [] and viewer.page.locator("[data-joint]").count() == 2
        assert all(r.startswith(batch.resolve().as_uri()) or r.startswith("data:") for r in viewer.requests)
        viewer.page.close()
    gallery.close()
