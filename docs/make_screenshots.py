"""Screenshots of the browser UI for docs/web.md: the solved page, a sweep and the die view.

    python docs/make_screenshots.py                # -> docs/web/solved.png, sweep.png, die.png
    python docs/make_screenshots.py --grid coarse --out /tmp/shots

Starts ``cmpsim serve``'s application on a free port of 127.0.0.1, drives the system Chromium
with Playwright (no browser download: set CMPSIM_CHROMIUM to its path if it is not
``chromium`` on PATH), solves 3 psi, runs a 9-point load sweep, polishes a small copper die
built here with gdstk (:func:`demo_layout`) and saves the three pictures.
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


def demo_layout(path: Path) -> Path:
    """A 400 um copper test chip (layer 1/0): 200 um blocks of 8 um lines at 10 um pitch (80 %)
    and of 2 um lines (20 %) in a checkerboard, with a 2 um line array rotated in one corner."""
    import gdstk

    lib = gdstk.Library(unit=1e-6, precision=1e-9)

    def lines(name, width, vertical=True):
        cell = gdstk.Cell(name)
        for i in range(20):
            a, b = (i * 10.0, 0.0), (i * 10.0 + width, 200.0)
            cell.add(gdstk.rectangle(a, b, layer=1) if vertical else gdstk.rectangle(a[::-1], b[::-1], layer=1))
        return cell

    dense, sparse, across = lines("DENSE", 8.0), lines("SPARSE", 2.0), lines("ACROSS", 4.0, vertical=False)
    top = gdstk.Cell("DEMO")
    top.add(gdstk.Reference(dense, (0, 0)), gdstk.Reference(sparse, (200, 0)), gdstk.Reference(across, (0, 200)),
            gdstk.Reference(dense, (200, 200)))
    lib.add(dense, sparse, across, top)
    lib.write_gds(str(path))
    return Path(path)


def take_die_screenshot(page, base_url: str, layout: Path, out: Path, grid: str = "default") -> Path:
    """Upload ``layout`` in the die view (layer 1/0, copper, limits thickness 40 nm and dishing 95 nm), run it, save die.png."""
    out = Path(out)
    out.mkdir(parents=True, exist_ok=True)
    page.set_viewport_size(VIEWPORT)
    wait_ready(page, base_url)
    page.fill('#inputs [name="grid"]', grid)
    page.set_input_files("#die-file", str(layout))
    page.select_option("#die-pdk", "sky130")  # shows the PDK's named layers; the chip's layer is given as L/D
    page.fill("#die-layers", "1/0")
    page.select_option("#die-process", "copper")
    page.fill("#die-spec-thickness", "40")
    page.fill("#die-spec-dishing", "95")
    page.click("#run-die")
    page.wait_for_selector("#die-hotspots .main-svg", timeout=120_000)
    shot = out / "die.png"
    page.locator("#die-panel").screenshot(path=str(shot))
    return shot


def main(argv=None) -> int:
    here = Path(__file__).resolve().parent
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--out", type=Path, default=here / "web", help="folder for solved.png, sweep.png and die.png (default docs/web)")
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
            import tempfile

            with tempfile.TemporaryDirectory() as tmp:
                print(f"wrote {take_die_screenshot(page, server.url, demo_layout(Path(tmp) / 'demo.gds'), args.out, args.grid)}")
        finally:
            browser.close()
    return 0


if __name__ == "__main__":
    sys.exit(main())
