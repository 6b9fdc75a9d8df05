"""Time evolution of every cell of a die under a blanket removal rate: oxide, or copper in stages.

Each cell has two levels (:mod:`cmpsim.die.stepheight`), at heights measured from the original
top of the field oxide; the film stack (:mod:`cmpsim.die.stacks`) says what they are:

* **oxide** (ILD/STI): level A is the oxide over the lines (local fraction rho, the pattern
  density), level B the oxide over the spaces, ``step_height`` below; both are oxide, removed at
  the blanket rate K. The pad sees the effective density rho_eff (Stine et al. 1998).
* **copper** (damascene): level A is the field (fraction 1 - rho: plated copper of
  ``copper_thickness`` on a barrier of ``barrier_thickness`` on oxide), level B the copper over
  the lines. Wide trenches print through the conformal plating as a step equal to the trench
  depth; trenches narrower than twice the plated thickness are closed and start flat. The field
  is removed at K while it is copper (stage 1, bulk removal), at ``barrier_selectivity`` K on the
  barrier and ``oxide_selectivity`` K on the oxide (stage 2, over-polish); the lines at K
  throughout. Dishing is the depth of the line below the field once the field copper has
  cleared; erosion is the field oxide lost below its original top.

The contact height of a lower level of width b is the pad's contact height limited by the depth
a pad summit of radius R can reach into a gap of width b, its sagitta b^2 / 8R:
h(b) = h_c (1 - exp(-b^2 / (8 R h_c))) (docs/model.md, section 18.5); with a ``feature``
(:class:`cmpsim.die.reach.FeatureContact`, the default of :func:`cmpsim.die.simulate`) the pad
body's elastic bulge into the gap, which grows with the gap's width, is added to it. Everything is exact
in time within a stage; the stage changes and the planarity events are located by Newton's
method on the exact trajectory.
"""

from __future__ import annotations

import copy

import numpy as np

from .stacks import film_stack
from .stepheight import advance, rates

__all__ = ["DieEvolution", "contact_heights", "DENSITY_FLOOR"]

#: Effective fractions are kept inside [DENSITY_FLOOR, 1 - DENSITY_FLOOR]: a level the pad sees
#: on less than a millionth of the area carries its share of the load on that area (the
#: pressure formula divides by the fraction). Only cells whose local fraction of that level is
#: 0 or 1 reach the floor (their other level then has no area, so nothing measurable changes).
DENSITY_FLOOR = 1e-6


def contact_heights(gap_width, contact_height: float, asperity_radius: float) -> np.ndarray:
    """h(b) = h_c (1 - exp(-b^2 / (8 R h_c))) (m) for gap widths b (m); h_c where b is NaN (wide)."""
    b = np.asarray(gap_width, dtype=float)
    sag = np.where(np.isfinite(b), b**2 / (8.0 * asperity_radius), np.inf)
    return contact_height * -np.expm1(-sag / contact_height)


