"""The viewer in a real headless Chromium (Debian's ``chromium``, driven by Playwright).

The page must load from a file URL and from ``jax3dc view --serve`` with no console error and no
request leaving the machine; dragging a hinge or a slide slider must change the pixels of the
moving parts only (screenshots compared with masks of the moving parts rendered alone); a flagged
joint must show flagged with its reason; hovering a relation highlights both of its parts.
Screenshots are kept in the folder the first test prints.
"""

from __future__ import annotations

import threading
from pathlib import Path

import numpy as np
import pytest

from browser_page import CHANGED, EDGE_PX, Page
from jax3dc.export.gltf import gltf_bytes
from jax3dc.viewer import ViewerInputs, write_viewer
from viewer_cases import FLAGGED, HINGE, MARKUP_NAME, MOVES_WITH, REASON, SLIDE, WARNING, cabinet, png, verdict


@pytest.fixture(scope="module")
def shots(tmp_path_factory) -> Path:
    folder = tmp_path_factory.mktemp("viewer_screenshots")
    print(f"\nviewer screenshots in {folder}")
    return folder


@pytest.fixture(scope="module")
def page_file(tmp_path_factory) -> Path:
    structure, parts = cabinet()
    inputs = ViewerInputs(gltf_bytes(structure, parts, 1.0), "test cabinet", "test", verdict(),
                          png((200, 60, 40)), png((40, 90, 200)))
    return write_viewer(inputs, tmp_path_factory.mktemp("viewer") / "viewer.html")


@pytest.fixture(scope="module")
def viewer(browser, page_file):
    page = Page(browser, page_file.resolve().as_uri())
    yield page
    page.page.close()


