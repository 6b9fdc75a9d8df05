"""Command line: ``cmpsim run | params | sweep | reproduce | validate | calibrate | tune-zones | polish | serve | die``.

A thin layer over the Python API: every command calls the function of the same name.
Bad input exits with status 2 and a message naming the parameter and its valid range;
an operating point without equilibrium exits with status 3 and the diagnosis.

Every command that solves takes its inputs the same way (:func:`config_options`): a preset
(``--preset``), then a TOML file (``--config FILE``), then changes (``--set NAME=VALUE``,
repeatable) and the grid (``--grid``), in that order. ``cmpsim run FILE`` is the same as
``cmpsim run --config FILE``.

The group and what the commands share live in :mod:`cmpsim.cli.group`, the inputs in
:mod:`cmpsim.cli.inputs`, and each command in a module of its own (``point`` is
``cmpsim run``); importing this package registers every command on :func:`main`.
"""

from __future__ import annotations

from . import calibrate, die, point, polish, reproduce, serve, sweep, tune_zones, validate  # noqa: F401 - each registers its command on main
from .calibrate import _ListOptionsCommand, _split_names, calibrate_command
from .die import die_command
from .group import _PACKAGE, EXIT_INPUT, EXIT_NO_EQUILIBRIUM, _fail, _rich_table, _warn, main, show_warning
from .inputs import PRESET_NAMES, config_options, load_config, params, parse_assignments
from .point import run, write_outputs
from .polish import polish_command
from .reproduce import reproduce_command
from .serve import serve_command
from .sweep import sweep_command
from .tune_zones import tune_zones_command
from .validate import validate_command

__all__ = [
    "main",
    "EXIT_INPUT",
    "EXIT_NO_EQUILIBRIUM",
    "parse_assignments",
    "load_config",
    "config_options",
    "PRESET_NAMES",
    "show_warning",
    "run",
    "write_outputs",
    "params",
    "sweep_command",
    "reproduce_command",
    "validate_command",
    "calibrate_command",
    "tune_zones_command",
    "polish_command",
    "serve_command",
    "die_command",
]
