"""Command line: ``cmpsim run | params | sweep | reproduce | validate | calibrate``.

A thin layer over the Python API: every command calls the function of the same name.
Bad input exits with status 2 and a message naming the parameter and its valid range;
an operating point without equilibrium exits with status 3 and the diagnosis.
"""

from __future__ import annotations

import sys
from pathlib import Path

import click

EXIT_INPUT = 2
EXIT_NO_EQUILIBRIUM = 3


def _fail(message: str, code: int = EXIT_INPUT):
    click.echo(f"cmpsim: error: {message}", err=True)
    sys.exit(code)


def parse_assignments(items) -> dict[str, str]:
    """``["NAME=VALUE", ...]`` -> {NAME: VALUE}; ValueError on a malformed item."""
    out = {}
    for item in items:
        if "=" not in item:
            raise ValueError(f"--set expects NAME=VALUE (e.g. applied_pressure=4psi); got {item!r}")
        name, value = item.split("=", 1)
        name = name.strip().replace("-", "_")
        if not name:
            raise ValueError(f"--set expects NAME=VALUE; got {item!r}")
        out[name] = value.strip()
    return out


def load_config(config_path, assignments):
    """Config from an optional TOML file plus --set overrides (raises ValueError)."""
    from .config import Config

    cfg = Config.from_toml(config_path) if config_path else Config.default()
    return cfg.replace(**parse_assignments(assignments))


def _rich_table(title, header, rows):
    from rich.table import Table

    t = Table(title=title, show_lines=False)
    for i, h in enumerate(header):
        t.add_column(h, justify="right" if i == 1 else "left")
    for r in rows:
        t.add_row(*[str(c) for c in r])
    return t


@click.group(context_settings={"help_option_names": ["-h", "--help"]})
@click.version_option(package_name="cmpsim")
def main():
    """cmpsim: wafer-scale CMP simulator (grain-flow lubrication + pad asperity contact)."""


@main.command()
@click.argument("config", required=False, type=click.Path(dir_okay=False))
@click.option("--set", "assignments", multiple=True, metavar="NAME=VALUE", help="Change an input, with units: --set applied_pressure=3psi (repeatable).")
@click.option("--json", "as_json", is_flag=True, help="Print exactly one JSON object (SI units) on stdout.")
@click.option("--out", "out_dir", type=click.Path(file_okay=False), help="Also write fields.nc, maps.png, result.json and config.toml to DIR.")
def run(config, assignments, as_json, out_dir):
    """Solve one operating point (the paper's base case by default).

    CONFIG is an optional TOML file (sections [wafer] [process] [slurry] [pad] [numerics]
    or flat keys; values with units such as "4 psi" or SI numbers). See `cmpsim params`.
    """
    from .equilibrium import EquilibriumError
    from .model import solve

    try:
        cfg = load_config(config, assignments)
    except ValueError as exc:
        _fail(str(exc))
    try:
        result = solve(cfg)
    except EquilibriumError as exc:
        _fail(f"no equilibrium: {exc}", EXIT_NO_EQUILIBRIUM)
    except ValueError as exc:
        _fail(str(exc))
    if out_dir:
        write_outputs(result, Path(out_dir))
    if as_json:
        click.echo(result.to_json())
        return
    from rich.console import Console

    console = Console()
    console.print(
        _rich_table(
            f"cmpsim {cfg.model}: one operating point (grid {cfg.grid_shape[0]}x{cfg.grid_shape[1]})",
            ["output", "value", "unit", "meaning"],
            result.summary_rows(),
        )
    )
    if result.flow_factor_floored_fraction > 0:
        console.print(
            f"[yellow]warning: the flow-factor tensor was regularised on {100 * result.flow_factor_floored_fraction:.1f} % "
            "of the faces: the film is outside the validity of the perturbation flow factors (docs/model.md)[/yellow]"
        )
    if out_dir:
        console.print(f"wrote {out_dir}/fields.nc, maps.png, result.json, config.toml")


def write_outputs(result, out: Path) -> None:
    """fields.nc, maps.png, result.json, config.toml into ``out`` (each written atomically)."""
    from .io import atomic_path, atomic_write_text

    out.mkdir(parents=True, exist_ok=True)
    result.to_netcdf(out / "fields.nc")
    fig = result.plot()
    with atomic_path(out / "maps.png", suffix=".png") as tmp:
        fig.savefig(tmp, dpi=110, format="png")
    import matplotlib.pyplot as plt

    plt.close(fig)
    atomic_write_text(out / "result.json", result.to_json(indent=2) + "\n")
    result.config.to_toml(out / "config.toml")


@main.command()
@click.option("--markdown", is_flag=True, help="Print the parameter table of docs/model.md.")
def params(markdown):
    """List every input: name, default, unit, valid range and source."""
    from .config import PARAMETERS, format_display, parameter_table_markdown

    if markdown:
        click.echo(parameter_table_markdown(), nl=False)
        return
    from rich.console import Console

    rows = [(n, format_display(n, p.default), p.display or "-", p.range_text(), p.source) for n, p in PARAMETERS.items()]
    Console().print(_rich_table("cmpsim inputs (set with --set NAME=VALUE)", ["name", "default", "unit", "valid range (SI)", "source"], rows))


if __name__ == "__main__":  # pragma: no cover
    main()
