"""Requests in, answers out: a request body to a :class:`~cmpsim.inputs.config.Config`, results and the
registries to JSON.

Bad input raises :class:`InputError` with cmpsim's own message and the parameter it names, which
the application answers as HTTP 422 ``{"detail": ..., "parameter": ...}``
(:func:`error_response`). JSON has no NaN: a value that is not finite goes out as ``null``
(:func:`finite`).
"""

from __future__ import annotations

import math
import re
from typing import Any

from fastapi.responses import JSONResponse

from .. import __version__

__all__ = [
    "SECTIONS",
    "InputError",
    "error_response",
    "named_parameter",
    "setting_names",
    "check_scalars",
    "config_from_request",
    "finite",
    "fields_payload",
    "maps_payload",
    "params_payload",
    "outputs_payload",
    "validation_payload",
]

#: The sections of a config file, which a request body may use as in TOML.
SECTIONS = ("wafer", "process", "slurry", "pad", "numerics")


class InputError(ValueError):
    """Bad input: HTTP 422 with the message and the parameter it concerns (or None)."""

    def __init__(self, message: str, parameter: str | None = None):
        super().__init__(message)
        self.parameter = parameter


def error_response(status: int, detail: str, parameter: str | None = None, headers: dict | None = None) -> JSONResponse:
    """The answer of every error: ``{"detail": message, "parameter": name or null}``."""
    return JSONResponse({"detail": detail, "parameter": parameter}, status_code=status, headers=headers)


def named_parameter(message: str, candidates) -> str | None:
    """The candidate name that the message mentions first (cmpsim's messages name the parameter)."""
    best = None
    for name in set(candidates):
        m = re.search(rf"(?<![A-Za-z0-9_]){re.escape(name)}(?![A-Za-z0-9_])", message)
        if m and (best is None or m.start() < best[0]):
            best = (m.start(), name)
    return best[1] if best else None


def setting_names(data: Any) -> list[str]:
    """Every setting name in a flat or sectioned mapping of inputs."""
    out: list[str] = []
    if isinstance(data, dict):
        for k, v in data.items():
            if k in SECTIONS and isinstance(v, dict):
                out += [str(kk) for kk in v]
            out.append(str(k))
    return out


def check_scalars(data: dict, where: str = "") -> None:
    """Refuse a JSON value that is no number or string (an object, array, boolean or null) for an input."""
    from ..inputs.config import PARAMETERS

    for key, value in data.items():
        if key in SECTIONS and isinstance(value, dict):
            check_scalars(value, where)
            continue
        if key not in PARAMETERS:
            continue  # cmpsim says "unknown parameter" with the known names
        if PARAMETERS[key].items and isinstance(value, list) and all(isinstance(v, (str, int, float)) and not isinstance(v, bool) for v in value):
            continue  # a list input as a JSON array (SI numbers or strings with units)
        if isinstance(value, bool) or not isinstance(value, (str, int, float)):
            kind = "null" if value is None else type(value).__name__.replace("dict", "object").replace("list", "array")
            raise InputError(f'{where}{key}: expected a number (SI) or a string with units such as "3 psi"; got a JSON {kind}', key)


def config_from_request(data: Any):
    """The :class:`~cmpsim.inputs.config.Config` of a request body (flat or sectioned; units or SI numbers)."""
    from ..inputs.config import Config

    if data is None:
        data = {}
    if not isinstance(data, dict):
        raise InputError('the request body must be a JSON object of inputs, e.g. {"applied_pressure": "3 psi"}')
    check_scalars(data)
    try:
        return Config.from_mapping(data)
    except ValueError as exc:
        raise InputError(str(exc), named_parameter(str(exc), setting_names(data))) from None


def finite(v):
    """``v`` for JSON: a float that is not finite becomes None (``null``); anything else is unchanged."""
    if isinstance(v, float) and not math.isfinite(v):
        return None
    return v


