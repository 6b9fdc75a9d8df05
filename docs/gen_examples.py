"""Build-time generator of the example pages (run by the mkdocs-gen-files plugin).

For every ``docs/examples/NAME.py`` (names starting with ``_`` are skipped) this script

1. runs ``python docs/examples/NAME.py`` in a subprocess, with ``CMPSIM_DOCS_GRID`` (default
   ``"default"``) and ``CMPSIM_DOCS_OUT`` set to a fresh temporary folder;
2. fails the build if the example exits non-zero, or produces no PNG, or its docstring shows a
   figure it did not produce;
3. writes the page ``examples/NAME.md``: the example's docstring (Markdown prose, with the
   figures it shows), then its code, what it printed, any figures not already shown, and a note
   saying which grid and cmpsim version produced them. The figures are copied to
   ``examples/NAME/*.png``.

So every figure on the site comes from running the code shown next to it. Set
``CMPSIM_DOCS_GRID=coarse`` for a quick draft build (the pages then say so).

Under ``mkdocs serve`` only, the output of an example is reused across rebuilds while nothing
it depends on has changed (key: the example's source, every file of ``src/cmpsim``, the grid
and the Python version), so editing prose does not rerun every example. ``mkdocs build``
always runs them all.
"""

from __future__ import annotations

import ast
import hashlib
import os
import shutil
import re
import subprocess
import sys
import tempfile
import time
from concurrent.futures import ThreadPoolExecutor
from pathlib import Path

import mkdocs_gen_files

DOCS = Path(__file__).resolve().parent if "__file__" in globals() else Path("docs").resolve()
ROOT = DOCS.parent
EXAMPLES = DOCS / "examples"
GRID = os.environ.get("CMPSIM_DOCS_GRID", "default")
JOBS = int(os.environ.get("CMPSIM_DOCS_JOBS", "2"))
TIMEOUT_S = float(os.environ.get("CMPSIM_DOCS_TIMEOUT", "900"))
SERVING = sys.argv[1:2] == ["serve"]  # this script runs inside the mkdocs process
CACHE = Path(tempfile.gettempdir()) / "cmpsim-docs-examples"
SNIPPET_MARKER = re.compile(r"^\s*# --8<-- \[(?:start|end):[\w-]+\]\s*$")  # sections for pymdownx.snippets
FIGURE_LINK = re.compile(r"!\[([^\]]*)\]\(([^)\s]+\.png)\)")


class ExampleError(RuntimeError):
    """An example failed: the documentation build stops."""


def _split(source: str) -> tuple[str, str]:
    """(module docstring, code after it) of an example script."""
    tree = ast.parse(source)
    doc = ast.get_docstring(tree, clean=True) or ""
    if doc and tree.body and isinstance(tree.body[0], ast.Expr):
        end = tree.body[0].end_lineno
        code = "\n".join(source.splitlines()[end:]).strip("\n")
    else:
        code = source.strip("\n")
    code = "\n".join(line for line in code.splitlines() if not SNIPPET_MARKER.match(line)).strip("\n")
    return doc, code


def _cache_key(script: Path) -> str:
    h = hashlib.sha256()
    h.update(f"{GRID}\0{sys.version}\0".encode())
    for path in [script, *sorted((ROOT / "src" / "cmpsim").rglob("*"))]:
        if path.is_file() and "__pycache__" not in path.parts:
            h.update(str(path.relative_to(ROOT)).encode() + b"\0" + path.read_bytes() + b"\0")
    return h.hexdigest()[:32]


def _run_cached(script: Path, out: Path) -> tuple[str, float]:
    """:func:`_run`, reusing a previous run with the same inputs when serving."""
    if not SERVING:
        return _run(script, out)
    entry = CACHE / f"{script.stem}-{_cache_key(script)}"
    if (entry / "stdout.txt").exists():
        shutil.copytree(entry / "out", out, dirs_exist_ok=True)
        return (entry / "stdout.txt").read_text(encoding="utf-8"), float((entry / "elapsed.txt").read_text())
    stdout, elapsed = _run(script, out)
    CACHE.mkdir(parents=True, exist_ok=True)
    tmp = Path(tempfile.mkdtemp(prefix=f"{script.stem}-", dir=CACHE))
    shutil.copytree(out, tmp / "out")
    (tmp / "elapsed.txt").write_text(f"{elapsed}")
    (tmp / "stdout.txt").write_text(stdout, encoding="utf-8")
    try:
        tmp.rename(entry)
    except OSError:  # another build stored it first
        shutil.rmtree(tmp, ignore_errors=True)
    return stdout, elapsed


