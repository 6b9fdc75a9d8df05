"""``cmpsim die``: a patterned die polished at the blanket rate of the wafer solve."""

from __future__ import annotations

import click

from .group import EXIT_NO_EQUILIBRIUM, _fail, _rich_table, main
from .inputs import config_options, load_config, parse_assignments


@main.command(name="die")
@click.argument("layout", required=False)
@click.option("--list", "list_dies", is_flag=True, help="Print the built-in test dies and exit.")
@click.option("--wafer", is_flag=True, help="Polish every die of the wafer, each at the blanket rate of the wafer solve at its site.")
@click.option("--time", "time_text", metavar="T", default=None, help="Polishing time with units (e.g. 90s, 2min; a number is seconds). Default: the end point times 1 + over_polish.")
@click.option("--process", type=click.Choice(["oxide", "copper"]), default="oxide", show_default=True, help="Oxide ILD planarization, or copper damascene (bulk removal, then over-polish: dishing and erosion).")
@click.option("--param", "params", multiple=True, metavar="NAME=VALUE", help="A die-model input with units, e.g. --param step_height=0.8um (repeatable; see docs/model.md section 18).")
@click.option("--planarization-length", "pl_text", metavar="L", default=None, help="Override the planarization length derived from the pad stack (e.g. 3mm).")
@click.option("--weighting", type=click.Choice(["gaussian", "pad", "elliptic"]), default="gaussian", show_default=True,
              help="Weighting function of the effective density: Gaussian, the pad stack's own response, or Ouma's elliptic kernel (the convention of the published planarization lengths); --planarization-length is in its convention.")
@click.option("--feature-contact", type=click.Choice(["elastic", "summit"]), default="elastic", show_default=True,
              help="Contact height of a gap: summit sagitta plus the pad body's elastic bulge into it (wide lines keep dishing deeper), or the summit sagitta alone (cmpsim 0.3).")
@click.option("--cell-size", "cell_text", metavar="SIZE", default=None, help="Cell size of a built-in die (default 50um).")
@click.option("--blanket-rate", "rate_text", metavar="RATE", default=None, help="Blanket rate of a single die (e.g. 200nm/min); default the wafer-mean rate of the wafer solve.")
@config_options
@click.option("--out", "out_dir", type=click.Path(file_okay=False), help="Write die.nc, die.png, die.json (and wafer.nc, wafer.png with --wafer) to DIR.")
@click.option("--json", "as_json", is_flag=True, help="Print exactly one JSON object (SI units) on stdout.")
def die_command(layout, list_dies, wafer, time_text, process, params, pl_text, weighting, feature_contact, cell_text, rate_text, config_path, preset, assignments, grid, out_dir, as_json):
    """Polish a patterned die: effective density, step heights, copper dishing and erosion.

    LAYOUT is a layout CSV (density grid, cell size, optional line widths; docs/model.md
    section 18) or the name of a built-in test die (`cmpsim die --list`). The blanket rate
    comes from a wafer-scale solve of the inputs (--config/--preset/--set/--grid).
    """
    from ..die import BUILTIN_LAYOUTS, simulate, simulate_wafer
    from ..die.report import to_json, write_die_outputs
    from ..solver.equilibrium import EquilibriumError
    from ..inputs.units import to_si

    if list_dies:
        for name, (text, _) in BUILTIN_LAYOUTS.items():
            click.echo(f"{name:10s} {text}")
        return
    if not layout:
        _fail("give a LAYOUT (a CSV file or a built-in die: cmpsim die --list)")
    try:
        cfg = load_config(config_path, assignments, preset, grid)
        kwargs = dict(process=process, planarization_length=to_si(pl_text, "m", "--planarization-length", "3 mm") if pl_text else None,
                      weighting=weighting, feature_contact=feature_contact, cell_size=to_si(cell_text, "m", "--cell-size", "50 um") if cell_text else None,
                      **parse_assignments(params))
        t = to_si(time_text, "s", "--time", "90 s") if time_text else None
        if wafer:
            if rate_text:
                raise ValueError("--blanket-rate applies to a single die; with --wafer the rates come from the wafer solve")
            result = simulate_wafer(layout, t, config=cfg, **kwargs)
        else:
            rate = to_si(rate_text, "m/s", "--blanket-rate", "200 nm/min") if rate_text else None
            result = simulate(layout, t, config=cfg, blanket_rate=rate, **kwargs)
    except EquilibriumError as exc:
        _fail(f"no equilibrium of the wafer solve: {exc}", EXIT_NO_EQUILIBRIUM)
    except ValueError as exc:
        _fail(str(exc))
    if out_dir:
        try:
            written = write_die_outputs(result, out_dir)
        except OSError as exc:
            _fail(f"cannot write to {out_dir}: {exc}")
    if as_json:
        click.echo(to_json(result))
        return
    from rich.console import Console

    console = Console()
    die = getattr(result, "die", result)
    d = result.to_dict()

    def um(v, scale=1e9, unit="nm"):
        return "-" if v is None else f"{v * scale:.4g} {unit}"

    rows = [[str(r["index"]), f"{100 * r['density']:.0f} %", um(r["line_width"], 1e6, "um"), f"{r['effective_density']:.3f}", um(r["step_height"]), um(r["dishing"]), um(r["erosion"])]
            for r in d["regions"]]
    console.print(_rich_table(f"die {die.layout.name!r} ({die.process.kind}) after {d['time']:.1f} s", ["region", "density", "line width", "eff. density", "step height", "dishing", "erosion"], rows))
    console.print(f"planarization length {d['planarization_length'] * 1e3:.3g} mm, {d['weighting']} weighting (from the pad stack: "
                  f"{d['planarization_length_gaussian_from_pad'] * 1e3:.3g} mm Gaussian, {d['planarization_length_elliptic_from_pad'] * 1e3:.3g} mm elliptic); "
                  f"blanket rate {die.blanket_rate * 6e10:.4g} nm/min; time to planarize {um(d['time_to_planarize'], 1, 's')}"
                  + (f"; time to clear {um(d['time_to_clear'], 1, 's')}" if d["time_to_clear"] is not None else ""), highlight=False)
    if wafer:
        import numpy as np

        end = ("clear", result.time_to_clear) if d["time_to_clear"] is not None else ("planarize", result.time_to_planarize)
        console.print(f"{len(result.x)} dies; blanket rate {np.min(result.blanket_rate) * 6e10:.4g}-{np.max(result.blanket_rate) * 6e10:.4g} nm/min; "
                      f"time to {end[0]} {np.nanmin(end[1]):.1f}-{np.nanmax(end[1]):.1f} s", highlight=False)
    if out_dir:
        console.print("wrote " + ", ".join(str(p) for p in written), highlight=False)
