"""Our HTML reports opened as a person opens them: Debian's Chromium (``/usr/bin/chromium``,
installed by the README's test command), headless, driven through the DevTools protocol by
playwright's Python client (no browser of playwright's own), with a new empty profile.
Console errors and page errors are collected; the page is ready when the report's script
has drawn every figure of its open sections (``<body data-drawn>``)."""

from __future__ import annotations

import contextlib
import tempfile
from pathlib import Path

CHROMIUM = "/usr/bin/chromium"
#: the launch flags (playwright adds --headless and --user-data-dir=<the new profile>)
FLAGS = [
    "--no-sandbox",
    "--disable-gpu",
    "--disable-quic",
    "--no-first-run",
    "--disable-background-networking",
    "--disable-component-update",
    "--disable-sync",
]


@contextlib.contextmanager
def opened(path, width: int = 1300, height: int = 1000, timeout: float = 120.0):
    """(page, problems) of the report at ``path`` once drawn; ``problems``: every console
    error and page error, as they come."""
    from playwright.sync_api import sync_playwright

    if not Path(CHROMIUM).exists():
        raise FileNotFoundError(
            f"{CHROMIUM} is missing: the README's test command installs Debian's chromium"
        )
    problems: list[str] = []
    with sync_playwright() as p, tempfile.TemporaryDirectory() as profile:
        context = p.chromium.launch_persistent_context(
            profile,
            executable_path=CHROMIUM,
            headless=True,
            args=FLAGS,
            viewport={"width": width, "height": height},
        )
        try:
            page = context.new_page()
            page.on("console", lambda m: problems.append(m.text) if m.type == "error" else None)
            page.on("pageerror", lambda e: problems.append(f"page error: {e}"))
            page.goto(Path(path).resolve().as_uri())
            page.wait_for_selector("body[data-drawn]", timeout=timeout * 1e3)
            yield page, problems
        finally:
            context.close()


def open_section(page, timeout: float = 120.0) -> None:
    """Open the closed section with the fewest outputs (its summary says how many) and
    wait until its figures are drawn (or failed)."""
    index = page.evaluate(
        """(() => { const sizes = Array.from(document.querySelectorAll('details summary'))
             .map((s) => parseInt((s.textContent.match(/\\((\\d+) outputs?\\)/) || [0, 1e9])[1]));
           return sizes.indexOf(Math.min(...sizes)); })()"""
    )
    page.evaluate(f"document.querySelectorAll('details')[{index}].open = true")
    page.wait_for_function(
        f"Array.from(document.querySelectorAll('details')[{index}].querySelectorAll('div.figure'))"
        ".every((d) => d.dataset.state === 'drawn' || d.dataset.state === 'failed')",
        timeout=timeout * 1e3,
    )
