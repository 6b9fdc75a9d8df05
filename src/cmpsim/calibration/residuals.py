"""The residuals of a calibration: every data point's model value, whitened, as a function of the fit variables."""

from __future__ import annotations

import math
from typing import Any, Callable

import numpy as np

from ..inputs.config import Config
from ..validation import Dataset, PointResult, evaluate_dataset, solve_points

__all__ = ["FAILED_POINT_PENALTY"]

#: Penalty (whitened units) of a point without equilibrium during the fit.
FAILED_POINT_PENALTY = 100.0


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
