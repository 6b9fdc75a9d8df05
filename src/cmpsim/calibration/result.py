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
    #: without --free: the inputs the data chose and those left fixed, each with why (:class:`cmpsim.calibration.identify.Choice`)
    choice: object = None
    #: what the data cannot separate, from the Jacobian at the fit (:func:`cmpsim.calibration.identify.separability`)
    identifiability: list[str] = field(default_factory=list)
    #: singular values of the Jacobian at the fit, columns scaled to unit norm
    singular_values: np.ndarray = field(default_factory=lambda: np.array([]))
    #: leave-one-out errors of each removal series (:class:`cmpsim.calibration.heldout.SeriesLOO`)
    loo: list = field(default_factory=list)
    #: the data files fitted
    data: list[str] = field(default_factory=list)
    #: model choices the fitted inputs need (``film_chemistry = "additive"``)
    settings: dict = field(default_factory=dict)

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
        """Write the process file, atomically: the fitted configuration (every input, SI), which every
        command's ``--config`` takes, and its ``[calibration]`` table (:mod:`cmpsim.calibration.processfile`:
        the constants fitted, which ``cmpsim polish`` and ``cmpsim lot`` apply with the recipe's own tool,
        their intervals and correlations)."""
        from .processfile import write_process_file

        return write_process_file(self, path)

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
                    f"[{format_display(n, lo) if np.isfinite(lo) else '-'}, {format_display(n, hi) if np.isfinite(hi) else 'inf' if hi > 0 else '-'}]",
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

    def loo_rows(self) -> list[list[str]]:
        return [[s.name, str(s.n), f"{s.calibrated:.4g}", f"{s.preston:.4g}", f"{s.mean:.4g}", s.unit, ", ".join(s.inputs) or "-",
                 "yes" if s.beats_preston else "no"] for s in self.loo]

    LOO_HEADER = ["series", "points", "LOO calibrated", "LOO Preston s*P*U", "LOO mean", "unit", "inputs (whole series)", "beats Preston"]

    def summary(self) -> str:
        """Plain-text report: the inputs chosen, fitted values with intervals, correlations, what the data
        cannot separate, residuals before and after, leave-one-out errors, goodness of fit."""
        out = []
        if self.choice is not None:
            out += ["inputs chosen by the data (no --free):"] + [f"  {line}" for line in self.choice.lines()] + [""]
        out += [text_table(self.PARAMETER_HEADER, self.parameter_rows()), ""]
        if len(self.free) > 1:
            out.append("correlation matrix:")
            out.append(text_table([""] + self.free, [[n] + [f"{c:+.3f}" for c in row] for n, row in zip(self.free, self.correlation)]))
            out.append("")
        if len(self.singular_values):
            sv = self.singular_values
            out.append("identifiability: singular values of the Jacobian (unit columns) " + ", ".join(f"{v:.3g}" for v in sv)
                       + (f"; condition number {sv[0] / sv[-1]:.3g}" if sv[-1] > 0 else "; singular"))
        out += [f"identifiability: {m}" for m in self.identifiability] or (["identifiability: every fitted input is separated by these data"] if len(self.free) > 1 else [])
        out.append("")
        out.append(text_table(self.RESIDUAL_HEADER, self.residual_rows()))
        out.append("")
        if self.loo:
            out.append("leave one out (each point predicted by the film chemistry refitted to the others, by Preston's law s*P*U and by the mean):")
            out.append(text_table(self.LOO_HEADER, self.loo_rows()))
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