def _run(script: Path, out: Path) -> tuple[str, float]:
    env = dict(os.environ)
    env.update(CMPSIM_DOCS_GRID=GRID, CMPSIM_DOCS_OUT=str(out), MPLBACKEND="Agg", PYTHONHASHSEED="0")
    t0 = time.perf_counter()
    try:
        proc = subprocess.run(
            [sys.executable, str(script)], cwd=ROOT, env=env, capture_output=True, text=True, timeout=TIMEOUT_S
        )
    except subprocess.TimeoutExpired as exc:
        raise ExampleError(f"docs example {script.name} did not finish in {TIMEOUT_S:g} s") from exc
    elapsed = time.perf_counter() - t0
    if proc.returncode != 0:
        raise ExampleError(
            f"docs example {script.relative_to(ROOT)} failed (exit {proc.returncode}, grid {GRID!r}):\n"
            f"{proc.stderr[-4000:]}"
        )
    if proc.stderr.strip():  # warnings of a successful run: shown in the build log, not on the page
        tail = "\n".join("    " + line for line in proc.stderr.rstrip().splitlines()[-20:])
        print(f"gen_examples: {script.name} wrote to stderr:\n{tail}", file=sys.stderr)
    return proc.stdout, elapsed


def _fence(text: str, lang: str) -> str:
    ticks = "```"
    while ticks in text:
        ticks += "`"
    return f"{ticks}{lang}\n{text.rstrip()}\n{ticks}\n"


def _page(script: Path, out: Path, stdout: str, elapsed: float) -> str:
    import cmpsim

    name = script.stem
    doc, code = _split(script.read_text(encoding="utf-8"))
    figures = sorted(p.name for p in out.glob("*.png"))
    if not figures:
        raise ExampleError(f"docs example {script.name} produced no PNG figure in CMPSIM_DOCS_OUT")
    shown: set[str] = set()

    def link(m: re.Match) -> str:
        fig = m.group(2)
        if fig not in figures:
            raise ExampleError(f"docs example {script.name}: its docstring shows {fig!r}, which it did not produce")
        shown.add(fig)
        return f"![{m.group(1)}]({name}/{fig})"

    prose = FIGURE_LINK.sub(link, doc)
    if not prose.lstrip().startswith("# "):
        prose = f"# {name.replace('_', ' ').capitalize()}\n\n" + prose
    parts = [prose.rstrip() + "\n"]
    parts.append(f"## The script\n\n[`docs/examples/{name}.py`]({name}.py) (run it with `python docs/examples/{name}.py`):\n")
    parts.append(_fence(code, "python"))
    if stdout.strip():
        lines = stdout.rstrip().splitlines()
        if len(lines) > 200:
            lines = lines[:200] + [f"... ({len(lines) - 200} more lines)"]
        parts.append("## What it prints\n\n" + _fence("\n".join(lines), "text"))
    rest = [f for f in figures if f not in shown]
    if rest:
        parts.append("## Figures\n")
        for fig in rest:
            parts.append(f"![{fig}]({name}/{fig})\n")
    shape = _grid_text(GRID)
    parts.append(
        f'!!! info "How this page was made"\n'
        f"    Generated by `docs/gen_examples.py` at build time: the script above was run with "
        f"`CMPSIM_DOCS_GRID={GRID}` (grid {shape}) on cmpsim {cmpsim.__version__} and took {elapsed:.1f} s; "
        f"every figure and printed value on this page is its output.\n"
    )
    return "\n".join(parts)


def _grid_text(grid: str) -> str:
    try:
        from cmpsim.inputs.config import GRID_PRESETS

        if grid in GRID_PRESETS:
            nr, nt = GRID_PRESETS[grid]
            return f"`{grid}`, {nr} rings x {nt} sectors"
    except Exception:  # pragma: no cover - cmpsim import problems surface in the examples
        pass
    return f"`{grid}`"


def main() -> None:
    scripts = sorted(p for p in EXAMPLES.glob("*.py") if not p.name.startswith("_"))
    if not scripts:
        raise ExampleError(f"no examples found in {EXAMPLES}")
    with tempfile.TemporaryDirectory(prefix="cmpsim-docs-") as tmp:
        outs = {s: Path(tmp) / s.stem for s in scripts}
        for o in outs.values():
            o.mkdir()
        with ThreadPoolExecutor(max_workers=max(1, JOBS)) as pool:
            runs = {s: pool.submit(_run_cached, s, outs[s]) for s in scripts}
            done = {s: f.result() for s, f in runs.items()}  # the first failure raises here
        for script in scripts:
            stdout, elapsed = done[script]
            name = script.stem
            out = outs[script]
            page = _page(script, out, stdout, elapsed)
            with mkdocs_gen_files.open(f"examples/{name}.md", "w") as fh:
                fh.write(page)
            mkdocs_gen_files.set_edit_path(f"examples/{name}.md", f"examples/{name}.py")
            for png in sorted(out.glob("*.png")):
                with mkdocs_gen_files.open(f"examples/{name}/{png.name}", "wb") as fh:
                    fh.write(png.read_bytes())
            print(f"gen_examples: {name}: {elapsed:.1f} s, grid {GRID}", file=sys.stderr)


main()
