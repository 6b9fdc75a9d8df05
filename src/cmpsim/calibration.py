"""Fit uncertain inputs to measurements: ``cmpsim calibrate`` and :func:`calibrate`.

The residual of each data point is whitened by its uncertainty (or, without one, by the
measured value, i.e. a relative error); "shape" data sets get their own scale, profiled out
in closed form at every evaluation (one degree of freedom each); "order" points use
``log10(model / value) / 0.5``. ``scipy.optimize.least_squares`` (trust-region reflective,
bounds) minimises the sum of squares over the free parameters, each fitted as
``z = ln(value / start)`` when the parameter is positive (all the physical ones) or
``(value - start) / scale`` otherwise.

Uncertainty: the covariance of z is ``(J^T J)^-1`` from a central-difference Jacobian at the
optimum, multiplied by the reduced chi-square unless every point carries an uncertainty
(then the uncertainties are trusted as absolute, as ``curve_fit(absolute_sigma=True)``).
Standard errors follow by the delta method; the 95 % intervals are computed in z (so they are
asymmetric for log-fitted parameters). The fitted configuration is written with
:meth:`Config.to_toml` and is accepted by every command (``cmpsim run CONFIG``,
``cmpsim validate --config``, ``cmpsim reproduce --config``).
"""

from __future__ import annotations

import math
import time
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any, Callable

import numpy as np

from .config import PARAMETERS, Config, format_display, parse_value
from .studies import solve_point, text_table
from .validation import (
    Dataset,
    PointResult,
    _as_datasets,
    evaluate_dataset,
    model_value,
    point_config,
    solve_points,
)

__all__ = ["calibrate", "CalibrationResult", "CalibrationError", "default_bounds", "CALIBRATABLE"]

#: Penalty (whitened units) of a point without equilibrium during the fit.
FAILED_POINT_PENALTY = 100.0


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


def default_bounds(name: str, start: float) -> tuple[float, float]:
    """Default bounds: a factor 10 either side of ``start`` for positive inputs, within the valid range."""
    p = PARAMETERS[name]
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


@dataclass
class CalibrationResult:
    """Fitted values, their uncertainty and the residuals before and after.

    Values are SI. ``stderr`` is the delta-method standard error, ``ci95`` the 95 % interval
    (computed in the fitted variable, hence asymmetric for log-fitted parameters).
    ``residuals_before`` / ``residuals_after`` are the whitened residuals of every point.
    """

    free: list[str]
    config: Config
    initial_config: Config
    values: dict[str, float]
    initial: dict[str, float]
    stderr: dict[str, float]
    ci95: dict[str, tuple[float, float]]
    correlation: np.ndarray
    bounds: dict[str, tuple[float, float]]
    log_scale: dict[str, bool]
    residuals_before: np.ndarray
    residuals_after: np.ndarray
    points_before: list[PointResult]
    points_after: list[PointResult]
    chi2_before: float
    chi2_after: float
    dof: int
    absolute_sigma: bool
    success: bool
    message: str
    nfev: int
    equilibria: int
    elapsed_s: float
    failed_points_after: int = 0
    notes: list[str] = field(default_factory=list)

    @property
    def reduced_chi2(self) -> float:
        return self.chi2_after / self.dof if self.dof > 0 else float("nan")

    @property
    def rms_before(self) -> float:
        return float(np.sqrt(np.mean(self.residuals_before**2)))

    @property
    def rms_after(self) -> float:
        return float(np.sqrt(np.mean(self.residuals_after**2)))

    def to_toml(self, path) -> Path:
        """Write the fitted configuration (every input, SI) to TOML, atomically."""
        self.config.to_toml(path)
        return Path(path)

    def parameter_rows(self) -> list[list[str]]:
        rows = []
        for n in self.free:
            p = PARAMETERS[n]
            lo, hi = self.ci95[n]
            unit = p.display or "-"
            rows.append(
                [
                    n,
                    f"{format_display(n, self.initial[n])}",
                    f"{format_display(n, self.values[n])}",
                    f"{_disp(n, self.stderr[n])}",
                    f"[{format_display(n, lo) if np.isfinite(lo) else '-'}, {format_display(n, hi) if np.isfinite(hi) else '-'}]",
                    f"[{format_display(n, self.bounds[n][0])}, {format_display(n, self.bounds[n][1])}]",
                    unit,
                    "log" if self.log_scale[n] else "linear",
                ]
            )
        return rows

    PARAMETER_HEADER = ["parameter", "start", "fitted", "std. error", "95 % interval", "bounds", "unit", "fitted as"]

    def residual_rows(self) -> list[list[str]]:
        rows = []
        for b, a, rb, ra in zip(self.points_before, self.points_after, self.residuals_before, self.residuals_after):
            rows.append([b.dataset, b.quantity, b.conditions, f"{b.measured:.4g}", f"{b.model:.4g}", f"{a.model:.4g}", f"{rb:+.3g}", f"{ra:+.3g}", b.unit])
        return rows

    RESIDUAL_HEADER = ["dataset", "quantity", "conditions", "measured", "model before", "model after", "resid. before", "resid. after", "unit"]

    def summary(self) -> str:
        """Plain-text report: fitted values, correlations, residuals, goodness of fit."""
        out = [text_table(self.PARAMETER_HEADER, self.parameter_rows()), ""]
        if len(self.free) > 1:
            out.append("correlation matrix:")
            out.append(text_table([""] + self.free, [[n] + [f"{c:+.3f}" for c in row] for n, row in zip(self.free, self.correlation)]))
            out.append("")
        out.append(text_table(self.RESIDUAL_HEADER, self.residual_rows()))
        out.append("")
        out.append(
            f"chi-square {self.chi2_before:.4g} -> {self.chi2_after:.4g} (dof {self.dof}, reduced {self.reduced_chi2:.3g}); "
            f"RMS whitened residual {self.rms_before:.3g} -> {self.rms_after:.3g}; "
            f"uncertainties {'absolute (every point has one)' if self.absolute_sigma else 'scaled by the reduced chi-square'}; "
            f"{self.nfev} evaluations, {self.equilibria} equilibria, {self.elapsed_s:.1f} s; optimiser: {self.message}"
        )
        out += [f"note: {n}" for n in self.notes]
        return "\n".join(out)


