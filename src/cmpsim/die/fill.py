"""Model-based dummy fill: add fill density where the die model says it flattens the die.

Not a flat density target: the added density x (one value per window, bounded by what the
window's free fill sites can hold, :class:`cmpsim.layout.fill.FillSites`) is chosen to
minimise the **thickness range** of the die model's final surface, the range of the mean
surface height of the windows after polishing, the quantity the hotspots of ``thickness`` are
measured on. Every die (as drawn, each trial fill) is polished by a
:class:`cmpsim.die.chip.DieModel` on :meth:`cmpsim.die.layout.Layout.from_windows` of its
window fields: the pipeline of ``cmpsim die LAYOUT``, so that ``before``/``after`` are the die
command's own ``thickness_range`` and ``hotspot_count`` (with its ``--spec`` limits).

**Algorithm** (sequential linearisation, docs/fill.md):

1. Polish the die as drawn (the die model's own end point, or the given time): the thickness T_i of every window.
2. The linear response of T to the fill: a window's final height depends on its own local
   fields (density, width) and on the effective density rho_eff = w * rho, the only coupling
   between windows. The die evolution is independent cell by cell given (rho, w, rho_eff), so
   two more evolutions at the same time give every window's derivatives at once:
   a_i = dT_i / d rho_eff_i (rho_eff + delta) and b_i = dT_i / dx_i at fixed rho_eff (the
   local fields of x + delta of square fill: area + n s^2, boundary + 4 n s). Then
   T(x) ~ T + a (w * dx) + b dx, linear in dx, with w * the FFT convolution of the weighting.
3. Minimise a smooth range of that linear model, LSE_beta(T) + LSE_beta(-T) (log-sum-exp,
   beta set so that its excess over max - min is about 1 % of the range), plus a small
   price per added density, over 0 <= x <= capacity (spectral projected gradient; the
   gradient is one convolution: the weighting is symmetric).
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
from .polish import DieResult

__all__ = ["FillPlan", "plan_fill", "fill_die", "die_layout", "thickness", "thickness_range", "hotspot_count", "DEFAULT_LIMITS"]

#: Hotspot limits used by the library call when neither a model nor limits are given (m): a window's final
#: surface more than 5 nm off the die's mean (the example of issue 33, ``--spec thickness=5nm``). ``cmpsim die
#: --fill`` never uses them: it counts with its own ``--spec`` limits (none given: no hotspots), as the die does.
DEFAULT_LIMITS = {"thickness": 5e-9}


def die_layout(windows, name: str | None = None) -> Layout:
    """The die model's :class:`Layout` of a :class:`cmpsim.layout.LayoutWindows`: :meth:`Layout.from_windows`,
    the die ``cmpsim die LAYOUT`` polishes (density, width and space per window, the edge windows' part inside the die)."""
    return Layout.from_windows(windows, name)


def thickness(result: DieResult) -> np.ndarray:
    """Each window's final surface height off the die's mean (m): :attr:`DieEvolution.thickness`."""
    return result.evolution.thickness


def thickness_range(result: DieResult) -> float:
    """max - min of the final surface over the die (m): :attr:`DieResult.thickness_range`."""
    return result.thickness_range


def hotspot_count(result: DieResult, limits: dict | None = None) -> int:
    """The die command's hotspot count (:meth:`DieResult.hotspot_count`, :func:`cmpsim.die.hotspots.count_hotspots`):
    windows over a limit, per quantity, summed: ``thickness`` (|height off the die mean|), ``step_height``,
    ``dishing``, ``erosion`` (m; NaN never counts). ``limits`` default :data:`DEFAULT_LIMITS`."""
    from .hotspots import SPEC_KINDS

    limits = DEFAULT_LIMITS if limits is None else limits
    for kind in limits:
        if kind not in SPEC_KINDS:
            raise ValueError(f"unknown hotspot quantity {kind!r}; valid: {', '.join(SPEC_KINDS)}")
    return result.hotspot_count(dict(limits)) if limits else 0


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


def _summary(result: DieResult, counter) -> dict:
    """{hotspot_count, thickness_range} of a polished die: the die command's own definitions (the result's ``spec``)."""
    return {"hotspot_count": int(counter(result) if counter is not None else result.hotspot_count()),
            "thickness_range": result.thickness_range}


@dataclass
class FillPlan:
    """The model-based fill of one die: the squares chosen, the die before and after.

    ``counts`` (ny, nx) squares per window; ``chosen`` the chosen lattice sites (for
    :func:`cmpsim.layout.fill.write_fill`); ``windows`` the window fields after fill;
    ``before``/``after`` the polished dies; ``added_area`` m^2; ``history`` the range (m) after
    each accepted outer iteration; ``stats`` the cost (s) and counts; ``sites`` the fill sites it chose from.
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
    sites: object = field(default=None, repr=False)

    def to_dict(self) -> dict:
        """The JSON ``fill`` object: {before: {hotspot_count, thickness_range}, after: {...}, added_area} (SI)."""
        return {"before": dict(self.summary_before), "after": dict(self.summary_after), "added_area": float(self.added_area),
                "squares": int(self.counts.sum()), "iterations": len(self.history) - 1,
                "thickness_range_history": [float(v) for v in self.history]}


def _with_squares(windows, n, side):
    """The :class:`LayoutWindows` with n (float) squares of side ``side`` (m) added per window: area A + n s^2 and
    boundary L + 4 n s (exact: :func:`cmpsim.layout.fill.filled_windows`), density, width, space from them."""
    from dataclasses import replace

    from ..layout.extract import window_fields

    if not np.any(n):
        return windows
    area = windows.density * windows.window**2 + n * side**2
    boundary = windows.boundary + 4.0 * n * side
    density, width, space = window_fields(area, boundary, windows.window)
    return replace(windows, density=density, width=width, space=space, boundary=boundary)


def _inside_fraction(windows) -> np.ndarray:
    """(ny, nx) the part of each window inside the die's outline (1 inside; :meth:`Layout.from_windows` divides by it)."""
    W = float(windows.window)
    x0, y0, x1, y1 = windows.bbox
    fx = np.clip((np.minimum(windows.x + 0.5 * W, x1) - np.maximum(windows.x - 0.5 * W, x0)) / W, 0.0, 1.0)
    fy = np.clip((np.minimum(windows.y + 0.5 * W, y1) - np.maximum(windows.y - 0.5 * W, y0)) / W, 0.0, 1.0)
    return np.maximum(fy[:, None] * fx[None, :], 1e-300)


def plan_fill(windows, sites, *, model=None, time: float | None = None, config=None, blanket_rate: float | None = None,
              process=None, planarization_length: float | None = None, weighting: str = "gaussian",
              feature_contact: str = "elastic", limits: dict | None = None, hotspot_counter=None, iterations: int = 3,
              area_price: float = 1e-3, max_steps: int = 300, before: DieResult | None = None, **process_values) -> FillPlan:
    """Choose the fill squares of every window that minimise the die model's thickness range.

    ``windows`` the :class:`cmpsim.layout.LayoutWindows` of the drawn layer; ``sites`` its
    :class:`cmpsim.layout.fill.FillSites`. Every die is polished by ``model``, a
    :class:`cmpsim.die.chip.DieModel` (the one ``cmpsim die`` runs: its wafer solve, weighting, pad
    contact and ``spec`` limits), on :meth:`Layout.from_windows` of the window fields with the
    squares added, for ``time`` (s; default each die's own end point x (1 + over_polish)), so the
    before/after ``hotspot_count`` and ``thickness_range`` are the die command's own. Without a
    model one is made from ``config``, ``blanket_rate`` (default: one wafer solve), ``process``,
    ``planarization_length``, ``weighting``, ``feature_contact`` and the process keywords, with
    ``limits`` as its spec (default :data:`DEFAULT_LIMITS`). ``hotspot_counter(result) -> int``
    replaces the count. ``before`` the die as drawn when the caller polished it already (with the
    same model and time). ``iterations`` the outer linearisations, ``max_steps`` the
    projected-gradient steps of each; ``area_price`` the price of added density relative to the
    range (a tie-breaker: among fills of equal range, less).
    """
    from ..layout.fill import filled_windows, select_fill
    from .chip import DieModel

    t_start = _time.perf_counter()
    if tuple(sites.shape) != tuple(windows.density.shape):
        raise ValueError(f"fill sites {sites.shape} and windows {windows.density.shape} are not the same grid")
    if model is None:
        model = DieModel(config, process, blanket_rate=blanket_rate, planarization_length=planarization_length, weighting=weighting,
                         feature_contact=feature_contact, spec=DEFAULT_LIMITS if limits is None else limits, **process_values)
    elif limits is not None:
        raise ValueError("give the hotspot limits as the model's spec, not as limits, when a model is given")
    base = Layout.from_windows(windows)
    side = sites.size * sites.dbu
    step = sites.density_step
    cap = sites.capacity.astype(float) * step  # the most density (of the whole window) each window can take
    cell = float(windows.window)
    gain = 1.0 / _inside_fraction(windows)  # the die's density per unit of window density (edge windows: > 1)
    w = model.weight

    def layout_of(n):
        return base if not np.any(n) else Layout.from_windows(_with_squares(windows, n, side), base.name)

    def polish(n):
        return model.run(layout_of(n), time)

    def evolve(lay, eff, t):
        ev = DieEvolution(lay, model.process, eff, model.blanket_rate, model.config.asperity_radius, model.feature)
        ev.advance_to(t)
        return ev.mean_height

    if before is None:
        before = polish(np.zeros(sites.shape))
    n = np.zeros(sites.shape)
    current = before
    history = [before.thickness_range]
    nsim = 1
    delta = 0.02
    for _ in range(max(int(iterations), 0)):
        x = n * step
        lay = layout_of(n)
        eff = current.effective_density
        t = current.time
        h0 = current.evolution.mean_height
        # a: d h / d rho_eff at fixed local fields; b: d h / d x at fixed rho_eff (one evolution each)
        up = np.where(eff + delta < 1.0, delta, -delta)
        a = (evolve(lay, eff + up, t) - h0) / up
        dn = np.minimum(delta, cap - x)
        dn = np.where(dn > 1e-9, dn, -np.minimum(delta, x))
        ok = np.abs(dn) > 1e-9
        hb = evolve(layout_of(n + np.where(ok, dn, 0.0) / step), eff, t)
        b = np.where(ok, (hb - h0) / np.where(ok, dn, 1.0), 0.0)
        nsim += 2
        scale = max(float(np.ptp(h0)), 1e-15)
        beta = 100.0 * math.log(2.0 * h0.size) / scale
        price = area_price * scale / max(float(np.sum(cap)), 1e-30)

        def objective(y):
            dx = y - x
            h = h0 + a * effective_density(gain * dx, cell, w) + b * dx
            z = beta * (h - h.max())
            zm = -beta * (h - h.min())
            ep, em = np.exp(z), np.exp(zm)
            sp, sm = ep.sum(), em.sum()
            f = (np.log(sp) / beta + h.max()) + (np.log(sm) / beta - h.min()) + price * y.sum()
            gh = ep / sp - em / sm
            grad = gain * effective_density(a * gh, cell, w) + b * gh + price
            return f / scale, grad / scale

        target = _projected_descent(objective, x, np.zeros_like(x), cap, max_steps)
        accepted = False
        for _half in range(4):
            n_new = np.clip(np.rint(target / step), 0, sites.capacity)
            trial = polish(n_new)
            nsim += 1
            if trial.thickness_range < history[-1]:
                n, current = n_new, trial
                history.append(trial.thickness_range)
                accepted = True
                break
            target = 0.5 * (target + x)
        if not accepted:
            break
    chosen = select_fill(sites, n)
    filled = filled_windows(windows, sites, chosen)
    after = current if n.any() else before
    plan = FillPlan(counts=n.astype(np.int64), chosen=chosen, windows=filled, before=before, after=after,
                    added_area=float(n.sum()) * side**2, limits=dict(model.spec), history=history,
                    summary_before=_summary(before, hotspot_counter), summary_after=_summary(after, hotspot_counter), sites=sites)
    plan.stats = {"seconds": _time.perf_counter() - t_start, "polishes": nsim, "windows": int(n.size)}
    return plan


def fill_die(layout, layers, window: float, rules, fill_layer, *, top: str | None = None, pdk: str | None = None,
             layer_map=None, config=None, process: str = "oxide", blanket_rate: float | None = None,
             time: float | None = None, with_file: bool = True, progress=None, **model_options):
    """The model-based fill of a real layout, as ``cmpsim die LAYOUT --fill`` runs it.

    Reads ``layout`` (a path or a :class:`cmpsim.layout.Layout`), extracts the windows of ``layers``
    (side ``window``, m), finds the free fill sites under ``rules``
    (:func:`cmpsim.layout.fill.fill_sites`), and plans the fill (:func:`plan_fill`) on the die
    command's own :class:`cmpsim.die.chip.DieModel` (``config``, ``process``, ``blanket_rate``
    (default one wafer solve), ``time`` and ``model_options`` such as ``spec``, ``weighting``,
    ``planarization_length``). ``fill_layer`` the fill's (layer, datatype). Returns (the filled
    die's result with its JSON ``fill`` object, the :class:`FillPlan`, the fill file's name:
    ``fill.oas`` for an OASIS layout, else ``fill.gds``; ``file`` in the object only
    ``with_file``). ``progress`` a callable told (stage, done, total) by the extraction. ValueError
    naming the option for a missing file or bad input.
    """
    from dataclasses import replace

    from ..layout import Layout as LayoutFile
    from ..layout import extract_windows, read_layout
    from ..layout.fill import fill_sites
    from .chip import DieModel

    if not isinstance(layout, LayoutFile):
        try:
            layout = read_layout(layout)
        except FileNotFoundError as exc:
            raise ValueError(str(exc)) from None
    windows = extract_windows(layout, layers, window, top=top, pdk=pdk, layer_map=layer_map, progress=progress)
    sites = fill_sites(layout, layers, windows, rules, top=top, pdk=pdk, layer_map=layer_map)
    model = DieModel(config, process, blanket_rate=blanket_rate, **model_options)
    plan = plan_fill(windows, sites, model=model, time=time)
    name = "fill.oas" if layout.format.startswith("oas") else "fill.gds"
    pair = tuple(fill_layer)
    fill = plan.to_dict() | {"layer": f"{pair[0]}/{pair[1]}", "file": name if with_file else None,
                             "rules": {"size": rules.size, "spacing": rules.spacing, "keepout": rules.keepout, "edge": rules.edge,
                                       "source": rules.source},
                             "units": {"added_area": "m^2", "thickness_range": "m", "hotspot_count": "1", "rules": "m"}}
    return replace(plan.after, fill=fill), plan, name
