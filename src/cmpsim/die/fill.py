"""Model-based dummy fill: add fill density where the die model says it flattens the die.

Not a flat density target: the added density x (one value per window, bounded by what the
window's free fill sites can hold, :class:`cmpsim.layout.fill.FillSites`) is chosen to
minimise the **thickness range** of the die model's final surface, the range of the mean
surface height of the windows after polishing (:func:`cmpsim.die.simulate`), the quantity
the hotspots of ``thickness`` are measured on.

**Algorithm** (sequential linearisation, docs/fill.md):

1. Polish the die as drawn (the die model's own end point): the thickness T_i of every window.
2. The linear response of T to the fill: a window's final height depends on its own local
   fields (density, width) and on the effective density rho_eff = w * rho, the only coupling
   between windows. The die evolution is independent cell by cell given (rho, w, rho_eff), so
   two more evolutions at the same time give every window's derivatives at once:
   a_i = dT_i / d rho_eff_i (rho_eff + delta) and b_i = dT_i / dx_i at fixed rho_eff (the
   local fields of x + delta of square fill: area + n s^2, boundary + 4 n s). Then
   T(x) ~ T + a (w * dx) + b dx, linear in dx, with w * the FFT convolution of the weighting.
3. Minimise a smooth range of that linear model, LSE_beta(T) + LSE_beta(-T) (log-sum-exp,
   beta set so that its excess over max - min is about 1 % of the range), plus a small
   price per added density, over 0 <= x <= capacity (L-BFGS-B with bounds; the gradient is
   one convolution: the weighting is symmetric).
4. Round x to whole squares per window, re-polish with the exact window fields, accept if
   the range fell (else halve the step), and repeat from 2 (``iterations`` times).

Optimality: each step solves its linearised problem to a stationary point of a smooth
convex surrogate of the range (the linear model's range is convex in x; LSE is a convex
upper bound within log(2N)/beta of it), so with an exact linear response the result is the
minimum range to within that tolerance and the rounding to whole squares. The die model is
not linear (the step-height regimes), which the outer re-polish and step control handle
only locally: the result is a local optimum of the rounded problem, not a certified
global one.
"""

from __future__ import annotations

import math
import time as _time
from dataclasses import dataclass, field

import numpy as np

from .density import effective_density
from .evolution import DieEvolution
from .layout import Layout
from .polish import DieResult, _prepare, simulate

__all__ = ["FillPlan", "plan_fill", "die_layout", "thickness", "thickness_range", "hotspot_count", "DEFAULT_LIMITS"]

#: Hotspot limits used when none are given (m): a window's final surface more than 5 nm off the
#: die's mean (the example of issue 33, ``--spec thickness=5nm``).
DEFAULT_LIMITS = {"thickness": 5e-9}


def die_layout(windows, name: str | None = None) -> Layout:
    """The die model's :class:`Layout` of a :class:`cmpsim.layout.LayoutWindows` (density, width per window)."""
    rho = np.clip(np.asarray(windows.density, dtype=float), 0.0, 1.0)
    width = np.where(rho > 0, np.asarray(windows.width, dtype=float), 0.0)
    return Layout(rho, float(windows.window), width, name or windows.top)


def thickness(result: DieResult) -> np.ndarray:
    """Each window's final surface height off the die's mean (m): the mean surface height minus its die mean."""
    h = result.evolution.mean_height
    return h - float(np.mean(h))


def thickness_range(result: DieResult) -> float:
    """max - min of the final surface over the die (m)."""
    h = result.evolution.mean_height
    return float(np.max(h) - np.min(h))


def hotspot_count(result: DieResult, limits: dict | None = None) -> int:
    """Windows over a limit, counted per quantity and summed: ``thickness`` (|height off the die mean|),
    ``step_height``, ``dishing``, ``erosion`` (m; NaN values never count)."""
    limits = DEFAULT_LIMITS if limits is None else limits
    ev = result.evolution
    fields = {"thickness": np.abs(thickness(result)), "step_height": ev.step_height, "dishing": ev.dishing, "erosion": ev.erosion}
    n = 0
    for kind, limit in limits.items():
        if kind not in fields:
            raise ValueError(f"unknown hotspot quantity {kind!r}; valid: {', '.join(fields)}")
        v = np.nan_to_num(np.asarray(fields[kind], dtype=float), nan=-np.inf)
        n += int(np.count_nonzero(v > limit))
    return n


