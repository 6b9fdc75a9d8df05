"""The lot controller's refit of its own pad-life model from the lot's wafers (issue 38: control that
holds under drift; docs/polisher.md, "A controller that refits its model", eqs. C6-C8).

The double EWMA on the glazing clock (:mod:`cmpsim.polisher.control`) takes its pad ages from the
controller's model of the pad's life (:mod:`cmpsim.polisher.pad`, eqs. L1-L4). When that model is
another pad's, the clock runs at the wrong pace and the filter chases the error
(docs/polisher.md, "When the controller's model is wrong"). With ``refit_model`` the controller
re-estimates the model's wear coefficient k_w, and its critical glazed area G_c when the rates
separate them, after each wafer from the rates it measured so far: the certainty equivalence of a
self-tuning controller (Astrom & Wittenmark, *Adaptive Control*, 2nd ed. 1995, ch. 3: estimate the
model's parameters from the plant's past, then control as if they were true):

- (C6) the rates follow the model's glazing factor, r_j = a f_j(k_w, G_c), j over the last monitor
  wafer and the lot's wafers: the constants minimise S = sum_j (e_j - mean e)^2,
  e_j = ln r_j - ln f_j (the level a profiled out). The model walks through the controller's
  history of polish times, and its worn volume is linear in k_w (eq. L2: dW/dt = k_w P U - r_c W
  from W = 0), so W_j(k_w) = (k_w / k_0) W_j(k_0): each wafer is walked once, as it comes, at the
  model's starting constants (:class:`History`), and every trial k_w is a scale on the samples; G_c
  enters eq. L4 only. k_w by bounded Brent, G_c by the profile of S over it.
- (C7) a refit is taken only when the data identify it: at least 4 rates for k_w (two degrees of
  freedom), 5 for k_w and G_c; the minimum inside [1/100, 100] times the model's starting
  constants and inside the constant's valid range; the 95 % half-width of each logarithm,
  t_{0.975, dof} sqrt(diag(2 s^2 H^-1)) with s^2 = S_min / dof, H the Hessian of S and Student's t
  (the scatter is estimated from the same few rates), below ln 2 (known within a factor 2). Both constants
  when both pass, else k_w alone when it passes, else the model keeps its constants (a pad in its
  in-situ balance: every f_j alike, S flat).
- (C8) with new constants the controller's model takes the state and the pad ages of the wafers
  polished that they give (from the same samples), and the double EWMA is replayed from its seed
  over the measured rates at those ages (eqs. C2-C3): the filter is the one the refitted model
  would have run.

The history (each wafer's step durations, zone pressures and measured rate), the seed and the
constants go into the lot's checkpoint (``refit``), so that a resumed lot refits identically.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field, replace

import numpy as np

from ..physics.padlife import GLAZING_CONSTANTS, PadLifeState, summit_constants
from .control import make_estimator
from .pad import PadLife, wear_samples

__all__ = ["Seen", "RefitState", "History", "refit", "walk", "refitted_model", "starting_model", "replay", "MIN_RATES", "IDENTIFIED", "SPAN"]

#: C7: the fewest measured rates a refit of k_w takes (the level and k_w fitted, two degrees of freedom left: with one,
#: the scatter estimated from three rates is too uncertain and the accepted refits' intervals missed the truth in 20-46 %
#: of noisy trials); one more for G_c.
MIN_RATES = 4
#: C7: the largest 95 % half-width of the logarithm of a refitted constant (known within a factor 2).
IDENTIFIED = math.log(2.0)
#: C7: each constant is looked for within [1/SPAN, SPAN] times the model's starting one.
SPAN = 100.0


@dataclass(frozen=True)
class Seen:
    """One wafer as the controller saw it: its steps' ``durations`` (s), the ``zone_pressures`` it ran
    at (Pa; None: the recipe's) and its measured mean ``rate`` over the zone pressure factor (m/s; None
    for a monitor wafer whose rate did not seed the controller). A rate that is not > 0 (a wafer that
    removed nothing as measured) is kept but not fitted."""

    durations: tuple
    zone_pressures: tuple | None = None
    rate: float | None = None

    def to_dict(self) -> dict:
        return {"durations": [float(d) for d in self.durations],
                "zone_pressures": None if self.zone_pressures is None else [float(p) for p in self.zone_pressures], "rate": self.rate}

    @classmethod
    def from_dict(cls, d: dict) -> "Seen":
        z = d.get("zone_pressures")
        return cls(tuple(float(x) for x in d["durations"]), None if z is None else tuple(float(p) for p in z),
                   None if d.get("rate") is None else float(d["rate"]))


@dataclass(frozen=True)
class RefitState:
    """The refitting controller's memory (JSON-able through :meth:`to_dict`): the model's k_w
    (``wear_coefficient``, 1/Pa) and G_c (``critical_glazed_area``, 1) now and before any refit
    (``start``, ``start_glazed_area``), the EWMA's seed rate (``seed_rate``, m/s: the last monitor
    wafer's, or the model's for a fresh pad), the wafers seen in order (monitor wafers first,
    ``monitors`` of them) and the last refit's outcome (``last``)."""

    wear_coefficient: float
    critical_glazed_area: float
    start: float
    start_glazed_area: float
    seed_rate: float
    monitors: int = 0
    wafers: tuple = ()
    last: dict = field(default_factory=dict)

    @classmethod
    def begin(cls, model: PadLife, config, seed_rate: float, monitors=()) -> "RefitState":
        """The memory before the lot's first wafer: ``model``'s constants at the step ``config``, the
        seed and the monitor wafers (:class:`Seen`)."""
        pad = model.at(config).pad
        return cls(pad.wear_coefficient, pad.critical_area, pad.wear_coefficient, pad.critical_area, float(seed_rate), len(monitors),
                   tuple(monitors))

    @property
    def moved(self) -> bool:
        """Whether a refit has changed the model's constants."""
        return (self.wear_coefficient, self.critical_glazed_area) != (self.start, self.start_glazed_area)

    def seen(self, wafer: Seen) -> "RefitState":
        return replace(self, wafers=self.wafers + (wafer,))

    def to_dict(self) -> dict:
        return {"wear_coefficient": self.wear_coefficient, "critical_glazed_area": self.critical_glazed_area, "start": self.start,
                "start_glazed_area": self.start_glazed_area, "seed_rate": self.seed_rate, "monitors": self.monitors,
                "wafers": [w.to_dict() for w in self.wafers], "last": dict(self.last)}

    @classmethod
    def from_dict(cls, d: dict) -> "RefitState":
        return cls(float(d["wear_coefficient"]), float(d["critical_glazed_area"]), float(d["start"]), float(d["start_glazed_area"]),
                   float(d["seed_rate"]), int(d["monitors"]), tuple(Seen.from_dict(w) for w in d["wafers"]), dict(d.get("last") or {}))


