"""Camera projection of the overlays, the overlay drawing, and the report's markdown and chart."""

from __future__ import annotations

import io
import math

import numpy as np
import pytest
from PIL import Image

from eval.metrics.score import Case, evaluate
from jax3dc.overlay import PREDICTED_RGB, REFERENCE_RGB, camera_matrices, draw_overlay, project
from eval.report import failure_chart, markdown_table, per_category_markdown
from jax3dc.structure import Box, Joint, Material, Node, Structure

LOOK_AT = {"position": [0.0, -3.0, 0.0], "lookat": [0.0, 0.0, 0.0], "up": [0.0, 0.0, 1.0], "fovy": 60.0,
           "width": 200, "height": 100}


def test_look_at_camera_geometry() -> None:
    size = (200, 100)
    centre, above, right, top_edge, behind = project(np.array([
        [0.0, 0.0, 0.0],  # the look-at point
        [0.0, 0.0, 0.5],  # along up
        [0.5, 0.0, 0.0],  # +x is to the right when looking along +y with +z up
        [0.0, 0.0, 3.0 * math.tan(math.radians(30))],  # on the upper edge of the 60 degree field
        [0.0, -4.0, 0.0],  # behind the camera
    ]), LOOK_AT, size)
    np.testing.assert_allclose(centre, [100, 50], atol=1e-9)
    assert above[1] < 50 and above[0] == pytest.approx(100)
    assert right[0] > 100 and right[1] == pytest.approx(50)
    np.testing.assert_allclose(top_edge, [100, 0], atol=1e-9)
    assert np.isnan(behind).all()
    # square pixels: the same offset moves the same number of pixels horizontally and vertically
    assert right[0] - 100 == pytest.approx(50 - project(np.array([[0, 0, 0.5]]), LOOK_AT, size)[0, 1])


def test_matrix_camera_matches_look_at_and_image_scaling() -> None:
    k, extrinsics, _ = camera_matrices(LOOK_AT, (200, 100))
    matrices = {"intrinsics": k.tolist(), "extrinsics": extrinsics.tolist(), "width": 200, "height": 100}
    points = np.random.default_rng(0).uniform(-0.5, 0.5, (20, 3))
    np.testing.assert_allclose(project(points, matrices, (200, 100)), project(points, LOOK_AT, (200, 100)))
    np.testing.assert_allclose(project(points, LOOK_AT, (400, 200)), 2 * project(points, LOOK_AT, (200, 100)))
    # independent pinhole: rotation rows are right / down / forward, K from the vertical fov
    cam = points - np.array([0.0, -3.0, 0.0])
    x, y, z = cam[:, 0], -cam[:, 2], cam[:, 1]
    focal = 50 / math.tan(math.radians(30))
    np.testing.assert_allclose(project(points, LOOK_AT, (200, 100)), np.stack([100 + focal * x / z, 50 + focal * y / z], 1))


def test_mujoco_free_camera_matches_mujoco_rendering() -> None:
    """Small spheres rendered by MuJoCo's free camera land where `project` puts their centres."""
    import jax3dc.render  # noqa: F401  (chooses the GL backend before mujoco is imported)
    import mujoco

    centres = np.array([[0.0, 0.0, 0.0], [0.3, -0.1, 0.2], [-0.25, 0.2, -0.15], [0.1, 0.3, 0.3]])
    spheres = "".join(f'<geom name="s{i}" type="sphere" size="0.012" pos="{x} {y} {z}"/>'
                      for i, (x, y, z) in enumerate(centres))
    model = mujoco.MjModel.from_xml_string(
        f'<mujoco><visual><global offwidth="240" offheight="240"/></visual><worldbody>{spheres}</worldbody></mujoco>')
    data = mujoco.MjData(model)
    mujoco.mj_forward(model, data)
    camera = {"lookat": [0.02, 0.01, 0.03], "distance": 2.4, "azimuth": 117.0, "elevation": -23.0}
    cam = mujoco.MjvCamera()
    cam.type = mujoco.mjtCamera.mjCAMERA_FREE
    cam.lookat[:] = camera["lookat"]
    cam.distance, cam.azimuth, cam.elevation = camera["distance"], camera["azimuth"], camera["elevation"]
    with mujoco.Renderer(model, 240, 240) as renderer:
        renderer.enable_segmentation_rendering()
        renderer.update_scene(data, camera=cam)
        seg = renderer.render()
    projected = project(centres, camera, (240, 240))
    for i, (u, v) in enumerate(projected):
        rows, cols = np.nonzero((seg[..., 0] == i) & (seg[..., 1] == int(mujoco.mjtObj.mjOBJ_GEOM)))
        assert len(rows) > 3, f"sphere {i} not visible"
        assert abs(cols.mean() + 0.5 - u) < 0.5 and abs(rows.mean() + 0.5 - v) < 0.5, (i, u, v)


def hinged(axis=(0.0, 0.0, 1.0)) -> Structure:
    joint = Joint("hinge", axis, (0.2, 0.0, 0.0), (0.0, 1.5))
    return Structure({0: Material("Wood")}, {1: Node(None, 0), 2: Node(1, 0, joint)})


BOXES = {1: Box((0.0, 0.0, 0.0), (0.4, 0.4, 0.4)), 2: Box((0.0, -0.1, 0.0), (0.4, 0.05, 0.4))}


def blank_png() -> bytes:
    buf = io.BytesIO()
    Image.new("RGB", (64, 32), (255, 255, 255)).save(buf, format="PNG")
    return buf.getvalue()


def colour_count(image: Image.Image, rgb) -> int:
    return int(np.all(np.asarray(image) == np.asarray(rgb, np.uint8), axis=-1).sum())


def test_overlay_draws_reference_and_prediction() -> None:
    camera = dict(LOOK_AT, width=64, height=32)
    only_ref = draw_overlay(blank_png(), camera, BOXES, hinged(), None)
    assert only_ref.size == (512, 256)
    assert colour_count(only_ref, REFERENCE_RGB) > 100 and colour_count(only_ref, PREDICTED_RGB) == 0
    both = draw_overlay(blank_png(), camera, BOXES, hinged(), hinged((1.0, 0.0, 0.0)))
    assert colour_count(both, PREDICTED_RGB) > 100 and colour_count(both, REFERENCE_RGB) > 100


def test_markdown_table_and_per_category() -> None:
    table = markdown_table((("Parse", "parse", 1), ("Pos.", "pos_err", 3)), [("a", {"parse": 50.0, "pos_err": None})])
    assert table.splitlines() == ["| system | Parse | Pos. |", "|---|---:|---:|", "| a | 50.0 | - |"]
    centroids = {i: b.centroid for i, b in BOXES.items()}
    cases = [Case("x", hinged(), centroids, hinged()), Case("y", hinged(), centroids, None, "json", "bad"),
             Case("z", hinged(), centroids, hinged())]
    text = per_category_markdown(cases, {"x": "door", "y": "door", "z": "oven"})
    assert "| door | 2 | 50.0 | 100.0 |" in text and "| oven | 1 | 100.0 | 100.0 |" in text


def test_failure_chart_writes_a_png(tmp_path) -> None:
    centroids = {i: b.centroid for i, b in BOXES.items()}
    metrics = evaluate([Case("x", hinged(), centroids, hinged((1.0, 0.0, 0.0)))]).metrics
    assert metrics["fail_axis"] == 100.0
    failure_chart(metrics, tmp_path / "chart.png")
    assert Image.open(tmp_path / "chart.png").size[0] > 100
