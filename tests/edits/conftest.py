"""One predicted folder for the edit tests: a factory cabinet (two hinged doors, parts 3 and 5, each
with a handle) through `predict` with its own target standing in for the structure model, as the
predict tests do; each test edits a copy of it."""

from __future__ import annotations

import shutil
from pathlib import Path

import pytest

from jax3dc.predict import PredictConfig, predict
from jax3dc.predict.stage1 import Stage1Config
from tests.predict.predict_cases import CAMERA, target_json, write_glb, write_image


@pytest.fixture(scope="session")
def predicted(tmp_path_factory) -> Path:
    root = tmp_path_factory.mktemp("edit_source")
    config = PredictConfig(Stage1Config(f"mesh:{write_glb(root / 'object.glb')}"),
                           generate_structure=lambda prompt: target_json(), camera=CAMERA)
    return predict(write_image(root / "image.png"), config, root / "cabinet").out


@pytest.fixture
def folder(predicted: Path, tmp_path: Path) -> Path:
    """A fresh copy of the predicted folder."""
    return Path(shutil.copytree(predicted, tmp_path / "cabinet"))

