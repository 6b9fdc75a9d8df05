"""What may be fitted, and the checks of a calibration request: names, data, start, bounds.

Every problem of a request raises :class:`CalibrationError` here, before the first fit
evaluation.
"""

from __future__ import annotations

import math
from typing import Any

from ..inputs.config import PARAMETERS, Config, parse_value
from ..validation import Dataset

__all__ = ["CALIBRATABLE", "CalibrationError", "default_bounds", "fitted_in_log", "fit_scale_of", "required_settings"]


def _calibratable(name: str) -> bool:
    p = PARAMETERS[name]
    return not p.choices and p.unit != "grid" and p.section != "numerics"


#: Parameters that may be fitted (every numeric, non-numerical-setting input).
CALIBRATABLE = tuple(n for n in PARAMETERS if _calibratable(n))


class CalibrationError(ValueError):
    """Bad calibration request (unknown or fixed parameter, bad bounds, unusable data)."""


def _positive(name: str) -> bool:
    p = PARAMETERS[name]
    return p.low is not None and p.low >= 0.0


def fitted_in_log(name: str, start: float) -> bool:
    """Whether ``name`` is fitted as z = ln(value / start): a positive input with a positive start whose
    outputs are not linear in it (the film chemistry's constants are fitted linearly)."""
    return _positive(name) and start > 0 and not PARAMETERS[name].linear


def fit_scale_of(name: str, start: float) -> float:
    """The scale of a linearly fitted input's variable z = (value - start) / scale (SI)."""
    typical = PARAMETERS[name].typical
    return max(abs(start), typical or 0.0, 1e-12)


def required_settings(name: str) -> dict:
    """The model choices an input needs to act: the film chemistry's constants need ``film_chemistry = 'additive'``."""
    from ..physics.chemistry import input_names
    from ..physics.materials import FILMS

    chemistry = {n for f in FILMS for n in input_names(f)}
    return {"film_chemistry": "additive"} if name in chemistry else {}


def default_bounds(name: str, start: float) -> tuple[float, float]:
    """Default bounds: a factor 10 either side of ``start`` for positive inputs, within the valid range."""
    p = PARAMETERS[name]
    if p.linear:  # outputs linear in it (film chemistry): from its lower limit to 100 typical values above the start
        lo, hi = (p.low if p.low is not None else start - 100.0 * p.typical), start + 100.0 * (p.typical or max(abs(start), 1.0))
        if p.low is not None and p.low_open:
            lo = p.low + 1e-9 * max(abs(p.low), 1.0)
        return lo, hi
    if _positive(name) and start > 0:
        lo, hi = start / 10.0, start * 10.0
    else:
        span = 10.0 * max(abs(start), 1.0)
        lo, hi = start - span, start + span
    if p.low is not None and lo <= p.low:
        lo = p.low + (1e-9 * max(abs(p.low), 1.0) if p.low_open else 0.0)
    if p.high is not None and hi >= p.high:
        hi = p.high - (1e-9 * max(abs(p.high), 1.0) if p.high_open else 0.0)
    return lo, hi


def free_names(free) -> list[str]:
    """The names to fit, normalised (``pad-modulus`` -> ``pad_modulus``) and checked."""
    if isinstance(free, str):
        free = [free]
    free = [f.strip().replace("-", "_") for f in free]
    if not free:
        raise CalibrationError("give at least one parameter to fit (--free NAME ...), or none at all to let the data choose")
    for n in free:
        if n not in PARAMETERS:
            raise CalibrationError(f"unknown parameter {n!r} in --free; fittable: {', '.join(CALIBRATABLE)}")
        if not _calibratable(n):
            raise CalibrationError(f"parameter {n!r} cannot be fitted (a choice or numerical setting); fittable: {', '.join(CALIBRATABLE)}")
    if len(set(free)) != len(free):
        raise CalibrationError(f"a parameter is repeated in --free: {', '.join(free)}")
    return free


def check_data(datasets: list[Dataset], free: list[str], include_model_predictions: bool) -> None:
    """Refuse another model's predictions (unless asked), free names that the data set per point, and a
    point of value 0 without an uncertainty (its relative error, the weight of a point without one, has no scale)."""
    for d in datasets:
        for p in d.points:
            if p.value == 0 and p.uncertainty is None and p.comparison in ("absolute", "range"):
                where = f"{d.path}:{p.line}: row {p.row}" if d.path is not None else f"data set {d.name!r}, line {p.line}"
                raise CalibrationError(f"{where}, column 'uncertainty': a measured {p.quantity} of 0 needs its uncertainty (> 0, in {p.unit}): "
                                       "without one a point is weighted by its relative error, which a value of 0 does not have")
    if not include_model_predictions:
        bad = [d.name for d in datasets if d.kind == "model_prediction"]
        if bad:
            raise CalibrationError(f"data set(s) {', '.join(bad)} hold another model's predictions, not measurements; refusing to calibrate against them")
    for d in datasets:
        for p in d.points:
            clash = [n for n in free if n in p.conditions or (n == "rotation_speed" and "sliding_speed" in p.conditions)]
            if clash:
                raise CalibrationError(f"parameter {clash[0]!r} is set per point by data set {d.name!r} (line {p.line}); it cannot be fitted")


def start_config(config: Config | None, grid: str | None, start: dict[str, Any] | None, free: list[str]) -> Config:
    """The starting configuration: ``config`` (default :meth:`Config.default`) with ``grid`` and ``start``."""
    base = config or Config.default()
    if grid is not None:
        base = base.replace(grid=grid)
    if start:
        unknown = [k for k in start if k not in free]
        if unknown:
            raise CalibrationError(f"start values given for parameters that are not free: {', '.join(unknown)}")
        base = base.replace(**start)
    return base


def fit_bounds(free: list[str], bounds: dict[str, tuple[Any, Any]] | None, start: dict[str, float], log: dict[str, bool]) -> dict[str, tuple[float, float]]:
    """SI bounds of every free name: given (with units) or :func:`default_bounds`."""
    bnds: dict[str, tuple[float, float]] = {}
    for n in free:
        if bounds and n in bounds:
            lo_t, hi_t = bounds[n]
            try:
                lo, hi = parse_value(n, lo_t), parse_value(n, hi_t)
            except ValueError as exc:
                raise CalibrationError(f"bounds of {n}: {exc}") from None
        else:
            lo, hi = default_bounds(n, start[n])
        if not lo < hi:
            raise CalibrationError(f"bounds of {n}: low {lo:g} must be below high {hi:g} (SI)")
        if log[n] and lo <= 0:
            raise CalibrationError(f"bounds of {n}: low must be > 0 for a positive parameter; got {lo:g}")
        bnds[n] = (lo, hi)
    if bounds:
        extra = [k for k in bounds if k not in free]
        if extra:
            raise CalibrationError(f"bounds given for parameters that are not free: {', '.join(extra)}")
    return bnds


def inside(value: float, bounds: tuple[float, float], log: bool, linear: bool = False) -> float:
    """``value`` if strictly inside ``bounds``; otherwise the middle of the bounds (geometric for ``log``);
    a ``linear`` input on its lower bound (a chemistry term at 0) starts just above it."""
    lo, hi = bounds
    if lo < value < hi:
        return value
    if linear and value == lo:
        return lo + 1e-4 * (hi - lo)
    v = min(max(value, lo), hi)
    if v not in (lo, hi):
        return v
    return math.sqrt(lo * hi) if log else lo + 0.5 * (hi - lo)