def _projected_descent(fun, x0, lo, hi, steps: int, tol: float = 1e-7):
    """Minimise ``fun`` (returning value and gradient) over the box lo <= x <= hi: spectral projected
    gradient (Birgin, Martinez & Raydan, SIAM J. Optim. 10, 1196, 2000) with a non-monotone
    Armijo line search over the last 10 values. Returns the last accepted x."""
    x = np.clip(x0, lo, hi)
    f, g = fun(x)
    recent = [f]
    alpha = 1.0 / max(float(np.max(np.abs(g))), 1e-30) * float(np.max(hi - lo) or 1.0) * 0.1
    for _ in range(steps):
        d = np.clip(x - alpha * g, lo, hi) - x
        if float(np.max(np.abs(d))) <= tol * max(float(np.max(hi)), 1e-30):
            break
        gd = float(np.sum(g * d))
        lam = 1.0
        fmax = max(recent[-10:])
        for _ls in range(30):
            xn = x + lam * d
            fn, gn = fun(xn)
            if fn <= fmax + 1e-4 * lam * gd:
                break
            lam *= 0.5
        s_, y_ = xn - x, gn - g
        sy = float(np.sum(s_ * y_))
        alpha = float(np.sum(s_ * s_)) / sy if sy > 0 else alpha * 10.0
        x, f, g = xn, fn, gn
        recent.append(f)
    return x


def _summary(result: DieResult, limits, counter) -> dict:
    return {"hotspot_count": int(counter(result) if counter is not None else hotspot_count(result, limits)),
            "thickness_range": thickness_range(result)}


@dataclass
class FillPlan:
    """The model-based fill of one die: the squares chosen, the die before and after.

    ``counts`` (ny, nx) squares per window; ``chosen`` the chosen lattice sites (for
    :func:`cmpsim.layout.fill.write_fill`); ``windows`` the window fields after fill;
    ``before``/``after`` the polished dies; ``added_area`` m^2; ``history`` the range (m) after
    each accepted outer iteration; ``stats`` the cost (s) and counts.
    """

    counts: np.ndarray
    chosen: np.ndarray = field(repr=False)
    windows: object = field(repr=False)
    before: DieResult = field(repr=False)
    after: DieResult = field(repr=False)
    added_area: float = 0.0
    limits: dict = field(default_factory=dict)
    history: list = field(default_factory=list)
    stats: dict = field(default_factory=dict)
    summary_before: dict = field(default_factory=dict)
    summary_after: dict = field(default_factory=dict)

    def to_dict(self) -> dict:
        """The JSON ``fill`` object: {before: {hotspot_count, thickness_range}, after: {...}, added_area} (SI)."""
        return {"before": dict(self.summary_before), "after": dict(self.summary_after), "added_area": float(self.added_area),
                "squares": int(self.counts.sum()), "iterations": len(self.history) - 1,
                "thickness_range_history": [float(v) for v in self.history]}


def _fields(windows, n, side):
    """(density, width) of the windows with n (float) squares of side ``side`` (m) added."""
    from ..layout.extract import window_fields

    area = windows.density * windows.window**2 + n * side**2
    boundary = windows.boundary + 4.0 * n * side
    rho, width, _ = window_fields(area, boundary, windows.window)
    rho = np.clip(rho, 0.0, 1.0)
    return rho, np.where(rho > 0, width, 0.0)


