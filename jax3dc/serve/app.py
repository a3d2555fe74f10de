"""The web app of `jax3dc serve` and `jax3dc view DIR --serve`: the page and its JSON API.

  GET  /                              the page (static/app.html, .js, .css: no build step, no CDN)
  GET  /api/jobs                      every job, in the order of submission
  POST /api/jobs                      an image (multipart/form-data, field "image") -> 202 {"id": ...}
  GET  /api/jobs/{id}                 its state, verdict, files
  GET  /api/jobs/{id}/joints          its joints as the edit form shows them (jax3dc.edits.folder.joint_rows)
  GET  /api/jobs/{id}/files/{path}    a file of its folder (viewer.html, object.xml, ...)
  GET  /api/jobs/{id}/zip             its folder as a zip
  POST /api/jobs/{id}/edit            a patch as `jax3dc edit` takes it -> the joint and verdict now

Every error is a JSON reply ``{"error": "..."}`` with a 4xx status, one line for a person; an
edit goes through ``jax3dc.edits.folder.edit_folder``, the command's own code path, so its
errors (a missing part, a non-finite axis: EditError) are 400 and an edit of a folder that another
edit holds (FolderBusyError) is 409, leaving the folder as it was. Files are served only from inside
a job's folder, never a hidden entry (an edit's stage, the uploads).

``SameOrigin`` guards the app: a POST (or any other method that changes something) whose Origin
is not this server's is refused, so a page on another site cannot make a visitor's browser submit
or edit; on loopback a request whose Host is not a loopback name is refused too (a DNS-rebinding
page would send its own).
"""

from __future__ import annotations

import io
import time
import zipfile
from importlib import resources
from pathlib import Path
from urllib.parse import urlsplit

from starlette.applications import Starlette
from starlette.concurrency import run_in_threadpool
from starlette.datastructures import Headers
from starlette.exceptions import HTTPException
from starlette.requests import Request
from starlette.responses import FileResponse, JSONResponse, Response
from starlette.routing import Mount, Route
from starlette.staticfiles import StaticFiles
from starlette.types import ASGIApp, Receive, Scope, Send

from jax3dc.edits.folder import JointRow, edit_folder, joint_rows, load_object
from jax3dc.edits.staging import folder_lock
from jax3dc.errors import EditError, FolderBusyError, Jax3dcError
from jax3dc.serve.jobs import DONE, Job, JobBoard, read_verdict
from jax3dc.serve.uploads import UploadError, check_image, receive_image

MAX_UPLOAD_BYTES = 20_000_000
MAX_PATCH_BYTES = 65_536
LOOPBACK_NAMES = frozenset({"127.0.0.1", "localhost", "::1"})
SAFE_METHODS = frozenset({"GET", "HEAD", "OPTIONS"})
ZIP_WAIT_S = 30.0  # a zip waits this long for a running edit of its folder to finish


def error(status: int, message: str) -> JSONResponse:
    return JSONResponse({"error": message}, status_code=status)


async def http_error(request: Request, exc: Exception) -> JSONResponse:
    """Starlette's own refusals (no such route, a method a route does not take) as JSON errors too."""
    status = exc.status_code if isinstance(exc, HTTPException) else 500
    detail = exc.detail if isinstance(exc, HTTPException) else "internal error"
    return error(status, f"{detail}: {request.method} {request.url.path[:200]}")


def _hostname(host: str) -> str:
    """The name part of a Host header value (``[::1]:8000`` -> ``::1``)."""
    return (urlsplit(f"//{host}").hostname or "").lower()


