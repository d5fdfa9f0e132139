"""A real browser for the tests of `coherent view`: Debian's chromium-headless-shell
driven by Playwright (from PyPI, without its own browser download), and a page that
records every request it makes and every error its console shows."""

from __future__ import annotations

import os
from collections.abc import Iterator
from contextlib import contextmanager
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import pytest

BROWSER = Path(os.environ.get("COHERENT_BROWSER", "/usr/lib/chromium/chromium-headless-shell"))


@contextmanager
def chromium() -> Iterator[Any]:
    """The browser, or a skip that says how to install it (`make browser`, as root)."""
    if not BROWSER.is_file():
        pytest.skip(
            f"{BROWSER} is not installed: `make browser` as root installs Debian's chromium-headless-shell "
            "(apt-get install --no-install-recommends chromium-headless-shell)"
        )
    try:
        from playwright.sync_api import sync_playwright
    except ImportError:
        pytest.fail("playwright is not installed: `make venv` installs it")
    with sync_playwright() as p:
        browser = p.chromium.launch(executable_path=str(BROWSER), headless=True)
        try:
            yield browser
        finally:
            browser.close()


@dataclass
class Watched:
    """A page and what it did: the URLs it requested, console errors, uncaught errors."""

    page: Any
    requests: list[str] = field(default_factory=list)
    errors: list[str] = field(default_factory=list)

    def open(self, url: str) -> None:
        self.page.goto(url)
        self.page.wait_for_selector("body[data-drawn]")

    def assert_quiet(self, *allowed_prefixes: str) -> None:
        """No console error, no uncaught error, and no request but the page's own files
        (or URLs under `allowed_prefixes`)."""
        assert self.errors == []
        strays = [u for u in self.requests if not u.startswith(("file://", *allowed_prefixes))]
        assert strays == []


def watch(browser: Any, width: int = 1500, height: int = 1000) -> Watched:
    """A new page that records its requests and errors; a request to anywhere but a file
    or loopback is refused, so none can leave even by mistake."""
    page = browser.new_page(viewport={"width": width, "height": height})
    w = Watched(page)
    page.on("request", lambda r: w.requests.append(r.url))
    page.on("console", lambda m: w.errors.append(m.text) if m.type == "error" else None)
    page.on("pageerror", lambda e: w.errors.append(str(e)))

    def only_here(route: Any) -> None:
        url = route.request.url
        if url.startswith(("file://", "http://127.0.0.1:", "http://localhost:", "data:", "about:")):
            route.continue_()
        else:
            route.abort()

    page.route("**/*", only_here)
    return w
