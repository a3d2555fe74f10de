"""``jax3dc view --serve``: a small local web server for the viewer's folder, for browsers or
settings that limit pages opened from a file URL. It listens on 127.0.0.1 only."""

from __future__ import annotations

import functools
import http.server
from pathlib import Path

from jax3dc.errors import Jax3dcError


class _QuietHandler(http.server.SimpleHTTPRequestHandler):
    def log_message(self, format: str, *args) -> None:  # one line per file would bury the URL
        pass


def start_server(folder: str | Path, port: int) -> http.server.ThreadingHTTPServer:
    """A server of ``folder`` on 127.0.0.1:``port`` (0: any free port), not yet serving."""
    handler = functools.partial(_QuietHandler, directory=str(folder))
    try:
        return http.server.ThreadingHTTPServer(("127.0.0.1", port), handler)
    except OSError as e:
        raise Jax3dcError(f"--port {port}: cannot listen on 127.0.0.1 ({e.strerror or e}); "
                          "pass another port (0 picks a free one)") from None


def page_url(server: http.server.ThreadingHTTPServer, page: str) -> str:
    host, port = server.server_address[:2]
    return f"http://{host}:{port}/{page}"