def refitted_model(model: PadLife, state: RefitState) -> PadLife:
    """The controller's ``model`` with the constants of ``state`` (k_w 1/Pa, G_c 1)."""
    return _with_constants(model, state.wear_coefficient, state.critical_glazed_area)


def _with_constants(model: PadLife, wear_coefficient: float, critical_glazed_area: float) -> PadLife:
    return replace(model, constants={**(model.constants or {}), "pad_wear_coefficient": float(wear_coefficient),
                                     "critical_glazed_area": float(critical_glazed_area)})


def _steps(recipe, overrides: dict, wafer: Seen):
    ov = dict(overrides) if wafer.zone_pressures is None else {**overrides, "zone_pressures": wafer.zone_pressures}
    return [(recipe.step_config(s, ov), d) for s, d in zip(recipe.steps, wafer.durations)]


class History:
    """The pad-life states the controller's model passes through over the wafers it has seen, at its
    constants before any refit (the worn volume is linear in k_w, C6: any k_w is a scale on them),
    sampled as the recipe engine samples a wafer (:func:`cmpsim.polisher.pad.wear_samples`); each wafer
    walked once, as it comes (:meth:`extend`). Kept in memory only: a resumed lot walks the checkpoint's
    wafers again, the same floats in the same order."""

    def __init__(self) -> None:
        self.worn, self.pad_of, self.weights, self.starts, self.spans = [], [], [], [], []
        self.pads: dict = {}
        self.life = PadLifeState()  # after the last wafer walked and its idle
        self.count = 0

    def extend(self, model: PadLife, recipe, overrides: dict, wafers, time_step: float, idle_time: float) -> "History":
        """Walk ``model`` through the ``wafers`` (:class:`Seen`) not walked yet, each followed by ``idle_time`` s idle."""
        life = self.life
        for w in wafers[self.count:]:
            times = []
            self.starts.append(len(self.worn))
            for clock, wear, life in wear_samples(model, _steps(recipe, overrides, w), life, time_step):
                times.append(clock)
                self.pad_of.append(self.pads.setdefault(wear.pad, len(self.pads)))
                self.worn.append(float(np.asarray(life.worn_volume)))
            t = np.asarray(times)
            dt = np.diff(t)  # the trapezoid: each sample carries half of the intervals on either side
            self.weights.extend(0.5 * (np.concatenate(([0.0], dt)) + np.concatenate((dt, [0.0]))))
            self.spans.append(t[-1] - t[0])
            life = model.idle(life, idle_time)
        self.life, self.count = life, len(wafers)
        return self

    def glazed(self, scale: float) -> np.ndarray:
        """The glazed area G (1, eq. L3) of every sample with the worn volumes times ``scale``."""
        worn, pad_of = np.asarray(self.worn), np.asarray(self.pad_of)
        G = np.empty_like(worn)
        for pad, k in self.pads.items():
            at = pad_of == k
            G[at] = np.asarray(summit_constants(PadLifeState(scale * worn[at]), pad).glazed_area, dtype=float)
        return G

    def means(self, factor: np.ndarray) -> np.ndarray:
        """Each wafer's time-mean of the sampled ``factor`` (as :func:`cmpsim.polisher.pad.time_mean`)."""
        starts, spans = np.asarray(self.starts), np.asarray(self.spans)
        summed = np.add.reduceat(np.asarray(self.weights) * factor, starts)
        return np.where(spans > 0, summed / np.where(spans > 0, spans, 1.0), factor[starts])

    def ages(self, scale: float, critical_glazed_area: float) -> np.ndarray:
        """Each wafer's pad age on the glazing clock (its time-mean rate factor, eq. L4) with the worn
        volumes times ``scale`` (k_w over the walked model's) and G_c = ``critical_glazed_area``."""
        return self.means(1.0 / (1.0 + self.glazed(scale) / critical_glazed_area))

    def state(self, scale: float) -> PadLifeState:
        """The model's pad-life state after the wafers walked, with the worn volume times ``scale``."""
        return PadLifeState(scale * self.life.worn_volume, self.life.polish_time)


