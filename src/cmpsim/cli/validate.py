"""``cmpsim validate``: the model against measured data sets."""

from __future__ import annotations

from pathlib import Path

import click

from .group import _fail, _rich_table, main, out_console
from .inputs import config_options, load_config


@main.command(name="validate")
@click.argument("data", nargs=-1, type=click.Path(dir_okay=False))
@config_options
@click.option("--out", "out_dir", type=click.Path(file_okay=False), default="validation", show_default=True, help="Directory for parity.png, points.csv and datasets.csv.")
@click.option("--markdown", is_flag=True, help="Print the tables as Markdown instead of rich tables.")
@click.option("--recipe", "recipe_path", type=click.Path(dir_okay=False), default=None, help="Lot rows (a wafer column) are compared with `cmpsim lot RECIPE` over as many wafers as they name, with the constants of --config (as `cmpsim lot --config`).")
@click.option("--lot-control", "lot_control", type=click.Choice(["none", "ewma"]), default="none", show_default=True, help="--recipe: the lot's run-to-run control (cmpsim lot --control).")
@click.option("--lot-seed", "lot_seed", type=int, default=0, show_default=True, help="--recipe: the seed of the lot's incoming thicknesses (cmpsim lot --seed).")
@click.option("--lot-conditioning", "lot_conditioning", type=click.Choice(["none", "ex_situ", "in_situ"]), default=None, help="--recipe: how the lot was conditioned (cmpsim lot --conditioning; default the recipe's, else in_situ).")
@click.option("--lot-qualification", "lot_qualification", type=click.IntRange(min=0), default=1, show_default=True, help="--recipe: monitor wafers before the lot (cmpsim lot --qualification).")
def validate_command(data, config_path, preset, assignments, grid, out_dir, markdown, recipe_path, lot_control, lot_seed, lot_conditioning,
                     lot_qualification):
    """Compare the model with measured data; with no DATA, every data set shipped with cmpsim.

    DATA are CSV files in the format of cmpsim/data/README.md (operating conditions with
    units, the measured quantity, its uncertainty and source). For each point the model is
    solved and compared; the tables give model vs measurement, error, RMS error and, for
    shape comparisons, the leave-one-out error beside that of predicting the mean. Test
    structures (dishing, erosion, step_height) are polished by the die model with the die
    constants of a process file (--config), pad rows (pad_temperature_rise, friction_coefficient)
    by the pad's heat balance with its friction and heat removal; lot rows (a wafer column) are
    read and checked, and with --recipe compared with `cmpsim lot` of that recipe. points.csv holds the measured and model values of every point.
    """
    from ..calibration.crosscheck import compare_lots, compare_pad, compare_structures, list_lots, write_points
    from ..calibration.heldout import compare_with_preston
    from ..calibration.mixed import read_all
    from ..calibration.processfile import die_constants, pad_base
    from ..validation import validate

    comparisons = []
    try:
        cfg = load_config(config_path, assignments, preset, grid)
        meas = read_all(list(data)) if data else None
        report = validate(meas.datasets if meas is not None else None, config=cfg, progress=not markdown) if meas is None or meas.datasets else None
        loo = compare_with_preston(report) if report is not None else []
        if meas is not None and meas.structures:
            dc = die_constants(config_path) if config_path else None
            procs = sorted({r.process for r in meas.structures})
            if dc is not None and procs != [dc.process]:
                raise ValueError(f"--config {config_path}: its die constants are {dc.process}'s; the structures are {' and '.join(procs)}")
            comparisons.append(compare_structures(meas.structures, dc.constants if dc else None, cfg))
        if meas is not None and meas.pad:
            comparisons.append(compare_pad(meas.pad, pad_base(config_path, cfg)))
        if recipe_path and not (meas is not None and meas.lots):
            raise ValueError("--recipe compares lot rows (a wafer column); the data hold none")
        if meas is not None and meas.lots:
            if recipe_path:
                from .inputs import recipe_overrides

                overrides = recipe_overrides(config_path, assignments) | ({"grid": grid} if grid else {})  # as `cmpsim lot --config --set`
                from ..calibration.padlife import padlife_constants

                comparisons.append(compare_lots(meas.lots, recipe_path, overrides, lot_control, lot_seed,
                                                padlife_constants(config_path) if config_path else None, lot_conditioning, lot_qualification))
            else:
                comparisons.append(list_lots(meas.lots))
    except ValueError as exc:
        _fail(str(exc))
    out = Path(out_dir)
    try:
        out.mkdir(parents=True, exist_ok=True)
        write_points(out / "points.csv", [p.as_row() for p in report.points] if report is not None else [], comparisons)
        if report is not None:
            report.summary_csv(out / "datasets.csv")
            report.parity_plot(out / "parity.png")
    except OSError as exc:
        _fail(f"cannot write to {out}: {exc}")
    written = f"{out}/points.csv" + (", datasets.csv, parity.png" if report is not None else "")
    kind_rows = [[c.kind, str(c.n), "-" if c.rms != c.rms else f"{c.rms:.4g}", c.unit if c.rms == c.rms else "-", c.note] for c in comparisons]
    kind_header = ["kind", "points", "RMS error", "unit", "model"]
    point_header = ["dataset", "quantity", "conditions", "measured", "model", "error", "unit", "status"]

    def point_rows(c):
        return [[r["dataset"], r["quantity"], r["conditions"], f"{r['measured']:.4g}", "-" if r["model"] == "" else f"{r['model']:.4g}",
                 "-" if r["error"] == "" else f"{r['error']:+.3g}", r["unit"], r["status"]] for r in c.rows]

    loo_rows = [[s.name, str(s.n), f"{s.calibrated:.4g}", f"{s.preston:.4g}", f"{s.mean:.4g}", s.unit, ", ".join(s.inputs) or "-", "yes" if s.beats_preston else "no"] for s in loo]
    loo_header = ["series", "points", "LOO calibrated", "LOO Preston s*P*U", "LOO mean", "unit", "inputs the series calibrates", "beats Preston"]
    loo_line = f"leave one out, the film chemistry calibrated without the point beats Preston's law on {sum(s.beats_preston for s in loo)} of {len(loo)} removal series"
    if markdown:
        from ..tables import markdown_table

        if report is not None:
            click.echo(report.to_markdown(), nl=False)
        if loo:
            click.echo("\n" + markdown_table(loo_header, loo_rows) + "\n" + loo_line)
        for c in comparisons:
            click.echo("\n" + markdown_table(point_header, point_rows(c)))
        if comparisons:
            click.echo("\n" + markdown_table(kind_header, kind_rows))
        return

    console = out_console()
    if report is not None:
        console.print(_rich_table("Model vs data, per point (shape data sets: model times the fitted scale)", report.POINT_HEADER, report.point_rows()))
        console.print(_rich_table("Per data set", report.DATASET_HEADER, report.dataset_rows()))
    if loo:
        console.print(_rich_table("Leave one out: the model calibrated on the other points (film chemistry) vs Preston's law and the mean", loo_header, loo_rows))
        console.print(loo_line, highlight=False)
    for c in comparisons:
        console.print(_rich_table(f"Model vs data: {c.kind}", point_header, point_rows(c)))
    if comparisons:
        console.print(_rich_table("Per kind", kind_header, kind_rows))
    console.print((f"{report.equilibria} equilibria in {report.elapsed_s:.1f} s (grid {cfg.numerics.grid}); " if report is not None else "")
                  + f"wrote {written}", highlight=False)
