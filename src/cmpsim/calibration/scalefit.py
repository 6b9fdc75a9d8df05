"""What every fit of one scale (the die's test structures, the pad's temperature) reports: the
fitted constants with their 95 % intervals and correlations, and the residuals before and after."""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np

from .identify import zero_columns
from .uncertainty import covariance

__all__ = ["ScaleFit", "log_intervals", "fit_statistics", "interval_text"]


def interval_text(lo: float, hi: float) -> str:
    """A 95 % interval as printed: ``[-, -]`` when undefined (NaN), as the wafer fit prints one."""
    return "[-, -]" if math.isnan(lo) or math.isnan(hi) else f"[{lo:.4g}, {hi:.4g}]"


def log_intervals(cov: np.ndarray, names, values: dict[str, float]):
    """From the covariance of ln(value): (standard errors of ln value, correlation, 95 % intervals, standard
    errors of the values by the delta method). Intervals are exp(+-1.96 se) around the value (asymmetric);
    an infinite or overflowing one is (0, inf); an undefined covariance (NaN: no scatter to scale it by,
    :func:`cmpsim.calibration.uncertainty.covariance`) gives undefined ones (NaN), not infinite ones."""
    if np.any(np.isnan(cov)):
        se = np.full(len(names), np.nan)
    else:
        se = np.sqrt(np.clip(np.diag(cov), 0.0, None)) if np.all(np.isfinite(cov)) else np.full(len(names), np.inf)
    with np.errstate(invalid="ignore", divide="ignore"):
        corr = cov / np.outer(se, se) if np.all(np.isfinite(se)) and np.all(se > 0) else np.full(cov.shape, np.nan)
    ci, stderr = {}, {}
    for k, n in enumerate(names):
        w = 1.96 * se[k]
        ci[n] = ((values[n] * math.exp(-w), values[n] * math.exp(w)) if np.isfinite(w) and w < 700 else
                 (math.nan, math.nan) if np.isnan(w) else (0.0, math.inf))
        stderr[n] = values[n] * se[k]
    return se, corr, ci, stderr


def fit_statistics(J: np.ndarray, residuals: np.ndarray, free, values: dict[str, float], absolute: bool, lo, hi,
                   notes=(), scale=None):
    """What a fit in z = ln(value) reports, from its whitened ``residuals`` and Jacobian ``J`` (d residual / dz)
    at the optimum: (chi2, degrees of freedom, notes, covariance of z, correlation, 95 % intervals, standard
    errors of the values). The covariance is (J^T J)^-1, scaled by the reduced chi-square unless every
    point carried an ``absolute`` uncertainty, undefined without a scatter to scale by
    (:func:`cmpsim.calibration.uncertainty.covariance`, as the wafer fit's); ``notes`` (said first) gain
    what the data cannot separate, read with the values and the bounds ``lo``, ``hi`` divided by
    ``scale`` (default 1: constants of order 1e-15 1/Pa are read relative to their start, or every
    value would sit on a bound)."""
    chi2 = float(np.sum(residuals**2))
    dof = len(residuals) - len(free)
    notes = list(notes)
    cov = covariance(J, chi2, dof, absolute, notes)
    se, corr, ci, stderr = log_intervals(cov, free, values)
    if scale is None:
        notes += _identifiability(free, J, se, corr, values, lo, hi)
    else:
        notes += _identifiability(free, J, se, corr, {n: values[n] / scale[k] for k, n in enumerate(free)}, lo / scale, hi / scale)
    return chi2, dof, notes, cov, corr, ci, stderr


def _identifiability(free, J, se, corr, vals, lo, hi) -> list[str]:
    out = []
    zero = zero_columns(J)
    for k, n in enumerate(free):
        if zero[k]:
            out.append(f"{n}: the data do not depend on it (its column of the Jacobian is zero)")
        elif se[k] > math.log(10.0):  # an infinite one too; an undefined one (NaN) is said by the covariance's note
            out.append(f"{n}: not determined by these data (standard error above a factor 10)")
        if np.isclose(vals[n], lo[k], rtol=1e-3) or np.isclose(vals[n], hi[k], rtol=1e-3):
            out.append(f"{n}: ended on a bound ({vals[n]:.4g}); its interval is not meaningful")
    if np.all(np.isfinite(corr)):
        for i in range(len(free)):
            for j in range(i + 1, len(free)):
                if abs(corr[i, j]) > 0.95:
                    out.append(f"{free[i]} and {free[j]} cannot be separated by these data (correlation {corr[i, j]:+.3f}): "
                               "only a combination of them is determined")
    if J.size:
        s = np.linalg.svd(J, compute_uv=False)
        out.append(f"singular values of the whitened Jacobian {', '.join(f'{v:.3g}' for v in s)} (condition {s[0] / max(s[-1], 1e-300):.3g})")
    return out



@dataclass
class ScaleFit:
    """Constants fitted as ln(value) (SI), their uncertainty and the residuals of the records.

    ``values``/``start``: fitted and starting constants; ``stderr``: standard errors (delta
    method); ``ci95``: 95 % intervals; ``correlation`` and ``covariance``: of the fitted
    ln(value); ``measured``, ``model_before``, ``model_after``: one value per record (the
    records' unit); ``reasons``: why each constant is free; ``identifiability``: what the data
    can and cannot separate.
    """

    free: list[str]
    values: dict[str, float]
    start: dict[str, float]
    stderr: dict[str, float]
    ci95: dict[str, tuple[float, float]]
    correlation: np.ndarray
    covariance: np.ndarray
    records: list = field(repr=False)
    measured: np.ndarray = field(repr=False)
    model_before: np.ndarray = field(repr=False)
    model_after: np.ndarray = field(repr=False)
    chi2: float = float("nan")
    dof: int = 0
    absolute_sigma: bool = False
    reasons: dict = field(default_factory=dict)
    identifiability: list = field(default_factory=list)

    @property
    def residuals_before(self) -> np.ndarray:
        """model - measured before the fit, per record."""
        return self.model_before - self.measured

    @property
    def residuals_after(self) -> np.ndarray:
        """model - measured after the fit, per record."""
        return self.model_after - self.measured

    @property
    def rms_before(self) -> float:
        """RMS of model - measured before the fit (the records' unit)."""
        return float(np.sqrt(np.nanmean(self.residuals_before**2)))

    @property
    def rms_after(self) -> float:
        """RMS of model - measured after the fit (the records' unit)."""
        return float(np.sqrt(np.nanmean(self.residuals_after**2)))
