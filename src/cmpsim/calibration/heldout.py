"""Leave one point out: the calibrated model against Preston's law and the mean.

For a series of removal measurements of a film, the calibrated model is the film chemistry of
eq. 13h.2 (docs/model.md) fitted to the other points: the inputs the registry offers
(:mod:`cmpsim.calibration.registry`) that the left-in points can separate
(:func:`cmpsim.calibration.identify.choose`, one degree of freedom kept), by bounded linear least
squares on their exact derivatives (:func:`cmpsim.calibration.film.chemistry_sensitivities`; the
rate is linear in them, so each refit is exact and needs no new equilibrium). Preston's law
``s P U`` and the mean are fitted to the same points with the same weights.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np

from ..validation.compare import _loo, _rms
from ..validation.data import from_si
from .film import chemistry_sensitivities
from .identify import choose
from .registry import FILM_REMOVAL, _film_candidates

__all__ = ["SeriesLOO", "series_loo", "linear_fit", "compare_with_preston"]


@dataclass
class SeriesLOO:
    """Leave-one-out RMS errors of one series in its ``unit``: the ``calibrated`` model, ``preston``
    (s P U), the ``mean``, and the scale-only model (``model``, None for an absolute series); the
    inputs the whole series would calibrate (``inputs``) and each point's calibrated LOO error."""

    name: str
    unit: str
    n: int
    calibrated: float
    preston: float
    mean: float
    model: float | None = None
    inputs: list = field(default_factory=list)
    errors: list = field(default_factory=list)

    @property
    def beats_preston(self) -> bool:
        return bool(np.isfinite(self.calibrated) and self.calibrated < self.preston * (1 - 1e-9))


def linear_fit(X: np.ndarray, y: np.ndarray, w: np.ndarray, low: np.ndarray) -> np.ndarray:
    """theta minimising sum w (X theta - y)^2 with theta >= ``low`` (scipy lsq_linear, bounded)."""
    from scipy.optimize import lsq_linear

    sw = np.sqrt(w)
    A = X * sw[:, None]
    col = np.linalg.norm(A, axis=0)
    col = np.where(col > 0, col, 1.0)
    res = lsq_linear(A / col, y * sw, bounds=(low * col, np.full(len(col), np.inf)), method="bvls")
    return res.x / col


def _choose(X, w, names, whys, max_free):
    """``choose`` on the weighted columns as directions (each scaled to unit norm: the derivatives
    of a rate in k, B and R_c differ by orders of magnitude, and only their directions matter here)."""
    A = X * np.sqrt(w)[:, None]
    norms = np.linalg.norm(A, axis=0)
    return choose(A / np.where(norms > 0, norms, 1.0), names, whys, max_free)


def series_loo(dataset, results, config, values_si=None) -> SeriesLOO | None:
    """The leave-one-out errors of a removal series (None if it is not one, or a point has no equilibrium).

    ``results`` are the solved points of ``dataset`` (``cmpsim.validation.solve_points``) under
    ``config``; ``values_si`` their model values (SI) for the scale-only model of a shape series.
    """
    pts = dataset.points
    if len(pts) < 3 or any(p.quantity not in FILM_REMOVAL.quantities for p in pts) or any(r is None for r in results):
        return None
    unit = pts[0].unit
    if any(p.unit != unit for p in pts):
        return None
    y = np.array([p.value_si for p in pts])
    unc = [p.uncertainty_si for p in pts]
    w = np.array([1.0 / u**2 for u in unc]) if all(unc) else np.ones(len(pts))
    cands = _film_candidates(pts, config)
    names, whys = [c.name for c in cands], [c.why for c in cands]
    sens = [chemistry_sensitivities(r, p.film, p.where, p.quantity) for p, r in zip(pts, results)]
    X = np.array([[s.get(n, 0.0) for n in names] for s in sens])
    fixed = np.array([[getattr(r.config, n) for n in names] for r in results])
    base = np.sum(X * fixed, axis=1)  # the model with the constants it has (the uncalibrated: the mechanical rate)
    low = np.array([0.0 for _ in names])
    err = np.full(len(pts), np.nan)
    for i in range(len(pts)):
        keep = np.arange(len(pts)) != i
        pick = _choose(X[keep], w[keep], names, whys, keep.sum() - 1).names
        cols = [names.index(n) for n in pick]
        offset = base - np.sum(X[:, cols] * fixed[:, cols], axis=1)  # the inputs left at their values
        theta = linear_fit(X[keep][:, cols], y[keep] - offset[keep], w[keep], low[cols])
        err[i] = offset[i] + X[i, cols] @ theta - y[i]
    whole = _choose(X, w, names, whys, len(pts) - 1)
    pu = np.array([r.config.applied_pressure * r.scalars["sliding_speed"] for r in results])
    q = pts[0].quantity

    def in_unit(e: float) -> float:  # an error (a difference, SI) in the series' unit
        return from_si(e, unit, q) - from_si(0.0, unit, q) if math.isfinite(e) else float("nan")

    def rms(errors) -> float:
        return _rms([in_unit(e) for e in errors])

    model = rms(_loo(np.asarray(values_si, dtype=float), y, w)) if dataset.comparison == "shape" and values_si is not None else None
    return SeriesLOO(dataset.name, unit, len(pts), rms(err), rms(_loo(pu, y, w)), rms(_loo(None, y, w)), model, whole.names, [in_unit(e) for e in err])


def compare_with_preston(report) -> list[SeriesLOO]:
    """The leave-one-out comparison of every removal series of a validation report
    (``cmpsim.validate``), stored in ``report.calibrated_loo`` and returned: the calibrated model
    (the film chemistry refitted without each point) beside Preston's law and the mean."""
    out = []
    for ds, values, results in report.solved.values():
        if ds.kind != "measurement":
            continue
        one = series_loo(ds, results, report.config, values)
        if one is not None:
            out.append(one)
    report.calibrated_loo = out
    return out