def walk(model: PadLife, recipe, overrides: dict, wafers, time_step: float, idle_time: float):
    """The controller's ``model`` from a fresh pad through ``wafers`` (:class:`Seen`, each followed by
    ``idle_time`` s idle): (each wafer's pad age on the glazing clock, eq. L4, the model's state after them)."""
    history = History().extend(model, recipe, overrides, wafers, time_step, idle_time)
    pad = next(iter(history.pads))
    return history.ages(1.0, pad.critical_area), history.state(1.0)


def starting_model(model: PadLife, state: "RefitState") -> PadLife:
    """The controller's ``model`` with its constants before any refit (those :class:`History` walks at)."""
    return _with_constants(model, state.start, state.start_glazed_area)


def _fit(spread, lo: float, hi: float):
    """(u, S, S'') at the minimum of ``spread(u)`` over [lo, hi] (u = ln of a constant over its start)."""
    from scipy.optimize import minimize_scalar

    best = minimize_scalar(spread, bounds=(lo, hi), method="bounded", options={"xatol": 1e-6})
    u, s_min = float(best.x), float(best.fun)
    h = 0.05
    curvature = (spread(u + h) - 2.0 * s_min + spread(u - h)) / h**2
    return u, s_min, curvature


def refit(state: RefitState, model: PadLife, recipe, overrides: dict, time_step: float, idle_time: float,
          history: History | None = None) -> RefitState:
    """C6-C7: ``state`` with the constants the rates seen identify (or kept, saying why in ``last``);
    ``model`` the controller's pad-life model (its k_w and G_c are taken from ``state``); ``history``
    the :class:`History` of the wafers walked so far (extended here; None: walked from the start)."""
    rated = [j for j, w in enumerate(state.wafers) if w.rate is not None and math.isfinite(w.rate) and w.rate > 0]
    n = len(rated)
    if n < MIN_RATES:
        return replace(state, last={"refit": False, "why": f"{n} rate(s) > 0 measured, a refit needs {MIN_RATES}"})
    gc_now = state.critical_glazed_area
    history = (History() if history is None else history).extend(starting_model(model, state), recipe, overrides, state.wafers,
                                                                  time_step, idle_time)
    rates = np.log([state.wafers[j].rate for j in rated])
    glazed = {}

    def spread(u: float, v: float) -> float:  # S of C6 at k_w = k_0 e^u, G_c = G_c0 e^v
        if u not in glazed:  # the glazed area G of every sample (eq. L3): the costly part, once per trial k_w
            glazed.clear()
            glazed[u] = history.glazed(math.exp(u))
        gc = state.start_glazed_area * math.exp(v)
        e = rates - np.log(history.means(1.0 / (1.0 + glazed[u] / gc))[rated])  # eq. L4, each wafer's time mean
        return float(np.sum((e - e.mean()) ** 2))

    ku = _bounds("pad_wear_coefficient", state.start)  # ln of the constant over its start: [1/SPAN, SPAN] within its valid range
    gv = _bounds("critical_glazed_area", state.start_glazed_area)
    v_now = math.log(gc_now / state.start_glazed_area)
    u, s_min, curvature = _fit(lambda x: spread(x, v_now), *ku)
    one = _verdict("k_w", [u], [curvature], s_min, n - 2, [ku])
    both = None
    if n >= MIN_RATES + 1:  # k_w and G_c together (the profile over G_c at each k_w), when the rates identify both
        inner = {}

        def profile(x: float) -> float:
            inner[x] = _fit(lambda y: spread(x, y), *gv)[:2]
            return inner[x][1]

        u2, s2, _ = _fit(profile, *ku)
        v2 = inner[u2][0] if u2 in inner else _fit(lambda y: spread(u2, y), *gv)[0]
        s2 = spread(u2, v2)
        both = _verdict("k_w and G_c", [u2, v2], _hessian(spread, u2, v2), s2, n - 3, [ku, gv])
    k, gc = state.wear_coefficient, state.critical_glazed_area
    if both is not None and both["why"] is None:
        k, gc = state.start * math.exp(u2), state.start_glazed_area * math.exp(v2)
        last = {"refit": True, "fitted": "k_w, G_c", "half_width": both["half_width"], "rates": n}
    elif one["why"] is None:
        k = state.start * math.exp(u)
        last = {"refit": True, "fitted": "k_w", "half_width": one["half_width"], "rates": n,
                **({} if both is None else {"why_not_G_c": both["why"]})}
    else:
        last = {"refit": False, "rates": n, "why": one["why"]}
    return replace(state, wear_coefficient=k, critical_glazed_area=gc, last=last)


