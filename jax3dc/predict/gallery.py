"""index.html of a batch of predictions: one card per image with its thumbnail, the physics
verdict (or the error), and links to the object's viewer and report.

Every link is relative (``<folder>/viewer.html``), so the gallery works from a file URL, from a
server, and after the batch folder is moved or zipped. The folder names are the batch's sanitised
ones (``jax3dc.predict.batch.folder_name``), and everything taken from a file name or an error
is HTML-escaped: an image called ``<script>.png`` shows as text.
"""

from __future__ import annotations

import html
import os
from collections.abc import Sequence
from dataclasses import dataclass
from pathlib import Path
from urllib.parse import quote

GALLERY_FILE = "index.html"
PASSES, FAILS, ERROR, WAITING = "passes", "fails", "error", "waiting"  # a card's state


@dataclass(frozen=True)
class Card:
    """One image of the batch as the gallery shows it."""

    folder: str  # the image's output folder, relative to the gallery
    image: str  # the input file's name, as given
    state: str  # PASSES / FAILS (the physics check), ERROR (no verdict), WAITING (not predicted yet)
    detail: str = ""  # "5 parts, 2 joints", or the error

    def links(self, root: Path) -> list[tuple[str, str]]:
        """(label, relative href) of the pages the folder holds (the viewer needs a structure)."""
        pages = (("viewer", "viewer.html"), ("report", "report.html"))
        return [(label, f"{quote(self.folder)}/{page}") for label, page in pages if (root / self.folder / page).is_file()]


STYLE = """body{font-family:sans-serif;margin:1.5em}
.grid{display:grid;grid-template-columns:repeat(auto-fill,minmax(220px,1fr));gap:1em}
figure{margin:0;padding:.6em;border:1px solid #ccc;border-radius:6px}
figure img{width:100%;height:180px;object-fit:contain;background:#f4f4f4}
figcaption{font-size:.9em;overflow-wrap:anywhere}
.passes .state{color:#1a7f37}.fails .state,.error .state{color:#b00}.waiting .state{color:#777}"""


def _card(card: Card, root: Path) -> str:
    links = card.links(root)
    thumb = f"{quote(card.folder)}/image.png"
    image = (f'<img src="{html.escape(thumb)}" alt="{html.escape(card.image)}" loading="lazy">'
             if (root / card.folder / "image.png").is_file() else "")
    if image and links:
        image = f'<a href="{html.escape(links[0][1])}">{image}</a>'
    state = {PASSES: "physics: passes", FAILS: "physics: fails", ERROR: "error", WAITING: "not predicted yet"}[card.state]
    detail = f" — {html.escape(card.detail)}" if card.detail else ""
    pages = " ".join(f'<a href="{html.escape(href)}">{label}</a>' for label, href in links)
    return (f'<figure class="{card.state}">{image}<figcaption><b>{html.escape(card.image)}</b><br>'
            f'<span class="state">{state}</span>{detail}<br>{pages}</figcaption></figure>')


def write_gallery(cards: Sequence[Card], root: Path) -> Path:
    """Writes ``root``/index.html (whole or not at all: a reader never sees half a page)."""
    said = {PASSES: "pass the physics check", FAILS: "fail it", ERROR: "failed to predict", WAITING: "not predicted yet"}
    counts = {s: sum(c.state == s for c in cards) for s in said}
    summary = ", ".join(f"{n} {said[s]}" for s, n in counts.items() if n)
    page = f"""<!DOCTYPE html>
<html><head><meta charset="utf-8"><title>jax3dc predictions</title>
<style>{STYLE}</style></head>
<body><h1>jax3dc predictions</h1>
<p>{len(cards)} images: {html.escape(summary)}</p>
<div class="grid">
{chr(10).join(_card(c, root) for c in cards)}
</div>
</body></html>
"""
    path = root / GALLERY_FILE
    partial = root / f".{GALLERY_FILE}.partial"
    partial.write_text(page, encoding="utf-8")
    os.replace(partial, path)
    return path