def maps_payload(ds, names: list[str] | None, parameter: str = "fields", default: list[str] | None = None) -> dict:
    """The (y, x) maps of an ``xarray.Dataset`` as JSON: ``x``, ``y``, ``units`` and ``maps`` {name: {units, long_name, z}}.

    ``names`` chooses the maps (unknown ones: :class:`InputError` naming ``parameter``); else
    ``default``, else every map. A value that is not finite goes out as null.
    """
    import numpy as np

    available = [k for k in ds.data_vars if ds[k].dims == ("y", "x")]
    if names:
        unknown = [n for n in names if n not in available]
        if unknown:
            raise InputError(f"{parameter}: unknown field(s) {', '.join(unknown)}; available: {', '.join(available)}", parameter)
    else:
        names = [n for n in default if n in available] if default else available
    maps = {}
    for name in names:
        z = np.asarray(ds[name].values, dtype=float)
        rows = [[float(f"{v:.6g}") if math.isfinite(v) else None for v in row] for row in z.tolist()]
        maps[name] = {"units": ds[name].attrs.get("units", ""), "long_name": ds[name].attrs.get("long_name", name), "z": rows}
    return {
        "x": [float(v) for v in ds["x"].values],
        "y": [float(v) for v in ds["y"].values],
        "units": {"x": ds["x"].attrs.get("units", "m"), "y": ds["y"].attrs.get("units", "m")},
        "maps": maps,
    }


def fields_payload(result, names: list[str] | None) -> dict:
    """The wafer maps of :attr:`cmpsim.results.result.Result.fields` as JSON (NaN outside the wafer -> null)."""
    return maps_payload(result.fields, names, "fields")


def params_payload() -> dict:
    """``GET /api/params``: every input with its section, unit, display unit, default, range, source and choices."""
    from ..inputs.config import PARAMETERS, format_display, to_display

    def shown(name, v):
        if v is None:
            return None
        try:
            return float(to_display(name, v))
        except Exception:  # pragma: no cover - a unit pint cannot convert: show SI
            return v

    out = []
    for n, p in PARAMETERS.items():
        kind = "choice" if p.choices else ("grid" if p.unit == "grid" else ("list" if p.items else "number"))
        out.append(
            {
                "name": n,
                "section": p.section,
                "symbol": p.symbol,
                "kind": kind,
                "unit": "" if kind not in ("number", "list") else p.unit,
                "display_unit": "" if kind not in ("number", "list") else p.display,
                "default": list(p.default) if kind == "list" else p.default,
                "default_display": format_display(n, p.default),
                "description": p.description,
                "source": p.source,
                "range": p.range_text(),
                "low": p.low,
                "high": p.high,
                "low_open": p.low_open,
                "high_open": p.high_open,
                "low_display": shown(n, p.low) if kind == "number" else None,
                "high_display": shown(n, p.high) if kind == "number" else None,
                "choices": list(p.choices),
            }
        )
    return {"cmpsim_version": __version__, "sections": list(SECTIONS), "parameters": out}


def outputs_payload() -> list[dict]:
    """``GET /api/outputs``: every scalar output of the registry with its SI and display units."""
    from ..results import outputs

    return [
        {"name": o.name, "kind": o.kind, "unit": o.unit, "display_unit": o.display_unit, "display_factor": o.display_factor, "long_name": o.long_name}
        for o in (outputs.scalar(n) for n in outputs.scalar_names())
    ]


def validation_payload(report) -> dict:
    """``POST /api/validate``: the tables ``cmpsim validate`` prints and each point's numbers."""
    return {
        "points": {"header": list(report.POINT_HEADER), "rows": report.point_rows()},
        "datasets": {"header": list(report.DATASET_HEADER), "rows": report.dataset_rows()},
        "records": [{k: finite(v) for k, v in p.as_row().items()} for p in report.points],
        "equilibria": report.equilibria,
        "elapsed_s": report.elapsed_s,
    }
