"""``cmpsim polish RECIPE.toml``: a recipe polished through time (issue 32)."""

from __future__ import annotations

import click

from .group import _rich_table, check_out, command_errors, main, out_console, writing_errors
from .inputs import recipe_overrides


@main.command(name="polish")
@click.argument("recipe", type=click.Path(dir_okay=False))
@click.option("--config", "config_path", type=click.Path(dir_okay=False), default=None, help="A configuration file applied to every step unless the step sets the input: a process file of `cmpsim calibrate` applies its fitted constants (and the model choices they need) with the recipe's own tool; any other file the inputs it names. --set wins over it.")
@click.option("--set", "assignments", multiple=True, metavar="NAME=VALUE", help="Change an input for every step unless the step sets it (repeatable), e.g. --set grid=coarse.")
@click.option("--time-step", "time_step", default="1 s", show_default=True, metavar="TIME", help="Time step of the integration and the end point's sampling.")
@click.option("--json", "as_json", is_flag=True, help="Print one JSON object (SI): steps [{name, duration (s), end ('time' or 'endpoint'), removal_rate_mean (m/s), pad_temperature {time (s), value (K)}, thickness {radius (m), film: (m)}, signals, endpoint, ...}], target, pad_state, units.")
@click.option("--out", "out_dir", type=click.Path(file_okay=False), default=None, metavar="DIR", help="Write polish.json, thickness.csv and the plots thickness.png, pad_temperature.png, endpoint.png into DIR; with --die also die.csv (the die per step and site) and per site die_<k>_r<mm>mm/ with the files of cmpsim die (die.json, die.nc, die.png; hotspots.csv, hotspots.lyrdb on a layout file).")
@click.option("--die", "die_layout", metavar="LAYOUT", default=None,
              help="A layout riding along: a .gds/.gds.gz/.oas file (with --layer), a layout CSV or a built-in die (cmpsim die --list), polished by the die model at each --sites radius through the steps; JSON steps[].die [{radius (m), time (s), blanket_rate (m/s), thickness_range, step_height_max, dishing_max, erosion_max (m), hotspot_count}].")
