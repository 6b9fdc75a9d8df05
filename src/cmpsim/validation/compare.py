"""Model against data: the model's value of each point, the comparison modes, the verdicts."""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any, Callable, Sequence

import numpy as np

from ..inputs.config import Config
from ..solver.points import PointCache
from .data import DEPTH_QUANTITIES, ORDER_TOLERANCE_DECADES, QUANTITIES, Dataset, from_si, point_config

__all__ = ["PointResult", "DatasetSummary", "model_value", "fit_scale", "evaluate_dataset", "solve_points", "run_dataset"]


def model_value(result, quantity: str, where: dict | None = None) -> float:
    """The model's value of a measurable quantity, SI; ``where`` (SI) places it: ``radius`` (m) reads the
    rotation-averaged removal-rate profile there, ``time`` (s) and ``initial_thickness`` (m) make a
    removal rate a ``removal`` depth or a remaining ``thickness`` (:data:`cmpsim.validation.data.DEPTH_QUANTITIES`)."""
    where = where or {}
    if "radius" not in where and quantity in QUANTITIES:
        return float(QUANTITIES[quantity][3](result))
    rate = removal_rate_at(result, where.get("radius"))
    if quantity not in DEPTH_QUANTITIES:
        return rate
    depth = rate * where["time"]
    return depth if quantity == "removal" else max(where["initial_thickness"] - depth, 0.0)


def removal_rate_at(result, radius: float | None) -> float:
    """The removal rate, m/s: the wafer mean, or the rotation-averaged profile at ``radius`` (m, linear
    between ring centres, the centre ring's value inside it); ValueError beyond the wafer."""
    if radius is None:
        return float(result.scalars["removal_rate_mean"])
    r = np.asarray(result.profiles["radius"], dtype=float)
    wafer = 0.5 * result.config.wafer_diameter
    if radius > wafer * (1 + 1e-9):
        raise ValueError(f"radius {radius:g} m lies beyond the wafer (radius {wafer:g} m, wafer_diameter = {result.config.wafer_diameter:g} m)")
    return float(np.interp(radius, r, np.asarray(result.profiles["removal_rate_profile"], dtype=float)))


def fit_scale(model: np.ndarray, data: np.ndarray, weights: np.ndarray | None = None) -> float:
    """The scale s minimising sum w (s m - y)^2."""
    w = np.ones_like(data) if weights is None else weights
    den = float(np.sum(w * model * model))
    return float(np.sum(w * model * data) / den) if den > 0 else float("nan")


def _loo(predictors: np.ndarray | None, data: np.ndarray, weights: np.ndarray) -> np.ndarray:
    """Leave-one-out errors: scale fit of ``predictors`` (None: weighted mean) on the others."""
    n = len(data)
    err = np.full(n, np.nan)
    for i in range(n):
        keep = np.arange(n) != i
        if predictors is None:
            pred = float(np.sum(weights[keep] * data[keep]) / np.sum(weights[keep]))
        else:
            s = fit_scale(predictors[keep], data[keep], weights[keep])
            pred = s * predictors[i]
        err[i] = pred - data[i]
    return err


def _rms(x) -> float:
    x = np.asarray(x, dtype=float)
    x = x[np.isfinite(x)]
    return float(np.sqrt(np.mean(x * x))) if x.size else float("nan")


@dataclass
class PointResult:
    """Model vs data at one point (values in the point's own unit)."""

    dataset: str
    kind: str
    quantity: str
    comparison: str
    conditions: str
    unit: str
    measured: float
    uncertainty: float | None
    model_raw: float  # model value in the point's unit (before any shape scale)
    model: float  # compared value (after the shape scale)
    error: float  # model - measured
    relative_error: float
    agrees: bool | None  # None: no verdict for this point
    floored_fraction: float
    fluid_load_fraction: float
    status: str  # "ok" or the reason no equilibrium was found
    source: str = ""

    def as_row(self) -> dict[str, Any]:
        return {
            "dataset": self.dataset,
            "kind": self.kind,
            "quantity": self.quantity,
            "comparison": self.comparison,
            "conditions": self.conditions,
            "unit": self.unit,
            "measured": self.measured,
            "uncertainty": "" if self.uncertainty is None else self.uncertainty,
            "model_raw": self.model_raw,
            "model": self.model,
            "error": self.error,
            "relative_error": self.relative_error,
            "agrees": "" if self.agrees is None else ("yes" if self.agrees else "no"),
            "flow_factor_floored_fraction": self.floored_fraction,
            "model_fluid_load_fraction": self.fluid_load_fraction,
            "status": self.status,
            "source": self.source,
        }