def _disp(name: str, value: float) -> str:
    if not np.isfinite(value):
        return "inf"
    return format_display(name, value)


class _Problem:
    """Residuals of all points as a function of the fitted variables z."""

    def __init__(self, datasets: list[Dataset], base: Config, free: list[str], start: dict[str, float], log: dict[str, bool], scale: dict[str, float]):
        self.datasets = datasets
        self.base = base
        self.free = free
        self.start = start
        self.log = log
        self.scale = scale
        self.points = [(ds, p) for ds in datasets for p in ds.points]
        self.warm: dict[tuple, np.ndarray] = {}
        self.equilibria = 0
        self.nfev = 0
        self.failed = 0
        self.callback: Callable[[int, float], None] | None = None
        y = []
        u = []
        self.absolute_sigma = True
        for ds, p in self.points:
            yv = p.value_si
            y.append(yv)
            if p.uncertainty is not None and p.comparison in ("absolute", "range", "shape"):
                u.append(p.uncertainty_si)
            else:
                self.absolute_sigma = False
                u.append(abs(yv) if yv != 0 else 1.0)
        self.y = np.array(y)
        self.u = np.array(u)

    def values_of(self, z) -> dict[str, float]:
        out = {}
        for n, zi in zip(self.free, z):
            out[n] = self.start[n] * math.exp(zi) if self.log[n] else self.start[n] + zi * self.scale[n]
        return out

    def z_of(self, values: dict[str, float]) -> np.ndarray:
        return np.array([math.log(values[n] / self.start[n]) if self.log[n] else (values[n] - self.start[n]) / self.scale[n] for n in self.free])

    def config_of(self, z) -> Config:
        return self.base.replace(**self.values_of(z))

    def model(self, z) -> tuple[np.ndarray, list[Any], list[str]]:
        vals, results, statuses, solved = solve_points([p for _, p in self.points], self.config_of(z), warm=self.warm)
        self.equilibria += solved
        return np.array(vals), results, statuses

    def whiten(self, m: np.ndarray) -> np.ndarray:
        r = np.empty(len(self.points))
        idx = 0
        for ds in self.datasets:
            n = len(ds.points)
            sl = slice(idx, idx + n)
            mm, yy, uu = m[sl], self.y[sl], self.u[sl]
            ok = np.isfinite(mm)
            if ds.comparison == "shape":
                w = 1.0 / uu**2
                den = np.sum(w[ok] * mm[ok] ** 2)
                s = np.sum(w[ok] * mm[ok] * yy[ok]) / den if den > 0 else 0.0
                rr = (s * mm - yy) / uu
            elif ds.comparison == "order":
                with np.errstate(divide="ignore", invalid="ignore"):
                    rr = np.log10(np.where(mm > 0, mm, np.nan) / yy) / 0.5
            else:
                rr = (mm - yy) / uu
            r[sl] = np.where(np.isfinite(rr), rr, FAILED_POINT_PENALTY)
            idx += n
        return r

    def __call__(self, z) -> np.ndarray:
        m, _, _ = self.model(z)
        self.nfev += 1
        self.failed = int((~np.isfinite(m)).sum())
        r = self.whiten(m)
        if self.callback is not None:
            self.callback(self.nfev, float(np.sum(r * r)))
        return r


