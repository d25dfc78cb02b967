"""The browser the web tests share: Debian's chromium through Playwright, WebGL 2 on SwiftShader.

No browser is a failure, never a skip (the README's test command installs it)."""

from __future__ import annotations

import shutil

import pytest

CHROMIUM_ARGS = ["--use-angle=swiftshader", "--enable-unsafe-swiftshader", "--no-sandbox"]


@pytest.fixture(scope="session")
def browser():
    chromium = shutil.which("chromium")
    assert chromium, "Debian's chromium is required (apt-get install chromium); browser tests do not skip"
    from playwright.sync_api import sync_playwright  # a missing package is a failure

    with sync_playwright() as pw:
        b = pw.chromium.launch(executable_path=chromium, args=CHROMIUM_ARGS)
        yield b
        b.close()