class SameOrigin:
    """ASGI middleware: refuses cross-origin changes and, when ``loopback``, foreign Host headers (module docstring)."""

    def __init__(self, app: ASGIApp, loopback: bool):
        self.app, self.loopback = app, loopback

    async def __call__(self, scope: Scope, receive: Receive, send: Send) -> None:
        if scope["type"] == "http":
            refused = self.refusal(Headers(scope=scope), scope["method"])
            if refused is not None:
                await error(403, refused)(scope, receive, send)
                return
        await self.app(scope, receive, send)

    def refusal(self, headers: Headers, method: str) -> str | None:
        host = headers.get("host", "")
        if self.loopback and _hostname(host) not in LOOPBACK_NAMES:
            return f"this server answers on loopback names only, not Host {host[:100]!r}"
        if method in SAFE_METHODS:
            return None
        origin = headers.get("origin")
        if origin is not None:
            parts = urlsplit(origin)
            if parts.scheme not in ("http", "https") or parts.netloc.lower() != host.lower():
                return f"a request from another origin ({origin[:100]}) may not change anything here"
        if headers.get("sec-fetch-site", "same-origin") not in ("same-origin", "none"):
            return "a request from another site may not change anything here"
        return None


def _files(folder: Path) -> list[str]:
    """The names of a folder's files (not its subfolders or hidden entries), sorted."""
    try:
        return sorted(p.name for p in folder.iterdir() if p.is_file() and not p.name.startswith("."))
    except OSError:
        return []


def job_json(board: JobBoard, job: Job) -> dict:
    """A job as the API replies it."""
    base = f"/api/jobs/{job.id}"
    data = {"id": job.id, "name": job.name, "number": job.number, "state": job.state, "error": job.error,
            "position": board.position(job),
            "seconds": None if job.started is None or job.finished is None else round(job.finished - job.started, 2),
            "verdict": None, "files": [], "viewer": None, "zip": None}
    if job.state == DONE:
        files = _files(job.folder)
        data.update(verdict=read_verdict(job.folder), files=files, zip=f"{base}/zip",
                    viewer=f"{base}/files/viewer.html" if "viewer.html" in files else None)
    elif job.folder.is_dir():  # a failed prediction may have its report
        data["files"] = _files(job.folder)
    return data


def _row_json(row: JointRow) -> dict:
    return {"part": row.part, "name": row.name, "parent": row.parent, "type": row.type,
            "axis": row.axis_name or (None if row.axis is None else list(row.axis)), "line": row.line,
            "range": None if row.range is None else list(row.range), "lines": row.lines}


def _inside(folder: Path, path: str) -> Path | None:
    """``folder``/``path`` when it is a file inside ``folder`` reached through no hidden, empty,
    ``.`` or ``..`` component; else None."""
    parts = path.split("/")
    if any(not p or p.startswith(".") or "\\" in p for p in parts):
        return None
    root = folder.resolve()
    target = root.joinpath(*parts).resolve()
    return target if target.is_relative_to(root) and target.is_file() else None


def _zip(folder: Path, root: str) -> bytes:
    """The folder (but its hidden entries) as a zip under ``root``/, read while no edit runs."""
    deadline = time.monotonic() + ZIP_WAIT_S
    while True:
        try:
            with folder_lock(folder):
                buffer = io.BytesIO()
                with zipfile.ZipFile(buffer, "w", zipfile.ZIP_DEFLATED) as archive:
                    for path in sorted(folder.rglob("*")):
                        relative = path.relative_to(folder)
                        if path.is_file() and not any(p.startswith(".") for p in relative.parts):
                            archive.write(path, f"{root}/{relative.as_posix()}")
                return buffer.getvalue()
        except FolderBusyError:
            if time.monotonic() > deadline:
                raise
            time.sleep(0.1)


