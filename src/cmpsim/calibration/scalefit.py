"""What every fit of one scale (the die's test structures, the pad's temperature) reports: the
fitted constants with their 95 % intervals and correlations, and the residuals before and after."""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

__all__ = ["ScaleFit", "log_intervals"]


def log_intervals(cov: np.ndarray, names, values: dict[str, float]):
    """From the covariance of ln(value): (standard errors of ln value, correlation, 95 % intervals, standard
    errors of the values by the delta method). Intervals are exp(+-1.96 se) around the value (asymmetric);
    an infinite or overflowing one is (0, inf)."""
    import math

    se = np.sqrt(np.clip(np.diag(cov), 0.0, None)) if np.all(np.isfinite(cov)) else np.full(len(names), np.inf)
    with np.errstate(invalid="ignore", divide="ignore"):
        corr = cov / np.outer(se, se) if np.all(np.isfinite(se)) and np.all(se > 0) else np.full(cov.shape, np.nan)
    ci, stderr = {}, {}
    for k, n in enumerate(names):
        w = 1.96 * se[k]
        ci[n] = (values[n] * math.exp(-w), values[n] * math.exp(w)) if np.isfinite(w) and w < 700 else (0.0, math.inf)
        stderr[n] = values[n] * se[k]
    return se, corr, ci, stderr


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
