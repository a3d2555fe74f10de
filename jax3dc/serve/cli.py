"""`jax3dc serve [--host H] [--port P] [--out DIR] [predict's options]`, and ``serve_folder`` for
`jax3dc view DIR --serve`: the app of ``jax3dc.serve.app`` under uvicorn."""

from __future__ import annotations

import argparse
import ipaddress
import socket
import sys
import webbrowser
from pathlib import Path

from jax3dc.errors import Jax3dcError
from jax3dc.predict.cli import add_predict_options, predict_config

DEFAULT_PORT = 8000

DESCRIPTION = """\
A local web app: drop photos in the page (or pick files, or a folder); each is predicted in turn, with
the models loaded once, into its own folder of --out (as `jax3dc predict IMG... --out DIR` names
them, with DIR/index.html of all of them). A finished one opens in the viewer with its physics
verdict and a form per joint: type, axis, hinge line and range; applying it is `jax3dc edit` (the
check runs again and every export is rewritten). One click downloads the folder as a zip.

Uploads are streamed to disk, at most 20 MB each, and refused when they are not an image the
predict command reads (its size rules are checked from the header, before decoding). The server
listens on 127.0.0.1 unless --host says otherwise. A JSON API serves scripts (see README.md):
  POST /api/jobs (form field "image") -> {"id": ...}; GET /api/jobs/ID; GET /api/jobs/ID/files/NAME;
  GET /api/jobs/ID/zip; POST /api/jobs/ID/edit with a patch as `jax3dc edit` takes it.
The models options are predict's (see `jax3dc predict --help`).
"""


def is_loopback(host: str) -> bool:
    """Whether ``host`` names this machine only (127.0.0.0/8, ::1, localhost)."""
    if host.lower() == "localhost":
        return True
    try:
        return ipaddress.ip_address(host).is_loopback
    except ValueError:
        return False


def listen(host: str, port: int) -> socket.socket:
    """A socket bound to (host, port), so a port in use is one error line before anything loads."""
    try:
        info = socket.getaddrinfo(host, port, type=socket.SOCK_STREAM)[0]
        sock = socket.socket(info[0], socket.SOCK_STREAM)
        sock.setsockopt(socket.SOL_SOCKET, socket.SO_REUSEADDR, 1)
        sock.bind(info[4])
    except OSError as e:
        raise Jax3dcError(f"--host {host} --port {port}: cannot listen ({e.strerror or e}); "
                          "pass another port (0 picks a free one)") from None
    sock.listen(128)
    sock.set_inheritable(True)
    return sock


def run_app(app, sock: socket.socket, path: str, open_browser: bool) -> None:
    """Serves ``app`` on ``sock`` until Ctrl-C, after printing (and opening) the page's URL."""
    import uvicorn  # lazy: the server, which no other command needs

    host, port = sock.getsockname()[:2]
    shown = f"[{host}]" if ":" in host else host
    url = f"http://{shown}:{port}{path}"
    print(f"serving at {url} (Ctrl-C stops)", flush=True)
    if open_browser:
        webbrowser.open(url)
    try:
        uvicorn.Server(uvicorn.Config(app, log_level="warning", access_log=False)).run(sockets=[sock])
    except KeyboardInterrupt:  # uvicorn shuts down on Ctrl-C, then raises it again: a server's normal way out
        print("stopped", flush=True)


def warn_if_exposed(host: str) -> None:
    if not is_loopback(host):
        print(f"warning: --host {host} makes this server reachable from the network: anyone who can reach it "
              "can upload images, edit the objects and download them; there is no login", file=sys.stderr, flush=True)


def run(args: argparse.Namespace) -> int:
    config = predict_config(args)
    from jax3dc.serve.app import create_app  # lazy: starlette, the exporters and the physics check
    from jax3dc.serve.jobs import RUNNING, JobBoard  # lazy: as the line above

    sock = listen(args.host, args.port)
    warn_if_exposed(args.host)
    out = Path(args.out)
    board = JobBoard.predicting(out, config)
    board.start()
    done = len(board.all())
    if done:
        print(f"{done} objects predicted before in {out}", flush=True)
    try:
        run_app(create_app(board, loopback=is_loopback(args.host)), sock, "/", not args.no_open)
    finally:
        if any(job.state == RUNNING for job in board.all()):  # a prediction cut short would be done again
            print("letting the running prediction finish (Ctrl-C again quits now)", file=sys.stderr, flush=True)
        board.stop()
    return 0


def serve_folder(folder: Path, host: str, port: int, open_browser: bool) -> None:
    """`jax3dc view DIR --serve` on a predict folder: the page with DIR's object and its edit form, no uploads."""
    from jax3dc.serve.app import create_app  # lazy: as in run
    from jax3dc.serve.jobs import JobBoard  # lazy: as the line above

    sock = listen(host, port)
    warn_if_exposed(host)
    run_app(create_app(JobBoard.single(folder), loopback=is_loopback(host)), sock, "/", open_browser)


def register(subparsers: argparse._SubParsersAction) -> None:
    p = subparsers.add_parser("serve", help="a local web app: drop photos, fix joints by hand, download the assets",
                              description=DESCRIPTION, formatter_class=argparse.RawDescriptionHelpFormatter)
    p.add_argument("--host", default="127.0.0.1",
                   help="address to listen on (default 127.0.0.1: this machine only; another one warns that the "
                        "server is reachable from the network)")
    p.add_argument("--port", type=int, default=DEFAULT_PORT, help="port (default %(default)s; 0: any free port)")
    p.add_argument("--out", default="serve_out", metavar="DIR",
                   help="folder of the predictions, one folder per image (default: %(default)s); the ones done "
                        "there before are listed again")
    p.add_argument("--no-open", action="store_true", help="do not open a browser")
    add_predict_options(p)
    p.set_defaults(func=run)
