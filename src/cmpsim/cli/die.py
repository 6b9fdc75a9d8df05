"""``cmpsim die``: a patterned die polished at the blanket rate of the wafer solve: a built-in die, a CSV grid, or a real layout (GDSII/OASIS)."""

from __future__ import annotations

from pathlib import Path

import click

from .group import _fail, _rich_table, check_out, command_errors, main, out_console
from .inputs import config_options, load_config, parse_assignments
from .progress import extraction_bar


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
@click.option("--layer", "layers", multiple=True, metavar="L/D|NAME", help="Layout: a layer/datatype (68/20) or a name (met1 with --pdk); repeatable, all merged.")
@click.option("--window", "window_text", metavar="SIZE", default=None, help="Layout: the window side (default 20um): every window a cell of the die model.")
@click.option("--top", "top", metavar="CELL", default=None, help="Layout: the top cell (where the file has several).")
@click.option("--pdk", type=click.Choice(["sky130", "gf180mcu", "sg13g2"]), default=None, help="Layout: the open PDK whose layer map names the layers.")
@click.option("--layer-map", "layer_map", type=click.Path(dir_okay=False), default=None, help="Layout: a TOML layer map (name = [\"L/D\", ...]).")
@click.option("--stack", "stack_path", type=click.Path(dir_okay=False), default=None, help="Layout: a stack file (TOML, [[level]] with name, layers, process): levels polished bottom first over the topography each leaves.")
@click.option("--spec", "specs", multiple=True, metavar="KIND=LIMIT", help="A hotspot limit: thickness=5nm, step_height=20nm, dishing=30nm, erosion=20nm (repeatable).")
@click.option("--fill", "fill", is_flag=True, help="Layout: add model-based dummy fill where the die model says it lowers the thickness range, write fill.gds/fill.oas to --out, re-simulate; JSON fill {before, after, added_area}. The maps, hotspots and scalars are then those of the filled die.")
@click.option("--fill-layer", "fill_layer", metavar="L/D", default=None, help="--fill: the fill's layer/datatype (default with --pdk: the PDK's fill datatype of the --layer, e.g. 36/28 for sky130 met1).")
@click.option("--fill-size", "fill_size", metavar="SIZE", default=None, help="--fill: side of a fill square (default with --pdk: the PDK's, docs/fill.md).")
@click.option("--fill-spacing", "fill_spacing", metavar="SIZE", default=None, help="--fill: least distance between two fill squares (default with --pdk: the PDK's).")
@click.option("--fill-keepout", "fill_keepout", metavar="SIZE", default=None, help="--fill: least distance from a fill square to a drawn shape of the --layer layers (default with --pdk: the PDK's).")
@click.option("--fill-edge", "fill_edge", metavar="SIZE", default=None, help="--fill: least distance from a fill square to the die's edge (default with --pdk: the PDK's, else 0).")
@config_options
@click.option("--out", "out_dir", type=click.Path(file_okay=False), help="Write die.nc, die.png, die.json (wafer.nc, wafer.png with --wafer; hotspots.lyrdb, hotspots.csv on a layout; fill.gds or fill.oas with --fill) to DIR.")
@click.option("--json", "as_json", is_flag=True, help="Print exactly one JSON object (SI units) on stdout.")
def die_command(layout, list_dies, wafer, time_text, process, params, pl_text, weighting, feature_contact, cell_text, rate_text, layers, window_text,
                top, pdk, layer_map, stack_path, specs, fill, fill_layer, fill_size, fill_spacing, fill_keepout, fill_edge, config_path, preset, assignments, grid, out_dir, as_json):
    """Polish a patterned die: effective density, step heights, copper dishing and erosion.

    LAYOUT is a layout CSV (density grid, cell size, optional line widths; docs/model.md
    section 18), the name of a built-in test die (`cmpsim die --list`), or a real layout
    (.gds, .gds.gz, .oas) with --layer or --stack: every window of it a cell of the model,
    with hotspots against --spec. The blanket rate comes from a wafer-scale solve of the
    inputs (--config/--preset/--set/--grid).
    """
    from ..die import BUILTIN_LAYOUTS, simulate, simulate_wafer
    from ..die.chip import (
        is_layout_file,
        layout_die,
        read_stack,
        simulate_stack,
        stack_settings,
        stack_settings_named,
    )
    from ..die.hotspots import parse_spec
    from ..die.report import to_json, write_die_outputs
    from ..inputs.units import to_si

    if list_dies:
        for name, (text, _) in BUILTIN_LAYOUTS.items():
            click.echo(f"{name:10s} {text}")
        return
    if not layout:
        _fail("give a LAYOUT (a CSV file or a built-in die: cmpsim die --list)")
    layout_arg = layout
    real = layout not in BUILTIN_LAYOUTS and is_layout_file(layout)
    stack = None
    plan = fill_file = None
    fill_given = [name for name, v in (("--fill-layer", fill_layer), ("--fill-size", fill_size), ("--fill-spacing", fill_spacing),
                                       ("--fill-keepout", fill_keepout), ("--fill-edge", fill_edge)) if v]
    with command_errors("no equilibrium of the wafer solve"):
        if out_dir:
            check_out(out_dir)  # before the extraction and the solve, not after them
        if fill_given and not fill:
            raise ValueError(f"{', '.join(fill_given)} {'needs' if len(fill_given) == 1 else 'need'} --fill")
        if not real:
            given = [name for name, v in (("--layer", layers), ("--window", window_text), ("--top", top), ("--pdk", pdk),
                                          ("--layer-map", layer_map), ("--stack", stack_path), ("--fill", fill)) if v]
            if given:
                what = (f"{layout!r} is a built-in die" if layout in BUILTIN_LAYOUTS else
                        f"{layout!r} is not a layout (a CSV grid or another file)" if Path(layout).is_file() else
                        f"{layout!r} is a directory" if Path(layout).is_dir() else f"{layout!r} does not exist")
                raise ValueError(f"{', '.join(given)} {'applies' if len(given) == 1 else 'apply'} to a layout file (.gds, .gds.gz, .oas, "
                                 f"recognised by its name or its first bytes); {what}")
        elif cell_text:
            raise ValueError("--cell-size applies to the built-in dies; a layout's cells are its windows (--window)")
        spec = parse_spec(list(specs))
        cfg = load_config(config_path, assignments, preset, grid)
        pl = to_si(pl_text, "m", "--planarization-length", "3 mm") if pl_text else None
        kwargs = dict(process=process, planarization_length=pl, weighting=weighting, feature_contact=feature_contact,
                      cell_size=to_si(cell_text, "m", "--cell-size", "50 um") if cell_text else None, spec=spec, **parse_assignments(params))
        kwargs = _calibrated(kwargs, config_path, params, wafer, stack_path)
        t = to_si(time_text, "s", "--time", "90 s") if time_text else None
        window = to_si(window_text, "m", "--window", "20 um") if window_text else None
        if fill and stack_path:
            raise ValueError("--fill with --stack is not supported: fill one level at a time (cmpsim die LAYOUT --layer ... --fill)")
        if fill and wafer:
            raise ValueError("--fill with --wafer is not supported: fill the die (--fill), then run --wafer on the layout merged with fill.gds")
        if real and stack_path:
            if layers:
                raise ValueError("give the layers in the stack file's [[level]] tables, not with --layer, when --stack is used")
            if wafer:
                raise ValueError("--wafer with --stack is not supported: run --wafer per level")
            if params or process != "oxide":
                raise ValueError("with --stack each level sets its process and inputs in the stack file (--process, --param do not apply)")
            levels, options = read_stack(stack_path)
            from_file = stack_settings(options, window, top)
            if window is None and "window" in options:
                window = to_si(options["window"], "m", f"window in {stack_path}", "20 um")
            rate = to_si(rate_text, "m/s", "--blanket-rate", "200 nm/min") if rate_text else None
            with extraction_bar() as told, stack_settings_named(Path(stack_path).name, from_file):
                result = stack = simulate_stack(layout, levels, window, top=top or options.get("top"), pdk=pdk or options.get("pdk"),
                                                layer_map=layer_map or options.get("layer_map"), config=cfg, blanket_rate=rate, time=t,
                                                spec=parse_spec(options.get("spec")) | spec, planarization_length=pl, weighting=weighting,
                                                feature_contact=feature_contact, progress=told, calibration=_stack_calibration(config_path))
        elif real:
            if not layers:
                raise ValueError("a layout file needs --layer L/D (or a name with --pdk / --layer-map), or --stack FILE.toml"
                                 + _layers_of(layout))
            if fill:
                from ..die.fill import fill_die
                from ..layout.fill import resolve_fill

                lengths = {k: to_si(v, "m", opt, "2 um") if v else None
                           for k, v, opt in (("size", fill_size, "--fill-size"), ("spacing", fill_spacing, "--fill-spacing"),
                                             ("keepout", fill_keepout, "--fill-keepout"), ("edge", fill_edge, "--fill-edge"))}
                rules, fill_pair = resolve_fill(list(layers), pdk, layer_map, fill_layer, **lengths)
                rate = to_si(rate_text, "m/s", "--blanket-rate", "200 nm/min") if rate_text else None
                options = {k: v for k, v in kwargs.items() if k not in ("cell_size", "process")}
                with extraction_bar() as told:
                    result, plan, fill_file = fill_die(layout, list(layers), window if window is not None else 20e-6, rules, fill_pair,
                                                       top=top, pdk=pdk, layer_map=layer_map, config=cfg, process=process,
                                                       blanket_rate=rate, time=t, with_file=bool(out_dir), progress=told, **options)
            else:
                with extraction_bar() as told:
                    layout = layout_die(layout, list(layers), window if window is not None else 20e-6, top=top, pdk=pdk,
                                        layer_map=layer_map, progress=told)
        if stack is not None or plan is not None:
            pass
        elif wafer:
            if rate_text:
                raise ValueError("--blanket-rate applies to a single die; with --wafer the rates come from the wafer solve")
            result = simulate_wafer(layout, t, config=cfg, **kwargs)
        else:
            rate = to_si(rate_text, "m/s", "--blanket-rate", "200 nm/min") if rate_text else None
            result = simulate(layout, t, config=cfg, blanket_rate=rate, **kwargs)
    if out_dir:
        try:
            written = write_die_outputs(result, out_dir, original_file=str(layout_arg) if real else "")
            if plan is not None:
                from ..layout.fill import write_fill

                written.append(write_fill(Path(out_dir) / fill_file, plan.sites, plan.chosen, fill_pair))
        except OSError as exc:
            _fail(f"cannot write to {out_dir}: {exc}")
    if as_json:
        click.echo(to_json(result))
        return

    console = out_console()
    if stack is not None or real:
        _print_layout_run(console, result, stack is not None, wafer)
        if plan is not None:
            f = result.fill
            console.print(f"fill on {f['layer']}: {f['squares']} squares of {f['rules']['size'] * 1e6:g} um, {f['added_area'] * 1e6:.4g} mm^2 added; "
                          f"thickness range {f['before']['thickness_range'] * 1e9:.4g} -> {f['after']['thickness_range'] * 1e9:.4g} nm, "
                          f"hotspots {f['before']['hotspot_count']} -> {f['after']['hotspot_count']} (the table above is the filled die)",
                          highlight=False)
        if out_dir:
            console.print("wrote " + ", ".join(str(p) for p in written), highlight=False)
        return
    die = getattr(result, "die", result)
    d = result.to_dict()

    def um(v, scale=1e9, unit="nm"):
        return "-" if v is None else f"{v * scale:.4g} {unit}"

    rows = [[str(r["index"]), f"{100 * r['density']:.0f} %", um(r["line_width"], 1e6, "um"), f"{r['effective_density']:.3f}", um(r["step_height"]), um(r["dishing"]), um(r["erosion"])]
            for r in d["regions"]]
    console.print(_rich_table(f"die {die.layout.name!r} ({die.process.kind}) after {d['time']:.1f} s", ["region", "density", "line width", "eff. density", "step height", "dishing", "erosion"], rows))
    if d.get("hotspots") and "probability" in d["hotspots"][0]:  # a calibrated run: the hotspots with their intervals
        _print_hotspots(console, d["hotspots"])
    _print_at_risk(console, d.get("at_risk"))
    console.print(f"planarization length {d['planarization_length'] * 1e3:.3g} mm, {d['weighting']} weighting (from the pad stack: "
                  f"{d['planarization_length_gaussian_from_pad'] * 1e3:.3g} mm Gaussian, {d['planarization_length_elliptic_from_pad'] * 1e3:.3g} mm elliptic); "
                  f"blanket rate {die.blanket_rate * 6e10:.4g} nm/min; time to planarize {um(d['time_to_planarize'], 1, 's')}"
                  + (f"; time to clear {um(d['time_to_clear'], 1, 's')}" if d["time_to_clear"] is not None else ""), highlight=False)
    if wafer:
        import numpy as np

        end = ("clear", result.time_to_clear) if d["time_to_clear"] is not None else ("planarize", result.time_to_planarize)
        console.print(f"{len(result.x)} dies; blanket rate {np.min(result.blanket_rate) * 6e10:.4g}-{np.max(result.blanket_rate) * 6e10:.4g} nm/min; "
                      f"time to {end[0]} {np.nanmin(end[1]):.1f}-{np.nanmax(end[1]):.1f} s", highlight=False)
        _print_wafer_risk(console, result)
    if out_dir:
        console.print("wrote " + ", ".join(str(p) for p in written), highlight=False)


