"""Calibrate the die model's constants on test-structure measurements (docs/calibrate-die.md).

A measured test structure (:class:`cmpsim.calibration.measurements.StructureRecord`) is a
square block of lines of width w and space s (an isolated line without s) of side S inside a
field without lines (a block larger than the planarization length without S). cmpsim builds it
as a die layout (:meth:`TestStructure.layout`: the block at the centre of a field, a grid of
cells) and polishes it with the die model (:class:`cmpsim.die.evolution.DieEvolution`,
docs/model.md section 18) for the step's time at the step's blanket rate; the quantity is read
at the block's centre (the measurement site).

**The site alone.** The die model couples cells only through the effective density, a fixed
linear filter of the layout (the evolution of each cell depends on its own effective density,
width and space). With the Gaussian weighting w(r) = exp(-pi r^2/L^2)/L^2 the effective density
at the centre of a square block of side S and density rho_b in a field of density 0 is exactly

    rho_eff = rho_b erf(sqrt(pi) S / (2 L))^2                                   (C1)

(the weight of the square is the product of two one-dimensional Gaussian integrals). The fit
therefore evolves the measurement sites only, one cell per structure, vectorised; the layout
built on a grid gives the same site value (tested against the FFT of
:func:`cmpsim.die.effective_density`). An isolated line is one line in a field: its pitch is
:data:`ISOLATED_PITCH` (the bulge's logarithm is then cut by the pad's thickness, docs/model.md
18.5) and its density w / pitch (the pad sees a field).

**The fit.** The free constants (:data:`DIE_CONSTANTS`) are fitted as z = ln(value / start) by
bounded least squares (``scipy.optimize.least_squares``, trust-region reflective) on the residuals
(model - measured) / u, u the point's standard uncertainty. The covariance of z is
(J^T J)^-1 (J by central differences at the optimum), taken as absolute when every point carries
an uncertainty and scaled by the reduced chi-square otherwise; 95 % intervals are
exp(z +- 1.96 sigma_z) (asymmetric in the value), correlations from the same matrix. What the
data cannot separate is read from J: a constant whose column of J is zero is not seen by the data;
a pair with |correlation| > 0.95, or a standard error above a factor 10, is reported.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np

from .identify import refuse_flat
from .measurements import StructureRecord
from .scalefit import ScaleFit, fit_statistics, interval_text
from .uncertainty import central_jacobian

__all__ = ["DIE_CONSTANTS", "ISOLATED_PITCH", "TestStructure", "DieCalibration", "predict_die", "calibrate_die",
           "choose_free", "heldout_comparison", "start_jacobian", "start_values"]

#: Pitch (m) of an isolated line in a field: far beyond every length of the die model (the
#: pad's bulge into the gap converges beyond 1000 pad thicknesses, cmpsim.die.reach).
ISOLATED_PITCH = 1.0

#: The constants a calibration may fit: name -> (SI unit, valid (low, high), meaning). The
#: planarization length is the Gaussian convention's (docs/model.md 18.2); the others are
#: inputs of :class:`cmpsim.die.DieProcess` (:data:`cmpsim.die.DIE_PARAMETERS`).
DIE_CONSTANTS = {
    "planarization_length": ("m", (1e-5, 0.1), "the pad's planarization length (Gaussian weighting)"),
    "contact_height": ("m", (1e-10, 1e-5), "step height below which the pad touches the lower level"),
    "summit_radius": ("m", (1e-8, 1e-3), "radius of the pad summits reaching into a gap (sagitta b^2/8R)"),
    "feature_modulus": ("Pa", (1e5, 1e11), "modulus of the pad body at the scale of a line array (bulge into a gap)"),
    "oxide_selectivity": ("1", (1e-6, 10.0), "oxide / copper removal rate (erosion once the field clears)"),
    "barrier_selectivity": ("1", (1e-6, 100.0), "barrier / copper removal rate"),
    "copper_thickness": ("m", (1e-8, 1e-4), "plated copper over the field (sets when the field clears)"),
    "trench_depth": ("m", (1e-8, 1e-4), "depth of the copper trenches"),
    "step_height": ("m", (1e-9, 1e-4), "oxide: initial step height"),
}
_PAD_START = {"summit_radius": "asperity_radius", "feature_modulus": "pad_bulk_modulus"}


@dataclass(frozen=True)
class TestStructure:
    """A square block of lines (width, space; space None: an isolated line) of side ``size`` (None: larger than L), m."""

    __test__ = False  # not a pytest class

    line_width: float
    line_space: float | None = None
    size: float | None = None

    @property
    def pitch(self) -> float:
        return self.line_width + (ISOLATED_PITCH if self.line_space is None else self.line_space)

    @property
    def density(self) -> float:
        """Local density of the block's cells, w / pitch."""
        return self.line_width / self.pitch

    @property
    def space(self) -> float:
        return self.pitch - self.line_width

    def site_effective_density(self, planarization_length: float) -> float:
        """rho_eff at the block's centre (eq. C1; the block's own density without a size)."""
        if self.size is None:
            return self.density
        return self.density * math.erf(math.sqrt(math.pi) * self.size / (2.0 * planarization_length)) ** 2

    def layout(self, planarization_length: float, cells: int = 129):
        """The structure as a die layout: the block at the centre of a field of side S + 4 L, ``cells`` across (odd).

        A block larger than L (``size`` None) is a uniform die. The cell holding the block's
        centre is ``(cells // 2, cells // 2)``. The field cells have no lines (density 0).
        """
        from ..die.layout import Layout

        if self.size is None:
            one = np.ones((1, 1))
            return Layout(self.density * one, 50e-6, self.line_width * one, "structure", self.space * one)
        side = self.size + 4.0 * planarization_length
        n = int(cells) | 1
        cell = side / n
        x = (np.arange(n) - n // 2) * cell
        # the block's share of each cell (exact area fraction of the square in the cell)
        frac = np.clip((np.minimum(x + cell / 2, self.size / 2) - np.maximum(x - cell / 2, -self.size / 2)) / cell, 0.0, 1.0)
        share = frac[:, None] * frac[None, :]
        rho = self.density * share
        width = np.where(share > 0, self.line_width, 0.0)
        space = np.where(share > 0, self.space, 0.0)
        return Layout(rho, cell, width, "structure", space)


def _structure(r: StructureRecord) -> TestStructure:
    return TestStructure(r.line_width, r.line_space, r.structure_size)


# ----------------------------------------------------------------------------- the model


def _base(config):
    from ..inputs.config import Config

    return config if config is not None else Config.default()


def start_values(config=None, process_kind: str = "copper") -> dict:
    """The uncalibrated constants (SI): the die model's defaults, the pad's planarization length, summit radius and modulus."""
    from ..die.pad import planarization_length_from_pad
    from ..die.process import DieProcess

    cfg = _base(config)
    p = DieProcess(kind=process_kind)
    out = {n: float(getattr(p, n)) for n in DIE_CONSTANTS if hasattr(p, n)}
    out["planarization_length"] = float(planarization_length_from_pad(cfg))
    for n, c in _PAD_START.items():
        out[n] = float(getattr(cfg, c))
    return out


def predict_die(records, constants: dict | None = None, config=None, blanket_rate: float | None = None) -> np.ndarray:
    """The die model's value (SI, m) of every test-structure record, with ``constants`` (name -> SI) over the defaults.

    Each record's structure is polished with the die model (gaussian weighting, the pad body's
    bulge on) at its ``blanket_rate`` (or ``blanket_rate`` here, or the wafer solve of ``config``
    for the film of the process) until its ``time`` (or its end point: the field cleared, copper;
    planarized, oxide), and the quantity read at the block's centre. NaN where the quantity is
    not reached (dishing before the field clears is 0).
    """
    from ..die.evolution import DieEvolution
    from ..die.layout import Layout
    from ..die.process import DieProcess
    from ..die.reach import FeatureContact

    records = list(records)
    cfg = _base(config)
    consts = dict(constants or {})
    L = consts.pop("planarization_length", None)
    if L is None:
        from ..die.pad import planarization_length_from_pad

        L = planarization_length_from_pad(cfg)
    groups: dict = {}
    for i, r in enumerate(records):
        inputs = {k: v for k, v in r.inputs.items() if k != "applied_pressure"}
        clash = [k for k in inputs if k in consts]
        if clash:
            raise ValueError(f"{r.where}: column {clash[0]!r} is set by the record and fitted at once; leave it out of free or of the file")
        rate = r.blanket_rate or blanket_rate
        if rate is None and r.time is not None:
            rate = _solved_rate(cfg, r.process)
        key = (r.process, tuple(sorted(inputs.items())), rate or 1e-8, r.inputs.get("applied_pressure", cfg.applied_pressure))
        groups.setdefault(key, []).append(i)
    out = np.full(len(records), np.nan)
    fc0 = FeatureContact.from_config(cfg)
    for (kind, inputs, rate, pressure), idx in groups.items():
        process = DieProcess(kind=kind, **dict(inputs), **consts)
        st = [_structure(records[i]) for i in idx]
        lay = Layout(np.array([[s.density for s in st]]), 50e-6, np.array([[s.line_width for s in st]]), "structures",
                     np.array([[s.space for s in st]]))
        eff = np.array([[s.site_effective_density(L) for s in st]])
        fc = _CachedFeature(FeatureContact(float(pressure), fc0.modulus, fc0.poisson, fc0.thickness, fc0.compliance))

        def fresh():
            return DieEvolution(lay, process, eff, float(rate), cfg.asperity_radius, fc)

        times = np.array([records[i].time if records[i].time is not None else np.nan for i in idx])
        if np.isnan(times).any():  # the end point of every cell
            probe = fresh()
            chunk = max(probe.stack.end_depth() / probe.rate, 1e-9) * 0.25
            for _ in range(400):
                if np.all(np.isfinite(probe.t_clear)):
                    break
                probe.advance_to(probe.t + chunk)
                chunk *= 1.2
            times = np.where(np.isnan(times), probe.t_clear[0], times)
        ev = fresh()
        for t in np.unique(times[np.isfinite(times)]):
            ev.advance_to(float(t))
            sel = np.nonzero(times == t)[0]
            field = {"dishing": ev.dishing, "erosion": ev.erosion, "step_height": ev.step_height}
            for j in sel:
                out[idx[j]] = field[records[idx[j]].quantity][0, j]
    return out


class _CachedFeature:
    """A :class:`cmpsim.die.reach.FeatureContact` whose G(b, lambda) is computed once per set of gaps and pitches.

    G depends on the structures and the top pad only, not on any fitted constant (the modulus
    scales it, :class:`cmpsim.die.evolution.DieEvolution`), so a fit pays for it once.
    """

    _G: dict = {}

    def __init__(self, feature):
        self.feature = feature
        self.modulus = feature.modulus
        self.pressure = feature.pressure

    def bulge(self, gap, pitch, up_fraction):
        f = self.feature
        key = (np.asarray(gap, dtype=float).tobytes(), np.asarray(pitch, dtype=float).tobytes(), f.modulus, f.poisson, f.thickness)
        if key not in self._G:
            if len(self._G) > 256:
                self._G.clear()
            self._G[key] = f.compliance_difference(gap, pitch)
        g = self._G[key]
        return np.where(np.isfinite(g), f.pressure * np.nan_to_num(g) / np.asarray(up_fraction, dtype=float), 0.0)


_RATE_CACHE: dict = {}


def _solved_rate(config, process: str) -> float:
    """The wafer-mean blanket rate (m/s) of ``config`` for the film of ``process`` (one solve, cached)."""
    from ..solver.model import solve

    film = "copper" if process == "copper" else "oxide"
    cfg = config.replace(film=film) if getattr(config, "film", film) != film else config
    key = repr(sorted(cfg.to_dict().items()))
    if key not in _RATE_CACHE:
        _RATE_CACHE[key] = float(solve(cfg, relative=False).removal_rate_mean)
    return _RATE_CACHE[key]


# ----------------------------------------------------------------------------- which constants the data identify


def choose_free(records) -> tuple[list[str], dict[str, str]]:
    """The constants the quantities of ``records`` can identify, and why (name -> reason)."""
    records = list(records)
    why: dict[str, str] = {}
    dish = [r for r in records if r.quantity == "dishing"]
    ero = [r for r in records if r.quantity == "erosion"]
    step = [r for r in records if r.quantity == "step_height"]
    given = {k for r in records for k in r.inputs}
    if dish or step:
        why["contact_height"] = "dishing and step height approach the contact height (d_inf = h (K_cu - K_f)/(K_cu + K_f rho/(1 - rho)), 18.5)"
    widths = sorted({r.line_width for r in dish})
    if len(widths) >= 3 and min(widths) < 2e-6:
        why["summit_radius"] = "dishing of lines narrower than a few um grows with the summit sagitta w^2/8R"
    if len(widths) >= 3 and max(widths) >= 2e-6:
        why["feature_modulus"] = "dishing of wide lines grows with the pad body's bulge into the gap, P G(w)/E"
    if ero:
        why["oxide_selectivity"] = "erosion grows at the oxide rate over the field's share, K_ox/(1 - rho_eff)"
        if any(r.time is not None for r in ero) and "copper_thickness" not in given:
            why["copper_thickness"] = "erosion against time starts when the field clears: T_cu / K"
    if len({r.structure_size for r in records if r.structure_size is not None}) >= 2 or (
            any(r.structure_size is None for r in records) and any(r.structure_size is not None for r in records)):
        why["planarization_length"] = "blocks of several sizes see the density of the field around them over L (eq. C1)"
    n = len(records)
    free = [k for k in DIE_CONSTANTS if k in why]
    dropped = free[max(n - 1, 1):]
    for k in dropped:  # never more constants than points - 1
        why.pop(k)
    return [k for k in free if k in why], why


def start_jacobian(records, names, config=None, step: float = 1e-3, values: dict | None = None) -> np.ndarray:
    """d((model - measured)/u)/d ln(constant) of every record at the start values (or at ``values``, SI, over them;
    central differences), one column per name.

    The columns' directions are what :func:`cmpsim.calibration.identify.choose` compares: a constant
    whose column the others span cannot be separated from them by these records.
    """
    records = list(records)
    s0 = {**start_values(config, records[0].process), **(values or {})}
    given = {k for r in records for k in r.inputs}
    u = np.array([r.uncertainty if r.uncertainty is not None else 1e-9 for r in records])
    J = np.zeros((len(records), len(names)))
    for k, n in enumerate(names):
        if n in given:
            continue  # set per point by the data: no direction of its own
        up = predict_die(records, {**(values or {}), n: s0[n] * math.exp(step)}, config)
        dn = predict_die(records, {**(values or {}), n: s0[n] * math.exp(-step)}, config)
        J[:, k] = np.nan_to_num((up - dn) / (2 * step * u))
    return J


# ----------------------------------------------------------------------------- the result


@dataclass
class DieCalibration(ScaleFit):
    """The die constants fitted to test structures (SI), their uncertainty and the residuals (m).

    As :class:`cmpsim.calibration.scalefit.ScaleFit`; ``covariance`` is what
    :class:`cmpsim.die.uncertainty.DieUncertainty` propagates; ``constants``: everything to
    write into a process file (the fitted values, with the die defaults they replace).
    """

    fixed: dict = field(default_factory=dict)
    config: object = field(default=None, repr=False)
    success: bool = True
    nfev: int = 0

    @property
    def constants(self) -> dict:
        """The constants to write into the process file (SI): the fitted values and the fixed ones given."""
        return {**self.fixed, **self.values}

    def predict(self, records) -> np.ndarray:
        """The calibrated model's value (m) of other structures."""
        return predict_die(records, self.constants, self.config)

    def uncertainty(self):
        """The fit's covariance for a die run (:class:`cmpsim.die.uncertainty.DieUncertainty`)."""
        from ..die.uncertainty import DieUncertainty

        return DieUncertainty(tuple(self.free), tuple(self.values[n] for n in self.free), np.array(self.covariance))

    def to_dict(self) -> dict:
        """A JSON-able summary (SI; units in ``units``)."""
        return {
            "free": list(self.free), "values": dict(self.values), "start": dict(self.start),
            "ci95": {k: list(v) for k, v in self.ci95.items()}, "stderr": dict(self.stderr),
            "correlation": np.asarray(self.correlation).tolist(), "covariance_log": np.asarray(self.covariance).tolist(),
            "rms_before": self.rms_before, "rms_after": self.rms_after, "chi2": self.chi2, "dof": self.dof,
            "absolute_sigma": self.absolute_sigma, "reasons": dict(self.reasons), "identifiability": list(self.identifiability),
            "constants": self.constants,
            "points": [{"dataset": r.dataset, "line": r.line, "quantity": r.quantity, "line_width": r.line_width, "line_space": r.line_space,
                        "structure_size": r.structure_size, "time": r.time, "measured": float(m), "model_before": float(b), "model_after": float(a)}
                       for r, m, b, a in zip(self.records, self.measured, self.model_before, self.model_after)],
            "units": {n: DIE_CONSTANTS[n][0] for n in self.constants if n in DIE_CONSTANTS}
            | {"measured": "m", "model_before": "m", "model_after": "m", "rms_before": "m", "rms_after": "m", "time": "s"},
        }

    def summary(self) -> str:
        """Plain-text report: constants with intervals, correlations, residuals, what the data cannot separate."""
        from ..tables import text_table

        rows = []
        for n in self.free:
            u = DIE_CONSTANTS[n][0]
            rows.append([n, f"{self.start[n]:.4g}", f"{self.values[n]:.4g}", interval_text(*self.ci95[n]), u, self.reasons.get(n, "")])
        out = [text_table(["constant", "start", "fitted", "95 % interval", "unit", "why free"], rows), ""]
        if len(self.free) > 1:
            out.append("correlation (of ln value):")
            out.append(text_table([""] + self.free, [[n] + [f"{c:+.3f}" for c in row] for n, row in zip(self.free, self.correlation)]))
            out.append("")
        pts = [[r.dataset, r.quantity, f"{r.line_width * 1e6:g}", "-" if r.line_space is None else f"{r.line_space * 1e6:g}",
                "-" if r.structure_size is None else f"{r.structure_size * 1e3:g}", "end" if r.time is None else f"{r.time:g}",
                f"{m * 1e9:.1f}", f"{b * 1e9:.1f}", f"{a * 1e9:.1f}"]
               for r, m, b, a in zip(self.records, self.measured, self.model_before, self.model_after)]
        out.append(text_table(["dataset", "quantity", "w um", "s um", "S mm", "t s", "measured nm", "before nm", "after nm"], pts))
        out.append("")
        out.append(f"RMS {self.rms_before * 1e9:.1f} nm -> {self.rms_after * 1e9:.1f} nm; chi-square {self.chi2:.3g} (dof {self.dof}); "
                   f"uncertainties {'absolute (every point has one)' if self.absolute_sigma else 'scaled by the reduced chi-square'}")
        out += [f"identifiability: {s}" for s in self.identifiability]
        return "\n".join(out)


# ----------------------------------------------------------------------------- the fit


def _check_free(free, records):
    given = {k for r in records for k in r.inputs}
    for n in free:
        if n not in DIE_CONSTANTS:
            raise ValueError(f"unknown die constant {n!r} in free; calibratable: {', '.join(DIE_CONSTANTS)}")
        if n in given:
            raise ValueError(f"die constant {n!r} is given per point by the data (column {n!r}); it cannot be fitted")
    if len(set(free)) != len(free):
        raise ValueError(f"a constant is repeated in free: {', '.join(free)}")


def calibrate_die(records, config=None, free=None, *, start: dict | None = None, bounds: dict | None = None,
                  fixed: dict | None = None, max_nfev: int = 200) -> DieCalibration:
    """Fit die constants to test-structure records (docs/calibrate-die.md).

    Parameters
    ----------
    records : sequence of StructureRecord, or a path
        The measurements (:func:`cmpsim.calibration.measurements.read_measurements`).
    config : cmpsim.Config, optional
        The wafer-scale inputs: the pad (planarization length, summit radius and modulus to start
        from) and, for timed records without a blanket rate, the blanket rate of its solve.
    free : sequence of str, optional
        Constants to fit (:data:`DIE_CONSTANTS`); default :func:`choose_free` (the data's quantities choose).
    start, bounds : dict, optional
        Starting values and (low, high) bounds, SI; default the die model's values and a factor
        30 either side (within the valid range).
    fixed : dict, optional
        Constants held at given values (SI) other than their defaults.

    Returns
    -------
    DieCalibration
    """
    from scipy.optimize import least_squares

    if isinstance(records, (str, bytes)) or hasattr(records, "__fspath__"):
        from .measurements import read_measurements

        records = read_measurements(records)
    records = [r for r in records if isinstance(r, StructureRecord)]
    if not records:
        raise ValueError("no test-structure records (dishing, erosion, step_height) to calibrate on")
    kinds = {r.process for r in records}
    if len(kinds) > 1:
        raise ValueError(f"one process per calibration; the records hold {sorted(kinds)}")
    auto = free is None
    if free is None:
        free, reasons = choose_free(records)
    else:
        free = [str(f).strip().replace("-", "_") for f in ([free] if isinstance(free, str) else free)]
        reasons = {n: "asked for" for n in free}
    if not free:
        raise ValueError("nothing to fit: give free names (valid: " + ", ".join(DIE_CONSTANTS) + ")")
    _check_free(free, records)
    fixed = dict(fixed or {})
    s0 = start_values(config, kinds.pop())
    s0.update(fixed)
    s0.update(start or {})
    x0 = np.array([s0[n] for n in free], dtype=float)
    lo = np.empty(len(free))
    hi = np.empty(len(free))
    for k, n in enumerate(free):
        vlo, vhi = DIE_CONSTANTS[n][1]
        b = (bounds or {}).get(n, (max(x0[k] / 30.0, vlo), min(x0[k] * 30.0, vhi)))
        if not (0 < b[0] < b[1]):
            raise ValueError(f"bounds of {n}: need 0 < low < high; got {b}")
        lo[k], hi[k] = b
        x0[k] = min(max(x0[k], b[0] * 1.0001), b[1] / 1.0001)
    y = np.array([r.value for r in records])
    have = np.array([r.uncertainty is not None for r in records])
    absolute = bool(have.all())
    u = np.array([r.uncertainty if r.uncertainty is not None else 1e-9 for r in records])

    def values_of(z):
        return {**fixed, **{n: float(x0[k] * math.exp(z[k])) for k, n in enumerate(free)}}

    nfev = [0]

    def resid(z):
        nfev[0] += 1
        m = predict_die(records, values_of(z), config)
        return np.where(np.isfinite(m), (m - y) / u, 1e3)

    z0 = np.zeros(len(free))
    m0 = predict_die(records, values_of(z0), config)
    fit = least_squares(resid, z0, bounds=(np.log(lo / x0), np.log(hi / x0)), method="trf", x_scale=1.0, diff_step=1e-3,
                        ftol=1e-10, xtol=1e-10, gtol=1e-12, max_nfev=max_nfev)
    z = fit.x
    J = central_jacobian(resid, z, len(records), h=1e-3)
    if not auto:  # asked for, and the structures do not change with it: its "fitted" value would be its start
        refuse_flat(J, free, "these test structures", "the constants")
    vals = {n: float(x0[k] * math.exp(z[k])) for k, n in enumerate(free)}
    chi2, dof, notes, cov, corr, ci, stderr = fit_statistics(J, resid(z), free, vals, absolute, lo, hi)
    if auto:
        held = [n for n in DIE_CONSTANTS if n not in free and n not in fixed and n not in {k for r in records for k in r.inputs}]
        if held:
            notes.append(f"held at their start values (these quantities do not identify them): {', '.join(held)}")
    m1 = predict_die(records, {**fixed, **vals}, config)
    return DieCalibration(list(free), vals, {n: float(s0[n]) for n in free}, stderr, ci, corr, cov, records, y, m0, m1, chi2, dof,
                          absolute, reasons, notes, fixed, config, bool(fit.success), nfev[0])


def heldout_comparison(calibration: DieCalibration, records) -> dict:
    """The calibrated model against structures it did not see: values (m), RMS error (m), and whether their order is right.

    ``order`` is True when sorting the structures by the model gives the measured order (ties in
    the measurement within their combined uncertainty are not counted).
    """
    records = [r for r in records if isinstance(r, StructureRecord)]
    m = calibration.predict(records)
    y = np.array([r.value for r in records])
    u = np.array([r.uncertainty or 0.0 for r in records])
    wrong = 0
    for i in range(len(y)):
        for j in range(len(y)):
            if records[i].quantity == records[j].quantity and y[i] - y[j] > 2 * math.hypot(u[i], u[j]) and not m[i] > m[j]:
                wrong += 1
    return {"model": m, "measured": y, "rms": float(np.sqrt(np.mean((m - y) ** 2))), "order": wrong == 0, "order_violations": wrong}
