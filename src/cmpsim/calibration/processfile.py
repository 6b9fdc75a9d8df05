"""The process file of a calibration: the fitted configuration and its ``[calibration]`` table.

Every command's ``--config`` takes it as a configuration (the ``[calibration]`` table is read as
metadata, :meth:`cmpsim.inputs.config.Config.from_mapping`). ``cmpsim polish`` and ``cmpsim lot`` run
a recipe on its own tool and take from it only the constants the table lists
(``cmpsim.inputs.processfile.process_constants``). The table::

    [calibration]
    constants = ["mechanical_factor_copper", ...]   # the fitted inputs
    settings = ["film_chemistry"]                   # model choices they need
    data = ["tugbawa2002_cu_blanket.csv"]
    chi2_before, chi2_after, dof, rms_before, rms_after
    [calibration.ci95]          name = [low, high]   (SI, 95 %)
    [calibration.stderr]        name = value         (SI)
    [calibration.correlation]   names = [...], matrix = [[...]]
"""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np

__all__ = ["calibration_table", "write_process_file"]


def _finite(x: float) -> float | str:
    return float(x) if math.isfinite(x) else ("inf" if x > 0 else "-inf" if x < 0 else "nan")


def calibration_table(result) -> dict:
    """The ``[calibration]`` table of a :class:`cmpsim.calibration.CalibrationResult` (SI, TOML-ready)."""
    corr = np.asarray(result.correlation, dtype=float)
    return {
        "constants": list(result.free),
        "settings": sorted(result.settings),
        "data": [Path(d).name for d in result.data],
        "chi2_before": _finite(result.chi2_before),
        "chi2_after": _finite(result.chi2_after),
        "dof": int(result.dof),
        "rms_before": _finite(result.rms_before),
        "rms_after": _finite(result.rms_after),
        "identifiability": list(result.identifiability),
        "ci95": {n: [_finite(lo), _finite(hi)] for n, (lo, hi) in result.ci95.items()},
        "stderr": {n: _finite(v) for n, v in result.stderr.items()},
        "correlation": {"names": list(result.free), "matrix": [[_finite(v) for v in row] for row in corr.reshape(len(result.free), len(result.free))]},
    }


def write_process_file(result, path) -> Path:
    """Write the fitted configuration with its ``[calibration]`` table to ``path`` (TOML, SI), atomically."""
    import tomli_w

    from ..io import atomic_write_text

    text = "# cmpsim process file from `cmpsim calibrate`; every value in SI units (see `cmpsim params`)\n"
    text += "# [calibration] lists the fitted constants: `cmpsim polish` and `cmpsim lot` apply those with the recipe's own tool\n"
    text += result.config.to_toml_text() + "\n" + tomli_w.dumps({"calibration": calibration_table(result)})
    atomic_write_text(Path(path), text)
    return Path(path)


# ----------------------------------------------------------------------------- every scale in one file


def _matrix(names, corr) -> dict:
    corr = np.asarray(corr, dtype=float).reshape(len(names), len(names))
    return {"names": list(names), "matrix": [[_finite(v) for v in row] for row in corr]}


def _scale_table(cal, unit_of) -> dict:
    """The table of a die or pad calibration (SI): constants, 95 % intervals, standard errors, correlations, residuals."""
    out = {
        "fitted": list(cal.free),
        "ci95": {n: [_finite(lo), _finite(hi)] for n, (lo, hi) in cal.ci95.items()},
        "stderr": {n: _finite(v) for n, v in cal.stderr.items()},
        "correlation": _matrix(cal.free, cal.correlation),
        "chi2": _finite(cal.chi2),
        "dof": int(cal.dof),
        "rms_before": _finite(float(np.sqrt(np.nanmean(cal.residuals_before ** 2)))),
        "rms_after": _finite(float(np.sqrt(np.nanmean(cal.residuals_after ** 2)))),
        "identifiability": list(cal.identifiability),
        "units": {n: unit_of(n) for n in cal.free},
    }
    return out