def _print_layout_run(console, result, is_stack: bool, wafer: bool) -> None:
    """The terminal summary of a run on a real layout: per level the windows, ranges and hotspots; the worst hotspots."""
    levels = result.levels if is_stack else [getattr(result, "die", result)]

    def nm(v):
        return "-" if v is None else f"{v * 1e9:.4g} nm"

    rows = []
    for lv in levels:
        d = lv.to_dict()
        ny, nx = lv.layout.shape
        rows.append([lv.level or lv.layout.name, lv.process.kind, f"{nx} x {ny} of {lv.layout.cell_size * 1e6:g} um",
                     f"{lv.time:.1f} s", nm(lv.thickness_range), nm(d["step_height_max"]), nm(d["dishing_max"]), nm(d["erosion_max"]),
                     str(d["hotspot_count"])])
    console.print(_rich_table("die on a real layout", ["level", "process", "windows", "time", "thickness range", "step height max",
                                                       "dishing max", "erosion max", "hotspots"], rows))
    whole = result.to_dict() if is_stack else levels[0].to_dict()
    hot = whole["hotspots"]
    if hot:
        _print_hotspots(console, hot)
    _print_at_risk(console, whole.get("at_risk"))
    if wafer:
        import numpy as np

        console.print(f"{len(result.x)} dies ({result.reading} reading); blanket rate {np.min(result.blanket_rate) * 6e10:.4g}-"
                      f"{np.max(result.blanket_rate) * 6e10:.4g} nm/min; hotspots per die {int(np.min(result.hotspot_count))}-"
                      f"{int(np.max(result.hotspot_count))}, {int(np.sum(result.hotspot_count))} on the wafer", highlight=False)
        _print_wafer_risk(console, result)


