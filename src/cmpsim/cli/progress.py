"""The progress bar of a long layout extraction (rich, on stderr): ``with extraction_bar() as told: ...``.

The layout floor reports (stage, done, total) through a plain callable; this face draws it.
Nothing is drawn for extractions that end within half a second, nor when stderr is not a terminal
(rich prints nothing then), so ``--json`` output and logs stay clean.
"""

from __future__ import annotations

import contextlib
import time


@contextlib.contextmanager
def extraction_bar(enabled: bool = True):
    """A callable ``told(stage, done, total)`` that drives one rich progress bar per stage."""
    if not enabled:
        yield None
        return
    from rich.console import Console
    from rich.progress import BarColumn, Progress, TextColumn, TimeElapsedColumn

    console = Console(stderr=True)
    bar = Progress(TextColumn("layout: {task.description}"), BarColumn(), TextColumn("{task.completed}/{task.total}"),
                   TimeElapsedColumn(), console=console, transient=True, disable=not console.is_terminal)
    tasks: dict[str, int] = {}
    start = time.perf_counter()
    shown = False

    def told(stage: str, done: int, total: int) -> None:
        nonlocal shown
        if not shown and time.perf_counter() - start > 0.5:
            bar.start()
            shown = True
        if stage not in tasks:
            tasks[stage] = bar.add_task(stage, total=total)
        bar.update(tasks[stage], completed=done, total=total)

    try:
        yield told
    finally:
        if shown:
            bar.stop()