def _point_rows(problem: _Problem, m, results, statuses) -> list[PointResult]:
    rows: list[PointResult] = []
    idx = 0
    for ds in problem.datasets:
        n = len(ds.points)
        r, _ = evaluate_dataset(ds, list(m[idx : idx + n]), results[idx : idx + n], statuses[idx : idx + n])
        rows.extend(r)
        idx += n
    return rows


def calibrate(
    data,
    free,
    config: Config | None = None,
    bounds: dict[str, tuple[Any, Any]] | None = None,
    grid: str | None = None,
    start: dict[str, Any] | None = None,
    max_nfev: int | None = None,
    progress: bool = False,
    include_model_predictions: bool = False,
) -> CalibrationResult:
    """Fit the ``free`` inputs to the data with bounded least squares.

    Parameters
    ----------
    data : path, Dataset, or a sequence of them
        Data files in the format of ``cmpsim/data/README.md``.
    free : str or sequence of str
        Names of the inputs to fit (see ``cmpsim params``), e.g. ``["asperity_density"]``.
    config : Config, optional
        Starting configuration (default :meth:`Config.default`); the other inputs stay fixed.
    bounds : dict, optional
        ``{name: (low, high)}`` with units (``"50 MPa"``) or SI numbers; default a factor 10
        either side of the start for positive inputs, clipped to the valid range.
    grid : str, optional
        Grid preset overriding ``config``'s.
    start : dict, optional
        Starting values overriding ``config``'s.
    max_nfev : int, optional
        Evaluations allowed to the optimiser (default 30 x (number of free inputs + 1)).
    progress : bool
        Print the evaluation count and cost while fitting.
    include_model_predictions : bool
        Allow data sets of kind ``model_prediction`` (off: fitting to another model's
        output is not calibration).

    Returns
    -------
    CalibrationResult

    Raises
    ------
    CalibrationError
        Unknown or non-fittable name, a name set per point by the data, bad bounds, no
        degrees of freedom, or no equilibrium at the start.
    """
    from scipy.optimize import least_squares

    t0 = time.perf_counter()
    if isinstance(free, str):
        free = [free]
    free = [f.strip().replace("-", "_") for f in free]
    if not free:
        raise CalibrationError("give at least one parameter to fit (--free NAME ...)")
    for n in free:
        if n not in PARAMETERS:
            raise CalibrationError(f"unknown parameter {n!r} in --free; fittable: {', '.join(CALIBRATABLE)}")
        if not _calibratable(n):
            raise CalibrationError(f"parameter {n!r} cannot be fitted (a choice or numerical setting); fittable: {', '.join(CALIBRATABLE)}")
    if len(set(free)) != len(free):
        raise CalibrationError(f"a parameter is repeated in --free: {', '.join(free)}")
    datasets = _as_datasets(data)
    if not include_model_predictions:
        bad = [d.name for d in datasets if d.kind == "model_prediction"]
        if bad:
            raise CalibrationError(f"data set(s) {', '.join(bad)} hold another model's predictions, not measurements; refusing to calibrate against them")
    for d in datasets:
        for p in d.points:
            clash = [n for n in free if n in p.conditions or (n == "rotation_speed" and "sliding_speed" in p.conditions)]
            if clash:
                raise CalibrationError(f"parameter {clash[0]!r} is set per point by data set {d.name!r} (line {p.line}); it cannot be fitted")
    base = config or Config.default()
    if grid is not None:
        base = base.replace(grid=grid)
    if start:
        unknown = [k for k in start if k not in free]
        if unknown:
            raise CalibrationError(f"start values given for parameters that are not free: {', '.join(unknown)}")
        base = base.replace(**start)
    start_vals = {n: float(getattr(base, n)) for n in free}
    log = {n: _positive(n) and start_vals[n] > 0 for n in free}
    scale = {n: max(abs(start_vals[n]), 1e-12) if not log[n] else 1.0 for n in free}
    bnds: dict[str, tuple[float, float]] = {}
    for n in free:
        if bounds and n in bounds:
            lo_t, hi_t = bounds[n]
            try:
                lo, hi = parse_value(n, lo_t), parse_value(n, hi_t)
            except ValueError as exc:
                raise CalibrationError(f"bounds of {n}: {exc}") from None
        else:
            lo, hi = default_bounds(n, start_vals[n])
        if not lo < hi:
            raise CalibrationError(f"bounds of {n}: low {lo:g} must be below high {hi:g} (SI)")
        if log[n] and lo <= 0:
            raise CalibrationError(f"bounds of {n}: low must be > 0 for a positive parameter; got {lo:g}")
        bnds[n] = (lo, hi)
    if bounds:
        extra = [k for k in bounds if k not in free]
        if extra:
            raise CalibrationError(f"bounds given for parameters that are not free: {', '.join(extra)}")
    # start strictly inside the bounds
    for n in free:
        lo, hi = bnds[n]
        if not lo < start_vals[n] < hi:
            v = min(max(start_vals[n], lo), hi)
            v = lo + 0.5 * (hi - lo) if v in (lo, hi) and not log[n] else (math.sqrt(lo * hi) if v in (lo, hi) else v)
            start_vals[n] = v
            base = base.replace(**{n: v})
    problem = _Problem(datasets, base, free, start_vals, log, scale)
    n_shape = sum(1 for d in datasets if d.comparison == "shape")
    n_pts = len(problem.points)
    dof = n_pts - len(free) - n_shape
    if dof < 0:
        raise CalibrationError(f"{n_pts} points cannot determine {len(free)} parameters plus {n_shape} shape scale(s)")
    z0 = np.zeros(len(free))
    lo_z = problem.z_of({n: bnds[n][0] for n in free})
    hi_z = problem.z_of({n: bnds[n][1] for n in free})
    m0, res0, st0 = problem.model(z0)
    if not np.isfinite(m0).all():
        bad = [f"{ds.name} line {p.line}" for (ds, p), v in zip(problem.points, m0) if not np.isfinite(v)]
        raise CalibrationError(f"no equilibrium at the starting values for {', '.join(bad)}")
    r0 = problem.whiten(m0)
    rows_before = _point_rows(problem, m0, res0, st0)
    if progress:
        from rich.console import Console

        console = Console(stderr=True)
        problem.callback = lambda k, c: console.print(f"  evaluation {k}: chi-square {c:.6g}", highlight=False)
    fit = least_squares(
        problem,
        z0,
        bounds=(lo_z, hi_z),
        jac="2-point",
        diff_step=1e-3,
        x_scale=1.0,
        ftol=1e-8,
        xtol=1e-6,
        gtol=1e-10,
        max_nfev=max_nfev or 30 * (len(free) + 1),
    )
    z = fit.x
    problem.callback = None
    # central-difference Jacobian at the optimum
    h = 1e-3
    J = np.empty((n_pts, len(free)))
    for k in range(len(free)):
        zp, zm = z.copy(), z.copy()
        zp[k] += h
        zm[k] -= h
        J[:, k] = (problem(zp) - problem(zm)) / (2 * h)
    m1, res1, st1 = problem.model(z)
    r1 = problem.whiten(m1)
    chi2 = float(np.sum(r1 * r1))
    notes = []
    jtj = J.T @ J
    try:
        cov = np.linalg.inv(jtj)
        if not np.all(np.isfinite(cov)) or np.linalg.cond(jtj) > 1e14:
            raise np.linalg.LinAlgError("ill-conditioned")
    except np.linalg.LinAlgError:
        cov = np.full((len(free), len(free)), np.inf)
        notes.append("J^T J is singular: the data do not determine the free parameters (not identifiable); standard errors are infinite")
    if not problem.absolute_sigma:
        factor = chi2 / dof if dof > 0 else float("nan")
        cov = cov * factor
        if dof == 0:
            notes.append("no degrees of freedom left: without absolute uncertainties the standard errors are undefined")
    se_z = np.sqrt(np.clip(np.diag(cov), 0, None)) if np.all(np.isfinite(np.diag(cov))) else np.full(len(free), np.inf)
    with np.errstate(invalid="ignore", divide="ignore"):
        corr = cov / np.outer(se_z, se_z) if np.all(np.isfinite(se_z)) and np.all(se_z > 0) else np.full_like(cov, np.nan)
    values = problem.values_of(z)
    stderr, ci95 = {}, {}
    for k, n in enumerate(free):
        v = values[n]
        if log[n]:
            stderr[n] = abs(v) * se_z[k]
            w = 1.96 * se_z[k]
            ci95[n] = (v * math.exp(-w), v * math.exp(w)) if np.isfinite(w) and w < 700 else (0.0, float("inf"))
        else:
            stderr[n] = se_z[k] * scale[n]
            ci95[n] = (v - 1.96 * stderr[n], v + 1.96 * stderr[n])
        if log[n] and se_z[k] > math.log(10.0):
            notes.append(f"{n} is not determined by these data: its standard error exceeds a factor 10 (the model output hardly changes with it near the fit)")
        elif not log[n] and stderr[n] > abs(v):
            notes.append(f"{n} is not determined by these data: its standard error exceeds its value")
        lo, hi = bnds[n]
        if np.isclose(v, lo, rtol=1e-4, atol=0.0) or np.isclose(v, hi, rtol=1e-4, atol=0.0):
            notes.append(f"{n} ended on a bound ({format_display(n, v)} {PARAMETERS[n].display}): the interval is not meaningful; widen --bounds")
    failed = int((~np.isfinite(m1)).sum())
    if failed:
        notes.append(f"{failed} point(s) have no equilibrium at the fitted values (penalised with a residual of {FAILED_POINT_PENALTY:g})")
    rows_after = _point_rows(problem, m1, res1, st1)
    return CalibrationResult(
        free=list(free),
        config=problem.config_of(z),
        initial_config=base,
        values=values,
        initial=dict(start_vals),
        stderr=stderr,
        ci95=ci95,
        correlation=corr,
        bounds=bnds,
        log_scale=log,
        residuals_before=r0,
        residuals_after=r1,
        points_before=rows_before,
        points_after=rows_after,
        chi2_before=float(np.sum(r0 * r0)),
        chi2_after=chi2,
        dof=dof,
        absolute_sigma=problem.absolute_sigma,
        success=bool(fit.success),
        message=str(fit.message),
        nfev=problem.nfev,
        equilibria=problem.equilibria,
        elapsed_s=time.perf_counter() - t0,
        failed_points_after=failed,
        notes=notes,
    )


