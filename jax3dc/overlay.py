"""Joint overlays (the paper's Figure 2): reference and predicted joints drawn over the input image.

Each joint is an arrow along its axis through the pivot; a hinge's range is a sector of a circle
around the axis (starting from the direction towards the moving part), a slide's range a thick
segment along the axis from the moving part's centre. Reference joints are green and drawn wider
underneath the predicted ones (red), so a correct prediction shows as red inside green.

Camera (record meta "camera"), in the structure's normalised frame (nu), one of three forms:
* MuJoCo free camera, what ``jax3dc data build`` writes: ``{"lookat": [x,y,z], "distance": nu,
  "azimuth": deg, "elevation": deg}`` with an optional ``"fovy"`` (default MuJoCo's 45 degrees);
* look-at: ``{"position": [x,y,z], "lookat": [x,y,z], "up": [x,y,z], "fovy": degrees (vertical)}``
  (pinhole, principal point at the image centre);
* matrices: ``{"intrinsics": 3x3 K, "extrinsics": 4x4 world->camera (OpenCV: x right, y down,
  z forward)}``.
``"width"`` / ``"height"`` (px) say which image size the camera was made for; absent, the size of
the image drawn on. An image of another size has its pixel coordinates scaled to it.
"""

from __future__ import annotations

import io
import math
from typing import Any, Mapping

import numpy as np
from PIL import Image, ImageDraw

from jax3dc.errors import InputFileError
from jax3dc.structure import Box, Joint, Structure

REFERENCE_RGB = (0, 190, 0)
PREDICTED_RGB = (230, 0, 0)
AXIS_HALF_LENGTH = 0.25  # nu, arrow extends this far either side of the pivot
ARC_RADIUS = 0.12  # nu
MIN_SIDE = 512  # small renders are enlarged so the drawing stays readable


def _vec(camera: Mapping[str, Any], name: str, size: int) -> np.ndarray:
    try:
        value = np.asarray(camera[name], dtype=np.float64)
    except (KeyError, TypeError, ValueError):
        raise InputFileError("meta.camera", f"missing or non-numeric {name!r}") from None
    if value.size != size or not np.all(np.isfinite(value)):
        raise InputFileError("meta.camera", f"{name!r} must hold {size} finite numbers")
    return value.reshape(-1)


MUJOCO_FOVY = 45.0  # degrees; MuJoCo's default visual/global fovy, used by its free camera


def mujoco_free_camera(camera: Mapping[str, Any]) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """(position, lookat, up) of a MuJoCo free camera, as mjv_updateCamera places it."""
    lookat = _vec(camera, "lookat", 3)
    distance = float(_vec(camera, "distance", 1)[0])
    azimuth, elevation = (math.radians(float(_vec(camera, k, 1)[0])) for k in ("azimuth", "elevation"))
    ca, sa, ce, se = math.cos(azimuth), math.sin(azimuth), math.cos(elevation), math.sin(elevation)
    forward = np.array([ce * ca, ce * sa, se])
    return lookat - distance * forward, lookat, np.array([-se * ca, -se * sa, ce])


def camera_matrices(camera: Mapping[str, Any], image_size: tuple[int, int]) -> tuple[np.ndarray, np.ndarray, tuple[int, int]]:
    """(K [3,3], world->camera [4,4] in OpenCV axes, (width, height) K is for) from any camera form."""
    width, height = (int(_vec(camera, k, 1)[0]) if k in camera else default
                     for k, default in (("width", image_size[0]), ("height", image_size[1])))
    if "intrinsics" in camera:
        k = _vec(camera, "intrinsics", 9).reshape(3, 3)
        return k, _vec(camera, "extrinsics", 16).reshape(4, 4), (width, height)
    if "distance" in camera:
        eye, target, up = mujoco_free_camera(camera)
        fovy = float(_vec(camera, "fovy", 1)[0]) if "fovy" in camera else MUJOCO_FOVY
    else:
        eye, target, up = (_vec(camera, k, 3) for k in ("position", "lookat", "up"))
        fovy = float(_vec(camera, "fovy", 1)[0])
    forward = target - eye
    right = np.cross(forward, up)
    if np.linalg.norm(forward) < 1e-9 or np.linalg.norm(right) < 1e-9:
        raise InputFileError("meta.camera", "position equals lookat, or up is parallel to the view direction")
    forward /= np.linalg.norm(forward)
    right /= np.linalg.norm(right)
    down = np.cross(forward, right)  # OpenCV y points down the image
    rotation = np.stack([right, down, forward])
    extrinsics = np.eye(4)
    extrinsics[:3, :3] = rotation
    extrinsics[:3, 3] = -rotation @ eye
    focal = 0.5 * height / math.tan(math.radians(fovy) / 2)
    k = np.array([[focal, 0.0, width / 2], [0.0, focal, height / 2], [0.0, 0.0, 1.0]])
    return k, extrinsics, (width, height)


