"""S of a non-square image: its own aspect with the camera's vertical field of view (45 degrees unless given).

References: a pinhole projection of the object's vertices (jax3dc.overlay.project, independent of
MuJoCo), and the square dataset render, whose central columns a same-height view must reproduce.
"""

from __future__ import annotations

import numpy as np
import pytest

from jax3dc.overlay import project
from jax3dc.predict.segmentation import camera_from_dict, render_part_ids
from jax3dc.errors import InputFileError
from predict_cases import CAMERA, factory_object


def silhouette_box(ids: np.ndarray) -> np.ndarray:
    rows, cols = np.nonzero(ids)
    return np.array([cols.min(), rows.min(), cols.max() + 1, rows.max() + 1], dtype=np.float64)


@pytest.mark.parametrize("width, height", [(96, 64), (64, 96)])
def test_silhouette_matches_a_pinhole_projection(width, height):
    parts = factory_object().parts
    ids = render_part_ids(parts, CAMERA, width, height)
    assert ids.shape == (height, width)
    vertices = np.concatenate([np.asarray(m.vertices) for m in parts.values()])
    uv = project(vertices, CAMERA.to_dict(), (width, height))
    want = np.array([*uv.min(axis=0), *uv.max(axis=0)])
    np.testing.assert_allclose(silhouette_box(ids), want, atol=1.5)


def test_same_height_views_share_the_central_columns():
    parts = factory_object().parts
    square = render_part_ids(parts, CAMERA, 64)
    wide = render_part_ids(parts, CAMERA, 96, 64)
    tall = render_part_ids(parts, CAMERA, 64, 96)
    assert np.mean(wide[:, 16:80] == square) > 0.995
    assert np.mean(tall == render_part_ids(parts, CAMERA, 96)[:, 16:80]) > 0.995
    assert np.count_nonzero(wide) > np.count_nonzero(square) * 0.99  # nothing lost off the sides


@pytest.mark.parametrize("fovy", [30.0, 60.0])
def test_camera_fovy_reaches_the_segmentation(fovy):
    """Varied-look records carry their field of view; S must be rendered with it."""
    camera = camera_from_dict({**CAMERA.to_dict(), "fovy": fovy}, "cam.json")
    assert camera.fovy == fovy
    parts = factory_object().parts
    ids = render_part_ids(parts, camera, 64)
    vertices = np.concatenate([np.asarray(m.vertices) for m in parts.values()])
    uv = project(vertices, camera.to_dict(), (64, 64))
    want = np.array([*uv.min(axis=0), *uv.max(axis=0)])
    np.testing.assert_allclose(silhouette_box(ids), want, atol=1.5)


def test_camera_fovy_is_checked():
    doc = CAMERA.to_dict()
    assert camera_from_dict({**doc, "fovy": 45}, "cam.json") == camera_from_dict(doc, "cam.json")
    with pytest.raises(InputFileError, match="fovy 200 is outside"):
        camera_from_dict({**doc, "fovy": 200}, "cam.json")
    with pytest.raises(InputFileError, match="fovy must be a number"):
        camera_from_dict({**doc, "fovy": "wide"}, "cam.json")