def plan_fill(windows, sites, *, config=None, blanket_rate: float | None = None, process=None,
              planarization_length: float | None = None, weighting: str = "gaussian", feature_contact: str = "elastic",
              limits: dict | None = None, hotspot_counter=None, iterations: int = 3, area_price: float = 1e-3, max_steps: int = 300,
              **process_values) -> FillPlan:
    """Choose the fill squares of every window that minimise the die model's thickness range.

    ``windows`` the :class:`cmpsim.layout.LayoutWindows` of the drawn layer; ``sites`` its
    :class:`cmpsim.layout.fill.FillSites`. The die inputs are those of :func:`cmpsim.die.simulate`
    (``blanket_rate`` default: one wafer solve of ``config``, made once). ``limits`` the
    hotspot limits (m, :func:`hotspot_count`) or ``hotspot_counter(result) -> int`` the
    caller's own count. ``iterations`` the outer linearisations, ``max_steps`` the projected-gradient
    steps of each; ``area_price`` the price of
    added density relative to the range (a tie-breaker: among fills of equal range, less).
    """
    from ..layout.fill import select_fill, filled_windows

    t_start = _time.perf_counter()
    if tuple(sites.shape) != tuple(windows.density.shape):
        raise ValueError(f"fill sites {sites.shape} and windows {windows.density.shape} are not the same grid")
    limits = DEFAULT_LIMITS if limits is None else dict(limits)
    base = die_layout(windows)
    config, base, process, w, _, _, fc = _prepare(base, config, process, planarization_length, weighting, None,
                                                  feature_contact, **process_values)
    if blanket_rate is None:
        from ..solver.model import solve

        blanket_rate = float(solve(config, relative=False).removal_rate_mean)
    sim = dict(config=config, blanket_rate=blanket_rate, process=process, planarization_length=planarization_length,
               weighting=weighting, feature_contact=feature_contact)
    side = sites.size * sites.dbu
    step = sites.density_step
    cap = sites.capacity.astype(float) * step  # the most density each window can take
    cell = float(windows.window)
    name = base.name

    def polish(n):
        rho, width = _fields(windows, n, side)
        return simulate(Layout(rho, cell, width, name), **sim)

    def evolve(rho, width, eff, t):
        ev = DieEvolution(Layout(rho, cell, width, name), process, eff, blanket_rate, config.asperity_radius, fc)
        ev.advance_to(t)
        return ev.mean_height

    before = polish(np.zeros(sites.shape))
    n = np.zeros(sites.shape)
    current = before
    history = [thickness_range(before)]
    nsim = 1
    delta = 0.02
    for _ in range(max(int(iterations), 0)):
        x = n * step
        rho, width = _fields(windows, n, side)
        eff = current.effective_density
        t = current.time
        h0 = current.evolution.mean_height
        # a: d h / d rho_eff at fixed local fields; b: d h / d x at fixed rho_eff (one evolution each)
        up = np.where(eff + delta < 1.0, delta, -delta)
        a = (evolve(rho, width, eff + up, t) - h0) / up
        dn = np.minimum(delta, cap - x)
        dn = np.where(dn > 1e-9, dn, -np.minimum(delta, x))
        ok = np.abs(dn) > 1e-9
        rho_b, width_b = _fields(windows, n + np.where(ok, dn, 0.0) / step, side)
        hb = evolve(rho_b, width_b, eff, t)
        b = np.where(ok, (hb - h0) / np.where(ok, dn, 1.0), 0.0)
        nsim += 2
        scale = max(float(np.ptp(h0)), 1e-15)
        beta = 100.0 * math.log(2.0 * h0.size) / scale
        price = area_price * scale / max(float(np.sum(cap)), 1e-30)

        def objective(y):
            dx = y - x
            h = h0 + a * effective_density(dx, cell, w) + b * dx
            z = beta * (h - h.max())
            zm = -beta * (h - h.min())
            ep, em = np.exp(z), np.exp(zm)
            sp, sm = ep.sum(), em.sum()
            f = (np.log(sp) / beta + h.max()) + (np.log(sm) / beta - h.min()) + price * y.sum()
            gh = ep / sp - em / sm
            grad = effective_density(a * gh, cell, w) + b * gh + price
            return f / scale, grad / scale

        target = _projected_descent(objective, x, np.zeros_like(x), cap, max_steps)
        accepted = False
        for _half in range(4):
            n_new = np.clip(np.rint(target / step), 0, sites.capacity)
            trial = polish(n_new)
            nsim += 1
            if thickness_range(trial) < history[-1]:
                n, current = n_new, trial
                history.append(thickness_range(trial))
                accepted = True
                break
            target = 0.5 * (target + x)
        if not accepted:
            break
    chosen = select_fill(sites, n)
    filled = filled_windows(windows, sites, chosen)
    after = current if n.any() else before
    counter = hotspot_counter
    plan = FillPlan(counts=n.astype(np.int64), chosen=chosen, windows=filled, before=before, after=after,
                    added_area=float(n.sum()) * side**2, limits=limits, history=history,
                    summary_before=_summary(before, limits, counter), summary_after=_summary(after, limits, counter))
    plan.stats = {"seconds": _time.perf_counter() - t_start, "polishes": nsim, "windows": int(n.size)}
    return plan