class DieEvolution:
    """The state of every cell of a die, advanced in time under blanket rate ``blanket_rate`` (m/s)."""

    def __init__(self, layout, process, effective_density, blanket_rate: float, asperity_radius: float, feature=None, incoming=None):
        """``incoming`` (optional): the topography a level below left, ``(height, step)`` per cell (m).

        ``height`` shifts both levels of a cell and every material interface of its film stack
        (the deposited films follow it); ``step`` deepens the lower level against the upper one
        by that much, at the cell's mean height (the new films' lower level over the old one's).
        """
        self.process = process
        self.stack = film_stack(process)
        self.f_local, self._eff_is_a, self._gap, self.za, self.zb = self.stack.levels(layout.density, layout.widths(), layout.spaces())
        self._pitches = layout.pitches
        self.base = np.zeros(self.za.shape)  # the height of the film stack's reference (the original field oxide top)
        if incoming is not None:
            height, step = (np.broadcast_to(np.nan_to_num(np.asarray(v, dtype=float)), self.za.shape) for v in incoming)
            a = self.f_local
            # the levels are tracked against the film stack's own reference (so its interfaces stay where they are),
            # which sits at `base`; the outputs add it
            self.base = height.copy()
            self.za = self.za + (1.0 - a) * step
            self.zb = self.zb - a * step
        self.condition(blanket_rate, effective_density, asperity_radius, feature)
        self.conditioned_by = None  # what set the conditions (a DieModel's mark: cmpsim.die.chip.DieModel.resume)
        self.za0, self.zb0 = self.za.copy(), self.zb.copy()
        self.t = 0.0
        s0 = np.abs(self.za - self.zb)
        self.t_planar = np.where(s0 <= process.planarity, 0.0, np.inf)
        self.t_copper_clear = np.full(self.za.shape, np.inf)
        # the end point: cleared (a metal stack), planarized (oxide)
        self.t_clear = np.full(self.za.shape, np.inf) if self.stack.metal else self.t_planar.copy()

    def condition(self, blanket_rate: float, effective_density, asperity_radius: float, feature=None) -> None:
        """Set what the pad does from now on: the blanket rate (m/s), the effective density the pad sees and the
        contact heights of the gaps (from the summit radius, m, and the pad body's ``feature`` contact).

        The state (both levels of every cell, the event times, the time) is kept: a later step of a recipe, at
        another rate or pressure, continues the same die (:meth:`cmpsim.die.chip.DieModel.resume`).
        """
        self.set_rate(blanket_rate)
        eff = np.asarray(effective_density, dtype=float)
        self.f = np.clip(eff if self._eff_is_a else 1.0 - eff, DENSITY_FLOOR, 1.0 - DENSITY_FLOOR)
        radius = self.process.summit_radius or asperity_radius  # a calibrated summit radius (DieProcess) before the pad's
        self.h = contact_heights(self._gap, self.process.contact_height, radius)
        if feature is not None:  # the pad body bulging into the gap (cmpsim.die.reach): h grows with the gap's width
            bulge = feature.bulge(self._gap, self._pitches(), self.f)
            if self.process.feature_modulus > 0:  # G is proportional to 1/E (half space and layer alike, same nu)
                bulge = bulge * (feature.modulus / self.process.feature_modulus)
            self.h = self.h + bulge

    def set_rate(self, blanket_rate: float) -> None:
        """Set the blanket rate (m/s) from now on, the rest of the conditions kept (:meth:`condition`)."""
        if not (np.isfinite(blanket_rate) and blanket_rate > 0):
            raise ValueError(f"blanket_rate must be > 0 m/s; got {blanket_rate!r}")
        self.rate = float(blanket_rate)

    def copy(self) -> "DieEvolution":
        """An independent copy of the state (advancing it leaves this one where it is)."""
        new = copy.copy(self)
        for name in ("za", "zb", "t_planar", "t_copper_clear", "t_clear"):
            setattr(new, name, getattr(self, name).copy())
        return new

    # ------------------------------------------------------------------ materials
    def _field_rate(self, za):
        return self.stack.field_rate(za, self.rate)

    def _boundary(self, za):
        """The height at which the field changes material next (-inf: none)."""
        return self.stack.boundary(za)

    def rates(self, za=None, zb=None):
        """Removal rates (R_A, R_B) of the two levels at a state (default: now), m/s."""
        za = self.za if za is None else za
        zb = self.zb if zb is None else zb
        return rates(za - zb, self.f, self.h, self._field_rate(za), self.rate)

    # ------------------------------------------------------------------ events
    @staticmethod
    def _newton(state, dt, g, dg, t_max):
        """Time in [0, t_max] where g(advance(state, t), cells) = 0 (g decreasing, g(0) > 0 >= g(t_max)).

        Safeguarded Newton (clipped to the bracket, bisection when a step leaves it far), from the
        first-order estimate; each cell stops when its step is below 1e-12 of t_max or
        |g| <= 1e-18 m.
        """
        za, zb, f, h, ka, kb = state
        lo, hi = np.zeros_like(t_max), t_max.copy()
        g0 = g(za, zb, np.arange(t_max.size))
        slope0 = dg(za, zb, f, h, ka, kb)
        with np.errstate(divide="ignore", invalid="ignore"):
            t = np.clip(-g0 / slope0, 0.0, t_max)
        t = np.where(np.isfinite(t), t, 0.5 * t_max)
        active = np.arange(t.size)
        for _ in range(60):
            if active.size == 0:
                break
            sub = (za[active], zb[active], f[active], h[active], ka[active], kb[active])
            a, b = advance(*sub, t[active])
            val = g(a, b, active)
            tl, th, ta = lo[active], hi[active], t[active]
            tl = np.where(val > 0, ta, tl)
            th = np.where(val <= 0, ta, th)
            slope = dg(a, b, *sub[2:])
            with np.errstate(divide="ignore", invalid="ignore"):
                nxt = ta - val / slope
            # a step beyond the bracket is cut back to its end (the root may sit on it), one
            # that leaves it far is replaced by bisection
            nxt = np.where(np.isfinite(nxt), nxt, 0.5 * (tl + th))
            far = (nxt < tl - (th - tl)) | (nxt > th + (th - tl))
            nxt = np.where(far, 0.5 * (tl + th), np.clip(nxt, tl, th))
            done = (np.abs(nxt - ta) <= 1e-12 * t_max[active]) | (th - tl <= 1e-12 * t_max[active]) | (np.abs(val) <= 1e-18)
            lo[active], hi[active], t[active] = tl, th, nxt
            active = active[~done]
        a, b = advance(za, zb, f, h, ka, kb, t)
        return t, a, b

    def advance_to(self, time: float) -> None:
        """Polish until ``time`` (s, not before the current time)."""
        if time < self.t:
            raise ValueError(f"cannot polish backwards: the die is at t = {self.t:g} s, asked for {time:g} s")
        dt_total = time - self.t
        if dt_total == 0:
            return
        left = np.full(self.za.shape, dt_total)
        for _ in range(4):  # at most two material changes per cell and step, plus the rest
            idx = np.nonzero(left > 0)
            if idx[0].size == 0:
                break
            za, zb, f, h = self.za[idx], self.zb[idx], self.f[idx], self.h[idx]
            ka = self._field_rate(za)
            kb = np.full(za.shape, self.rate)
            dt = left[idx]
            a1, b1 = advance(za, zb, f, h, ka, kb, dt)
            bound = self._boundary(za)
            cross = a1 <= bound
            t_seg = dt.copy()
            if cross.any():
                st = tuple(v[cross] for v in (za, zb, f, h, ka, kb))
                bc = bound[cross]
                def g_bound(a, b, sel):
                    return a - bc[sel]

                tc, ac, bcz = self._newton(st, None, g_bound, lambda a, b, f_, h_, ka_, kb_: -rates(a - b, f_, h_, ka_, kb_)[0], dt[cross])
                t_seg[cross] = tc
                # on the boundary: the next segment polishes the next material (a round-off move)
                a1[cross], b1[cross] = np.minimum(ac, bc), bcz
            elapsed = dt_total - dt  # time already polished in this call before the segment
            self._planarity_events(idx, (za, zb, f, h, ka, kb), a1, b1, t_seg, elapsed)
            if self.stack.metal and cross.any():
                when = self.t + elapsed[cross] + t_seg[cross]
                sub = tuple(i[cross] for i in idx)
                cu = bound[cross] > 0  # the copper/barrier interface was reached
                self.t_copper_clear[tuple(i[cu] for i in sub)] = when[cu]
                self.t_clear[tuple(i[~cu] for i in sub)] = when[~cu]
                # a cell whose copper cleared before it planarized: its bulk stage ends there
                pending = np.isinf(self.t_planar[sub]) & cu
                self.t_planar[tuple(i[pending] for i in sub)] = when[pending]
            self.za[idx], self.zb[idx] = a1, b1
            left[idx] = dt - t_seg
        if np.any(left > 0):  # cannot happen: a field changes material at most twice
            raise RuntimeError("die evolution left time unpolished after four material changes")
        self.t = float(time)

    def _planarity_events(self, idx, state, a1, b1, t_seg, elapsed):
        p = self.process
        za, zb = state[0], state[1]
        open_ = np.isinf(self.t_planar[idx]) & self.stack.planarizing(za)
        s0, s1 = np.abs(za - zb), np.abs(a1 - b1)
        hit = open_ & (s0 > p.planarity) & (s1 <= p.planarity)
        if not hit.any():
            return
        st = tuple(v[hit] for v in state)

        def g(a, b, sel):
            return np.abs(a - b) - p.planarity

        def dg(a, b, f_, h_, ka_, kb_):
            ra, rb = rates(a - b, f_, h_, ka_, kb_)
            return -np.sign(a - b) * (ra - rb) - (a == b)

        tp, _, _ = self._newton(st, None, g, dg, t_seg[hit])
        self.t_planar[tuple(i[hit] for i in idx)] = self.t + elapsed[hit] + tp
        if not self.stack.metal:
            self.t_clear[tuple(i[hit] for i in idx)] = self.t + elapsed[hit] + tp

    # ------------------------------------------------------------------ outputs
    @property
    def step_height(self) -> np.ndarray:
        """|zA - zB| (m): the local step height (the dishing, once a copper field has cleared); NaN where one level has no area."""
        two = (self.f_local > 0.0) & (self.f_local < 1.0)
        return np.where(two, np.abs(self.za - self.zb), np.nan)

    @property
    def dishing(self) -> np.ndarray:
        """Copper: depth of the line below the field where the field copper has cleared (m); NaN without lines or for oxide."""
        if not self.stack.metal:
            return np.full(self.za.shape, np.nan)
        lines = self.f_local < 1.0
        cleared = ~self.stack.planarizing(self.za)
        return np.where(lines, np.where(cleared, self.za - self.zb, 0.0), np.nan)

    @property
    def erosion(self) -> np.ndarray:
        """Copper: field oxide lost below its original top (m); NaN for oxide."""
        if not self.stack.metal:
            return np.full(self.za.shape, np.nan)
        return np.maximum(-self.za, 0.0)

    @property
    def mean_height(self) -> np.ndarray:
        """Area-weighted mean surface height of each cell (m): f zA + (1 - f) zB with the local fractions, plus the incoming height."""
        return self.f_local * self.za + (1.0 - self.f_local) * self.zb + self.base

    @property
    def upper_height(self) -> np.ndarray:
        """Height of level A (m), with the incoming height (``za`` is measured from the film stack's own reference)."""
        return self.za + self.base

    @property
    def lower_height(self) -> np.ndarray:
        """Height of level B (m), with the incoming height."""
        return self.zb + self.base

    def removed_thickness(self) -> np.ndarray:
        """Removed volume per area of each cell since the start (m)."""
        return self.f_local * (self.za0 - self.za) + (1.0 - self.f_local) * (self.zb0 - self.zb)

    @property
    def thickness(self) -> np.ndarray:
        """The final surface of each cell off the die's mean (m): :attr:`mean_height` minus its mean over the die."""
        h = self.mean_height
        return h - float(np.mean(h))

    def topography(self) -> tuple[np.ndarray, np.ndarray]:
        """What this level leaves to the next (``incoming`` of the next level): (surface off the die's mean, the residual local step), m."""
        return self.thickness, np.nan_to_num(self.step_height)

    def removal_rate(self) -> np.ndarray:
        """Local volume removal rate per area (m/s): f R_A + (1 - f) R_B with the local fractions."""
        ra, rb = self.rates()
        return self.f_local * ra + (1.0 - self.f_local) * rb