def _print_hotspots(console, hot) -> None:
    """The ten worst hotspots; a calibrated run (--config with the die's covariance) adds the 95 % interval and the probability of failing."""
    def nm(v):
        return "-" if v is None else f"{v * 1e9:.4g} nm"

    sure = any("probability" in h for h in hot)  # a calibrated run (in a stack, its calibrated levels)

    def spread(h):
        if "probability" not in h:
            return ["-", "-"]  # a level the calibration does not cover
        return [f"{h['interval'][0] * 1e9:.4g}-{h['interval'][1] * 1e9:.4g}", f"{h['probability']:.3f}"]

    levels = any(h.get("level") for h in hot)
    show = [([h.get("level", "")] if levels else []) + [h["kind"], f"{h['x'] * 1e6:.1f}", f"{h['y'] * 1e6:.1f}", nm(h["value"]), nm(h["limit"])]
            + (spread(h) if sure else []) for h in hot[:10]]
    header = (["level"] if levels else []) + ["kind", "x (um)", "y (um)", "value", "limit"] + (["interval nm", "probability"] if sure else [])
    title = f"worst hotspots ({len(hot)} in all" + (f"; 95 % intervals; {sum(h.get('probability', 0.0) > 0.975 for h in hot)} exceed their limit with "
                                                     "probability > 0.975)" if sure else ")")
    console.print(_rich_table(title, header, show))


