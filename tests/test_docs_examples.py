"""The documentation examples run: every docs/examples/*.py exits 0 and makes its figures.

Each example runs as a script in a subprocess, as `python docs/examples/NAME.py` would, on
the coarse grid (CMPSIM_DOCS_GRID=coarse) with its output folder in a temporary directory
(CMPSIM_DOCS_OUT). They run two at a time in a module fixture; the tests then check each
one. The documentation build (docs/gen_examples.py) runs the same scripts on the default
grid and fails on the same conditions.
"""

from __future__ import annotations

import ast
import os
import re
import subprocess
import sys
import time
from concurrent.futures import ThreadPoolExecutor
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]
EXAMPLES = ROOT / "docs" / "examples"
SCRIPTS = sorted(p for p in EXAMPLES.glob("*.py") if not p.name.startswith("_"))
FIGURE_LINK = re.compile(r"!\[[^\]]*\]\(([^)\s]+\.png)\)")
TIMEOUT_S = 300


def _shown_figures(script: Path) -> set[str]:
    doc = ast.get_docstring(ast.parse(script.read_text(encoding="utf-8"))) or ""
    return set(FIGURE_LINK.findall(doc))


def _run(script: Path, out: Path) -> dict:
    env = dict(os.environ, CMPSIM_DOCS_GRID="coarse", CMPSIM_DOCS_OUT=str(out), MPLBACKEND="Agg")
    t0 = time.perf_counter()
    proc = subprocess.run([sys.executable, str(script)], cwd=ROOT, env=env, capture_output=True, text=True, timeout=TIMEOUT_S)
    return {"proc": proc, "out": out, "elapsed": time.perf_counter() - t0}


@pytest.fixture(scope="module")
def runs(tmp_path_factory):
    base = tmp_path_factory.mktemp("docs-examples")
    jobs = max(1, min(2, os.cpu_count() or 1))
    with ThreadPoolExecutor(max_workers=jobs) as pool:
        # longest first (roughly: the biggest scripts), so the two lanes finish together
        order = sorted(SCRIPTS, key=lambda s: -s.stat().st_size)
        futures = {s.stem: pool.submit(_run, s, base / s.stem) for s in order}
        return {name: f.result() for name, f in futures.items()}


def test_there_are_examples():
    assert len(SCRIPTS) >= 5


@pytest.mark.slow  # the module fixture runs every example (tens of seconds)
@pytest.mark.parametrize("script", SCRIPTS, ids=[s.stem for s in SCRIPTS])
def test_example_runs_and_makes_its_figures(script, runs):
    run = runs[script.stem]
    proc = run["proc"]
    assert proc.returncode == 0, f"{script.name} failed:\n{proc.stderr[-3000:]}"
    made = {p.name for p in run["out"].glob("*.png")}
    assert made, f"{script.name} made no PNG in CMPSIM_DOCS_OUT"
    missing = _shown_figures(script) - made
    assert not missing, f"{script.name} shows figures it did not make: {sorted(missing)}"
    for png in run["out"].glob("*.png"):
        assert png.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n" and png.stat().st_size > 1000


@pytest.mark.parametrize("script", SCRIPTS, ids=[s.stem for s in SCRIPTS])
def test_example_has_a_page_in_the_site(script):
    """Every example is in mkdocs.yml (its generated page in the nav, or deliberately not)."""
    config = (ROOT / "mkdocs.yml").read_text(encoding="utf-8")
    assert f"examples/{script.stem}.md" in config, f"add examples/{script.stem}.md to the nav of mkdocs.yml"
    doc = ast.get_docstring(ast.parse(script.read_text(encoding="utf-8"))) or ""
    assert doc.lstrip().startswith("# "), f"{script.name}: the docstring (the page's prose) must start with a '# Title'"


def test_api_page_documents_every_module():
    """docs/api.md has a `::: cmpsim.NAME` block for every module and package of the API (every module of
    the floor folders too), and no other.

    The command line and the web face have pages of their own (docs/cli.md, the web page).
    """
    api = (ROOT / "docs" / "api.md").read_text(encoding="utf-8")
    blocks = set(re.findall(r"^::: (cmpsim(?:\.\w+)*)\s*$", api, flags=re.M))
    src = ROOT / "src" / "cmpsim"
    existing = {f"cmpsim.{p.stem}" for p in src.glob("*.py") if not p.stem.startswith("_")}
    existing |= {f"cmpsim.{p.parent.name}" for p in src.glob("*/__init__.py")}
    existing |= {f"cmpsim.{p.parent.name}.{p.stem}" for p in src.glob("*/*.py") if not p.stem.startswith("_")}
    floors = ("physics", "numerics", "operators", "inputs", "results", "solver", "head")  # folders of modules: each module its own block
    modules = {m for m in existing if m.count(".") == 1 or m.split(".")[1] in floors} - {"cmpsim.cli", "cmpsim.web"}
    assert modules - blocks == set(), f"add to docs/api.md: {sorted(modules - blocks)}"
    stale = {b for b in blocks if b != "cmpsim" and b not in existing}
    assert not stale, f"docs/api.md documents modules that do not exist: {sorted(stale)}"
