"""``cmpsim tune-zones``: the zone pressures of a membrane head that flatten the removal profile."""

from __future__ import annotations

import click

from .group import _rich_table, command_errors, main, out_console
from .inputs import config_options, load_config


@main.command(name="tune-zones")
@config_options
@click.option("--bounds", default="0.5,8 psi", show_default=True, metavar="LOW,HIGH UNIT", help="Bounds of every zone pressure.")
@click.option(
    "--keep",
    type=click.Choice(["none", "pressure", "rate"]),
    default=None,
    help="Also keep the zones' mean pressure (the load) or the mean removal rate of the start (inside the edge exclusion), "
    "or nothing ('none': flatness alone, the rate may fall). [default: rate with --ring, none without]",
)
@click.option("--incoming", "incoming", type=click.Path(dir_okay=False), default=None, metavar="FILE.csv", help="Incoming thickness profile to flatten after --polish-time: CSV with header radius_<unit>,thickness_<unit> (e.g. radius_mm,thickness_nm).")
@click.option("--polish-time", "polish_time", default=None, metavar="TIME", help="Polish time with units (e.g. '60 s', '1.5 min'); required with --incoming.")
@click.option("--ring", "ring", is_flag=True, help="Also tune the retaining ring's pressure (retaining_ring_pressure is the start; the layered pad): the edge band is the ring's to shape, not a zone's.")
@click.option("--ring-bounds", "ring_bounds", default=None, metavar="LOW,HIGH UNIT", help="Bounds of the ring pressure with --ring [default: 1.5,9 psi].")
@click.option("--json", "as_json", is_flag=True, help="Print one JSON object (SI): zone_pressures (Pa), within_wafer_nonuniformity (fraction), profile (radius, rate), before; mean_rate and wafer_mean_rate (m/s), keep; with --ring also ring_pressure (Pa); with --incoming also remaining_thickness (radius, thickness; m) and remaining_nonuniformity (fraction).")
def tune_zones_command(config_path, preset, assignments, grid, bounds, keep, incoming, polish_time, ring, ring_bounds, as_json):
    """Find the zone pressures of a membrane head that flatten the removal profile.

    Starts from the configuration's zone_pressures (or applied_pressure in every zone);
    needs --set carrier=membrane and zone_radii. Prints the pressures, the profile before
    and after, and the within-wafer non-uniformity. With --incoming FILE.csv and
    --polish-time, flattens the thickness left after polishing instead. With --ring, the
    retaining ring's pressure is tuned with the zones, keeping the mean removal rate unless
    --keep says otherwise (--keep none lets the rate fall).
    """
    import json

    from ..head.tuning import CLI_NAMES, tune_zones_from_text

    with command_errors():
        cfg = load_config(config_path, assignments, preset, grid)
        if incoming is not None and polish_time is None:
            raise ValueError("--incoming needs --polish-time (e.g. --polish-time '60 s')")
        if polish_time is not None and incoming is None:
            raise ValueError("--polish-time needs --incoming FILE.csv (the incoming thickness profile)")
        result = tune_zones_from_text(cfg, bounds, keep=keep, ring=ring, ring_bounds=ring_bounds, names=CLI_NAMES, incoming=incoming, polish_time=polish_time)
    if as_json:
        click.echo(json.dumps(result.to_dict()))
        return
    psi = 6894.757293168361
    rows = [
        (f"{1e3 * r:.1f}", f"{p0 / psi:.3f}", f"{p1 / psi:.3f}")
        for r, p0, p1 in zip(result.zone_radii, result.before["zone_pressures"], result.zone_pressures)
    ]

    console = out_console()
    if result.ring_pressure is not None:
        rows.append(("ring", f"{result.before['ring_pressure'] / psi:.3f}", f"{result.ring_pressure / psi:.3f}"))
    console.print(_rich_table("zone pressures", ["zone outer radius (mm)", "before (psi)", "tuned (psi)"], rows))
    nm_min = 1e9 * 60.0
    prof = [
        (f"{1e3 * r:.2f}", f"{nm_min * a:.3f}", f"{nm_min * b:.3f}")
        for r, a, b in zip(result.profile["radius"], result.before["profile"]["rate"], result.profile["rate"])
    ]
    console.print(_rich_table("removal-rate profile", ["radius (mm)", "before (nm/min)", "tuned (nm/min)"], prof))
    if result.remaining_thickness is not None:
        left = [
            (f"{1e3 * r:.2f}", f"{1e9 * a:.3f}", f"{1e9 * b:.3f}")
            for r, a, b in zip(result.remaining_thickness["radius"], result.before["remaining_thickness"]["thickness"], result.remaining_thickness["thickness"])
        ]
        console.print(_rich_table(f"remaining thickness after {result.polish_time:g} s", ["radius (mm)", "before (nm)", "tuned (nm)"], left))
        console.print(
            f"remaining-thickness non-uniformity: {100 * result.before['remaining_nonuniformity']:.3f} % -> "
            f"{100 * result.remaining_nonuniformity:.3f} %"
        )
    console.print(
        f"mean removal rate inside the edge exclusion ({'kept' if result.keep == 'rate' else 'not kept'}): "
        f"{nm_min * result.before['mean_rate']:.2f} nm/min -> {nm_min * result.mean_rate:.2f} nm/min; "
        f"over the whole wafer {nm_min * result.before['wafer_mean_rate']:.2f} nm/min -> {nm_min * result.wafer_mean_rate:.2f} nm/min"
    )
    console.print(
        f"within-wafer non-uniformity: {100 * result.before['within_wafer_nonuniformity']:.3f} % -> "
        f"{100 * result.within_wafer_nonuniformity:.3f} % ({result.solves} operating points solved)"
    )
    widths = ", ".join(
        f"{1e3 * b.boundary:g} mm: " + ("no fall" if b.width is None else f"{1e3 * b.width:.1f} mm")
        for b in result.response_widths
    )
    if widths:
        console.print(f"zone response width (10-90 % of a pressure step) at each boundary: {widths}")