def _stack_calibration(config_path):
    """The die constants of a process file (--config) for a stack's levels of their process, or None."""
    from ..calibration.processfile import die_constants

    return die_constants(config_path) if config_path else None


def _print_wafer_risk(console, result) -> None:
    """A calibrated wafer of dies: expected hotspots, sure ones and windows at risk, over the wafer."""
    import numpy as np

    if getattr(result, "hotspot_expected", None) is None:
        return
    console.print(f"calibrated: {np.sum(result.hotspot_expected):.1f} hotspots expected on the wafer, {int(np.sum(result.hotspot_sure))} "
                  f"fail for sure (probability > 0.975), {int(np.sum(result.at_risk_count))} windows under their limit at risk; "
                  f"dies with a sure hotspot: {int(np.count_nonzero(result.hotspot_sure))} of {len(result.x)}", highlight=False)


def _print_at_risk(console, risk) -> None:
    """A calibrated run: how many windows pass their limit but may exceed it (95 % interval reaching it), the likeliest five."""
    if risk is None:
        return
    if not risk:
        console.print("no window under its limit has a 95 % interval reaching it (JSON at_risk: [])", highlight=False)
        return
    top = "; ".join(f"{h.get('level', '') + ' ' if h.get('level') else ''}{h['kind']} at ({h['x'] * 1e6:.1f}, {h['y'] * 1e6:.1f}) um "
                    f"{h['value'] * 1e9:.4g} nm, [{h['interval'][0] * 1e9:.4g}, {h['interval'][1] * 1e9:.4g}] nm, p {h['probability']:.3f}"
                    for h in risk[:5])
    console.print(f"{len(risk)} window(s) under their limit may exceed it (95 % interval reaches it; JSON at_risk); likeliest: {top}",
                  highlight=False)


def _calibrated(kwargs: dict, config_path, params, wafer: bool, stack_path) -> dict:
    """The die keywords with the calibrated die constants of a process file (--config) and, except with --wafer, their covariance."""
    from ..calibration.processfile import apply_die_constants, die_constants

    dc = die_constants(config_path) if config_path else None
    if dc is None:
        return kwargs
    if stack_path:
        return kwargs  # a stack applies them level by level, to the levels of their process (simulate_stack(calibration=))
    return apply_die_constants(kwargs, dc, given=tuple(parse_assignments(params)))



def _layers_of(layout) -> str:
    """"; FILE's layers with shapes: ..." for a message (empty if the file cannot be read: its own error comes later)."""
    from ..layout.reader import layer_listing, layers_in, read_layout

    try:
        db = layout if hasattr(layout, "db") else read_layout(layout)
        return f"; {db.name}'s layers with shapes: {layer_listing(layers_in(db))}"
    except Exception:  # noqa: BLE001 - a file that cannot be read is reported by the read itself
        return ""
