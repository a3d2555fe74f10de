"""`jax3dc serve` in headless Chromium (Debian's, driven by Playwright as the viewer's tests are):
a photo set on the page's file input is predicted and opens in the viewer with its verdict;
a folder picked in it sends its images;
moving the left door's hinge to its other edge in the edit form changes the verdict and the
exported MJCF; the zip downloaded with one click loads in MuJoCo and its URDF in yourdfpy.

With JAX3DC_UPDATE_SCREENSHOTS=1 the page after the edit is saved as docs/images/serve.png (the
README's picture)."""

from __future__ import annotations

import os
import threading
import time
import zipfile
from pathlib import Path

import pytest

from jax3dc.predict.pipeline import Checkpoints
from jax3dc.render import mujoco  # mujoco imported after render chose the GL backend
from jax3dc.serve.app import create_app
from jax3dc.serve.cli import listen
from jax3dc.serve.jobs import JobBoard

browser_page = pytest.importorskip("tests.viewer.browser_page")
yourdfpy = pytest.importorskip("yourdfpy")
uvicorn = pytest.importorskip("uvicorn")

SCREENSHOT = Path(__file__).resolve().parents[2] / "docs" / "images" / "serve.png"


@pytest.fixture
def server(inputs, tmp_path):
    """The app on a free loopback port (uvicorn in a thread), predicting into an empty --out."""
    board = JobBoard.predicting(tmp_path / "out", inputs[0], Checkpoints("float32"))
    board.start()
    sock = listen("127.0.0.1", 0)
    uv = uvicorn.Server(uvicorn.Config(create_app(board), log_level="warning"))
    thread = threading.Thread(target=uv.run, kwargs={"sockets": [sock]}, daemon=True)
    thread.start()
    while not uv.started:
        time.sleep(0.02)
    yield f"http://127.0.0.1:{sock.getsockname()[1]}", board
    uv.should_exit = True
    thread.join()
    board.stop()
    sock.close()


@pytest.fixture
def browser(tmp_path):
    with browser_page.sync_api.sync_playwright() as playwright:
        context = playwright.chromium.launch_persistent_context(
            str(tmp_path / "chromium_profile"), executable_path=browser_page.CHROMIUM, headless=True,
            args=browser_page.FLAGS, viewport=browser_page.VIEWPORT, accept_downloads=True)
        yield context
        context.close()


def test_drop_a_photo_fix_a_hinge_and_download_the_zip(server, browser, inputs, tmp_path):
    url, board = server
    page = browser.new_page()
    errors: list[str] = []
    page.on("pageerror", lambda e: errors.append(str(e)))
    requests: list[str] = []
    page.on("request", lambda r: requests.append(r.url))
    page.goto(url)
    page.wait_for_selector("body[data-ready=true]")
    page.set_input_files("#files", str(inputs[1]))
    page.wait_for_selector("#jobs li[data-state=done]", timeout=60_000)
    page.wait_for_selector("#verdict[data-ok=true]")
    assert page.text_content("#verdict") == "physics check: passes"
    viewer = page.frame_locator("#viewer")
    viewer.locator("body[data-ready=true]").wait_for(timeout=60_000)
    folder = board.out / "cabinet"
    xml = (folder / "object.xml").read_bytes()

    door = page.locator('form[data-part="3"]')
    assert door.locator("select[name=type]").input_value() == "hinge"
    assert door.locator("select[name=axis]").input_value() == "+z"
    door.locator("select[name=line]").select_option("edge +x +y")
    door.locator("button[type=submit]").click()
    page.wait_for_selector("#verdict[data-ok=false]", timeout=60_000)
    assert "edited; physics check: fails" in page.text_content("#edit-message")
    assert page.locator('form[data-part="3"].flagged').count() == 1
    viewer.locator("body[data-ready=true]").wait_for(timeout=60_000)
    assert (folder / "object.xml").read_bytes() != xml
    if os.environ.get("JAX3DC_UPDATE_SCREENSHOTS") == "1":
        SCREENSHOT.parent.mkdir(parents=True, exist_ok=True)
        page.evaluate("window.scrollTo(0, 0)")
        page.screenshot(path=str(SCREENSHOT))

    with page.expect_download() as download:
        page.click("#zip")
    archive = tmp_path / "cabinet.zip"
    download.value.save_as(archive)
    with zipfile.ZipFile(archive) as z:
        z.extractall(tmp_path / "unzipped")
    got = tmp_path / "unzipped" / "cabinet"
    assert (got / "object.xml").read_bytes() == (folder / "object.xml").read_bytes()
    model = mujoco.MjModel.from_xml_path(str(got / "object.xml"))
    assert model.njnt >= 2
    urdf = yourdfpy.URDF.load(str(got / "object.urdf"), build_scene_graph=False, load_meshes=False)
    assert len(urdf.actuated_joints) == 2
    for name in ("object.usda", "object.glb", "object_blender.py", "structure.json", "physics.json"):
        assert (got / name).is_file(), name

    photos = tmp_path / "photos"  # a folder picked: its images go, its other files are left out
    photos.mkdir()
    (photos / "second.png").write_bytes(inputs[1].read_bytes())
    (photos / "notes.txt").write_text("not an image")
    page.set_input_files("#folder", str(photos))
    page.wait_for_selector('#jobs li[data-job="second"][data-state=done]', timeout=60_000)
    assert [job.id for job in board.all()] == ["cabinet", "second"]
    assert errors == []
    assert all(r.startswith(url) or r.startswith(("data:", "blob:", "about:")) for r in requests), requests
