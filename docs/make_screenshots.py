"""Screenshots of the browser UI for docs/web.md: the solved page and a sweep.

    python docs/make_screenshots.py                # -> docs/web/solved.png, docs/web/sweep.png
    python docs/make_screenshots.py --grid coarse --out /tmp/shots

Starts ``cmpsim serve``'s application on a free port of 127.0.0.1, drives the system Chromium
with Playwright (no browser download: set CMPSIM_CHROMIUM to its path if it is not
``chromium`` on PATH), solves 3 psi, runs a 9-point load sweep and saves the two pictures.
tests/test_web_browser.py runs :func:`take_screenshots` on every test run, so the script keeps
working; the PNGs in docs/web/ are committed (the documentation build needs no browser).
"""

from __future__ import annotations

import argparse
import os
import shutil
import sys
from pathlib import Path

#: Chromium flags: no sandbox (CI runs as root), no GPU, and nothing that phones home.
CHROMIUM_ARGS = [
    "--no-sandbox",
    "--disable-gpu",
    "--disable-background-networking",
    "--disable-component-update",
    "--disable-sync",
    "--no-first-run",
]
VIEWPORT = {"width": 1400, "height": 1000}


def find_chromium() -> str | None:
    """The system Chromium: $CMPSIM_CHROMIUM, else chromium / chromium-browser on PATH."""
    env = os.environ.get("CMPSIM_CHROMIUM")
    if env:
        return env if Path(env).is_file() else None
    for name in ("chromium", "chromium-browser"):
        path = shutil.which(name)
        if path:
            return path
    return None


def launch(playwright, executable: str | None = None):
    """A headless system Chromium (never a downloaded one)."""
    executable = executable or find_chromium()
    if executable is None:
        raise RuntimeError("no Chromium found: install it (Debian: apt-get install chromium) or set CMPSIM_CHROMIUM")
    return playwright.chromium.launch(executable_path=executable, args=CHROMIUM_ARGS, headless=True)


def wait_ready(page, base_url: str) -> None:
    page.goto(base_url + "/")
    page.wait_for_selector("body[data-ready=true]", timeout=30_000)


def take_screenshots(page, base_url: str, out: Path, grid: str = "default", sweep_points: int = 9) -> list[Path]:
    """Solve 3 psi and run a load sweep (2-6 psi) on the page at ``base_url``; save two PNGs in ``out``."""
    out = Path(out)
    out.mkdir(parents=True, exist_ok=True)
    page.set_viewport_size(VIEWPORT)
    wait_ready(page, base_url)
    page.fill('#inputs [name="grid"]', grid)
    page.fill('#inputs [name="applied_pressure"]', "3 psi")
    page.click("#solve")
    page.wait_for_selector('#results td[data-key]', timeout=120_000)
    page.wait_for_selector("#map-removal_rate .main-svg", timeout=30_000)
    page.evaluate("window.scrollTo(0, 0)")
    solved = out / "solved.png"
    page.screenshot(path=str(solved))

    page.select_option("#sweep-param-1", "applied_pressure")
    page.fill("#sweep-start-1", "2")
    page.fill("#sweep-stop-1", "6")
    page.fill("#sweep-num-1", str(sweep_points))
    page.click("#run-sweep")
    page.wait_for_selector("#sweep-status[data-state=done]", timeout=300_000)
    page.wait_for_selector("#sweep-plot .main-svg", timeout=30_000)
    sweep = out / "sweep.png"
    page.locator("#sweep-panel").screenshot(path=str(sweep))
    return [solved, sweep]


def main(argv=None) -> int:
    here = Path(__file__).resolve().parent
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--out", type=Path, default=here / "web", help="folder for solved.png and sweep.png (default docs/web)")
    ap.add_argument("--grid", default="default", help="grid of the solve and the sweep (default: default)")
    args = ap.parse_args(argv)
    from playwright.sync_api import sync_playwright

    from cmpsim.web.app import create_app
    from cmpsim.web.server import start_in_background

    with start_in_background(create_app(workers=1)) as server, sync_playwright() as pw:
        browser = launch(pw)
        try:
            page = browser.new_page()
            for path in take_screenshots(page, server.url, args.out, args.grid):
                print(f"wrote {path}")
        finally:
            browser.close()
    return 0


if __name__ == "__main__":
    sys.exit(main())
