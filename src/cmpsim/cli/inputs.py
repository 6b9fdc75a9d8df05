"""The inputs of every command that solves (``--preset``, ``--config``, ``--set``, ``--grid``)
and ``cmpsim params``, the list of every input."""

from __future__ import annotations

import click

from .group import main, out_console

#: The names of cmpsim.inputs.config.PRESETS (written out so that the command line starts without importing the config; a test keeps them equal).
PRESET_NAMES = ("default", "paper", "300mm")


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


def load_config(config_path, assignments, preset: str | None = None, grid: str | None = None):
    """Config from a preset, an optional TOML file, --set overrides and the grid, in that order (raises ValueError)."""
    from ..inputs.config import Config

    base = Config.preset(preset) if preset else Config.default()
    cfg = Config.from_toml(config_path, base=base) if config_path else base
    cfg = cfg.replace(**parse_assignments(assignments))
    return cfg.replace(grid=grid) if grid else cfg


def recipe_overrides(config_path, assignments) -> dict:
    """The inputs for every step of a recipe (``cmpsim polish``, ``cmpsim lot``): the constants of
    ``--config`` (``cmpsim.inputs.processfile.process_constants``: a process file's fitted constants),
    then ``--set`` (raises ValueError)."""
    from ..inputs.processfile import process_constants

    constants = process_constants(config_path) if config_path else {}
    return {**constants, **parse_assignments(assignments)}


def config_options(command):
    """The options of the inputs, the same on every command that solves: --config, --preset, --set, --grid."""
    for option in reversed(
        [
            click.option("--config", "config_path", type=click.Path(dir_okay=False), help="TOML file of inputs: sections [wafer] [process] [slurry] [pad] [numerics] or flat keys, values with units or SI (e.g. from `cmpsim calibrate`)."),
            click.option("--preset", type=click.Choice(PRESET_NAMES), default=None, help="Start from a named preset: 'paper' is the paper's model exactly; 'default' the predictive model; '300mm' a 300 mm wafer in a five-zone membrane head with a retaining ring on concentrically grooved IC1000/Suba IV, a production oxide recipe (docs/model.md)."),
            click.option("--set", "assignments", multiple=True, metavar="NAME=VALUE", help="Change an input, with units: --set applied_pressure=3psi (repeatable)."),
            click.option("--grid", default=None, metavar="GRID", help="Grid: coarse, default, fine or NRxNT (rings x sectors); default: the configuration's."),
        ]
    ):
        command = option(command)
    return command


@main.command()
@click.option("--markdown", is_flag=True, help="Print the parameter table of docs/model.md.")
def params(markdown):
    """List every input: name, default, unit, valid range and source."""
    from ..inputs.config import PARAMETERS, format_display, parameter_table_markdown

    if markdown:
        click.echo(parameter_table_markdown(), nl=False)
        return

    from ..tables import WIDE, legible_table

    console = out_console()
    rows, detail = [], []
    for n, p in PARAMETERS.items():
        unit = p.display if p.unit not in ("choice", "grid") else ""
        default = format_display(n, p.default) + (f" {unit}" if unit else "") if p.default != () else "unset"
        # narrow terminals: the default above its valid range, both in the display unit
        rows.append((n, default, p.display_range_text()) if console.width >= WIDE else (n, f"{default}\n{p.display_range_text()}"))
        detail.append(f"{p.description}. Source: {p.source}")
    header = ["name", "default", "valid range"] if console.width >= WIDE else ["name", "default / valid range"]
    console.print(legible_table("cmpsim inputs (set with --set NAME=VALUE)", header, rows, detail=detail, detail_header="meaning and source", width=console.width))