def scales_table(cal) -> dict:
    """The ``[calibration]`` table of a :class:`cmpsim.calibration.scales.ScaleCalibration`: the film's as
    :func:`calibration_table`, the pad's constants added to ``constants`` (inputs a recipe takes) with a
    ``[calibration.pad]`` table, and a ``[calibration.die]`` table (the die constants and the fit's covariance)."""
    from .die import DIE_CONSTANTS
    from .thermal import THERMAL_CONSTANTS

    table = calibration_table(cal.film) if cal.film is not None else {"constants": [], "settings": [], "ci95": {}, "stderr": {}}
    table["data"] = [Path(d).name for d in cal.data]
    if cal.pad is not None:
        table["constants"] = list(table["constants"]) + [n for n in cal.pad.free if n not in table["constants"]]
        table["ci95"].update({n: [_finite(lo), _finite(hi)] for n, (lo, hi) in cal.pad.ci95.items()})
        table["stderr"].update({n: _finite(v) for n, v in cal.pad.stderr.items()})
        table["pad"] = _scale_table(cal.pad, lambda n: THERMAL_CONSTANTS[n][0]) | {"constants": {n: float(v) for n, v in cal.pad.values.items()}}
        if cal.pad_base is None:  # the records' base: the 300mm preset on the coarse grid (what `cmpsim validate` compares on)
            table["pad"] |= {"base_preset": "300mm", "base_grid": "coarse"}
    if cal.die is not None:
        die = _scale_table(cal.die, lambda n: DIE_CONSTANTS[n][0])
        die["process"] = cal.die.records[0].process
        die["constants"] = {n: float(v) for n, v in cal.die.constants.items()}
        try:
            die["uncertainty"] = cal.die.uncertainty().to_dict()
        except ValueError as exc:  # an infinite covariance: the constants apply, without intervals on the hotspots
            die["uncertainty_note"] = f"no covariance written: {exc}"
        table["die"] = die
    if getattr(cal, "padlife", None) is not None:
        from ..physics.padlife import GLAZING_CONSTANTS

        pl = _scale_table(cal.padlife, lambda n: GLAZING_CONSTANTS[n][0])
        pl["constants"] = {n: float(v) for n, v in cal.padlife.constants.items()}  # every constant the lot runs with: fitted or default
        pl["lot"] = cal.padlife.table()
        pl["fixed"] = [f"{n}: {why}" for n, why in cal.padlife.left]  # what the lot could not separate, and why
        pl["warnings"] = list(cal.padlife.warnings)
        table["padlife"] = pl
    return table


def write_scales_file(cal, path) -> Path:
    """Write one process file of every scale calibrated (TOML, SI), atomically."""
    import tomli_w

    from ..io import atomic_write_text

    text = "# cmpsim process file from `cmpsim calibrate`; every value in SI units (see `cmpsim params`)\n"
    text += "# [calibration] lists the fitted constants: `cmpsim polish` and `cmpsim lot` apply those with the recipe's own tool;\n"
    text += "# [calibration.die] holds the die constants and their covariance, which `cmpsim die --config` applies;\n"
    text += "# [calibration.padlife] the pad life's glazing and conditioning constants, which `cmpsim lot --config` applies\n"
    text += cal.config.to_toml_text() + "\n" + tomli_w.dumps({"calibration": scales_table(cal)})
    atomic_write_text(Path(path), text)
    return Path(path)


# ----------------------------------------------------------------------------- the die constants back


class DieConstants:
    """The die constants of a process file: ``process`` (copper | oxide), ``constants`` {name: SI} and
    ``uncertainty`` (:class:`cmpsim.die.uncertainty.DieUncertainty`, None without a covariance)."""

    def __init__(self, process: str, constants: dict, uncertainty=None, source: str = ""):
        self.process, self.constants, self.uncertainty, self.source = process, dict(constants), uncertainty, source


def read_scale_table(source, key: str):
    """(the ``[calibration.<key>]`` table of a process file, the name messages use): ``source`` is a path or its
    parsed mapping (a dict, e.g. the JSON of the web page's inputs); the table is None where there is none.
    ValueError naming the file when it is not TOML."""
    import tomllib

    if isinstance(source, dict):
        data, name = source, "the inputs"
    else:
        from ..io import read_text

        name = f"config file {str(source)!r}"
        try:
            data = tomllib.loads(read_text(Path(source), "config file"))
        except tomllib.TOMLDecodeError as exc:
            raise ValueError(f"{name} is not valid TOML: {exc}") from None
    table = data.get("calibration")
    return (table.get(key) if isinstance(table, dict) else None), name


