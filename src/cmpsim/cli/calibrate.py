"""``cmpsim calibrate``: fit uncertain inputs to measurements."""

from __future__ import annotations

import click

from .group import _fail, main
from .inputs import config_options, load_config


class _ListOptionsCommand(click.Command):
    """A command whose list options take several values after one flag: ``--free A B C``.

    Before click parses the command line, ``--free A B C`` is rewritten as ``--free A --free B
    --free C``: the values run to the next option, or to a value that looks like a file
    (contains '.' or '/'), so ``--free A data.csv`` still reads data.csv as an argument.
    Values may also be repeated (``--free A --free B``) or comma-separated.
    """

    list_options = ("--free",)

    def parse_args(self, ctx, args):
        out, rest = [], list(args)
        while rest:
            arg = rest.pop(0)
            out.append(arg)
            if arg == "--":
                out += rest
                break
            if arg in self.list_options and rest:
                out.append(rest.pop(0))
                while rest and not rest[0].startswith("-") and "." not in rest[0] and "/" not in rest[0]:
                    out += [arg, rest.pop(0)]
        return super().parse_args(ctx, out)


def _split_names(values) -> list[str]:
    out = []
    for v in values:
        out += [s.strip() for s in str(v).split(",") if s.strip()]
    return out


@main.command(name="calibrate", cls=_ListOptionsCommand)
@click.argument("data", nargs=-1, required=True, type=click.Path(dir_okay=False))
@click.option("--free", "free", multiple=True, metavar="NAME [NAME ...]", help="Inputs to fit, e.g. --free asperity_density asperity_radius (or repeated, or comma-separated); die constants (contact_height, summit_radius, ...) and pad constants (friction_coefficient, pad_heat_transfer_coefficient) are fitted at their scale. Without it the data's quantities choose the inputs they can identify (removal rates of a film: its chemistry constants; test structures: the die constants; pad temperature and friction: the friction and the heat removal) and the report says which and why.")
@click.option("--bounds", "bounds", multiple=True, metavar="NAME=LOW:HIGH", help="Bounds with units of an input fitted through the wafer solve, e.g. --bounds pad_modulus=20MPa:500MPa (repeatable; default a factor 10 either side).")
@config_options
@click.option("--out", "out_path", type=click.Path(dir_okay=False), default="calibrated.toml", show_default=True, help="The process file: the fitted configuration, accepted by every command's --config (and `cmpsim run FILE`), with a [calibration] table (constants, 95 % intervals, correlations) whose constants `cmpsim polish --config` and `cmpsim lot --config` apply with the recipe's own tool, and the die constants with their covariance ([calibration.die]) that `cmpsim die --config` applies.")
@click.option("--recipe", "recipe_path", type=click.Path(dir_okay=False), default=None, help="The recipe of the lot whose rows (a wafer column, quantity thickness or removal) the data hold: the pad life's glazing and conditioning constants are fitted to them, the lot run as `cmpsim lot RECIPE` runs it (with the constants of --config and of this calibration), and written to [calibration.padlife], which `cmpsim lot --config` applies.")
@click.option("--lot-conditioning", "lot_conditioning", type=click.Choice(["none", "ex_situ", "in_situ"]), default=None, help="--recipe: how the measured lot was conditioned (cmpsim lot --conditioning; default the recipe's, else in_situ).")
@click.option("--lot-control", "lot_control", type=click.Choice(["none", "ewma"]), default="none", show_default=True, help="--recipe: the measured lot's run-to-run control (cmpsim lot --control).")
@click.option("--lot-seed", "lot_seed", type=int, default=0, show_default=True, help="--recipe: the seed of the lot's incoming thicknesses (cmpsim lot --seed).")
@click.option("--lot-qualification", "lot_qualification", type=click.IntRange(min=0), default=1, show_default=True, help="--recipe: monitor wafers before the measured lot (cmpsim lot --qualification).")
@click.option("--max-evaluations", type=click.IntRange(min=1), default=None, help="Model evaluations allowed to the optimiser of the wafer-scale fit.")
@click.option("--quiet", is_flag=True, help="Do not print the evaluations while fitting.")
def calibrate_command(data, free, bounds, config_path, preset, assignments, grid, out_path, recipe_path, lot_conditioning, lot_control, lot_seed,
                      lot_qualification, max_evaluations, quiet):
    """Fit inputs to measurements at every scale (scipy least_squares, bounded); without --free the data choose them.

    DATA may mix removal rates (a `film` column), test structures (quantity dishing, erosion,
    step_height), pad rows (pad_temperature_rise, friction_coefficient) and, with --recipe, a
    lot's rows (wafer, thickness or removal): the pad is calibrated first, then the films with its
    constants, then the die at the calibrated rates, then the pad life on the lot. Reports, per
    scale, the inputs chosen and why (and what the data cannot separate, from the Jacobian),
    fitted values with 95 % intervals, their correlations, the residuals before and after (and
    the leave-one-out error of removal series beside Preston's law's), and writes one process file
    to --out (nothing is written when a file or the fit cannot be used).
    """
    from ..calibration.mixed import read_all
    from ..calibration.scales import calibrate_scales

    names = _split_names(free)
    bnds = {}
    from pathlib import Path

    inputs = [Path(p) for p in (*data, *([config_path] if config_path else []), *([recipe_path] if recipe_path else []))]
    if any(p.exists() and Path(out_path).exists() and p.resolve() == Path(out_path).resolve() for p in inputs):
        _fail(f"--out {out_path} is one of the input files; it would be overwritten by the process file: give another --out")
    try:
        for item in bounds:
            if "=" not in item or ":" not in item.split("=", 1)[1]:
                raise ValueError(f"--bounds expects NAME=LOW:HIGH (e.g. pad_modulus=20MPa:500MPa); got {item!r}")
            name, rng = item.split("=", 1)
            lo, hi = rng.split(":", 1)
            bnds[name.strip().replace("-", "_")] = (lo.strip(), hi.strip())
        cfg = load_config(config_path, assignments, preset, grid)
        measurements = read_all(list(data))
        # the pad's records: on the configuration given, else on the base of docs/calibrate.md (the 300mm preset, coarse grid)
        given = bool(config_path or preset or assignments or grid)
        lot = None
        if recipe_path:
            from ..calibration.padlife import LotSetting
            from .inputs import recipe_overrides

            overrides = recipe_overrides(config_path, assignments) | ({"grid": grid} if grid else {})  # as `cmpsim lot --config --set`
            lot = LotSetting(recipe_path, lot_conditioning, lot_control, lot_seed, lot_qualification, overrides=overrides)
        result = calibrate_scales(measurements, cfg, names or None, bounds=bnds or None, max_nfev=max_evaluations, progress=not quiet,
                                  pad_config=cfg if given else None, lot=lot)
    except ValueError as exc:
        _fail(str(exc))
    try:
        result.to_toml(out_path)
    except OSError as exc:
        _fail(f"cannot write {out_path}: {exc}")
    click.echo(result.summary())
    click.echo(f"wrote {out_path}")
