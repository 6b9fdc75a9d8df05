"""Tables: terminal tables that stay legible at 80 columns, and the plain-text and Markdown
tables of the study reports.

The first column of a terminal table (names a user types) keeps its full width; on a narrow
terminal the long free text (meaning, source) is stacked under the name instead of being
squeezed into a column of its own, and the other long cells wrap.
"""

from __future__ import annotations

from typing import Any, Iterable, Sequence

__all__ = ["legible_table", "render_text", "WIDE", "text_table", "markdown_table"]

#: Terminal width from which the long text gets a column of its own.
WIDE = 110
#: Widest column after the first (longer cells wrap).
MAX_CELL = 28


def legible_table(title: str, header: list[str], rows: list[tuple], detail: list[str] | None = None, detail_header: str = "", width: int = 80, sections: tuple[int, ...] = (), plain: bool = False):
    """A ``rich`` Table of ``rows``; ``detail[i]`` is the long text of row i.

    The first column is never wrapped or cut (its minimum width is its longest cell). With
    ``width >= WIDE`` the detail is the last column; otherwise it is stacked, dimmed, under
    the first cell. ``sections`` are row indices after which a rule is drawn. ``plain``: no box
    lines (columns separated by spaces), for text that is printed or logged.
    """
    from rich import box
    from rich.table import Table
    from rich.text import Text

    names = [str(r[0]) for r in rows]
    name_width = max([len(header[0]), *map(len, names)])
    stacked = detail is not None and width < WIDE
    t = Table(title=title, show_lines=False, width=None, expand=False, title_justify="left", box=None if plain else box.HEAVY_HEAD, pad_edge=not plain)
    t.add_column(header[0] if not stacked else f"{header[0]} / {detail_header}", min_width=name_width, overflow="fold")
    for i, h in enumerate(header[1:], start=1):
        t.add_column(h, justify="right" if i == 1 and len(header) > 2 else "left", overflow="fold", max_width=MAX_CELL)
    if detail is not None and not stacked:
        t.add_column(detail_header, overflow="fold", ratio=1)
    for k, r in enumerate(rows):
        first = Text(names[k], style="bold")
        cells = [str(c) for c in r[1:]]
        if stacked and detail[k]:
            first.append("\n" + detail[k], style="dim")
        row = [first, *cells]
        if detail is not None and not stacked:
            row.append(detail[k])
        t.add_row(*row, end_section=k in sections)
    return t


def render_text(table, width: int = 80) -> str:
    """A rich renderable as plain text at ``width`` columns."""
    import io

    from rich.console import Console

    buf = io.StringIO()
    Console(file=buf, width=width, color_system=None, force_terminal=False, highlight=False).print(table)
    return "\n".join(line.rstrip() for line in buf.getvalue().rstrip("\n").splitlines())


def text_table(header: Sequence[str], rows: Iterable[Sequence[Any]]) -> str:
    """A plain-text table: left-aligned columns under a header line."""
    rows = [list(map(str, r)) for r in rows]
    widths = [max([len(h)] + [len(r[i]) for r in rows]) for i, h in enumerate(header)]
    line = "  ".join(h.ljust(w) for h, w in zip(header, widths))
    out = [line, "-" * len(line)]
    out += ["  ".join(c.ljust(w) for c, w in zip(r, widths)) for r in rows]
    return "\n".join(out)


def markdown_table(header: Sequence[str], rows: Iterable[Sequence[Any]]) -> str:
    """A Markdown table (cells escaped: ``|`` as ``\\|``, newlines as spaces), ending with a newline."""

    def cell(text) -> str:
        return str(text).replace("|", "\\|").replace("\n", " ")

    lines = ["| " + " | ".join(map(cell, header)) + " |", "|" + "---|" * len(header)]
    lines += ["| " + " | ".join(map(cell, r)) + " |" for r in rows]
    return "\n".join(lines) + "\n"
