"""What the serve tests share: the stand-in prediction of the factory cabinet (its own target as
the structure model, as the predict and edit tests do: parts 3 and 5 are hinged doors), and a
board behind the app through Starlette's TestClient (fixtures in conftest.py)."""

from __future__ import annotations

import shutil
import time
from pathlib import Path

from starlette.testclient import TestClient

from jax3dc.predict import PredictConfig
from jax3dc.predict.batch import image_digest, predict_one
from jax3dc.predict.pipeline import Checkpoints
from jax3dc.predict.stage1 import Stage1Config
from jax3dc.serve.app import create_app
from jax3dc.serve.jobs import JobBoard
from tests.predict.predict_cases import CAMERA, target_json, write_glb, write_image

ORIGIN = "http://127.0.0.1:8000"


def predicted_inputs(root: Path) -> tuple[PredictConfig, Path, Path]:
    """(the stand-in config, the cabinet's image, an --out in ``root`` with it predicted as "cabinet")."""
    config = PredictConfig(Stage1Config(f"mesh:{write_glb(root / 'object.glb')}"),
                           generate_structure=lambda prompt: target_json(), camera=CAMERA)
    image = write_image(root / "cabinet.png")
    predict_one(image, "cabinet", image_digest(image), config, root / "out", Checkpoints("float32"))
    return config, image, root / "out"


class Served:
    """A running board and its app's client; ``root`` holds ``out`` and nothing else."""

    def __init__(self, root: Path, board: JobBoard, client):
        self.root, self.board, self.client = root, board, client
        self.out = board.out

    def wait(self, job_id: str, timeout: float = 60.0) -> dict:
        """The job's JSON once it is done or failed."""
        deadline = time.monotonic() + timeout
        while time.monotonic() < deadline:
            job = self.client.get(f"/api/jobs/{job_id}").json()
            if job["state"] in ("done", "failed"):
                return job
            time.sleep(0.05)
        raise AssertionError(f"job {job_id} not finished in {timeout} s")


def served_app(inputs, tmp_path: Path, **options) -> Served:
    """A board on a copy of ``inputs``' --out in ``tmp_path``/root, its worker started, and the
    app's client (``options`` go to ``create_app``); the caller stops the board."""
    config, _image, predicted = inputs
    root = tmp_path / "root"
    out = Path(shutil.copytree(predicted, root / "out"))
    board = JobBoard.predicting(out, config, Checkpoints("float32"))
    board.start()
    client = TestClient(create_app(board, **options), base_url=ORIGIN)
    return Served(root, board, client)
