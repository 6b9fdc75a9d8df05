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

Rooms: ``request`` (what may be fitted; the checks of a request),
``residuals`` (the whitened residuals as a function of the fit
variables), ``uncertainty`` (covariance, standard errors, intervals),
``result`` (:class:`CalibrationResult` and its report);
:func:`calibrate` runs them in order.
"""

from __future__ import annotations

import time
from typing import Any

import numpy as np

from ..inputs.config import Config
from ..validation import _as_datasets
from ..inputs.config import PARAMETERS
from .heldout import series_loo
from .identify import ZERO_JACOBIAN, choose, refuse_flat, separability  # noqa: F401 - ZERO_JACOBIAN: kept where it was
from .registry import candidates
from .request import (CALIBRATABLE, CalibrationError, check_data, default_bounds, fit_bounds, fit_scale_of, fitted_in_log, free_names, inside,
                      required_settings, start_config)
from .residuals import FAILED_POINT_PENALTY, _point_rows, _Problem
from .result import CalibrationResult
from .uncertainty import central_jacobian, uncertainty

__all__ = ["calibrate", "CalibrationResult", "CalibrationError", "default_bounds", "CALIBRATABLE"]


def __getattr__(name: str):
    if name == "synthetic_dataset":  # moved to cmpsim.testing: data for tests, not a step of a calibration
        from ..testing import synthetic_dataset

        return synthetic_dataset
    raise AttributeError(f"module {__name__!r} has no attribute {name!r}")


def calibrate(
    data,
    free=None,
    config: Config | None = None,
    bounds: dict[str, tuple[Any, Any]] | None = None,
    grid: str | None = None,
    start: dict[str, Any] | None = None,
    max_nfev: int | None = None,
    progress: bool = False,
    include_model_predictions: bool = False,
) -> CalibrationResult:
    """Fit inputs to the data with bounded least squares; without ``free`` the data choose them.

    Parameters
    ----------
    data : path, Dataset, or a sequence of them
        Data files in the format of ``cmpsim/data/README.md``.
    free : str or sequence of str, optional
        Names of the inputs to fit (see ``cmpsim params``), e.g. ``["asperity_density"]``. None (or
        empty): the data's quantities choose the inputs they can identify
        (:mod:`cmpsim.calibration.registry`: removal rates of a film -> its chemistry constants k_F,
        R_c,F, B_F), keeping those the Jacobian at the start can separate with one degree of freedom
        left (:func:`cmpsim.calibration.identify.choose`); ``CalibrationResult.choice`` says which and why.
    config : Config, optional
        Starting configuration (default :meth:`Config.default`); the other inputs stay fixed.
    bounds : dict, optional
        ``{name: (low, high)}`` with units (``"50 MPa"``) or SI numbers; default a factor 10
        either side of the start for positive inputs, clipped to the valid range; for the film
        chemistry's constants (fitted linearly) from 0 to 100 typical values.
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
        degrees of freedom, data that choose no input, or no equilibrium at the start.
    """
    from scipy.optimize import least_squares

    t0 = time.perf_counter()
    datasets = _as_datasets(data)
    original = config or Config.default()
    if grid is not None:
        original = original.replace(grid=grid)
    choice = None
    if free is None or (not isinstance(free, str) and len(list(free)) == 0):
        if start or bounds:
            raise CalibrationError("start values and bounds name free inputs: give --free with them, or neither")
        check_data(datasets, [], include_model_predictions)
        choice, free = _choose_free(datasets, original)
    free = free_names(free)
    check_data(datasets, free, include_model_predictions)
    settings = {k: v for n in free for k, v in required_settings(n).items()}
    original = original.replace(**settings) if settings else original
    base = start_config(original, None, start, free)
    # the request: start values, how each is fitted, bounds; the start strictly inside them
    start_vals = {n: float(getattr(base, n)) for n in free}
    log = {n: fitted_in_log(n, start_vals[n]) for n in free}
    scale = {n: fit_scale_of(n, start_vals[n]) if not log[n] else 1.0 for n in free}
    bnds = fit_bounds(free, bounds, start_vals, log)
    before_config = base
    for n in free:
        v = inside(start_vals[n], bnds[n], log[n], PARAMETERS[n].linear)
        if v != start_vals[n]:
            start_vals[n] = v
            base = base.replace(**{n: v})
    problem = _Problem(datasets, base, free, start_vals, log, scale)
    n_shape = sum(1 for d in datasets if d.comparison == "shape")
    n_pts = len(problem.points)
    dof = n_pts - len(free) - n_shape
    if dof < 0:
        raise CalibrationError(f"{n_pts} points cannot determine {len(free)} parameters plus {n_shape} shape scale(s)")
    # before: the model as given (the start moved inside the bounds only for the fit)
    z_before = problem.z_of({n: float(getattr(before_config, n)) for n in free}) if before_config is not base else np.zeros(len(free))
    m0, res0, st0 = problem.model(z_before)
    if not np.isfinite(m0).all():
        bad = [f"{ds.name} line {p.line}" for (ds, p), v in zip(problem.points, m0) if not np.isfinite(v)]
        raise CalibrationError(f"no equilibrium at the starting values for {', '.join(bad)}")
    r0 = problem.whiten(m0)
    rows_before = _point_rows(problem, m0, res0, st0)
    # the fit
    if progress:
        from rich.console import Console

        console = Console(stderr=True)
        problem.callback = lambda k, c: console.print(f"  evaluation {k}: chi-square {c:.6g}", highlight=False)
    lower = problem.z_of({n: bnds[n][0] for n in free})
    upper = problem.z_of({n: bnds[n][1] for n in free})
    z0 = np.zeros(len(free))
    fit = least_squares(
        problem,
        z0,
        bounds=(lower, upper),
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
    # after: uncertainty at the optimum, then the model there
    J = central_jacobian(problem, z, n_pts, lower=lower, upper=upper)
    # the optimiser moved an input the data do not depend on for nothing: its "fitted" value would be arbitrary
    refuse_flat(J, free, "the model's values at these data", "inputs", "--free", CalibrationError)
    m1, res1, st1 = problem.model(z)
    r1 = problem.whiten(m1)
    chi2 = float(np.sum(r1 * r1))
    values = problem.values_of(z)
    unc = uncertainty(J, chi2, dof, problem.absolute_sigma, values, log, scale, bnds)
    given = sum(p.uncertainty is not None and p.comparison in ("absolute", "range", "shape") for _, p in problem.points)
    if 0 < given < n_pts:  # say how the two kinds of point were weighted against each other
        unc.notes.append(f"{n_pts - given} of {n_pts} points have no uncertainty: each is weighted as if its uncertainty were its own "
                         f"value (its relative error), the other {given} by their uncertainty; give every point one, or none")
    failed = int((~np.isfinite(m1)).sum())
    if failed:
        unc.notes.append(f"{failed} point(s) have no equilibrium at the fitted values (penalised with a residual of {FAILED_POINT_PENALTY:g})")
    separations, singular = separability(J, list(free), unc.correlation)
    fitted = problem.config_of(z)
    loo = []
    idx = 0
    for ds in datasets:  # leave one out on each removal series: the film chemistry refitted without the point
        n = len(ds.points)
        one = series_loo(ds, res1[idx : idx + n], fitted, list(m1[idx : idx + n]))
        if one is not None:
            loo.append(one)
        idx += n
    return CalibrationResult(
        free=list(free),
        config=fitted,
        initial_config=before_config,
        values=values,
        initial={n: float(getattr(before_config, n)) for n in free},
        stderr=unc.stderr,
        ci95=unc.ci95,
        correlation=unc.correlation,
        bounds=bnds,
        log_scale=log,
        residuals_before=r0,
        residuals_after=r1,
        points_before=rows_before,
        points_after=_point_rows(problem, m1, res1, st1),
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
        notes=unc.notes,
        choice=choice,
        identifiability=separations,
        singular_values=singular,
        loo=loo,
        data=[str(d.path or d.name) for d in datasets],
        settings=settings,
    )


def _choose_free(datasets, config: Config):
    """The inputs the data choose (:mod:`cmpsim.calibration.registry`), kept if the Jacobian at the start separates them."""
    cands, notes = candidates(datasets, config)
    if not cands:
        raise CalibrationError("the data choose no input to fit" + (": " + "; ".join(notes) if notes else "") + "; give --free NAME ...")
    names = [c.name for c in cands]
    settings = {k: v for c in cands for k, v in c.settings}
    base = config.replace(**settings) if settings else config
    start_vals = {n: float(getattr(base, n)) for n in names}
    log = {n: fitted_in_log(n, start_vals[n]) for n in names}
    scale = {n: fit_scale_of(n, start_vals[n]) if not log[n] else 1.0 for n in names}
    bnds = {n: default_bounds(n, start_vals[n]) for n in names}
    problem = _Problem(datasets, base, names, start_vals, log, scale)
    n_pts = len(problem.points)
    n_shape = sum(1 for d in datasets if d.comparison == "shape")
    J = central_jacobian(problem, np.zeros(len(names)), n_pts, lower=problem.z_of({n: bnds[n][0] for n in names}), upper=problem.z_of({n: bnds[n][1] for n in names}))
    choice = choose(J, names, [c.why for c in cands], max(n_pts - n_shape - 1, 0))
    choice.notes = notes
    if not choice.names:
        raise CalibrationError("the data identify none of the inputs they could choose: " + "; ".join(f"{n}: {why}" for n, why in choice.left))
    return choice, choice.names
