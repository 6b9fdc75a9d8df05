"""``cmpsim lot RECIPE.toml --wafers N``: a lot of wafers on one pad, with run-to-run control (issue 32)."""

from __future__ import annotations

import click

from ..polisher.control import CLOCKS, CONTROL, DRIFT_PRIORS, DRIFT_WEIGHT, WEIGHT
from .group import _rich_table, check_out, command_errors, main, out_console, writing_errors
from .inputs import recipe_overrides


@main.command(name="lot")
@click.argument("recipe", type=click.Path(dir_okay=False))
@click.option("--wafers", type=click.IntRange(min=1), default=25, show_default=True, help="Number of wafers polished in sequence on one pad.")
@click.option("--conditioning", type=click.Choice(["none", "ex_situ", "in_situ"]), default=None, help="The diamond disk: never, between wafers, or while polishing. Default: the recipe's conditioning, else in_situ.")
@click.option("--control", type=click.Choice(CONTROL), default="none", show_default=True, help="Run-to-run control: ewma, the double EWMA (rate and its drift, Butler & Stefani 1994), or single_ewma (the rate only), sets each wafer's polish time (feed-forward) and, on a zoned head, the zone feedback its zone pressures.")
@click.option("--weight", type=float, default=WEIGHT, show_default=True, help="lambda_1, the EWMA weight of the rate's level, in (0, 1].")
@click.option("--drift-weight", "drift_weight", type=float, default=DRIFT_WEIGHT, show_default=True, help="lambda_2, the double EWMA's weight of the rate's drift (per unit of pad age), in (0, 1].")
@click.option("--drift-clock", "clock", type=click.Choice(CLOCKS), default="glazing", show_default=True, help="The double EWMA's pad-age clock: the drift per unit of the pad-life model's glazing factor over the wafer, or per wafer (Butler & Stefani's per run).")
@click.option("--drift-prior", "drift_prior", type=click.Choice(DRIFT_PRIORS), default="model", show_default=True, help="The double EWMA's first drift on the glazing clock: the pad-life model's (the rate proportional to the glazing factor) or none (learnt from the wafers).")
@click.option("--zone-weight", "zone_weight", type=float, default=0.5, show_default=True, help="lambda_z, the EWMA weight of the removal profile's shape, in (0, 1].")
@click.option("--zone-feedback/--no-zone-feedback", "zone_feedback", default=True, show_default=True, help="With control on a zoned head, set the zone pressures (only steps the zone response predicts lower the non-uniformity).")
@click.option("--seed", type=int, default=None, help="Seed of the incoming thickness draw (2 % spread of the mean, 1 % tilt, 1 sigma): the same seed, the same lot.")
@click.option("--idle-time", "idle_time", default="30 s", show_default=True, metavar="TIME", help="Time between two wafers (the pad cools; ex-situ conditioning works then).")
@click.option("--qualification", type=click.IntRange(min=0), default=1, show_default=True, help="Monitor wafers polished with the recipe as written on the pad before the lot: the last one's measured rate seeds the EWMA and the lot starts on the pad they leave (0: a fresh pad, the EWMA seeded by the model).")
@click.option("--worn-summits", "worn_summits", is_flag=True, help="The worn pad's summit-height std enters every step's wafer solve (docs/polisher.md: below about 2 um the solver finds no equilibrium).")
@click.option("--config", "config_path", type=click.Path(dir_okay=False), default=None, help="A configuration file applied to every step unless the step sets the input: a process file of `cmpsim calibrate` applies its fitted constants (and the model choices they need) with the recipe's own tool, and its pad life's glazing and conditioning constants ([calibration.padlife]); any other file the inputs it names. --set wins over it.")
@click.option("--controller-config", "controller_path", type=click.Path(dir_okay=False), default=None, metavar="FILE", help="The controller's model of the pad's life (its glazing clock and drift prior): the [calibration.padlife] constants of this process file. Default: the pad's own (--config's, else the defaults). A what-if: the pad of --config controlled with the model of another calibration.")
@click.option("--refit-model", "refit_model", is_flag=True, help="With --control ewma on the glazing clock and a one-step recipe: after each wafer the controller refits its pad-life model's wear coefficient k_w, and its critical glazed area G_c when the rates separate them, to the rates measured so far (when they identify them within a factor 2) and replays its filter on the refitted clock: a pad that glazes at another pace than the model's is followed (docs/polisher.md, C6-C8).")
@click.option("--metrology-noise", "metrology_noise", default="0 nm", show_default=True, metavar="LENGTH", help="One sigma of the metrology the controller sees the wafers through: each radius of every incoming and post-polish profile is measured with an independent normal error of this size (from --seed). The lot's results keep the true thicknesses.")
@click.option("--set", "assignments", multiple=True, metavar="NAME=VALUE", help="Change an input for every step unless the step sets it (repeatable).")
@click.option("--json", "as_json", is_flag=True, help="Print one JSON object (SI): wafers [{index, polish_time (s), removal_rate_mean (m/s), final_thickness_mean (m), final_thickness_nonuniformity (fraction), zone_pressures (Pa), ...}], target, units.")
@click.option("--out", "out_dir", type=click.Path(file_okay=False), default=None, metavar="DIR", help="Write lot.json, lot.csv and the lot plot lot.png into DIR, and the checkpoint lot.checkpoint.json after every wafer.")
@click.option("--resume", is_flag=True, help="Go on from the checkpoint in --out DIR (an interrupted lot, even killed with -9): the same results as without the interruption. Refused if the checkpoint's inputs differ; without a checkpoint the lot starts.")
def lot_command(recipe, wafers, conditioning, control, weight, drift_weight, clock, drift_prior, zone_weight, zone_feedback, seed, idle_time, qualification, worn_summits,
                config_path, controller_path, refit_model, metrology_noise, assignments, as_json, out_dir, resume):
    """Polish a lot of wafers of RECIPE.toml in sequence on one pad that warms, glazes and is conditioned.

    Each wafer's incoming thickness varies (reproducible with --seed); with --control ewma the
    recipe needs a [target] remaining thickness. Bad input exits with status 2 and writes nothing.
    """
    from ..inputs.units import to_si
    from ..polisher.lot import run_lot, write_lot
    from ..polisher.recipe import read_recipe

    from pathlib import Path

    from ..polisher.checkpoint import NAME

    with command_errors():
        if resume and out_dir is None:
            raise ValueError("--resume continues the lot whose checkpoint is in --out DIR: give --out")
        if out_dir is not None:
            check_out(out_dir)
        for option, value in (("--weight", weight), ("--drift-weight", drift_weight), ("--zone-weight", zone_weight)):
            if not 0 < value <= 1:
                raise ValueError(f"{option} is an EWMA weight in (0, 1]; got {value!r}")
        parsed = read_recipe(recipe)
        overrides = recipe_overrides(config_path, assignments)
        from ..calibration.padlife import padlife_constants

        pad_constants = padlife_constants(config_path) if config_path else None  # [calibration.padlife]: the glazing and conditioning
        model_constants = None
        if controller_path:
            model_constants = padlife_constants(controller_path)
            if model_constants is None:
                raise ValueError(f"--controller-config {controller_path}: no [calibration.padlife] table (calibrate one with "
                                 "cmpsim calibrate LOT.csv --recipe RECIPE.toml)")
            if control == "none":
                raise ValueError("--controller-config sets the controller's model: it needs --control ewma or single_ewma")
        idle = to_si(idle_time, "s", "--idle-time", example="s")
        noise = to_si(metrology_noise, "m", "--metrology-noise", example="nm")
        if not (noise >= 0 and noise < float("inf")):
            raise ValueError(f"--metrology-noise is a standard deviation >= 0 (e.g. 1 nm); got {metrology_noise!r}")
        result = run_lot(parsed, wafers, conditioning=conditioning, control=control, seed=seed, overrides=overrides, idle_time=idle,
                         qualification=qualification, worn_summits=worn_summits, weight=weight, drift_weight=drift_weight,
                         zone_weight=zone_weight, zone_feedback=zone_feedback, clock=clock, drift_prior=drift_prior,
                         checkpoint=None if out_dir is None else Path(out_dir) / NAME, resume=resume, pad_constants=pad_constants,
                         model_pad_constants=model_constants, refit_model=refit_model,
                         metrology_noise=noise)
    if out_dir is not None:
        with writing_errors(out_dir):
            write_lot(result, out_dir)
    if as_json:
        click.echo(result.to_json())
        return

    rows = [
        (str(w.index), f"{w.polish_time:.1f}", f"{w.removal_rate_mean * 6e10:.1f}", f"{w.final_thickness_mean * 1e9:.1f}", f"{100 * w.final_thickness_nonuniformity:.2f}",
         f"{w.rate_factor:.3f}", " ".join(f"{p / 6894.757293168361:.2f}" for p in w.zone_pressures))
        for w in result.wafers
    ]
    console = out_console()
    console.print(_rich_table(f"lot of {len(rows)} wafers ({parsed.source}): control {control}, conditioning {result.conditioning}",
                              ["wafer", "polish time (s)", "mean rate (nm/min)", "final mean (nm)", "non-uniformity (%)", "rate factor", "zone pressures (psi)"], rows))
    if result.qualification is not None:
        q = result.qualification
        console.print(f"qualification: {q['wafers']} monitor wafer(s) before the lot, last at {q['removal_rate_mean'] * 6e10:.1f} nm/min over {q['polish_time']:.1f} s")
    if result.target is not None:
        console.print(f"target {result.target * 1e9:.1f} nm")
    console.print(f"{result.solves} wafer equilibria solved in {result.wall_time:.1f} s")

