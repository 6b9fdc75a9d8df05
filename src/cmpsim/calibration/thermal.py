"""Calibrate the pad's friction and heat removal on a measured temperature or friction (docs/calibrate-die.md).

The pad's temperature in ``cmpsim polish`` (docs/polisher.md, section 1) is the thermal column of
:func:`cmpsim.physics.thermal.polisher_column` heated by the frictional power per unit wafer area
q = <tau . (u_pad - u_wafer)> of the solved step. Two constants decide its rise:

* the summit friction mu (``friction_coefficient``): the frictional power of a solved state is
  exactly linear in it, q(mu) = q_s + mu q_c, q_s from the slurry's shear and
  q_c = <p_c |u_pad - u_wafer|> from the summits' contact pressure (mu enters neither the
  equilibrium nor the slurry's shear), so one solve per operating condition gives q for every mu
  (T1);
* the heat removal h_s (``pad_heat_transfer_coefficient``, W/(m^2 K) per unit track area): the
  column's surface loss, by default rho_w c_w Q / A_track from the slurry flow (an upper bound).

Measured quantities (:class:`cmpsim.calibration.measurements.ThermalRecord`):
``pad_temperature_rise`` at a ``time`` from the start of the step (the column's surface, from the
slurry's temperature), and ``friction_coefficient``, compared with q / (P U), U the wafer-mean
sliding speed (the effective friction of the heat balance; 0.45 on the 300mm preset at 3 psi).
A rise alone fixes only the ratio q / h_s near the plateau; its rise time fixes h_s through the
column's capacity, a friction fixes q: the Jacobian's correlation says which is the case.

The fit is :func:`calibrate_thermal`: ln(value) least squares, covariance (J^T J)^-1 (absolute
when every point has an uncertainty), 95 % intervals exp(z +- 1.96 sigma), as
:func:`cmpsim.calibration.die.calibrate_die`.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np

from .identify import refuse_flat
from .measurements import ThermalRecord
from .scalefit import ScaleFit, fit_statistics, interval_text
from .uncertainty import central_jacobian

__all__ = ["THERMAL_CONSTANTS", "FrictionalPower", "frictional_power", "predict_thermal", "calibrate_thermal", "ThermalCalibration",
           "step_rise", "choose_free", "start_values", "start_jacobian"]

#: The constants a pad calibration may fit: name -> (SI unit, valid (low, high), meaning).
THERMAL_CONSTANTS = {
    "friction_coefficient": ("1", (1e-3, 5.0), "Coulomb friction of the pad summits on the wafer"),
    "pad_heat_transfer_coefficient": ("W/(m^2*K)", (1.0, 1e6), "heat carried from the pad surface to the slurry per track area and kelvin"),
}


@dataclass(frozen=True)
class FrictionalPower:
    """q(mu) = slurry + mu * contact (W/m^2 of wafer) of one solved state; ``pressure`` (Pa) and ``speed`` (m/s, wafer mean)."""

    slurry: float
    contact: float
    pressure: float
    speed: float
    wafer_radius: float
    centre_distance: float
    slurry_temperature: float

    def power(self, mu: float) -> float:
        """Frictional power per unit wafer area, W/m^2 (eq. T1)."""
        return self.slurry + mu * self.contact

    def friction(self, mu: float) -> float:
        """Effective friction q / (P U), dimensionless."""
        return self.power(mu) / (self.pressure * self.speed)


_CACHE: dict = {}


def frictional_power(config) -> FrictionalPower:
    """Solve ``config`` once and split its frictional power into the slurry's and the summits' per unit mu (cached)."""
    from ..solver.model import solve
    from ..solver.postprocess import stress_fields

    key = repr(sorted((k, repr(v)) for k, v in config.to_dict().items() if k not in ("friction_coefficient", "pad_heat_transfer_coefficient")))
    if key in _CACHE:
        return _CACHE[key]
    r = solve(config)
    problem, state = r.problem, r.solution.state
    kin = problem.lub.kinematics
    area = problem.grid.area

    def q(mu):
        st = stress_fields(config.replace(friction_coefficient=mu), problem, state, kin, problem.lub)
        tx, ty = st["shear_stress"]
        dux, duy = st["relative_velocity"]
        return float(np.sum((tx * dux + ty * duy) * area) / np.sum(area)), float(np.sum(np.hypot(dux, duy) * area) / np.sum(area))

    q0, speed = q(0.0)
    q1, _ = q(1.0)
    out = FrictionalPower(q0, q1 - q0, float(config.applied_pressure), speed, 0.5 * float(config.wafer_diameter),
                          float(config.centre_distance), float(config.slurry_temperature))
    _CACHE[key] = out
    return out


def step_rise(fp: FrictionalPower, mu: float, h_s: float | None, time: float, flow_rate: float | None = None) -> float:
    """The pad surface's rise (K) after ``time`` s of a step from the slurry's temperature (the column of cmpsim polish)."""
    from ..physics.thermal import polisher_column
    from ..polisher.engine import PLATEN, SLURRY_FLOW_RATE

    col = polisher_column(fp.wafer_radius, fp.centre_distance, flow_rate or SLURRY_FLOW_RATE, platen=PLATEN,
                          slurry_temperature=fp.slurry_temperature, surface_coefficient=h_s)
    T0 = fp.slurry_temperature
    return float(col.advance(col.initial_state(T0), fp.power(mu), float(time)).surface - T0)


def _record_config(record: ThermalRecord, base):
    from ..validation.data import point_config

    cond = dict(record.conditions)
    if "wafer_diameter" in cond and "zone_radii" not in cond and getattr(base, "zone_radii", ()):
        # another wafer than the base's: its head's zones are not known, one zone over the wafer
        base = base.replace(zone_radii=(), wafer_diameter=cond.pop("wafer_diameter"))
    return point_config(base, cond)


def predict_thermal(records, constants: dict | None = None, config=None) -> np.ndarray:
    """The model's value (SI) of every pad record with ``constants`` (friction_coefficient, pad_heat_transfer_coefficient) over ``config``'s."""
    from ..inputs.config import Config

    base = config if config is not None else Config.preset("300mm").replace(grid="coarse")
    consts = dict(constants or {})
    out = []
    for r in records:
        cfg = _record_config(r, base)
        fp = frictional_power(cfg)
        mu = consts.get("friction_coefficient", cfg.friction_coefficient)
        if r.quantity == "friction_coefficient":
            out.append(fp.friction(mu))
        else:
            hs = consts.get("pad_heat_transfer_coefficient", cfg.pad_heat_transfer_coefficient) or None
            out.append(step_rise(fp, mu, hs, r.time, r.slurry_flow_rate))
    return np.array(out)


@dataclass
class ThermalCalibration(ScaleFit):
    """Fitted pad constants (SI) with 95 % intervals, correlations, residuals before/after and what the data cannot
    separate (:class:`cmpsim.calibration.scalefit.ScaleFit`)."""

    config: object = field(default=None, repr=False)

    @property
    def constants(self) -> dict:
        """The constants to write into the process file (SI): ``friction_coefficient``, ``pad_heat_transfer_coefficient``."""
        return dict(self.values)

    def predict(self, records) -> np.ndarray:
        return predict_thermal(records, self.values, self.config)

    def to_dict(self) -> dict:
        return {"free": list(self.free), "values": dict(self.values), "start": dict(self.start),
                "ci95": {k: list(v) for k, v in self.ci95.items()}, "stderr": dict(self.stderr),
                "correlation": np.asarray(self.correlation).tolist(), "chi2": self.chi2, "dof": self.dof,
                "reasons": dict(self.reasons), "identifiability": list(self.identifiability), "constants": self.constants,
                "points": [{"dataset": r.dataset, "line": r.line, "quantity": r.quantity, "time": r.time, "measured": float(m),
                            "model_before": float(b), "model_after": float(a)}
                           for r, m, b, a in zip(self.records, self.measured, self.model_before, self.model_after)],
                "units": {"friction_coefficient": "1", "pad_heat_transfer_coefficient": "W/(m^2*K)", "time": "s",
                          "pad_temperature_rise": "K"}}

    def summary(self) -> str:
        from ..tables import text_table

        rows = [[n, f"{self.start[n]:.4g}", f"{self.values[n]:.4g}", interval_text(*self.ci95[n]),
                 THERMAL_CONSTANTS[n][0], self.reasons.get(n, "")] for n in self.free]
        out = [text_table(["constant", "start", "fitted", "95 % interval", "unit", "why free"], rows), ""]
        if len(self.free) > 1:
            out.append(f"correlation of ln values: {self.correlation[0, 1]:+.3f}")
        pts = [[r.dataset, r.quantity, "-" if r.time is None else f"{r.time:g}", f"{m:.4g}", f"{b:.4g}", f"{a:.4g}"]
               for r, m, b, a in zip(self.records, self.measured, self.model_before, self.model_after)]
        out.append(text_table(["dataset", "quantity", "t s", "measured", "before", "after"], pts))
        out += [f"identifiability: {s}" for s in self.identifiability]
        return "\n".join(out)


def choose_free(records) -> tuple[list[str], dict[str, str]]:
    """The pad constants the quantities of ``records`` could identify, and why (name -> reason), in preference order."""
    temps = [r for r in records if r.quantity == "pad_temperature_rise"]
    fric = [r for r in records if r.quantity == "friction_coefficient"]
    reasons = {}
    if fric or len({r.time for r in temps}) >= 3:
        reasons["friction_coefficient"] = ("a measured friction is q/(P U) of the summits and the slurry" if fric else
                                           "a trace's early slope is q/(heat capacity), independent of the heat removal")
    if temps:
        reasons["pad_heat_transfer_coefficient"] = "the rise approaches f q / h_s: with q known, it fixes the heat removal"
    return [n for n in THERMAL_CONSTANTS if n in reasons], reasons


def start_values(records, config=None) -> dict:
    """The uncalibrated pad constants (SI): the configuration's friction, the heat removal of the slurry flow of the first record."""
    from ..inputs.config import Config
    from ..physics.thermal import slurry_heat_transfer_coefficient
    from ..polisher.engine import SLURRY_FLOW_RATE

    base = config if config is not None else Config.preset("300mm").replace(grid="coarse")
    cfg0 = _record_config(records[0], base)
    hs0 = cfg0.pad_heat_transfer_coefficient or float(slurry_heat_transfer_coefficient(
        records[0].slurry_flow_rate or SLURRY_FLOW_RATE, 4 * math.pi * cfg0.centre_distance * 0.5 * cfg0.wafer_diameter))
    return {"friction_coefficient": float(cfg0.friction_coefficient), "pad_heat_transfer_coefficient": hs0}