def _hessian(spread, u: float, v: float, h: float = 0.05) -> np.ndarray:
    """The 2 x 2 Hessian of ``spread`` at (u, v), central differences of step h."""
    f0 = spread(u, v)
    uu = (spread(u + h, v) - 2 * f0 + spread(u - h, v)) / h**2
    vv = (spread(u, v + h) - 2 * f0 + spread(u, v - h)) / h**2
    uv = (spread(u + h, v + h) - spread(u + h, v - h) - spread(u - h, v + h) + spread(u - h, v - h)) / (4 * h**2)
    return np.array([[uu, uv], [uv, vv]])


def _bounds(name: str, start: float) -> tuple[float, float]:
    """The search interval of ln(constant / ``start``) (C7): [1/SPAN, SPAN] times the start, within the
    constant's valid range (:data:`cmpsim.physics.padlife.GLAZING_CONSTANTS`)."""
    low, high = GLAZING_CONSTANTS[name][1]
    return max(-math.log(SPAN), math.log(low / start)), min(math.log(SPAN), math.log(high / start))


def _verdict(what: str, x, curvature, s_min: float, dof: int, bounds) -> dict:
    """C7 on a fit at ``x`` (ln of the constants over their starts, each within its ``bounds`` (lo, hi))
    with the Hessian of S there (``curvature``: the second derivative, or the 2 x 2 matrix): the 95 %
    half-widths (Student's t of ``dof`` degrees of freedom: the scatter s^2 is estimated from the same
    few rates), and why the fit is not taken (None: taken)."""
    from scipy.stats import t as student

    H = np.atleast_2d(np.asarray(curvature, dtype=float))
    half = np.full(len(x), math.inf)
    if dof > 0 and math.isfinite(s_min) and np.all(np.isfinite(H)) and np.all(np.linalg.eigvalsh(H) > 0):
        half = float(student.ppf(0.975, dof)) * np.sqrt(np.diag(2.0 * (s_min / dof) * np.linalg.inv(H)))
    why = None
    if any(min(xi - lo, hi - xi) < 1e-3 for xi, (lo, hi) in zip(x, bounds)):
        why = f"the best {what} lies on a bound ([1/{SPAN:g}, {SPAN:g}] times the model's own, within the valid range)"
    elif not np.all(half < IDENTIFIED):
        why = f"{what} not identified: 95 % half-width of the logarithm {', '.join(f'{h:.3g}' for h in half)}, not all < ln 2"
    return {"half_width": [float(h) for h in half], "why": why}


def replay(state: RefitState, history: History, model: PadLife, control: str, weight: float, drift_weight: float, clock: str,
           drift_prior: str):
    """C8: (the controller's ``model`` with the refitted constants of ``state``, its double EWMA replayed from
    the seed over the rates measured at the pad ages the refitted model gives the wafers (eqs. C2-C3, with
    the lot's weights, clock and drift prior), the model's pad-life state now)."""
    scale = state.wear_coefficient / state.start
    ages = history.ages(scale, state.critical_glazed_area)
    seed_age = float(ages[state.monitors - 1]) if state.monitors else 1.0  # a fresh pad's factor without monitor wafers
    estimator = make_estimator(control, state.seed_rate, weight, drift_weight, clock, seed_age, drift_prior)
    for w, age in list(zip(state.wafers, ages))[state.monitors:]:
        if w.rate is not None:
            estimator = estimator.update(w.rate, float(age))
    return refitted_model(model, state), estimator, history.state(scale)
