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
    from ..calibration.heldout import compare_with_preston
    from ..validation import validate

    try:
        cfg = load_config(config_path, assignments, preset, grid)
        report = validate(list(data) or None, config=cfg, progress=not markdown)
        loo = compare_with_preston(report)
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
    loo_rows = [[s.name, str(s.n), f"{s.calibrated:.4g}", f"{s.preston:.4g}", f"{s.mean:.4g}", s.unit, ", ".join(s.inputs) or "-", "yes" if s.beats_preston else "no"] for s in loo]
    loo_header = ["series", "points", "LOO calibrated", "LOO Preston s*P*U", "LOO mean", "unit", "inputs the series calibrates", "beats Preston"]
    loo_line = f"leave one out, the film chemistry calibrated without the point beats Preston's law on {sum(s.beats_preston for s in loo)} of {len(loo)} removal series"
    if markdown:
        from ..tables import markdown_table

        click.echo(report.to_markdown(), nl=False)
        if loo:
            click.echo("\n" + markdown_table(loo_header, loo_rows) + "\n" + loo_line)
        return
    from rich.console import Console

    console = Console()
    console.print(_rich_table("Model vs data, per point (shape data sets: model times the fitted scale)", report.POINT_HEADER, report.point_rows()))
    console.print(_rich_table("Per data set", report.DATASET_HEADER, report.dataset_rows()))
    if loo:
        console.print(_rich_table("Leave one out: the model calibrated on the other points (film chemistry) vs Preston's law and the mean", loo_header, loo_rows))
        console.print(loo_line, highlight=False)
    console.print(
        f"{report.equilibria} equilibria in {report.elapsed_s:.1f} s (grid {cfg.numerics.grid}); wrote {out}/points.csv, datasets.csv, parity.png",
        highlight=False,
    )
