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
