"""``cmpsim reproduce``: the paper's figures, their CSVs and the trend-table report."""

from __future__ import annotations

import click

from .group import _fail, _rich_table, main, out_console
from .inputs import config_options, load_config


@main.command(name="reproduce", short_help="Regenerate the paper's Figs. 3-12, their CSVs and a trend-table report.")
@click.option("--out", "out_dir", type=click.Path(file_okay=False), default="reproduction", show_default=True, help="Directory for the ten PNG + CSV figures, trends.csv, REPORT.md and REPORT.html.")
@config_options
def reproduce_command(out_dir, config_path, preset, assignments, grid):
    """Regenerate the paper's Figs. 3-12, their CSVs and a report with the trend table.

    Solves every equilibrium behind the figures (load 2-6 psi, speed 30-90 rpm; the paper's
    curves), writes figNN_*.png and figNN_*.csv, and checks each qualitative statement the
    paper makes about them against the data of the run (REPORT.md / REPORT.html, trends.csv).
    The inputs set the parameters the figures do not vary.
    """
    from ..reproduction import reproduce

    try:
        cfg = load_config(config_path, assignments, preset or "paper", grid)  # the paper's figures: the paper's model by default
    except ValueError as exc:
        _fail(str(exc))
    command = " ".join(
        ["cmpsim reproduce"]
        + ([f"--out {out_dir}"] if out_dir != "reproduction" else [])
        + ([f"--preset {preset}"] if preset else [])
        + ([f"--config {config_path}"] if config_path else [])
        + [f"--set {a}" for a in assignments]
        + ([f"--grid {grid}"] if grid else [])
    )
    try:
        rep = reproduce(out=out_dir, progress=True, config=cfg, command=command)
    except (ValueError, OSError) as exc:
        _fail(str(exc))

    console = out_console()
    rows = [[s.id, s.figure, s.text, "[green]yes[/green]" if s.reproduced else "[red]no[/red]"] for s in rep.statements]
    console.print(_rich_table(f"Statements of the paper reproduced: {rep.n_reproduced} of {len(rep.statements)}", ["#", "Fig.", "statement", "reproduced"], rows))
    console.print(
        f"{rep.equilibria} equilibria ({rep.factorizations} factorisations) in {rep.solve_s:.1f} s; total {rep.elapsed_s:.1f} s. "
        f"Wrote {len(rep.figures)} figures (PNG + CSV), {rep.report_md} and {rep.report_html}.",
        highlight=False,
    )
    if rep.failures:
        console.print(f"[yellow]{len(rep.failures)} operating point(s) without equilibrium: see the report[/yellow]")
