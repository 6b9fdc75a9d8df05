"""The pad life's glazing and conditioning constants from a lot's wafers: ``cmpsim calibrate LOT.csv --recipe RECIPE``.

A lot's per-wafer rows (``wafer``, ``thickness`` or ``removal``: :mod:`cmpsim.calibration.lotdata`)
are compared with ``cmpsim lot`` of the recipe (:func:`cmpsim.polisher.lot.run_lot`) over as many
wafers as the rows name. The constants of the pad's life (:mod:`cmpsim.physics.padlife`,
docs/polisher.md "Pad life") are fitted to them by bounded least squares in ln(value):

- ``pad_wear_coefficient`` k_w (1/Pa): Archard's wear of the summit caps, dW/dt = k_w P U (eq. L2),
  i.e. how fast the glazing front moves with the polish time;
- ``critical_glazed_area`` G_c (1): the glazed area at which the rate is halved, RR/RR_fresh =
  1/(1 + G/G_c) (eq. L4), i.e. how much the glazing costs in rate;
- ``conditioner_rate_constant`` k_c (1/(N s)): the disk's renewal r_c = k_c F_d s_d, i.e. how much
  of the glazing the conditioning undoes (only a lot that is conditioned can say).

The glazing changes a wafer's rate, not its equilibrium, so one lot's solves serve every
evaluation (a shared cache). Covariance (J^T J)^-1 at the optimum (scaled by the reduced
chi-square without uncertainties, undefined without a scatter: :func:`cmpsim.calibration.uncertainty.covariance`), 95 % intervals in ln(value), correlations, and what the data
cannot separate (:func:`cmpsim.calibration.identify.choose` before the fit, the correlations after).
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np

from ..physics.padlife import GLAZING_CONSTANTS, check_constants, default_constants
from .identify import refuse_flat
from .scalefit import ScaleFit, fit_statistics, interval_text

__all__ = ["GLAZING_CONSTANTS", "LotSetting", "PadLifeCalibration", "default_constants", "check_constants", "predict_lot",
           "choose_free", "start_jacobian", "calibrate_padlife", "padlife_constants"]


@dataclass
class LotSetting:
    """How the measured lot was run: its ``recipe`` (path or parsed), ``conditioning`` (None: the recipe's,
    else in situ), ``control``, incoming ``seed``, ``qualification`` wafers, ``idle_time`` (s) and the
    ``overrides`` (the process file's constants, as ``cmpsim lot --config``)."""

    recipe: object
    conditioning: str | None = None
    control: str = "none"
    seed: int | None = 0
    qualification: int = 1
    idle_time: float = 30.0
    overrides: dict = field(default_factory=dict)
    cache: dict = field(default_factory=dict, repr=False)

    def __post_init__(self) -> None:
        from ..polisher.recipe import read_recipe

        if not hasattr(self.recipe, "steps"):
            self.recipe = read_recipe(self.recipe)

    @property
    def effective_conditioning(self) -> str:
        return self.conditioning or self.recipe.conditioning or "in_situ"


def predict_lot(records, constants: dict | None, setting: LotSetting) -> np.ndarray:
    """The model value (m) of every lot record under ``constants`` (missing names: the defaults)."""
    from ..polisher.lot import run_lot

    top = setting.recipe.films[0].material
    for r in records:
        if r.film is not None and r.film != top:
            raise ValueError(f"{r.path}:{r.line}: column 'film': {r.film!r} is not the recipe's top film ({top}), the film a lot measures")
    from .lotdata import logged_times, logged_zone_pressures

    n = max(r.wafer for r in records)
    times = logged_times(records)  # a lot under the fab's own control: replayed at its logged times (and zone pressures)
    lot = run_lot(setting.recipe, n, conditioning=setting.conditioning, control="none" if times else setting.control, seed=setting.seed,
                  overrides=dict(setting.overrides), idle_time=setting.idle_time, qualification=setting.qualification,
                  pad_constants=dict(constants or {}), cache=setting.cache, polish_times=times,
                  polish_zone_pressures=logged_zone_pressures(records))
    out = []
    for r in records:
        w = lot.wafers[r.wafer - 1]
        out.append(w.final_thickness_mean if r.quantity == "thickness" else w.incoming_mean - w.final_thickness_mean)
    return np.array(out, dtype=float)


def _sigma(records) -> tuple[np.ndarray, bool]:
    """Each record's uncertainty (m; without one, 1 % of its value) and whether all were given."""
    absolute = all(r.uncertainty is not None for r in records)
    return np.array([r.uncertainty if r.uncertainty is not None else max(abs(r.value), 1e-12) * 0.01 for r in records]), absolute


def choose_free(records, setting: LotSetting) -> tuple[list[str], dict[str, str]]:
    """The constants a lot's records could identify, and why, in order of preference."""
    wafers = sorted({r.wafer for r in records})
    reasons = {}
    if len(wafers) >= 2:
        reasons["critical_glazed_area"] = (f"{len(wafers)} wafer(s): how far the rate falls as the pad glazes is 1/(1 + G/G_c)")
        reasons["pad_wear_coefficient"] = ("the shape of the decay over the wafers: how fast the glazing front moves with the polish time "
                                           "(k_w P U)")
    cond = setting.effective_conditioning
    if cond != "none":
        reasons["conditioner_rate_constant"] = f"a lot conditioned {cond.replace('_', ' ')}: the disk's renewal sets the glazing it leaves"
    return [n for n in GLAZING_CONSTANTS if n in reasons], reasons


def start_jacobian(records, names, setting: LotSetting, values: dict | None = None, step: float = 0.05) -> np.ndarray:
    """d((model - measured)/u)/d ln(constant) of every record (central differences), one column per name."""
    s0 = {**default_constants(), **(values or {})}
    u, _ = _sigma(records)
    J = np.empty((len(records), len(names)))
    for k, n in enumerate(names):
        up = predict_lot(records, {**s0, n: s0[n] * math.exp(step)}, setting)
        dn = predict_lot(records, {**s0, n: s0[n] * math.exp(-step)}, setting)
        J[:, k] = (up - dn) / (2 * step * u)
    return J


@dataclass
class PadLifeCalibration(ScaleFit):
    """Fitted pad life constants (SI) with 95 % intervals, correlations, residuals before and after, and identifiability
    (:class:`cmpsim.calibration.scalefit.ScaleFit`); ``left``: the constants the lot could not separate, and why;
    ``setting``: how the lot ran."""

    left: list = field(default_factory=list)
    setting: object = field(default=None, repr=False)

    @property
    def constants(self) -> dict:
        """Every pad life constant the lot runs with (SI): the fitted ones, the others at their defaults."""
        return {**default_constants(), **self.values}

    def table(self) -> dict:
        """The ``[calibration.padlife]`` extras: the lot's setting (what a held-out lot must share)."""
        s = self.setting
        return {"recipe": str(s.recipe.source), "conditioning": s.effective_conditioning, "control": s.control,
                "seed": -1 if s.seed is None else int(s.seed), "qualification": int(s.qualification), "idle_time": float(s.idle_time)}

    def summary(self) -> str:
        from ..tables import text_table

        rows = [[n, f"{self.start[n]:.4g}", f"{self.values[n]:.4g}", interval_text(*self.ci95[n]),
                 GLAZING_CONSTANTS[n][0], self.reasons.get(n, "")] for n in self.free]
        out = [text_table(["constant", "start", "fitted", "95 % interval", "unit", "why free"], rows), ""]
        if len(self.free) > 1:
            out.append("correlation of ln values:")
            out.append(text_table(["", *self.free], [[n, *(f"{c:+.3f}" for c in row)] for n, row in zip(self.free, np.asarray(self.correlation))]))
        pts = [[str(r.wafer), r.quantity, f"{m * 1e9:.1f}", f"{b * 1e9:.1f}", f"{a * 1e9:.1f}"]
               for r, m, b, a in zip(self.records, self.measured, self.model_before, self.model_after)]
        out.append(text_table(["wafer", "quantity", "measured nm", "before nm", "after nm"], pts))
        rb = float(np.sqrt(np.mean(self.residuals_before**2))) * 1e9
        ra = float(np.sqrt(np.mean(self.residuals_after**2))) * 1e9
        out.append(f"RMS residual {rb:.2f} nm before, {ra:.2f} nm after (chi-square {self.chi2:.4g}, {self.dof} degree(s) of freedom)")
        out += [f"fixed {n}: {why}" for n, why in self.left]
        out += [f"identifiability: {s}" for s in self.identifiability]
        out += [f"warning: {w}" for w in self.warnings]
        return "\n".join(out)

    @property
    def warnings(self) -> list[str]:
        """What the intervals do not cover: they are conditional on the constants left at their values, and
        with uncertainties on every row a chi-square far above its degrees of freedom says those values are off."""
        from scipy.stats import chi2 as chi2_dist

        out = []
        if self.left:
            out.append("the intervals are conditional on " + ", ".join(n for n, _ in self.left) + " at the value(s) they were left at")
        if self.absolute_sigma and self.dof > 0:
            p = float(chi2_dist.sf(self.chi2, self.dof))
            if p < 0.01:
                out.append(f"chi-square {self.chi2:.4g} for {self.dof} degrees of freedom with the rows' uncertainties (p = {p:.2g}): the "
                           "lot is not described within its uncertainties; a constant left at its value is likely off, and the fitted "
                           "ones absorb it (their intervals are then too narrow)")
        return out


def calibrate_padlife(records, setting: LotSetting, free=None, *, max_nfev: int = 60) -> PadLifeCalibration:
    """Fit the glazing and conditioning constants to a lot's per-wafer rows (:class:`cmpsim.calibration.lotdata.LotRecord`).

    ``setting``: how the lot ran (:class:`LotSetting`); ``free``: names of :data:`GLAZING_CONSTANTS`
    (default: those the records could identify, :func:`choose_free`, kept where the Jacobian at the
    start separates them with one degree of freedom left).
    """
    from .uncertainty import central_jacobian
    from .identify import choose

    records = list(records)
    if not records:
        raise ValueError("no lot rows (a wafer column, quantity thickness or removal) to calibrate the pad life on")
    s0 = default_constants()
    left: list = []
    if free is None:
        from .identify import choose_records

        names, reasons = choose_free(records, setting)
        if not names:
            raise ValueError("the lot rows identify no pad life constant: they need two wafers or more")
        choice = choose_records(names, [reasons[n] for n in names], start_jacobian, records, setting, label="pad life")
        free, left = choice.names, choice.left
        reasons = dict(choice.chosen)
        choice_names, choice_whys = names, choose_free(records, setting)[1]
        if not free:
            raise ValueError("the lot rows identify no pad life constant: " + "; ".join(w for _, w in left))
    else:
        free = [free] if isinstance(free, str) else list(free)
        reasons = {n: "asked for" for n in free}
        choice_names = None
    for n in free:
        if n not in GLAZING_CONSTANTS:
            raise ValueError(f"unknown pad life constant {n!r}; calibratable: {', '.join(GLAZING_CONSTANTS)}")
    x0 = np.array([s0[n] for n in free])
    lo = np.array([GLAZING_CONSTANTS[n][1][0] for n in free])
    hi = np.array([GLAZING_CONSTANTS[n][1][1] for n in free])
    y = np.array([r.value for r in records])
    u, absolute = _sigma(records)

    m0 = predict_lot(records, s0, setting)
    z = _fit(records, setting, free, x0, lo, hi, y, u, s0, max_nfev)
    chosen_again = []
    if choice_names is not None and len(free) < len(choice_names):
        # chosen again at the first fit's values: the start's Jacobian can hide a direction the fitted constants show
        J1 = start_jacobian(records, choice_names, setting, values=values_from(z, free, x0))
        again = choose(J1, choice_names, [choice_whys[n] for n in choice_names], len(records) if absolute else max(len(records) - 1, 1))
        if set(free) < set(again.names):
            added = [n for n in again.names if n not in free]
            chosen_again.append(f"chosen again at the first fit's values ({', '.join(free)}): {', '.join(added)} now separated by the "
                                "Jacobian there, and fitted")
            left, reasons, free = list(again.left), dict(again.chosen), list(again.names)
            x0 = np.array([s0[n] for n in free])
            lo = np.array([GLAZING_CONSTANTS[n][1][0] for n in free])
            hi = np.array([GLAZING_CONSTANTS[n][1][1] for n in free])
            z = _fit(records, setting, free, x0, lo, hi, y, u, s0, max_nfev)

    def values_of(z):
        return values_from(z, free, x0)

    def resid(z):
        return (predict_lot(records, {**s0, **values_of(z)}, setting) - y) / u

    J = central_jacobian(resid, z, len(records), h=1e-3)
    if choice_names is None:  # asked for, and the lot's rows do not change with it: its "fitted" value would be its start
        refuse_flat(J, free, "this lot's rows", "the constants")
    vals = values_of(z)
    # the bounds read relative to the start (the constants are of order 1e-15 1/Pa: an absolute tolerance would call every value a bound)
    chi2, dof, notes, cov, corr, ci, stderr = fit_statistics(J, resid(z), free, vals, absolute, lo, hi, chosen_again, scale=x0)
    m1 = predict_lot(records, {**s0, **vals}, setting)
    return PadLifeCalibration(free=list(free), values=vals, start={n: float(s0[n]) for n in free}, stderr=stderr, ci95=ci, correlation=corr,
                              covariance=cov, records=records, measured=y, model_before=m0, model_after=m1, chi2=chi2, dof=dof,
                              absolute_sigma=absolute, reasons=reasons, identifiability=notes, left=left, setting=setting)


def values_from(z, free, x0) -> dict:
    """{name: value} of the fit variables z = ln(value / start)."""
    return {n: float(x0[k] * math.exp(z[k])) for k, n in enumerate(free)}


def _fit(records, setting, free, x0, lo, hi, y, u, s0, max_nfev) -> np.ndarray:
    """The least-squares optimum z = ln(value / start) of ``free`` (scipy least_squares, trust-region reflective, bounded)."""
    from scipy.optimize import least_squares

    def resid(z):
        return (predict_lot(records, {**s0, **values_from(z, free, x0)}, setting) - y) / u

    fit = least_squares(resid, np.zeros(len(free)), bounds=(np.log(lo / x0), np.log(hi / x0)), method="trf", diff_step=1e-3,
                        x_scale=1.0, ftol=1e-10, xtol=1e-10, gtol=1e-12, max_nfev=max_nfev)
    return fit.x


def padlife_constants(source) -> dict | None:
    """The ``[calibration.padlife]`` constants of a process file (a path), checked; None where there are none."""
    from .processfile import read_scale_table

    if source is None:
        return None
    pl, name = read_scale_table(source, "padlife")
    if not isinstance(pl, dict):
        return None
    consts = pl.get("constants", {})
    if not isinstance(consts, dict):
        raise ValueError(f"{name}: [calibration.padlife] constants must be a table of name = SI value")
    return check_constants(consts, f"{name}: [calibration.padlife] constants")