def die_constants(source) -> DieConstants | None:
    """The ``[calibration.die]`` table of a process file (a path) or of its parsed mapping (a dict, e.g. the
    JSON of the web page's inputs); None where there is none. ValueError naming the file and the key."""
    from ..die.process import PROCESSES
    from ..die.uncertainty import DieUncertainty
    from .die import DIE_CONSTANTS

    die, name = read_scale_table(source, "die")
    if die is None:
        return None
    where = f"{name}: [calibration.die]"
    if not isinstance(die, dict):
        raise ValueError(f"{where} must be a table")
    process = die.get("process")
    if process not in PROCESSES:
        raise ValueError(f"{where}: process = {process!r} must be one of {', '.join(PROCESSES)}")
    consts = die.get("constants", {})
    if not isinstance(consts, dict):
        raise ValueError(f"{where}: constants must be a table of name = SI value")
    out = {}
    for n, v in consts.items():
        if n not in DIE_CONSTANTS:
            raise ValueError(f"{where}: constants.{n} is not a die constant; valid: {', '.join(DIE_CONSTANTS)}")
        lo, hi = DIE_CONSTANTS[n][1]
        if isinstance(v, bool) or not isinstance(v, (int, float)) or not (lo <= float(v) <= hi):
            raise ValueError(f"{where}: constants.{n} = {v!r} must be a number in [{lo:g}, {hi:g}] {DIE_CONSTANTS[n][0]}")
        out[n] = float(v)
    unc = None
    if "uncertainty" in die:
        raw = die["uncertainty"]
        lacking = [k for k in ("names", "values", "covariance_log") if k not in raw] if isinstance(raw, dict) else None
        if lacking is None or lacking:
            raise ValueError(f"{where}: uncertainty must be a table with names, values and covariance_log"
                             + (f"; {', '.join(lacking)} missing" if lacking else f"; got {raw!r}"))
        try:
            unc = DieUncertainty.from_dict(raw)
        except (KeyError, TypeError, ValueError) as exc:
            raise ValueError(f"{where}: uncertainty: {exc}") from None
        missing = [n for n in unc.names if n not in out]
        if missing:
            raise ValueError(f"{where}: uncertainty names {', '.join(missing)}, which constants does not give")
        differ = [n for n, v in zip(unc.names, unc.values) if not math.isclose(v, out[n], rel_tol=1e-9)]
        if differ:  # the uncertainty's values are the ones the die model runs with: two values, one silently dropped
            n = differ[0]
            raise ValueError(f"{where}: uncertainty.values gives {n} = {unc.values[unc.names.index(n)]!r}, constants.{n} = {out[n]!r}; "
                             "they must agree (edit both, or rerun cmpsim calibrate)")
    return DieConstants(process, out, unc, name)


def apply_die_constants(kwargs: dict, dc: DieConstants | None, *, given: tuple = (), with_uncertainty: bool = True,
                        option: dict | None = None) -> dict:
    """The keywords of :func:`cmpsim.die.simulate` (``kwargs``: process, planarization_length, weighting, die
    inputs, ...) with the calibrated die constants of ``dc`` applied, and its ``uncertainty`` if ``with_uncertainty``.

    ``given``: the die inputs the user set (``--param``); ``option``: how the messages name the
    options (keys ``process``, ``planarization_length``, ``weighting``, ``param``). ValueError
    where the run and the calibration disagree.
    """
    if dc is None:
        return kwargs
    opt = {"process": "--process", "planarization_length": "--planarization-length", "weighting": "--weighting", "param": "--param"}
    opt.update(option or {})
    out = dict(kwargs)
    proc = out.get("process") or "oxide"
    if proc != dc.process:
        raise ValueError(f"{opt['process']} {proc}: the die constants of {dc.source} were calibrated on {dc.process} structures; "
                         f"run with {opt['process']} {dc.process}")
    clash = [n for n in given if n in dc.constants]
    if clash:
        raise ValueError(f"{opt['param']} {', '.join(clash)}: calibrated in {dc.source}; leave it to the process file or use a file without it")
    consts = dict(dc.constants)
    if "planarization_length" in consts:
        if out.get("planarization_length") is not None:
            raise ValueError(f"{opt['planarization_length']} and the planarization_length calibrated in {dc.source}: give one")
        if out.get("weighting", "gaussian") != "gaussian":
            raise ValueError(f"{opt['weighting']} {out.get('weighting')}: the planarization_length calibrated in {dc.source} is the Gaussian "
                             f"weighting's; use {opt['weighting']} gaussian")
    unc = dc.uncertainty if with_uncertainty else None
    if unc is not None:
        for n in unc.names:
            consts.pop(n)
        out["uncertainty"] = unc
    if "planarization_length" in consts:
        out["planarization_length"] = consts.pop("planarization_length")
    out.update(consts)
    return out


def pad_base(source, config):
    """The base configuration of pad records under a process file (``source``: its path, or None): the pad's
    calibration base (the 300mm preset on the coarse grid) with the file's pad constants, else ``config``;
    without a file None (the default base of :func:`cmpsim.calibration.thermal.predict_thermal`)."""
    from ..inputs.config import Config

    if source is None:
        return None
    pad, _ = read_scale_table(source, "pad")
    if isinstance(pad, dict) and pad.get("base_preset"):
        base = Config.preset(str(pad["base_preset"])).replace(grid=str(pad.get("base_grid", "coarse")))
        return base.replace(friction_coefficient=config.friction_coefficient, pad_heat_transfer_coefficient=config.pad_heat_transfer_coefficient)
    return config
