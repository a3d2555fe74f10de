"""A viewer page loaded in Debian's headless chromium through Playwright (tests/viewer only)."""

from __future__ import annotations

import io
import shutil
from pathlib import Path

import numpy as np
import pytest
from PIL import Image

sync_api = pytest.importorskip("playwright.sync_api", reason="Playwright for Python is not installed")
CHROMIUM = shutil.which("chromium") or "/usr/bin/chromium"
if not Path(CHROMIUM).exists():
    pytest.skip("Debian's chromium is not installed (apt-get install chromium)", allow_module_level=True)

# Headless, software WebGL (SwiftShader), and nothing that would try to reach the network.
FLAGS = ["--headless", "--no-sandbox", "--disable-gpu", "--disable-quic", "--no-first-run",
         "--disable-background-networking", "--disable-component-update", "--disable-sync",
         "--use-angle=swiftshader", "--enable-unsafe-swiftshader"]
VIEWPORT = {"width": 1280, "height": 800}
BACKGROUND = np.array([244, 244, 244])  # the page's clear colour (viewer.js BACKGROUND)
CHANGED = 24  # a pixel changed when a channel moved by more than this (0..255)
EDGE_PX = 2  # antialiased silhouettes may bleed this far past a part's own pixels


class Page:
    """One loaded viewer page with what its console said and every URL it asked for."""

    def __init__(self, context, url: str):
        self.errors: list[str] = []
        self.requests: list[str] = []
        self.page = context.new_page()
        self.page.on("console", lambda m: self.errors.append(m.text) if m.type == "error" else None)
        self.page.on("pageerror", lambda e: self.errors.append(str(e)))
        self.page.on("request", lambda r: self.requests.append(r.url))
        self.page.goto(url)
        self.page.wait_for_selector("body[data-ready=true]", timeout=60_000)

    def canvas(self, path: Path | None = None) -> np.ndarray:
        png_bytes = self.page.locator("#canvas").screenshot(path=path)
        return np.asarray(Image.open(io.BytesIO(png_bytes)).convert("RGB")).astype(np.int16)

    def alone(self, ids: list[int] | None) -> np.ndarray:
        """Pixels covered by parts ``ids`` drawn alone (then every part is shown again)."""
        self.page.evaluate("ids => window.jax3dcViewer.showOnly(ids)", ids)
        mask = np.abs(self.canvas() - BACKGROUND).max(axis=2) > CHANGED
        self.page.evaluate("() => window.jax3dcViewer.showOnly(null)")
        return mask

    def slider(self, part: int):
        return self.page.locator(f'[data-joint="{part}"] input[type=range]')
