"""``cmpsim run``: one operating point, printed, as JSON, or written to a directory."""

from __future__ import annotations

from pathlib import Path

import click

from .group import _fail, _warn, check_out, command_errors, main, out_console, writing_errors
from .inputs import config_options, load_config


@main.command()
@click.argument("config", required=False, type=click.Path(dir_okay=False))
@config_options
@click.option("--json", "as_json", is_flag=True, help="Print exactly one JSON object (SI units) on stdout: schema 2, see cmpsim/data/result.schema.json.")
@click.option("--schema", "schema", type=click.Choice(["1", "2"]), default="2", show_default=True, help="JSON layout of --json and result.json: 2, or the flat object of cmpsim 0.1 (deprecated).")
@click.option("--out", "out_dir", type=click.Path(file_okay=False), help="Also write fields.nc, maps.png, profile.png, result.json and config.toml to DIR.")
@click.option("--check-roots", is_flag=True, help="Scan the attack angle for other equilibria (adds moment_roots_found).")
@click.option(
    "--relative/--no-relative",
    default=None,
    help="Give removal_rate_relative (solves the reference case too); default: only with the paper's removal law (the paper preset).",
)
def run(config, config_path, preset, assignments, grid, as_json, schema, out_dir, check_roots, relative):
    """Solve one operating point (the paper's base case by default).

    CONFIG is an optional TOML file, the same as --config (sections `[wafer]` `[process]`
    `[slurry]` `[pad]` `[numerics]` or flat keys; values with units such as "4 psi" or SI
    numbers). See `cmpsim params`.
    """
    from ..solver.model import solve

    if config and config_path:
        _fail(f"give the configuration once: CONFIG ({config}) or --config ({config_path})")
    try:
        cfg = load_config(config or config_path, assignments, preset, grid)
    except ValueError as exc:
        _fail(str(exc))
    with command_errors():
        if out_dir:
            check_out(out_dir)
        result = solve(cfg, check_roots=check_roots, relative=relative)
    schema = int(schema)
    if schema == 1:
        _warn("--schema 1 (the flat JSON of cmpsim 0.1) is deprecated and will be removed; use schema 2 (cmpsim/data/result.schema.json)")
    if out_dir:
        with writing_errors(out_dir):
            write_outputs(result, Path(out_dir), schema=schema)
    if as_json:
        click.echo(result.to_json(schema=schema))
        return

    console = out_console()
    console.print(result.summary_table(console.width))
    if result.flow_factor_floored_fraction > 0:
        _warn(
            f"the flow-factor tensor was regularised on {100 * result.flow_factor_floored_fraction:.1f} % "
            "of the faces: the film is outside the validity of the perturbation flow factors (docs/model.md)"
        )
    if result.root_scan is not None and len(result.root_scan.roots) != 1:
        roots = ", ".join(f"{r:.3g}" for r in result.root_scan.roots) or "none"
        _warn(
            f"the attack-angle scan found {len(result.root_scan.roots)} moment roots "
            f"(at {roots} rad); the equilibrium above is the one Newton reached from the default start"
        )
    if out_dir:
        console.print(f"wrote {out_dir}/fields.nc, maps.png, profile.png, result.json, config.toml")


def write_outputs(result, out: Path, schema: int = 2) -> None:
    """fields.nc, maps.png, profile.png, result.json, config.toml into ``out`` (each written atomically)."""
    import matplotlib.pyplot as plt

    from ..io import atomic_path, atomic_write_text

    out.mkdir(parents=True, exist_ok=True)
    result.to_netcdf(out / "fields.nc")
    for name, fig in (("maps.png", result.plot()), ("profile.png", result.plot_profiles())):
        with atomic_path(out / name, suffix=".png") as tmp:
            fig.savefig(tmp, dpi=110, format="png")
        plt.close(fig)
    atomic_write_text(out / "result.json", result.to_json(indent=2, schema=schema) + "\n")
    result.config.to_toml(out / "config.toml")
