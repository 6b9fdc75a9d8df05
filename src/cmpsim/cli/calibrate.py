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
@click.option("--free", "free", multiple=True, metavar="NAME [NAME ...]", help="Inputs to fit, e.g. --free asperity_density asperity_radius (or repeated, or comma-separated). Without it the data's quantities choose the inputs they can identify (removal rates of a film: its chemistry constants) and the report says which and why.")
@click.option("--bounds", "bounds", multiple=True, metavar="NAME=LOW:HIGH", help="Bounds with units, e.g. --bounds pad_modulus=20MPa:500MPa (repeatable; default a factor 10 either side).")
@config_options
@click.option("--out", "out_path", type=click.Path(dir_okay=False), default="calibrated.toml", show_default=True, help="The process file: the fitted configuration, accepted by every command's --config (and `cmpsim run FILE`), with a [calibration] table (constants, 95 % intervals, correlations) whose constants `cmpsim polish --config` and `cmpsim lot --config` apply with the recipe's own tool.")
@click.option("--max-evaluations", type=click.IntRange(min=1), default=None, help="Model evaluations allowed to the optimiser.")
@click.option("--quiet", is_flag=True, help="Do not print the evaluations while fitting.")
def calibrate_command(data, free, bounds, config_path, preset, assignments, grid, out_path, max_evaluations, quiet):
    """Fit inputs to measurements (scipy least_squares, bounded); without --free the data choose them.

    Reports the inputs chosen and why (and what the data cannot separate, from the fit's Jacobian),
    fitted values with standard errors and 95 % intervals, their correlations, the residuals before
    and after and the leave-one-out error beside Preston's law's and the mean's, and writes the
    process file to --out (nothing is written when the fit cannot run).
    """
    from ..calibration import calibrate

    names = _split_names(free)
    bnds = {}
    try:
        for item in bounds:
            if "=" not in item or ":" not in item.split("=", 1)[1]:
                raise ValueError(f"--bounds expects NAME=LOW:HIGH (e.g. pad_modulus=20MPa:500MPa); got {item!r}")
            name, rng = item.split("=", 1)
            lo, hi = rng.split(":", 1)
            bnds[name.strip().replace("-", "_")] = (lo.strip(), hi.strip())
        cfg = load_config(config_path, assignments, preset, grid)
        result = calibrate(list(data), names or None, config=cfg, bounds=bnds or None, max_nfev=max_evaluations, progress=not quiet)
    except ValueError as exc:
        _fail(str(exc))
    try:
        result.to_toml(out_path)
    except OSError as exc:
        _fail(f"cannot write {out_path}: {exc}")
    click.echo(result.summary())
    click.echo(f"wrote {out_path}")
