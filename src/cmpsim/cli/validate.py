"""``cmpsim validate``: the model against measured data sets."""

from __future__ import annotations

from pathlib import Path

import click

from .group import _fail, _rich_table, main
from .inputs import config_options, load_config


@main.command(name="validate")
@click.argument("data", nargs=-1, type=click.Path(dir_okay=False))
@config_options
@click.option("--out", "out_dir", type=click.Path(file_okay=False), default="validation", show_default=True, help="Directory for parity.png, points.csv and datasets.csv.")
@click.option("--markdown", is_flag=True, help="Print the tables as Markdown instead of rich tables.")
def validate_command(data, config_path, preset, assignments, grid, out_dir, markdown):
    """Compare the model with measured data; with no DATA, every data set shipped with cmpsim.

    DATA are CSV files in the format of cmpsim/data/README.md (operating conditions with
    units, the measured quantity, its uncertainty and source). For each point the model is
    solved and compared; the tables give model vs measurement, error, RMS error and, for
    shape comparisons, the leave-one-out error beside that of predicting the mean.
    """
    from ..validation import validate

    try:
        cfg = load_config(config_path, assignments, preset, grid)
        report = validate(list(data) or None, config=cfg, progress=not markdown)
    except ValueError as exc:
        _fail(str(exc))
    out = Path(out_dir)
    try:
        out.mkdir(parents=True, exist_ok=True)
        report.to_csv(out / "points.csv")
        report.summary_csv(out / "datasets.csv")
        report.parity_plot(out / "parity.png")
    except OSError as exc:
        _fail(f"cannot write to {out}: {exc}")
    if markdown:
        click.echo(report.to_markdown(), nl=False)
        return
    from rich.console import Console

    console = Console()
    console.print(_rich_table("Model vs data, per point (shape data sets: model times the fitted scale)", report.POINT_HEADER, report.point_rows()))
    console.print(_rich_table("Per data set", report.DATASET_HEADER, report.dataset_rows()))
    console.print(
        f"{report.equilibria} equilibria in {report.elapsed_s:.1f} s (grid {cfg.numerics.grid}); wrote {out}/points.csv, datasets.csv, parity.png",
        highlight=False,
    )