def start_jacobian(records, names, config=None, step: float = 1e-3) -> np.ndarray:
    """d((model - measured)/u)/d ln(constant) of every record at the start values (central differences), one column per name."""
    s0 = start_values(records, config)
    base = config if config is not None else None
    u = np.array([r.uncertainty if r.uncertainty is not None else max(abs(r.value), 1e-12) * 0.1 for r in records])
    J = np.empty((len(records), len(names)))
    for k, n in enumerate(names):
        up = predict_thermal(records, {**s0, n: s0[n] * math.exp(step)}, base)
        dn = predict_thermal(records, {**s0, n: s0[n] * math.exp(-step)}, base)
        J[:, k] = (up - dn) / (2 * step * u)
    return J


def calibrate_thermal(records, config=None, free=None, *, start: dict | None = None, max_nfev: int = 100) -> ThermalCalibration:
    """Fit the summit friction and the pad's heat removal to measured pad temperatures or frictions.

    ``records``: :class:`ThermalRecord` (or a path); ``config``: the base configuration of the
    records' conditions (default the 300mm preset on the coarse grid); ``free``: names of
    :data:`THERMAL_CONSTANTS` (default: friction records free ``friction_coefficient``,
    temperature records ``pad_heat_transfer_coefficient``, both when the data hold both or a
    temperature trace of three or more times). One wafer solve per operating condition.
    """
    from scipy.optimize import least_squares

    from ..inputs.config import Config

    if isinstance(records, (str, bytes)) or hasattr(records, "__fspath__"):
        from .measurements import read_measurements

        records = read_measurements(records)
    records = [r for r in records if isinstance(r, ThermalRecord)]
    if not records:
        raise ValueError("no pad records (pad_temperature_rise, friction_coefficient) to calibrate on")
    base = config if config is not None else Config.preset("300mm").replace(grid="coarse")
    asked = free is not None
    if free is None:
        free, reasons = choose_free(records)
    else:
        free = [free] if isinstance(free, str) else list(free)
        reasons = {n: "asked for" for n in free}
    for n in free:
        if n not in THERMAL_CONSTANTS:
            raise ValueError(f"unknown pad constant {n!r}; calibratable: {', '.join(THERMAL_CONSTANTS)}")
    s0 = start_values(records, base)
    s0.update(start or {})
    x0 = np.array([s0[n] for n in free])
    lo = np.array([THERMAL_CONSTANTS[n][1][0] for n in free])
    hi = np.array([THERMAL_CONSTANTS[n][1][1] for n in free])
    y = np.array([r.value for r in records])
    absolute = all(r.uncertainty is not None for r in records)
    u = np.array([r.uncertainty if r.uncertainty is not None else max(abs(r.value), 1e-12) * 0.1 for r in records])

    def values_of(z):
        return {**s0, **{n: float(x0[k] * math.exp(z[k])) for k, n in enumerate(free)}}

    def resid(z):
        return (predict_thermal(records, values_of(z), base) - y) / u

    z0 = np.zeros(len(free))
    m0 = predict_thermal(records, s0, base)
    fit = least_squares(resid, z0, bounds=(np.log(lo / x0), np.log(hi / x0)), method="trf", diff_step=1e-4, ftol=1e-12, xtol=1e-12,
                        gtol=1e-14, max_nfev=max_nfev)
    z = fit.x
    J = central_jacobian(resid, z, len(records), h=1e-4)
    if asked:  # asked for, and the pad rows do not change with it: its "fitted" value would be its start
        refuse_flat(J, free, "these pad rows", "the constants")
    vals = {n: float(x0[k] * math.exp(z[k])) for k, n in enumerate(free)}
    chi2, dof, notes, cov, corr, ci, stderr = fit_statistics(J, resid(z), free, vals, absolute, lo, hi)
    m1 = predict_thermal(records, {**s0, **vals}, base)
    return ThermalCalibration(list(free), vals, {n: float(s0[n]) for n in free}, stderr, ci, corr, cov, records, y, m0, m1, chi2, dof,
                              absolute, reasons, notes, base)