def create_app(board: JobBoard, loopback: bool = True, max_upload_bytes: int = MAX_UPLOAD_BYTES) -> Starlette:
    """The app serving ``board``'s jobs (module docstring). The caller starts and stops the board's worker."""
    static = resources.files("jax3dc.serve") / "static"

    def done_job(request: Request) -> Job | JSONResponse:
        job = board.get(request.path_params["job"])
        if job is None:
            return error(404, f"no job {request.path_params['job'][:100]!r}")
        if job.state != DONE:
            return error(409, f"job {job.id} is {job.state}: only a done prediction has files to edit or download")
        return job

    async def page(request: Request) -> Response:
        return FileResponse(str(static / "app.html"), media_type="text/html")

    async def settings(request: Request) -> JSONResponse:
        return JSONResponse({"uploads": board.takes_uploads, "max_upload_bytes": max_upload_bytes})

    async def list_jobs(request: Request) -> JSONResponse:
        return JSONResponse({"jobs": [job_json(board, job) for job in board.all()]})

    async def submit(request: Request) -> JSONResponse:
        if not board.takes_uploads:
            return error(405, "this server edits one folder (jax3dc view DIR --serve); `jax3dc serve` predicts images")
        incoming = board.incoming()
        try:
            upload = await receive_image(request.headers.get("content-type"), request.stream(), incoming,
                                         max_upload_bytes)
            try:
                await run_in_threadpool(check_image, upload.path, board.config.max_image_pixels)
            except UploadError as e:
                raise UploadError(e.status, f"{upload.filename}: {e.message}") from None
            job = await run_in_threadpool(board.submit, upload.path, upload.filename)
        except UploadError as e:
            incoming.unlink(missing_ok=True)
            return error(e.status, e.message)
        return JSONResponse(job_json(board, job), status_code=202)

    async def show_job(request: Request) -> JSONResponse:
        job = board.get(request.path_params["job"])
        if job is None:
            return error(404, f"no job {request.path_params['job'][:100]!r}")
        return JSONResponse(job_json(board, job))

    def joints(request: Request) -> JSONResponse:  # a plain function: Starlette runs it in a thread (meshes load)
        job = done_job(request)
        if isinstance(job, JSONResponse):
            return job
        try:
            rows = joint_rows(load_object(job.folder))
        except Jax3dcError as e:
            return error(409, str(e))
        return JSONResponse({"id": job.id, "joints": [_row_json(r) for r in rows], "verdict": read_verdict(job.folder)})

    def file(request: Request) -> Response:
        job = board.get(request.path_params["job"])
        if job is None:
            return error(404, f"no job {request.path_params['job'][:100]!r}")
        path = _inside(job.folder, request.path_params["path"])
        if path is None:
            return error(404, f"no file {request.path_params['path'][:100]!r} in job {job.id}")
        return FileResponse(path, headers={"Cache-Control": "no-store", "X-Content-Type-Options": "nosniff"})

    def download(request: Request) -> Response:
        job = done_job(request)
        if isinstance(job, JSONResponse):
            return job
        try:
            data = _zip(job.folder, job.id)
        except FolderBusyError as e:
            return error(409, str(e))
        return Response(data, media_type="application/zip",
                        headers={"Content-Disposition": f'attachment; filename="{job.id}.zip"'})

    async def edit(request: Request) -> JSONResponse:
        job = done_job(request)
        if isinstance(job, JSONResponse):
            return job
        body = b""
        async for chunk in request.stream():
            body += chunk
            if len(body) > MAX_PATCH_BYTES:
                return error(413, f"a patch is at most {MAX_PATCH_BYTES} bytes")
        try:
            result = await run_in_threadpool(edit_folder, job.folder, body)
        except EditError as e:
            return error(400, str(e))
        except FolderBusyError as e:
            return error(409, str(e))
        except Jax3dcError as e:  # the folder cannot be edited (no structure, a file missing)
            return error(409, str(e))
        return JSONResponse({"id": job.id, "part": result.patch.part, "ok": result.verdict.ok,
                             "job": job_json(board, job)})

    routes = [
        Route("/", page),
        Route("/api/settings", settings),
        Route("/api/jobs", list_jobs, methods=["GET"]),
        Route("/api/jobs", submit, methods=["POST"]),
        Route("/api/jobs/{job}", show_job),
        Route("/api/jobs/{job}/joints", joints),
        Route("/api/jobs/{job}/files/{path:path}", file),
        Route("/api/jobs/{job}/zip", download),
        Route("/api/jobs/{job}/edit", edit, methods=["POST"]),
        Mount("/static", app=StaticFiles(directory=str(static)), name="static"),
    ]
    app = Starlette(routes=routes, exception_handlers={HTTPException: http_error})
    app.add_middleware(SameOrigin, loopback=loopback)
    return app