def synthetic_dataset(
    path,
    truth: dict[str, Any],
    points: list[dict[str, str]],
    quantities: list[str],
    config: Config | None = None,
    relative_noise: float = 0.01,
    seed: int = 0,
    name: str = "synthetic",
) -> Path:
    """Write a data file generated by the model itself (for testing :func:`calibrate`).

    Every point in ``points`` (condition dicts) is solved with ``config`` changed to
    ``truth``; each quantity gets Gaussian noise of ``relative_noise`` times its value and
    that uncertainty. Quantities are written in SI.
    """
    import csv
    import io

    from .io import atomic_write_text
    from .validation import QUANTITIES

    cfg = (config or Config.default()).replace(**truth)
    rng = np.random.default_rng(seed)
    cond_cols = sorted({k for p in points for k in p})
    buf = io.StringIO()
    buf.write(f"# dataset: {name}\n# kind: measurement\n# citation: synthetic data generated by cmpsim itself\n")
    buf.write(f"# provenance: cmpsim.calibration.synthetic_dataset with {truth}, relative noise {relative_noise}, seed {seed}\n")
    w = csv.writer(buf)
    w.writerow(["dataset", "quantity", "value", "unit", "uncertainty", "comparison", *cond_cols, "source"])
    for p in points:
        out = solve_point(point_config(cfg, p))
        if not out.ok:
            raise CalibrationError(f"synthetic point {p}: {out.error}")
        res = out.result
        for q in quantities:
            v = model_value(res, q)
            sd = abs(v) * relative_noise
            unit = QUANTITIES[q][0]
            unit = "1" if unit == "dimensionless" else unit
            w.writerow([name, q, f"{v + sd * rng.standard_normal():.10g}", unit, f"{sd:.6g}", "absolute", *[p.get(c, "") for c in cond_cols], "synthetic"])
    atomic_write_text(Path(path), buf.getvalue())
    return Path(path)
