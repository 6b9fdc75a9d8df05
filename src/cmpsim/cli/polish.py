"""``cmpsim polish RECIPE.toml``: a recipe polished through time (issue 32)."""

from __future__ import annotations

import click

from .group import EXIT_NO_EQUILIBRIUM, _fail, _rich_table, main


@main.command(name="polish")
@click.argument("recipe", type=click.Path(dir_okay=False))
@click.option("--set", "assignments", multiple=True, metavar="NAME=VALUE", help="Change an input for every step unless the step sets it (repeatable), e.g. --set grid=coarse.")
@click.option("--time-step", "time_step", default="1 s", show_default=True, metavar="TIME", help="Time step of the integration and the end point's sampling.")
@click.option("--json", "as_json", is_flag=True, help="Print one JSON object (SI): steps [{name, duration (s), end ('time' or 'endpoint'), removal_rate_mean (m/s), pad_temperature {time (s), value (K)}, thickness {radius (m), film: (m)}, signals, endpoint, ...}], target, pad_state, units.")
@click.option("--out", "out_dir", type=click.Path(file_okay=False), default=None, metavar="DIR", help="Write polish.json, thickness.csv and the plots thickness.png, pad_temperature.png, endpoint.png into DIR.")
def polish_command(recipe, assignments, time_step, as_json, out_dir):
    """Polish RECIPE.toml through time: the film stack per radius, the end point, the pad's temperature.

    The recipe names a preset or inputs, the film stack ([[film]]: material, thickness; top first)
    and the steps ([[step]]: name, any input with units, time = "60 s" or until = "endpoint" with
    max_time). Bad recipes exit with status 2 and write nothing; a step without equilibrium exits 3.
    """
    from ..inputs.units import to_si
    from ..polisher.engine import polish
    from ..polisher.recipe import read_recipe
    from ..solver.equilibrium import EquilibriumError
    from .inputs import parse_assignments

    try:
        parsed = read_recipe(recipe)
        overrides = parse_assignments(assignments)
        dt = to_si(time_step, "s", "--time-step", example="s")
        result = polish(parsed, overrides=overrides, time_step=dt)
    except EquilibriumError as exc:
        _fail(f"no equilibrium: {exc}", EXIT_NO_EQUILIBRIUM)
    except ValueError as exc:
        _fail(str(exc))
    if out_dir is not None:
        from ..polisher.report import write_outputs

        write_outputs(result, out_dir)
    if as_json:
        click.echo(result.to_json())
        return
    from rich.console import Console

    console = Console()
    console.print(_rich_table(f"recipe {parsed.source}", ["step", "end", "duration (s)", "mean rate (nm/min)", "pad temperature (K)", "top film", "cleared (% area)"], result.summary_rows()))
    for s in result.steps:
        if s.endpoint is not None:
            ep = s.endpoint
            if ep["detected"]:
                console.print(f"step {s.name!r}: end point at {ep['time']:.1f} s (reflectance {ep['level_start']:.3f} -> {ep['level_cleared']:.3f}); {ep['film']} cleared on {100 * ep['cleared_fraction']:.1f} % of the wafer area")
            else:
                console.print(f"step {s.name!r}: no end point before max_time = {ep['max_time']:g} s; {ep['film']} cleared on {100 * ep['cleared_fraction']:.1f} % of the wafer area")
    t = result.target
    if t is not None:
        console.print(f"target: {t['film']} remaining {1e9 * t['remaining']:.1f} nm; after the recipe {1e9 * t['final_mean']:.1f} nm (area mean), {1e9 * t['deviation']:+.1f} nm")
    console.print(f"{result.solves} wafer equilibria solved in {result.wall_time:.1f} s")