def changed(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    return np.abs(a - b).max(axis=2) > CHANGED


def grown(mask: np.ndarray, px: int) -> np.ndarray:
    out = mask.copy()
    for dy in range(-px, px + 1):
        for dx in range(-px, px + 1):
            out |= np.roll(np.roll(mask, dy, axis=0), dx, axis=1)
    return out


def test_page_loads_offline_without_console_errors(viewer, shots):
    viewer.canvas(shots / "loaded.png")
    assert viewer.errors == []
    assert all(url.startswith(("file://", "data:")) for url in viewer.requests), viewer.requests
    page = viewer.page
    assert page.evaluate("() => THREE.REVISION") == "187"  # the pinned three.js (VENDORED.json)
    # I and S beside the 3D view, decoded
    assert page.eval_on_selector_all("#images img", "imgs => imgs.map(i => i.naturalWidth)") == [48, 48]
    assert page.locator("#images figcaption").all_inner_texts() == ["image I", "segmentation S"]
    parts = page.locator("#parts li").all_inner_texts()
    assert len(parts) == 5 and "part 4 drawer (Plastic: red)" in parts[3]
    assert any(MARKUP_NAME in text for text in parts)  # a name is shown as text...
    assert page.evaluate("() => window.injected") is None  # ...never run as markup
    assert page.locator("#relations li").all_inner_texts() == ["symmetric 2 – 3 (plane yz)"]


@pytest.mark.parametrize("part", [HINGE, SLIDE], ids=["hinge", "slide"])
def test_slider_moves_its_parts_and_not_the_base(viewer, shots, part):
    slider = viewer.slider(part)
    lo, hi = float(slider.get_attribute("min")), float(slider.get_attribute("max"))
    assert (lo, hi) == ((0.0, 1.571) if part == HINGE else (0.0, 0.4))
    rest = viewer.canvas(shots / f"joint_{part}_rest.png")
    moving_at_rest = viewer.alone(MOVES_WITH[part])
    base_at_rest = viewer.alone([1])
    slider.focus()
    viewer.page.keyboard.press("End")  # as a user would: the slider's far end
    viewer.page.keyboard.press("ArrowRight")  # past the end: the slider must stay at its limit
    assert float(slider.input_value()) == pytest.approx(hi)
    moved = viewer.canvas(shots / f"joint_{part}_moved.png")
    moving_moved = viewer.alone(MOVES_WITH[part])
    base_moved = viewer.alone([1])

    diff = changed(rest, moved)
    assert diff.sum() > 500  # the part visibly moved
    assert (moving_at_rest != moving_moved).sum() > 500
    outside = diff & ~grown(moving_at_rest | moving_moved, EDGE_PX)
    assert outside.sum() == 0, f"{outside.sum()} pixels changed away from the moving parts"
    assert (base_at_rest == base_moved).all()  # the base, drawn alone, did not move at all
    viewer.page.click("#rest")
    assert float(slider.input_value()) == 0.0
    assert changed(rest, viewer.canvas()).sum() == 0


def test_flagged_joint_is_marked_with_its_reason(viewer, shots):
    page = viewer.page
    flagged = page.locator(f'[data-joint="{FLAGGED}"]')
    assert "flagged" in flagged.get_attribute("class").split()
    assert flagged.locator(".flag").inner_text() == "flagged"
    assert flagged.locator("ul.reasons li").all_inner_texts() == [REASON]
    for part in (HINGE, SLIDE):
        row = page.locator(f'[data-joint="{part}"]')
        assert "flagged" not in row.get_attribute("class").split() and "ok" in row.inner_text()
    warned = page.locator(f'[data-joint="{HINGE}"]')  # a warning is shown, and does not flag the joint
    assert "flagged" not in warned.get_attribute("class").split()
    assert warned.locator(".warn").inner_text() == "ok, with a warning"
    assert warned.locator("ul.warnings li").all_inner_texts() == [WARNING]
    assert page.locator("#verdict-badge").inner_text() == f"physics: FAIL (joints of parts {FLAGGED} flagged)"
    # the flagged part carries a red box in the 3D view; nothing else in the scene is red
    red = lambda rgb: (rgb[..., 0] > 150) & (rgb[..., 1] < 90) & (rgb[..., 2] < 90)  # noqa: E731
    image = viewer.canvas(shots / "flagged.png")
    assert red(image).sum() > 100
    page.evaluate("id => window.jax3dcViewer.showOnly([1, 3, 4, 5])", FLAGGED)
    assert red(viewer.canvas()).sum() == 0
    page.evaluate("() => window.jax3dcViewer.showOnly(null)")


def test_hovering_a_relation_highlights_both_parts(viewer, shots):
    rest = viewer.canvas()
    masks = {pid: viewer.alone([pid]) for pid in (2, 3)}
    relation = viewer.page.locator("#relations li").first
    relation.hover()
    lit = viewer.canvas(shots / "relation_hover.png")
    assert "hot" in relation.get_attribute("class").split()
    diff = changed(rest, lit)
    for pid, mask in masks.items():
        assert (diff & mask).sum() > 0.5 * mask.sum(), f"part {pid} is not highlighted"
    assert (diff & ~grown(masks[2] | masks[3], EDGE_PX)).sum() == 0
    viewer.page.mouse.move(0, 0)
    assert changed(rest, viewer.canvas()).sum() == 0


def test_axes_and_pivots_are_drawn_on_request(viewer, shots):
    rest = viewer.canvas()
    viewer.page.check("#show-axes")
    with_axes = viewer.canvas(shots / "axes.png")
    assert changed(rest, with_axes).sum() > 200
    viewer.page.uncheck("#show-axes")
    assert changed(rest, viewer.canvas()).sum() == 0


def test_served_page_loads_without_console_errors(browser, page_file):
    from jax3dc.viewer.serve import page_url, start_server

    server = start_server(page_file.parent, 0)
    threading.Thread(target=server.serve_forever, daemon=True).start()
    try:
        page = Page(browser, page_url(server, page_file.name))
        assert page.errors == []
        assert all(url.startswith(page_url(server, "")) or url.startswith("data:") for url in page.requests)
        assert page.page.locator("[data-joint]").count() == 3
        page.page.close()
    finally:
        server.shutdown()
        server.server_close()
