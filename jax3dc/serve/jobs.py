"""The jobs of `jax3dc serve`: each uploaded image is one job, predicted in turn by one worker thread.

One thread, one ``Checkpoints``: the models load once and one prediction runs at a time (two
would share the CPU or GPU and the memory of one model for no gain), so a job's place in the
queue is its place in the order of submission. Each job predicts through the batch's own
``jax3dc.predict.batch.predict_one`` into a folder of --out named from its file name as the batch
names it (``folder_name``, unique among the folder's entries): done.json, the gallery (index.html
of every job) and the files are those `jax3dc predict IMG... --out DIR` writes, and a server started
again on the same --out lists the folders done before as done jobs.

The upload waits in --out/.uploads/ (a hidden entry: never a job's folder) and is removed once
its job ran. A job's id is its folder's name, so the URLs of its files are the folder's paths.
"""

from __future__ import annotations

import json
import queue
import shutil
import sys
import threading
import time
import traceback
from dataclasses import dataclass, field, replace
from pathlib import Path
from typing import TYPE_CHECKING

from jax3dc.predict.batch import IMAGE_SUFFIXES, RESERVED, done_card, folder_name, image_digest, predict_one
from jax3dc.predict.gallery import ERROR, WAITING, Card, write_gallery
from jax3dc.serve.uploads import UploadError

if TYPE_CHECKING:
    from jax3dc.predict.pipeline import Checkpoints, PredictConfig

QUEUED, RUNNING, DONE, FAILED = "queued", "running", "done", "failed"
UPLOADS = ".uploads"
MAX_WAITING = 500  # jobs queued at once: each holds its upload on disk until it runs


@dataclass
class Job:
    """One image to predict (or predicted): its folder, the uploaded file's name as text, its
    number in the order of submission and where it stands."""

    id: str
    folder: Path
    name: str
    number: int
    state: str
    upload: Path | None = None
    error: str | None = None
    submitted: float = field(default_factory=time.time)
    started: float | None = None
    finished: float | None = None

    def card(self) -> Card:
        """The job as the gallery shows it."""
        if self.state == DONE:
            card = done_card(self.folder)
            return Card(self.id, self.name, ERROR, "its folder changed on disk") if card is None else replace(
                card, image=self.name)
        if self.state == FAILED:
            return Card(self.id, self.name, ERROR, self.error or "")
        return Card(self.id, self.name, WAITING)


