"""The browser shared by the viewer tests: one headless chromium with a fresh profile."""

from __future__ import annotations

import pytest


@pytest.fixture(scope="module")
def browser(tmp_path_factory):
    browser_page = pytest.importorskip("browser_page")
    with browser_page.sync_api.sync_playwright() as playwright:
        context = playwright.chromium.launch_persistent_context(
            str(tmp_path_factory.mktemp("chromium_profile")), executable_path=browser_page.CHROMIUM, headless=True,
            args=browser_page.FLAGS, viewport=browser_page.VIEWPORT)
        yield context
        context.close()
