"""``cmpsim lot RECIPE.toml --wafers N``: a lot of wafers on one pad, with run-to-run control (issue 32)."""

from __future__ import annotations

import click

from .group import _rich_table, command_errors, main
from .inputs import recipe_overrides


@main.command(name="lot")
@click.argument("recipe", type=click.Path(dir_okay=False))
@click.option("--wafers", type=click.IntRange(min=1), default=25, show_default=True, help="Number of wafers polished in sequence on one pad.")
@click.option("--conditioning", type=click.Choice(["none", "ex_situ", "in_situ"]), default=None, help="The diamond disk: never, between wafers, or while polishing. Default: the recipe's conditioning, else in_situ.")
@click.option("--control", type=click.Choice(["none", "ewma"]), default="none", show_default=True, help="Run-to-run control: the EWMA controller sets each wafer's polish time (feed-forward) and zone pressures (feedback).")
@click.option("--seed", type=int, default=None, help="Seed of the incoming thickness draw (2 % spread of the mean, 1 % tilt, 1 sigma): the same seed, the same lot.")
@click.option("--idle-time", "idle_time", default="30 s", show_default=True, metavar="TIME", help="Time between two wafers (the pad cools; ex-situ conditioning works then).")
@click.option("--qualification", type=click.IntRange(min=0), default=1, show_default=True, help="Monitor wafers polished with the recipe as written on the pad before the lot: the last one's measured rate seeds the EWMA and the lot starts on the pad they leave (0: a fresh pad, the EWMA seeded by the model).")
@click.option("--worn-summits", "worn_summits", is_flag=True, help="The worn pad's summit-height std enters every step's wafer solve (docs/polisher.md: below about 2 um the solver finds no equilibrium).")
@click.option("--config", "config_path", type=click.Path(dir_okay=False), default=None, help="A configuration file applied to every step unless the step sets the input: a process file of `cmpsim calibrate` applies its fitted constants (and the model choices they need) with the recipe's own tool, and its pad life's glazing and conditioning constants ([calibration.padlife]); any other file the inputs it names. --set wins over it.")
@click.option("--set", "assignments", multiple=True, metavar="NAME=VALUE", help="Change an input for every step unless the step sets it (repeatable).")
@click.option("--json", "as_json", is_flag=True, help="Print one JSON object (SI): wafers [{index, polish_time (s), removal_rate_mean (m/s), final_thickness_mean (m), final_thickness_nonuniformity (fraction), zone_pressures (Pa), ...}], target, units.")
@click.option("--out", "out_dir", type=click.Path(file_okay=False), default=None, metavar="DIR", help="Write lot.json, lot.csv and the lot plot lot.png into DIR.")
def lot_command(recipe, wafers, conditioning, control, seed, idle_time, qualification, worn_summits, config_path, assignments, as_json, out_dir):
    """Polish a lot of wafers of RECIPE.toml in sequence on one pad that warms, glazes and is conditioned.

    Each wafer's incoming thickness varies (reproducible with --seed); with --control ewma the
    recipe needs a [target] remaining thickness. Bad input exits with status 2 and writes nothing.
    """
    from ..inputs.units import to_si
    from ..polisher.lot import run_lot, write_lot
    from ..polisher.recipe import read_recipe

    with command_errors():
        parsed = read_recipe(recipe)
        overrides = recipe_overrides(config_path, assignments)
        from ..calibration.padlife import padlife_constants

        pad_constants = padlife_constants(config_path) if config_path else None  # [calibration.padlife]: the glazing and conditioning
        idle = to_si(idle_time, "s", "--idle-time", example="s")
        result = run_lot(parsed, wafers, conditioning=conditioning, control=control, seed=seed, overrides=overrides, idle_time=idle,
                         qualification=qualification, worn_summits=worn_summits, pad_constants=pad_constants)
    if out_dir is not None:
        write_lot(result, out_dir)
    if as_json:
        click.echo(result.to_json())
        return
    from rich.console import Console

    rows = [
        (str(w.index), f"{w.polish_time:.1f}", f"{w.removal_rate_mean * 6e10:.1f}", f"{w.final_thickness_mean * 1e9:.1f}", f"{100 * w.final_thickness_nonuniformity:.2f}",
         f"{w.rate_factor:.3f}", " ".join(f"{p / 6894.757293168361:.2f}" for p in w.zone_pressures))
        for w in result.wafers
    ]
    console = Console()
    console.print(_rich_table(f"lot of {len(rows)} wafers ({parsed.source}): control {control}, conditioning {result.conditioning}",
                              ["wafer", "polish time (s)", "mean rate (nm/min)", "final mean (nm)", "non-uniformity (%)", "rate factor", "zone pressures (psi)"], rows))
    if result.qualification is not None:
        q = result.qualification
        console.print(f"qualification: {q['wafers']} monitor wafer(s) before the lot, last at {q['removal_rate_mean'] * 6e10:.1f} nm/min over {q['polish_time']:.1f} s")
    if result.target is not None:
        console.print(f"target {result.target * 1e9:.1f} nm")
    console.print(f"{result.solves} wafer equilibria solved in {result.wall_time:.1f} s")

