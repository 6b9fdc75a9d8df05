"""Reproduce the paper's parameter studies (Figs. 3-12) on the wafer solver: ``cmpsim reproduce``.

For every figure of section 3 of the paper this module solves the equilibria behind it
(warm-started along each curve, identical operating points solved once and shared between
figures), writes the figure as a PNG and the data behind it as a CSV, and evaluates every
qualitative statement the paper makes about the figures against the data of the run. The
verdicts (``reproduced`` = yes / no) are computed by the functions of :data:`STATEMENTS`,
never written by hand; ``REPORT.md`` and ``REPORT.html`` (figures inline) collect them with
the parameter set used.

Curves (the paper's section 3): load 2-6 psi at 60 rpm, speed 30-90 rpm at 4 psi, every
other input from :meth:`Config.default` (or the ``config`` given):

* Figs. 3-4: d = 100 nm; hydrodynamic only with sigma = 20 and 10 um; LEP with sigma = 15 um.
* Figs. 5-6: LEP, sigma = 15 um, d = 100 and 200 nm (film thickness and attack angle).
* Figs. 7-12: LEP, cases (a) d = 100 nm, sigma = 15 um; (b) 100 nm, 20 um; (c) 200 nm, 20 um.

Rooms: ``paper`` (the curves and figures of the paper and the
equilibria behind them), ``checks`` (the paper's statements and
their checks), ``report`` (figures, CSVs, REPORT.md/.html);
:func:`reproduce` runs the three in order.
"""

from __future__ import annotations

import time
from pathlib import Path

from .._version import __version__
from ..inputs.config import Config
from .checks import SIMILAR, SLIGHT, STATEMENTS, Statement, StatementResult, evaluate_statements
from .paper import BASE_LOAD_PSI, BASE_SPEED_RPM, CURVES, FIGURES, LOADS_PSI, SPEEDS_RPM, Curve, FigureSpec, Point, RunData, _solve_all
from .report import CSV_COLUMNS, FigureResult, ReproductionReport, _blocks, _csv_rows, _notes, FigureWriter, _render_html, _render_md, _write_csv, _write_csv_trends

__all__ = [
    "reproduce",
    "ReproductionReport",
    "StatementResult",
    "Statement",
    "STATEMENTS",
    "FIGURES",
    "CURVES",
    "LOADS_PSI",
    "SPEEDS_RPM",
    "SLIGHT",
    "SIMILAR",
]


def reproduce(out=None, grid: str | None = None, progress: bool = True, config: Config | None = None, command: str | None = None) -> ReproductionReport:
    """Regenerate Figs. 3-12 of the paper, their CSVs, the trend table and REPORT.md/.html.

    Parameters
    ----------
    out : path, optional
        Output directory (created; default ``./reproduction``).
    grid : {"coarse", "default", "fine"} or "NRxNT", optional
        Grid of every solve; default: the configuration's (``"default"``).
    progress : bool
        Show a rich progress bar.
    config : Config, optional
        Inputs the figures do not vary (default :meth:`Config.paper`, the paper's model).
    command : str, optional
        Command line recorded in the report.

    Returns
    -------
    ReproductionReport
    """
    from ..io import atomic_write_text

    t0 = time.perf_counter()
    out = Path(out if out is not None else "reproduction")
    out.mkdir(parents=True, exist_ok=True)
    base = config or Config.paper()
    if grid is not None:
        base = base.replace(grid=grid)
    # figures are drawn (on a second core, if there is one) as soon as their curves are solved
    writer = FigureWriter()
    sent: set[str] = set()

    def curve_done(data, _curve) -> None:
        for spec in FIGURES:
            if spec.name not in sent and all((c, spec.sweep) in data.curves for c in spec.curves):
                writer.submit(spec, data, out / f"{spec.name}.png")
                sent.add(spec.name)

    try:
        data, n_eq, n_fact, failures, solve_s = _solve_all(base, progress, on_curve=curve_done)
        figures = []
        for spec in FIGURES:
            rows = _csv_rows(spec, data)
            csv_path = out / f"{spec.name}.csv"
            png_path = out / f"{spec.name}.png"
            header = [
                f"cmpsim {__version__} reproduction of Fig. {spec.number} of the paper: {spec.title}",
                f"grid {base.numerics.grid}; other inputs: see REPORT.md (parameter set); SI unless the column name says otherwise",
            ]
            _write_csv(csv_path, rows, header)
            if spec.name not in sent:  # (every figure's curves are solved by now: none is left)
                writer.submit(spec, data, png_path)
            figures.append(FigureResult(spec, png_path, csv_path, rows))
        writer.finish()
    finally:
        writer.close()
    statements = evaluate_statements(data)
    rep = ReproductionReport(
        out=out,
        grid=base.numerics.grid,
        config=base,
        data=data,
        figures=figures,
        statements=statements,
        equilibria=n_eq,
        factorizations=n_fact,
        failures=failures,
        elapsed_s=0.0,
        solve_s=solve_s,
        report_md=out / "REPORT.md",
        report_html=out / "REPORT.html",
        notes=_notes(data, failures),
    )
    rep.elapsed_s = time.perf_counter() - t0
    command = command or f"cmpsim reproduce --out {out} --grid {base.numerics.grid}"
    blocks = _blocks(rep, command)
    atomic_write_text(rep.report_md, _render_md(blocks, out))
    atomic_write_text(rep.report_html, _render_html(blocks, out))
    _write_csv_trends(out / "trends.csv", statements)
    return rep