def project(points: np.ndarray, camera: Mapping[str, Any], image_size: tuple[int, int]) -> np.ndarray:
    """Pixel (x, y) of each 3-D point ``[N, 3]`` in an image of ``image_size``; NaN behind the camera."""
    k, extrinsics, (width, height) = camera_matrices(camera, image_size)
    pts = np.asarray(points, dtype=np.float64).reshape(-1, 3)
    cam = pts @ extrinsics[:3, :3].T + extrinsics[:3, 3]
    uvw = cam @ k.T
    with np.errstate(divide="ignore", invalid="ignore"):
        uv = uvw[:, :2] / uvw[:, 2:3]
    uv[cam[:, 2] <= 1e-6] = np.nan
    return uv * np.array([image_size[0] / width, image_size[1] / height])


def _perpendicular(axis: np.ndarray, towards: np.ndarray) -> np.ndarray:
    """Unit vector perpendicular to ``axis``, as close as possible to ``towards``."""
    v = towards - axis * float(np.dot(towards, axis))
    if np.linalg.norm(v) < 1e-6:
        v = np.cross(axis, [1.0, 0.0, 0.0] if abs(axis[0]) < 0.9 else [0.0, 1.0, 0.0])
    return v / np.linalg.norm(v)


def joint_polylines(joint: Joint, child_centroid: np.ndarray) -> list[tuple[np.ndarray, int]]:
    """3-D polylines (points, line width) of one joint: axis arrow, then its range."""
    axis = np.asarray(joint.axis, dtype=np.float64)
    axis /= np.linalg.norm(axis)
    pivot = np.asarray(joint.pivot, dtype=np.float64)
    tip = pivot + AXIS_HALF_LENGTH * axis
    side = _perpendicular(axis, child_centroid - pivot)
    head = [tip - 0.05 * axis + 0.025 * side, tip, tip - 0.05 * axis - 0.025 * side]
    lines = [(np.stack([pivot - AXIS_HALF_LENGTH * axis, tip]), 3), (np.stack(head), 3)]
    lo, hi = joint.range
    if joint.type == "hinge":
        turns = np.linspace(lo, hi, 33)
        other = np.cross(axis, side)
        arc = pivot + ARC_RADIUS * (np.cos(turns)[:, None] * side + np.sin(turns)[:, None] * other)
        lines.append((np.concatenate([pivot[None], arc, pivot[None]]), 2))
    else:
        lines.append((np.stack([child_centroid + lo * axis, child_centroid + hi * axis]), 6))
    return lines


def _draw(draw: ImageDraw.ImageDraw, structure: Structure, boxes: Mapping[int, Box], camera: Mapping[str, Any],
          size: tuple[int, int], colour: tuple[int, int, int], widen: int) -> None:
    for child, joint in structure.joints().items():
        box = boxes.get(child)
        centroid = np.asarray(box.centroid if box else joint.pivot, dtype=np.float64)
        for points, width in joint_polylines(joint, centroid):
            uv = project(points, camera, size)
            if np.isnan(uv).any():
                continue
            draw.line([tuple(p) for p in uv.tolist()], fill=colour, width=width + widen)


def draw_overlay(image_png: bytes, camera: Mapping[str, Any], boxes: Mapping[int, Box], reference: Structure,
                 prediction: Structure | None) -> Image.Image:
    """The input image, enlarged to at least MIN_SIDE, with reference and predicted joints drawn."""
    image = Image.open(io.BytesIO(image_png)).convert("RGB")
    scale = max(1, math.ceil(MIN_SIDE / max(image.size)))
    image = image.resize((image.width * scale, image.height * scale), Image.Resampling.NEAREST)
    draw = ImageDraw.Draw(image)
    _draw(draw, reference, boxes, camera, image.size, REFERENCE_RGB, widen=3)
    if prediction is not None:
        _draw(draw, prediction, boxes, camera, image.size, PREDICTED_RGB, widen=0)
    return image
