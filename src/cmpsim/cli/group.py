"""The ``cmpsim`` command group and what every command shares: exit codes, the error and
warning lines on stderr, and the terminal tables."""

from __future__ import annotations

import contextlib
import functools
import sys
import warnings
from pathlib import Path

import click

from .._version import __version__

EXIT_INPUT = 2
EXIT_NO_EQUILIBRIUM = 3


def _fail(message: str, code: int = EXIT_INPUT):
    click.echo(f"cmpsim: error: {message}", err=True)
    sys.exit(code)


@contextlib.contextmanager
def command_errors(no_equilibrium: str = "no equilibrium"):
    """What a command does when its work fails: bad input (a ``ValueError`` naming the parameter)
    exits with status 2 and its message; a wafer equilibrium that was not found exits with status 3,
    ``<no_equilibrium>: <why>``. The commands write their files after the block, so nothing is written."""
    from ..operators.state import EquilibriumError

    try:
        yield
    except EquilibriumError as exc:
        _fail(f"{no_equilibrium}: {exc}", EXIT_NO_EQUILIBRIUM)
    except ValueError as exc:
        _fail(str(exc))
    except MemoryError:
        _fail("out of memory: the problem does not fit in this machine's memory; choose a larger --window or a smaller "
              "region (--top a sub-cell), or use a machine with more memory")


def check_out(path, option: str = "--out") -> None:
    """ValueError (exit status 2) if ``path``, an output directory or file not yet written, cannot be made:
    its nearest existing ancestor is a file, or a directory this user may not write in. Called before the
    solve, so that a run is not computed in vain and nothing is left half-written."""
    import os

    anc = Path(path).absolute()
    while not anc.exists():
        anc = anc.parent
    if not anc.is_dir():
        raise ValueError(f"{option} {path}: cannot be created, {anc} is a file, not a directory")
    if not os.access(anc, os.W_OK | os.X_OK):
        raise ValueError(f"{option} {path}: cannot write in {anc} (permission denied); choose a directory you may write in")


@contextlib.contextmanager
def writing_errors(path):
    """Exit with status 2 and ``cannot write to PATH: why`` where writing the outputs fails (a full disk, a
    directory removed under the run), not with a traceback."""
    try:
        yield
    except OSError as exc:
        _fail(f"cannot write to {path}: {exc}")


def _warn(message: str) -> None:
    """A warning of cmpsim as the command line prints every one: ``cmpsim: warning: <message>``, one line on stderr."""
    text = " ".join(str(message).split())
    click.echo(f"cmpsim: warning: {text}", err=True)


#: Columns of the tables when stdout is not a terminal (a log file, a pipe): rich's 80 would cut the headers short.
PIPE_WIDTH = 240


def out_console():
    """The console of a command's tables on stdout: the terminal's width, or :data:`PIPE_WIDTH` columns
    when stdout is a file or a pipe (unless ``COLUMNS`` says otherwise)."""
    import os

    from rich.console import Console

    piped = not sys.stdout.isatty() and "COLUMNS" not in os.environ
    return Console(width=PIPE_WIDTH if piped else None)


def _rich_table(title, header, rows):
    from rich.table import Table

    t = Table(title=title, show_lines=False)
    for i, h in enumerate(header):
        t.add_column(h, justify="right" if i == 1 else "left")
    for r in rows:
        t.add_row(*[str(c) for c in r])
    return t


_PACKAGE = Path(__file__).resolve().parents[1]  # the cmpsim package: its warnings are ours


def show_warning(message, category, filename, lineno, file=None, line=None, other=warnings.showwarning):
    """``warnings.showwarning`` of the command line: a warning raised in cmpsim's code is one
    line on stderr, ``cmpsim: warning: <message>``, without Python's file, line and source echo;
    other packages' warnings go to ``other`` (Python's format: their source says where they come from)."""
    try:
        ours = Path(filename).resolve().is_relative_to(_PACKAGE)
    except (TypeError, ValueError, OSError):
        ours = False
    if not ours:
        other(message, category, filename, lineno, file, line)
        return
    _warn(str(message))


@click.group(context_settings={"help_option_names": ["-h", "--help"]})
@click.version_option(version=__version__, prog_name="cmpsim")  # the source's version, not an install's metadata
@click.pass_context
def main(ctx):
    """cmpsim: wafer-scale CMP simulator (grain-flow lubrication + pad asperity contact)."""
    # for this command only (restored when it ends): importing cmpsim changes no warning display
    ctx.with_resource(warnings.catch_warnings())
    warnings.showwarning = functools.partial(show_warning, other=warnings.showwarning)