@click.option("--layer", "layers", multiple=True, metavar="L/D|NAME", help="--die: a layer/datatype (68/20) or a name (met1 with --pdk); repeatable, all merged.")
@click.option("--pdk", type=click.Choice(["sky130", "gf180mcu", "sg13g2"]), default=None, help="--die: the open PDK whose layer map names the layers.")
@click.option("--layer-map", "layer_map", type=click.Path(dir_okay=False), default=None, help="--die: a TOML layer map (name = [\"L/D\", ...]).")
@click.option("--top", "top", metavar="CELL", default=None, help="--die: the top cell (where the file has several).")
@click.option("--window", "window_text", metavar="SIZE", default=None, help="--die: the window side (default 20um): every window a cell of the die model.")
@click.option("--sites", "sites_text", metavar="R1,R2,...", default=None, help="--die: the radii of the dies (e.g. 0,70mm,140mm; a bare number is mm). Default: the centre, mid-radius and the outermost whole die.")
@click.option("--die-param", "die_params", multiple=True, metavar="NAME=VALUE", help="--die: a die-model input with units, e.g. --die-param trench_depth=0.4um (repeatable; default copper_thickness and barrier_thickness from the recipe's films).")
@click.option("--spec", "specs", multiple=True, metavar="KIND=LIMIT", help="--die: a hotspot limit: thickness=5nm, step_height=20nm, dishing=30nm, erosion=20nm (repeatable).")
def polish_command(recipe, config_path, assignments, time_step, as_json, out_dir, die_layout, layers, pdk, layer_map, top, window_text, sites_text,
                   die_params, specs):
    """Polish RECIPE.toml through time: the film stack per radius, the end point, the pad's temperature.

    The recipe names a preset or inputs, the film stack ([[film]]: material, thickness; top first)
    and the steps ([[step]]: name, any input with units, time = "60 s" or until = "endpoint" with
    max_time). Bad recipes exit with status 2 and write nothing; a step without equilibrium exits 3.
    """
    from ..inputs.units import to_si
    from ..polisher.engine import polish
    from ..polisher.recipe import read_recipe

    with command_errors():
        if out_dir is not None:
            check_out(out_dir)
        parsed = read_recipe(recipe)
        overrides = recipe_overrides(config_path, assignments)
        dt = to_si(time_step, "s", "--time-step", example="s")
        die = _riding_die(die_layout, layers, pdk, layer_map, top, window_text, sites_text, die_params, specs)
        from ..calibration.padlife import padlife_constants
        from ..polisher.pad import PadLife

        pad_constants = padlife_constants(config_path) if config_path else None
        # a recipe that runs its pad's life (conditioning = ...) glazes with the process file's constants
        pad_life = PadLife(parsed.conditioning, parsed.conditioner, constants=pad_constants) if pad_constants and parsed.conditioning else None
        result = polish(parsed, overrides=overrides, time_step=dt, die=die, pad_life=pad_life)
    if out_dir is not None:
        from ..polisher.report import write_outputs

        with writing_errors(out_dir):
            write_outputs(result, out_dir)
    if as_json:
        click.echo(result.to_json())
        return

    console = out_console()
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
    if result.ride is not None:
        console.print(_rich_table(f"die {result.ride.layout.name!r} ({result.ride.process.kind}) riding along", ["step", "radius (mm)", "time (s)", "rate (nm/min)", "thickness range (nm)",
                                                                       "step height max (nm)", "dishing max (nm)", "erosion max (nm)", "hotspots"], _die_rows(result)))
    glazed = [s for s in result.steps if s.glazing is not None]
    if glazed:
        console.print(f"pad life ({parsed.conditioning or 'given'} conditioning): glazed-pad rate factor "
                      + ", ".join(f"{s.name} {s.glazing['rate_factor'][0]:.3f} -> {s.glazing['rate_factor'][-1]:.3f}" for s in glazed))
    console.print(f"{result.solves} wafer equilibria solved in {result.wall_time:.1f} s")


def _nm(v):
    return "-" if v is None else f"{v * 1e9:.4g}"


def _die_rows(result) -> list:
    return [[s.name, f"{d['radius'] * 1e3:.1f}", f"{d['time']:.1f}", f"{d['blanket_rate'] * 6e10:.1f}", _nm(d["thickness_range"]),
             _nm(d["step_height_max"]), _nm(d["dishing_max"]), _nm(d["erosion_max"]), str(d["hotspot_count"])] for s in result.steps for d in s.die]


def _riding_die(layout, layers, pdk, layer_map, top, window_text, sites_text, die_params, specs):
    """The :class:`~cmpsim.polisher.ride.RidingDie` of the --die options (None without --die); ValueError naming the option."""
    from ..die.hotspots import parse_spec
    from ..inputs.units import to_si
    from ..polisher.ride import RidingDie, parse_sites

    if layout is None:
        given = [n for n, v in (("--layer", layers), ("--pdk", pdk), ("--layer-map", layer_map), ("--top", top), ("--window", window_text),
                                ("--sites", sites_text), ("--die-param", die_params), ("--spec", specs)) if v]
        if given:
            raise ValueError(f"{', '.join(given)} {'needs' if len(given) == 1 else 'need'} --die LAYOUT")
        return None
    window = to_si(window_text, "m", "--window", "20 um") if window_text else 20e-6
    if not (window > 0):
        raise ValueError(f"--window must be a length > 0; got {window_text!r}")
    return RidingDie(layout, tuple(layers), window, top=top, pdk=pdk, layer_map=layer_map,
                     sites=parse_sites(sites_text) if sites_text else None, params=_die_params(die_params), spec=parse_spec(list(specs)))


def _die_params(items) -> dict:
    from .inputs import parse_assignments

    try:
        return parse_assignments(items)
    except ValueError as exc:
        raise ValueError(str(exc).replace("--set", "--die-param").replace("applied_pressure=4psi", "trench_depth=0.4um")) from None

