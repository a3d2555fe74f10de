"""S for stage-1 parts: the flat-colour segmentation rendered from the camera of the image I.

The camera is a MuJoCo free camera in the normalised object frame (nu), the form ``jax3dc data
build`` stores in a record's meta: ``{"lookat": [x, y, z], "distance": d, "azimuth": deg,
"elevation": deg}``. Without one, the default looks at the object's centre from the front
(azimuth 90 looks along +Y, at the -Y front) and slightly above, far enough that the whole object
fits the 45-degree view, like the dataset's cameras.

The renderer's field of view is MuJoCo's default, 45 degrees vertical; a camera that says otherwise
(``"fovy"``) is refused rather than rendered wrong. A non-square image gets a non-square S with the
same vertical field of view (as MuJoCo and the image's camera both keep it), never a square S.
"""

from __future__ import annotations

import json
import math
from pathlib import Path
from typing import Any, Mapping

import numpy as np
import trimesh

from jax3dc.render import Camera, Lighting, PartRenderer, offscreen_renderer, paint_segmentation
from jax3dc.errors import InputFileError
from jax3dc.geometry.parts import parts_bounds

FOVY_DEGREES = 45.0  # MuJoCo's default vertical field of view: the only one rendered here
DEFAULT_AZIMUTH = 90.0
DEFAULT_ELEVATION = -20.0
FIT_MARGIN = 1.07  # the middle of the dataset's distance jitter (1.0 .. 1.15)
# The lighting only shades the RGB pass, which is not used: S comes from the segmentation pass.
_FLAT = Lighting(ambient=0.3, headlight=0.5, key_dir=(0.0, 0.0, -1.0), key_strength=0.4)


def default_camera(parts: Mapping[int, trimesh.Trimesh]) -> Camera:
    lo, hi = parts_bounds(dict(parts))
    radius = float(np.linalg.norm(hi - lo)) / 2.0
    return Camera(lookat=tuple(float(v) for v in (lo + hi) / 2.0),
                  distance=radius / math.sin(math.radians(22.5)) * FIT_MARGIN,
                  azimuth=DEFAULT_AZIMUTH, elevation=DEFAULT_ELEVATION)


def camera_from_dict(doc: Any, where: str) -> Camera:
    """A Camera from the record-meta form; anything else is an InputFileError naming ``where``."""
    if not isinstance(doc, Mapping):
        raise InputFileError(where, "camera must be a JSON object with lookat, distance, azimuth, elevation")
    try:
        lookat = tuple(float(v) for v in doc["lookat"])
        values = [float(doc[k]) for k in ("distance", "azimuth", "elevation")]
    except KeyError as e:
        raise InputFileError(where, f"camera has no {e.args[0]!r}") from None
    except (TypeError, ValueError):
        raise InputFileError(where, "camera values must be numbers (lookat: 3 numbers)") from None
    if len(lookat) != 3 or not np.isfinite([*lookat, *values]).all():
        raise InputFileError(where, "camera lookat must be 3 finite numbers and distance/azimuth/elevation finite")
    if values[0] <= 0:
        raise InputFileError(where, "camera distance must be positive")
    fovy = FOVY_DEGREES
    if "fovy" in doc:
        try:
            fovy = float(doc["fovy"])
        except (TypeError, ValueError):
            raise InputFileError(where, "camera fovy must be a number of degrees") from None
        if not 1.0 <= fovy <= 170.0:
            raise InputFileError(where, f"camera fovy {fovy:g} is outside 1-170 degrees")
    return Camera(lookat=lookat, distance=values[0], azimuth=values[1], elevation=values[2], fovy=fovy)


def load_camera(path: str | Path) -> Camera:
    """A camera JSON file: the camera object itself, or a record meta holding it under "camera"."""
    path = Path(path)
    try:
        doc = json.loads(path.read_text(encoding="utf-8"))
    except OSError as e:
        raise InputFileError(path, f"cannot read the camera file: {e.strerror or e}") from None
    except json.JSONDecodeError as e:
        raise InputFileError(path, f"camera file is not valid JSON: {e}") from None
    if isinstance(doc, dict) and isinstance(doc.get("camera"), dict):
        doc = doc["camera"]
    return camera_from_dict(doc, str(path))


def render_part_ids(parts: Mapping[int, trimesh.Trimesh], camera: Camera, size: int,
                    height: int | None = None) -> np.ndarray:
    """Part id per pixel [height, size] (0 = background; height defaults to size) of the parts at
    rest seen from ``camera``."""
    height = size if height is None else height
    grey = {pid: (0.7, 0.7, 0.7, 1.0) for pid in parts}
    renderer = PartRenderer(dict(parts), grey, _FLAT, max(size, height))
    try:
        if height != size:
            # PartRenderer draws squares; its offscreen buffer (the longer side) also holds a
            # size x height view, which MuJoCo draws with the same vertical field of view.
            renderer.renderer.close()
            renderer.renderer = offscreen_renderer(renderer.model, height, size)
        return renderer.render({}, camera)[1]
    finally:
        renderer.close()


def render_segmentation(parts: Mapping[int, trimesh.Trimesh], camera: Camera, palette: np.ndarray,
                        size: int, height: int | None = None) -> tuple[np.ndarray, np.ndarray]:
    """(S as RGB uint8 [height, size, 3], part ids [height, size]); height defaults to size."""
    ids = render_part_ids(parts, camera, size, height)
    return paint_segmentation(ids, palette), ids
