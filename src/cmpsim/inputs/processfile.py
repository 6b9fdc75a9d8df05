"""The constants a process file carries to a recipe (``cmpsim polish --config``, ``cmpsim lot --config``).

A recipe runs on its own tool (its preset and inputs); a configuration file given with it sets only
what it is about: a calibrated process file (with a ``[calibration]`` table,
:mod:`cmpsim.calibration.processfile`) its fitted constants and the model choices they need, any
other configuration file the inputs it names.
"""

from __future__ import annotations

import tomllib
from pathlib import Path

from .config import PARAMETERS, Config

__all__ = ["process_constants"]


def process_constants(path) -> dict:
    """{input: SI value} that the configuration file ``path`` applies to a recipe's steps (ValueError naming the file)."""
    from ..io import read_text

    path = Path(path)
    try:
        data = tomllib.loads(read_text(path, "config file"))
    except tomllib.TOMLDecodeError as exc:
        raise ValueError(f"config file {str(path)!r} is not valid TOML: {exc}") from None
    table = data.get("calibration")
    try:
        config = Config.from_mapping(data)  # every value checked
    except ValueError as exc:  # say which file holds the bad key or value, as Config.from_toml does
        raise ValueError(f"config file {str(path)!r}: {exc}") from None
    if isinstance(table, dict):
        names = list(table.get("settings", [])) + list(table.get("constants", []))
        unknown = [n for n in names if n not in PARAMETERS]
        if unknown:
            raise ValueError(f"config file {str(path)!r}: [calibration] names unknown inputs {', '.join(unknown)}")
        given = {k for k, v in data.items() if k != "calibration" and not isinstance(v, dict)}
        given |= {k for v in data.values() if isinstance(v, dict) for k in v}
        absent = [n for n in names if n not in given]
        if absent:  # a fitted constant taken out of the file by hand: the default would stand in for it silently
            raise ValueError(f"config file {str(path)!r}: [calibration] lists {', '.join(absent)}, which the file does not set "
                             f"(put back {PARAMETERS[absent[0]].section}.{absent[0]} = its fitted value in SI, or rerun cmpsim calibrate)")
        return {n: getattr(config, n) for n in names}
    named = []
    for key, value in data.items():
        if key == "preset":
            raise ValueError(f"config file {str(path)!r}: preset = {value!r} would replace the recipe's tool; a recipe names its own preset")
        named += list(value) if isinstance(value, dict) else [key]
    return {n: getattr(config, n) for n in named}
