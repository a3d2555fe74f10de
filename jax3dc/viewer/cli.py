"""``jax3dc view PATH``: write the interactive viewer of an object and open it in a browser."""

from __future__ import annotations

import argparse
import webbrowser
from pathlib import Path

from jax3dc.cli_args import positive_float
from jax3dc.serve.cli import serve_folder
from jax3dc.viewer.page import write_viewer
from jax3dc.viewer.serve import page_url, start_server
from jax3dc.viewer.sources import view_inputs

DESCRIPTION = """\
Write the interactive 3D viewer of an object (an HTML page) and open it in the web browser.

PATH is a `jax3dc predict` output folder, an export folder or .glb file from `jax3dc export
--format gltf`, or a structure JSON given with --parts DIR. The page shows the object (drag to
turn it, scroll to zoom), one slider per joint limited to its range, a rest button, the joint
axes and pivots on request, the physics verdict per joint (from physics.json beside the object;
flagged joints are marked in red with their reasons), the image I and segmentation S (image.png,
seg.png beside it) and the relations (hover one to highlight its parts).

The page works offline from its file; it goes to PATH/viewer.html (or <name>_viewer.html beside a
file) with its scripts in viewer_files/ beside it. --serve serves that folder on 127.0.0.1 instead
of opening the file, until Ctrl-C; for a `jax3dc predict` folder it serves the page of `jax3dc
serve` with this object alone: the viewer, its verdict and a form per joint that edits it as
`jax3dc edit` does, and a zip of the folder.

Example: jax3dc view prediction/
"""


def run(args: argparse.Namespace) -> int:
    inputs, default_page = view_inputs(args.path, args.parts, args.scale)
    page = write_viewer(inputs, Path(args.out) if args.out else default_page)
    print(f"wrote {page}")
    if not args.serve:
        if not args.no_open:
            webbrowser.open(page.resolve().as_uri())
        return 0
    from jax3dc.predict.outputs import CONTEXT_FILE  # lazy: the exporters (0.15 s) that `jax3dc --help` skips

    folder = Path(args.path)
    if args.out is None and (folder / CONTEXT_FILE).is_file():  # a predict folder: the page with the edit form
        serve_folder(folder, "127.0.0.1", args.port, not args.no_open)
        return 0

    server = start_server(page.parent, args.port)
    url = page_url(server, page.name)
    print(f"serving {page.parent} at {url} (Ctrl-C stops)", flush=True)
    if not args.no_open:
        webbrowser.open(url)
    try:
        server.serve_forever()
    finally:
        server.server_close()
    return 0


def register(subparsers: argparse._SubParsersAction) -> None:
    p = subparsers.add_parser("view", help="open the interactive 3D viewer of an object (joint sliders, physics)",
                              description=DESCRIPTION, formatter_class=argparse.RawDescriptionHelpFormatter)
    p.add_argument("path", metavar="PATH", help="predict or export folder, a .glb, or a structure JSON with --parts")
    p.add_argument("--parts", metavar="DIR", help="folder of <id>.obj part meshes for a structure JSON PATH")
    p.add_argument("--scale", type=positive_float, metavar="METRES_PER_NU",
                   help="metres per normalised unit with --parts (default: 'scale' of meta.json beside it, else 1)")
    p.add_argument("--out", metavar="FILE.html", help="where to write the page (default: beside the object)")
    p.add_argument("--serve", action="store_true", help="serve the page's folder on 127.0.0.1 instead of a file URL (a predict folder: "
                        "with the edit form)")
    p.add_argument("--port", type=int, default=8765, help="port of --serve (default 8765; 0: any free port)")
    p.add_argument("--no-open", action="store_true", help="write (and serve) the page without opening a browser")
    p.set_defaults(func=run)
