"""The result of a calibration: fitted values, their uncertainty, residuals before and after, and its report."""

from __future__ import annotations

from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from ..inputs.config import PARAMETERS, Config, format_display
from ..tables import text_table
from ..validation import PointResult

__all__ = ["CalibrationResult"]


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