@dataclass
class DatasetSummary:
    """Errors of one data set."""

    name: str
    kind: str
    quantity: str
    comparison: str
    unit: str
    n: int
    n_solved: int
    rms_error: float  # in ``unit``
    rms_relative_error: float
    scale: float | None  # shape: fitted scale (model unit -> data unit, dimensionless)
    loo_rms_model: float | None
    loo_rms_mean: float | None
    loo_rms_preston: float | None
    verdict: str  # "pass", "fail" or "n/a"
    reason: str
    citation: str = ""
    path: str = ""

    @property
    def passed(self) -> bool:
        return self.verdict == "pass"

    @property
    def failed(self) -> bool:
        return self.verdict == "fail"


# --------------------------------------------------------------------------- the comparison
def evaluate_dataset(ds: Dataset, values_si: Sequence[float], results: Sequence[Any], statuses: Sequence[str]) -> tuple[list[PointResult], DatasetSummary]:
    """Compare the model values (SI, NaN = no equilibrium) with the data set; rows + summary."""
    pts = ds.points
    unit = pts[0].unit
    q = pts[0].quantity
    measured = np.array([p.value for p in pts])
    raw = np.array([from_si(v, p.unit, p.quantity) for v, p in zip(values_si, pts)])
    unc = [p.uncertainty for p in pts]
    ok = np.isfinite(raw)
    scale = None
    compared = raw.copy()
    loo_model = loo_mean = loo_preston = None
    if ds.comparison == "shape":
        w = np.array([1.0 / u**2 if u else 1.0 for u in unc]) if all(unc) else np.ones(len(pts))
        if ok.sum() >= 2:
            scale = fit_scale(raw[ok], measured[ok], w[ok])
            compared = scale * raw
            loo_model = _rms(_loo(raw[ok], measured[ok], w[ok]))
            loo_mean = _rms(_loo(None, measured[ok], w[ok]))
            pu = np.array([r.config.applied_pressure * r.scalars["sliding_speed"] if r is not None else np.nan for r in results])
            loo_preston = _rms(_loo(pu[ok], measured[ok], w[ok]))
    err = compared - measured
    rel = err / np.where(measured != 0, np.abs(measured), np.nan)
    agrees: list[bool | None] = []
    for i, p in enumerate(pts):
        if not ok[i]:
            agrees.append(False if ds.kind != "model_prediction" else None)
        elif ds.kind == "model_prediction":
            agrees.append(None)
        elif p.comparison == "absolute":
            agrees.append(None if p.uncertainty is None else bool(abs(err[i]) <= 2.0 * p.uncertainty))
        elif p.comparison == "range":
            agrees.append(bool(abs(err[i]) <= p.uncertainty))
        elif p.comparison == "order":
            agrees.append(bool(raw[i] > 0 and abs(math.log10(raw[i] / p.value)) <= ORDER_TOLERANCE_DECADES))
        else:
            agrees.append(None)
    rows = []
    for i, p in enumerate(pts):
        r = results[i]
        rows.append(
            PointResult(
                ds.name,
                ds.kind,
                p.quantity,
                p.comparison,
                p.conditions_text(),
                p.unit,
                p.value,
                p.uncertainty,
                float(raw[i]),
                float(compared[i]),
                float(err[i]),
                float(rel[i]),
                agrees[i],
                r.scalars["flow_factor_floored_fraction"] if r is not None else float("nan"),
                r.scalars["fluid_load_fraction"] if r is not None else float("nan"),
                statuses[i],
                p.source,
            )
        )
    # verdict
    n_fail_solve = int((~ok).sum())
    if ds.kind == "model_prediction":
        verdict, reason = "n/a", "model-to-model comparison: errors only, no verdict"
    elif ds.comparison == "shape":
        if loo_model is None:
            verdict, reason = "fail", f"{n_fail_solve} of {len(pts)} points have no equilibrium"
        elif loo_model < loo_mean * (1.0 - 1e-9):  # a tie at round-off (a flat model) is no win
            verdict = "pass"
            reason = f"leave-one-out error {loo_model:.3g} < {loo_mean:.3g} of predicting the mean"
            if loo_preston is not None and np.isfinite(loo_preston):
                reason += "; " + ("also beats" if loo_model < loo_preston else "but worse than") + f" Preston s*P*U ({loo_preston:.3g})"
        else:
            verdict = "fail"
            reason = f"leave-one-out error {loo_model:.3g} is not below {loo_mean:.3g} of predicting the mean: the model's shape adds nothing"
    else:
        verdicts = [a for a in agrees if a is not None]
        if not verdicts:
            verdict, reason = "n/a", "no uncertainty given: errors only"
        elif all(verdicts):
            verdict, reason = "pass", {"absolute": "every point within 2 uncertainties", "range": "inside the measured range", "order": "within a factor 10^0.5 at every point"}[ds.comparison]
        else:
            bad = [i for i, a in enumerate(agrees) if a is False]
            if ds.comparison == "range":
                i = bad[0]
                reason = f"model {raw[i]:.3g} {unit} outside the measured range {pts[i].value - pts[i].uncertainty:.3g}-{pts[i].value + pts[i].uncertainty:.3g} {unit}"
            elif ds.comparison == "order":
                ratios = [raw[i] / pts[i].value for i in bad if np.isfinite(raw[i])]
                reason = f"{len(bad)} of {len(pts)} points off by more than a factor 3.16 (model/measured {min(ratios):.3g}-{max(ratios):.3g})" if ratios else "no equilibrium"
            else:
                reason = f"{len(bad)} of {len(pts)} points outside 2 uncertainties"
            verdict = "fail"
        if n_fail_solve:
            reason += f"; {n_fail_solve} point(s) without equilibrium"
    summary = DatasetSummary(
        ds.name,
        ds.kind,
        q if len({p.quantity for p in pts}) == 1 else ds.quantity,
        ds.comparison,
        unit if len({p.unit for p in pts}) == 1 else "mixed",
        len(pts),
        int(ok.sum()),
        _rms(err) if len({p.unit for p in pts}) == 1 else float("nan"),
        _rms(rel),
        scale,
        loo_model,
        loo_mean,
        loo_preston,
        verdict,
        reason,
        ds.citation,
        str(ds.path or ""),
    )
    return rows, summary


