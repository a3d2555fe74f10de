"""The Python interpreter with Blender's `bpy` module that the Blender tests run scripts in.

bpy needs numpy < 2, so it lives in its own virtual environment, which .ci/run creates and
names in JAX3DC_BLENDER_PYTHON. Without it the Blender tests fail with this message rather
than skip: a skipped test checks nothing."""

import os


def blender_python() -> str:
    path = os.environ.get("JAX3DC_BLENDER_PYTHON", "")
    if not os.path.isfile(path):
        raise FileNotFoundError(
            f"JAX3DC_BLENDER_PYTHON={path!r} is not a Python with bpy: run the tests through `bash .ci/run`, "
            "or create one (python3 -m venv V && V/bin/pip install bpy==5.0.1) and export its bin/python")
    return path
