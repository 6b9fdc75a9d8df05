"""The uncertainty of a calibration: Jacobian at the optimum, covariance, standard errors, 95 % intervals.

The covariance of the fitted variables z is ``(J^T J)^-1``, scaled by the reduced
chi-square unless every point carries an uncertainty (then the uncertainties are trusted as
absolute). Standard errors follow by the delta method; the 95 % intervals are computed in z,
so they are asymmetric for log-fitted parameters.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np

from ..inputs.config import PARAMETERS, format_display

__all__ = ["EXACT_FIT_REDUCED_CHI2", "Uncertainty", "central_jacobian", "covariance", "uncertainty"]


@dataclass
class Uncertainty:
    """Standard errors, 95 % intervals and correlations of the fitted values (SI), with notes."""

    stderr: dict[str, float]
    ci95: dict[str, tuple[float, float]]
    correlation: np.ndarray
    notes: list[str] = field(default_factory=list)


def central_jacobian(residuals, z: np.ndarray, n_points: int, h: float = 1e-3, lower=None, upper=None) -> np.ndarray:
    """d(residuals)/dz at ``z`` by central differences (two evaluations per variable); one-sided where
    a step would leave the bounds ``lower``/``upper`` of z (an input at its physical limit, e.g. 0)."""
    J = np.empty((n_points, len(z)))
    r0 = None
    for k in range(len(z)):
        zp, zm = z.copy(), z.copy()
        zp[k] += h
        zm[k] -= h
        below = lower is not None and zm[k] < lower[k]
        above = upper is not None and zp[k] > upper[k]
        if below or above:
            if r0 is None:
                r0 = residuals(z)
            J[:, k] = (residuals(zp) - r0) / h if below else (r0 - residuals(zm)) / h
        else:
            J[:, k] = (residuals(zp) - residuals(zm)) / (2 * h)
    return J


#: Reduced chi-square below which a fit without absolute uncertainties is exact (whitened residuals of
#: relative size ~1e-5 and less: no transcribed measurement is that precise), so its scatter cannot scale
#: the covariance (it would shrink the intervals to nothing).
EXACT_FIT_REDUCED_CHI2 = 1e-10


def covariance(J: np.ndarray, chi2: float, dof: int, absolute_sigma: bool, notes: list[str]) -> np.ndarray:
    """The covariance of the fit variables z from the Jacobian ``J`` of the whitened residuals at the optimum
    (every fit: the wafer's, the die's, the pad's and the pad life's); ``notes`` gain why it is not finite.

    With every point's uncertainty (``absolute_sigma``) it is (J^T J)^-1, whatever ``dof``. Without, it is
    scaled by the reduced chi-square chi2/dof, which needs a scatter to scale by: with no degree of
    freedom left (``dof`` <= 0), or points fitted exactly (chi2/dof < :data:`EXACT_FIT_REDUCED_CHI2`),
    it is undefined (NaN, the intervals then undefined too), not shrunk to nothing. A singular J^T J
    (condition above 1e14) gives an infinite covariance (intervals [0, inf])."""
    n = J.shape[1]
    jtj = J.T @ J
    try:
        cov = np.linalg.inv(jtj)
        if not np.all(np.isfinite(cov)) or np.linalg.cond(jtj) > 1e14:
            raise np.linalg.LinAlgError("ill-conditioned")
    except np.linalg.LinAlgError:
        cov = np.full((n, n), np.inf)
        notes.append("J^T J is singular: the data do not determine the free parameters (not identifiable); standard errors are infinite")
    if absolute_sigma:
        return cov
    if dof <= 0:
        notes.append("no degrees of freedom left: without absolute uncertainties the standard errors are undefined")
        return np.full((n, n), np.nan)
    if chi2 / dof < EXACT_FIT_REDUCED_CHI2:
        notes.append(f"the points are fitted exactly (reduced chi-square {chi2 / dof:.3g}: e.g. repeated or proportional points, which give "
                     "no more settings than free inputs): without absolute uncertainties there is no scatter to estimate the standard "
                     "errors from, so they are undefined; give each point its uncertainty")
        return np.full((n, n), np.nan)
    return cov * (chi2 / dof)


def uncertainty(
    J: np.ndarray,
    chi2: float,
    dof: int,
    absolute_sigma: bool,
    values: dict[str, float],
    log: dict[str, bool],
    scale: dict[str, float],
    bounds: dict[str, tuple[float, float]],
) -> Uncertainty:
    """The uncertainty of the fitted ``values`` from the Jacobian ``J`` of the whitened residuals in z.

    ``log[n]``: z = ln(value / start); otherwise z = (value - start) / ``scale[n]``. The notes
    say which parameters the data do not determine and which ended on a bound.
    """
    free = list(values)
    notes: list[str] = []
    cov = covariance(J, chi2, dof, absolute_sigma, notes)
    diag = np.diag(cov)
    if np.any(np.isnan(diag)):  # undefined (no scatter to scale by): no interval, not an infinite one
        se_z = np.full(len(free), np.nan)
    else:
        se_z = np.sqrt(np.clip(diag, 0, None)) if np.all(np.isfinite(diag)) else np.full(len(free), np.inf)
    with np.errstate(invalid="ignore", divide="ignore"):
        corr = cov / np.outer(se_z, se_z) if np.all(np.isfinite(se_z)) and np.all(se_z > 0) else np.full_like(cov, np.nan)
    stderr, ci95 = {}, {}
    for k, n in enumerate(free):
        v = values[n]
        if log[n]:
            stderr[n] = abs(v) * se_z[k]
            w = 1.96 * se_z[k]
            ci95[n] = (v * math.exp(-w), v * math.exp(w)) if np.isfinite(w) and w < 700 else (math.nan, math.nan) if np.isnan(w) else (0.0, float("inf"))
        else:
            stderr[n] = se_z[k] * scale[n]
            ci95[n] = (v - 1.96 * stderr[n], v + 1.96 * stderr[n])
        if log[n] and se_z[k] > math.log(10.0):
            notes.append(f"{n} is not determined by these data: its standard error exceeds a factor 10 (the model output hardly changes with it near the fit)")
        elif not log[n] and stderr[n] > abs(v):
            notes.append(f"{n} is not determined by these data: its standard error exceeds its value")
        lo, hi = bounds[n]
        if np.isclose(v, lo, rtol=1e-4, atol=0.0) or np.isclose(v, hi, rtol=1e-4, atol=0.0):
            notes.append(f"{n} ended on a bound ({format_display(n, v)} {PARAMETERS[n].display}): the interval is not meaningful; widen --bounds")
    return Uncertainty(stderr, ci95, corr, notes)