def _where(p) -> str:
    """A data point's place in its file for a message: ``file:line: row N`` (its data set's name if it has no file)."""
    return f"{p.path}:{p.line}: row {p.row}" if p.path else f"{p.dataset}, row {p.row} (line {p.line})"


def solve_points(points, config: Config, relative: bool = False, warm: dict | None = None, advance: Callable[[bool], None] | None = None):
    """Model value, result and status of each measured point; returns (values, results, statuses, equilibria).

    Points at identical conditions share one equilibrium. Each new equilibrium starts from
    ``warm[conditions]`` when a ``warm`` dict is given (it is updated in place with every
    converged position, as calibration needs across its iterations), otherwise from the
    previous converged point; a failed warm start is retried cold
    (:func:`cmpsim.solver.points.solve_point`). ``advance(ok)`` is called after every point.
    """
    cache = PointCache(relative=relative)
    values, results, statuses = [], [], []
    previous = None
    for p in points:  # a position beyond its wafer is refused before any point is solved
        wafer = 0.5 * point_config(config, p.conditions).wafer_diameter
        if p.where.get("radius", 0.0) > wafer * (1 + 1e-9):
            raise ValueError(f"{_where(p)}, column 'radius': radius {p.where['radius'] * 1e3:g} mm lies beyond the wafer (radius {wafer * 1e3:g} mm: "
                             "wafer_diameter {0:g} mm{1}); give the wafer_diameter of the measurement".format(
                                 2e3 * wafer, "" if "wafer_diameter" in p.conditions else ", the configuration's"))
    for p in points:
        key = tuple(sorted(p.conditions.items()))
        out = cache.solve(point_config(config, p.conditions), start=warm.get(key) if warm is not None else previous)
        if not out.ok:
            values.append(float("nan"))
            results.append(None)
            statuses.append(out.error)
        else:
            res = out.result
            previous = res.solution.state.u
            if warm is not None:
                warm[key] = previous
            try:
                values.append(model_value(res, p.quantity, p.where))
            except ValueError as exc:
                raise ValueError(f"{_where(p)}, column 'radius': {exc}") from None
            results.append(res)
            floored = res.scalars["flow_factor_floored_fraction"]
            statuses.append("ok" if floored == 0 else f"ok (flow factors regularised on {100 * floored:.0f} % of faces)")
        if advance is not None:
            advance(out.ok)
    return values, results, statuses, len(cache)


def run_dataset(ds: Dataset, config: Config, relative: bool = False, advance: Callable[[bool], None] | None = None):
    """Solve every point of a data set (warm start from the previous point). Returns (values, results, statuses)."""
    return solve_points(ds.points, config, relative=relative, advance=advance)[:3]