class JobBoard:
    """The jobs of one server and the worker that predicts them (``start``; ``stop`` ends it after
    the running job). With no ``config`` it takes no uploads: `jax3dc view DIR --serve` edits the
    one folder it was given (``single``)."""

    def __init__(self, out: Path, config: PredictConfig | None, checkpoints: Checkpoints | None = None):
        self.out = out
        self.config = config
        self.checkpoints = checkpoints
        self.jobs: dict[str, Job] = {}
        self.lock = threading.Lock()
        self.queue: queue.Queue[Job | None] = queue.Queue()
        self.worker: threading.Thread | None = None

    @classmethod
    def predicting(cls, out: Path, config: PredictConfig, checkpoints: Checkpoints | None = None) -> JobBoard:
        """A board predicting uploads into ``out``, listing the folders an earlier run completed
        there as done jobs (oldest first); a stale .uploads/ of a killed server is removed."""
        out.mkdir(parents=True, exist_ok=True)
        shutil.rmtree(out / UPLOADS, ignore_errors=True)
        (out / UPLOADS).mkdir()
        board = cls(out, config, checkpoints)
        done = [(card, folder) for folder in out.iterdir()
                if folder.is_dir() and not folder.name.startswith(".") and (card := done_card(folder)) is not None]
        for card, folder in sorted(done, key=lambda item: item[1].stat().st_mtime):
            number = len(board.jobs) + 1
            board.jobs[folder.name] = Job(folder.name, folder, card.image, number, DONE)
        return board

    @classmethod
    def single(cls, folder: Path) -> JobBoard:
        """A board of the one predict folder ``folder``, done, taking no uploads."""
        board = cls(folder.parent, None)
        name = folder_name(folder.resolve().name)
        board.jobs[name] = Job(name, folder, folder.resolve().name, 1, DONE)
        return board

    @property
    def takes_uploads(self) -> bool:
        return self.config is not None

    def start(self) -> None:
        """Starts the worker thread (the models load on its first job)."""
        if self.takes_uploads and self.worker is None:
            self.worker = threading.Thread(target=self._work, name="jax3dc-serve-worker", daemon=True)
            self.worker.start()

    def stop(self) -> None:
        """Lets the worker finish its running job and end; the jobs still queued stay queued."""
        if self.worker is not None:
            self.queue.put(None)
            self.worker.join()
            self.worker = None

    def incoming(self) -> Path:
        """A fresh path in .uploads/ to stream an upload into before it is a job."""
        return self.out / UPLOADS / f"incoming-{threading.get_ident()}-{time.monotonic_ns()}"

    def _new_id(self, filename: str) -> str:
        """``folder_name`` of ``filename``, made unique against the jobs and every entry of --out."""
        taken = set(RESERVED) | {j.lower() for j in self.jobs} | {p.name.lower() for p in self.out.iterdir()}
        base = folder_name(filename)
        name, k = base, 1
        while name.lower() in taken:
            k += 1
            name = f"{base}-{k}"
        return name

    def submit(self, upload: Path, filename: str) -> Job:
        """Queues the checked image at ``upload`` (a path of ``incoming``) as a new job, moving it
        to its job's name; UploadError 503 when MAX_WAITING jobs are waiting already."""
        if not self.takes_uploads:
            upload.unlink(missing_ok=True)
            raise UploadError(405, "this server edits one folder (jax3dc view DIR --serve); "
                                   "`jax3dc serve` predicts uploaded images")
        with self.lock:
            waiting = sum(j.state == QUEUED for j in self.jobs.values())
            if waiting >= MAX_WAITING:
                upload.unlink(missing_ok=True)
                raise UploadError(503, f"{waiting} images are waiting already; submit this one when some are done")
            job_id = self._new_id(filename)
            suffix = Path(filename).suffix.lower()
            stored = upload.with_name(job_id + (suffix if suffix in IMAGE_SUFFIXES else ""))
            upload.rename(stored)
            job = Job(job_id, self.out / job_id, filename, len(self.jobs) + 1, QUEUED, upload=stored)
            self.jobs[job_id] = job
        self.queue.put(job)
        self._write_gallery()
        return job

    def get(self, job_id: str) -> Job | None:
        with self.lock:
            return self.jobs.get(job_id)

    def all(self) -> list[Job]:
        with self.lock:
            return sorted(self.jobs.values(), key=lambda j: j.number)

    def position(self, job: Job) -> int:
        """How many jobs run or wait before ``job`` (0 once it runs)."""
        if job.state != QUEUED:
            return 0
        with self.lock:
            return sum(j.state in (QUEUED, RUNNING) and j.number < job.number for j in self.jobs.values())

    def _write_gallery(self) -> None:
        if self.takes_uploads:
            write_gallery([job.card() for job in self.all()], self.out)

    def _work(self) -> None:
        """The worker: each job in turn, until ``stop``. A job's failure is its own: an input error
        is its card's detail, and any other error (a bug) is printed and fails only that job."""
        from jax3dc.predict.pipeline import Checkpoints  # lazy: jax, once the server runs (1.7 s)

        if self.checkpoints is None:
            self.checkpoints = Checkpoints(self.config.decoding.dtype)
        while (job := self.queue.get()) is not None:
            with self.lock:
                job.state, job.started = RUNNING, time.time()
            try:
                card = predict_one(job.upload, job.id, image_digest(job.upload), self.config, self.out, self.checkpoints)
            except Exception as e:  # noqa: BLE001 - the server keeps serving the other jobs
                traceback.print_exc(file=sys.stderr)
                card = Card(job.id, job.name, ERROR, f"internal error: {type(e).__name__}: {e}")
            finally:
                job.upload.unlink(missing_ok=True)
            with self.lock:
                job.state = FAILED if card.state == ERROR else DONE
                job.error = card.detail if card.state == ERROR else None
                job.finished = time.time()
            self._write_gallery()


def read_verdict(folder: Path) -> dict | None:
    """physics.json's verdict as the page shows it: whether it passes and, per joint, its reasons;
    None when the folder has none (a prediction that stopped before the check)."""
    try:
        data = json.loads((folder / "physics.json").read_text(encoding="utf-8"))
        return {"ok": bool(data["ok"]), "joints": {str(k): {"ok": bool(v["ok"]), "reasons": list(v["reasons"])}
                                                   for k, v in data["joints"].items()}}
    except (OSError, ValueError, KeyError, TypeError, AttributeError):
        return None
