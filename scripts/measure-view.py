#!/usr/bin/env python3
"""Page size and time to first paint of `coherent view` pages in the headless browser the
tests use (Debian's chromium-headless-shell, driven by Playwright).

    .venv/bin/python scripts/measure-view.py PAGE.html [PAGE.html ...] [--runs 15]

Each page is opened from disk in a fresh browser page `--runs` times; the time to first
paint is the browser's `first-contentful-paint` entry (from the start of navigation),
and the time until the page has drawn itself whole (`body[data-drawn]`: a results
page puts its episodes' rows in a few hundred at a time after the first paint). Printed:
bytes, then the median and the spread (min-max) of each, in milliseconds.
"""

from __future__ import annotations

import argparse
import os
import statistics
from pathlib import Path

from playwright.sync_api import sync_playwright

BROWSER = os.environ.get("COHERENT_BROWSER", "/usr/lib/chromium/chromium-headless-shell")


def measure(browser, page_file: Path, runs: int) -> tuple[list[float], list[float]]:
    paints, drawn = [], []
    for _ in range(runs):
        page = browser.new_page(viewport={"width": 1500, "height": 1000})
        page.goto(page_file.resolve().as_uri(), wait_until="load")
        page.wait_for_selector("body[data-drawn]")
        # Polled from here: the page's policy forbids the browser evaluating strings.
        while not page.evaluate("performance.getEntriesByName('first-contentful-paint').length"):
            page.wait_for_timeout(20)
        paints.append(page.evaluate("performance.getEntriesByName('first-contentful-paint')[0].startTime"))
        drawn.append(page.evaluate("performance.getEntriesByName('coherent-drawn')[0].startTime"))
        page.close()
    return paints, drawn


def spread(xs: list[float]) -> str:
    return f"{statistics.median(xs):.0f} ms ({min(xs):.0f}-{max(xs):.0f})"


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("pages", nargs="+", type=Path)
    ap.add_argument("--runs", type=int, default=15)
    args = ap.parse_args()
    with sync_playwright() as p:
        browser = p.chromium.launch(executable_path=BROWSER, headless=True)
        for page_file in args.pages:
            paints, drawn = measure(browser, page_file, args.runs)
            print(
                f"{page_file}: {page_file.stat().st_size:,} bytes; first contentful paint {spread(paints)}; "
                f"drawn {spread(drawn)}; {args.runs} runs"
            )
        browser.close()


if __name__ == "__main__":
    main()
