"""The step-height contact model of two surface levels, integrated exactly in time (pure numpy).

A patterned cell has two levels: level A (area fraction ``f``) at height ``zA`` and level B
(fraction ``1 - f``) at ``zB``; ``s = zA - zB`` is the step height. The pad presses the upper
level harder (Smith et al. 1999; Gbondo-Tugbawa (Tugbawa), MIT PhD 2002; Lee, Boning &
Economikos, CMP-MIC 2001, eq. 4-5). With ``u`` the upper level's fraction and
``m = min(|s|, h) / h`` (``h`` the contact height):

    p_up   = P [1 + (1 - u) m / u],      p_down = P (1 - m),

so that u p_up + (1 - u) p_down = P (the pad's load balance over the cell), the down level is
out of contact (p_down = 0, p_up = P / u: Stine's density model) while the step exceeds ``h``,
and both levels carry P when the step has gone. Each level is removed at its blanket rate times
its pressure over P (Preston): R_A = K_A p_A / P, R_B = K_B p_B / P.

For constant blanket rates the step obeys a linear ODE in each regime,

    |s| >= h:     d|s|/dt = -K_up / u                              (linear),
    |s| <  h:     ds/dt   = -a - b s,  b = (K_up (1 - u) / u + K_down) / h   (exponential),

so :func:`advance` integrates it exactly, splitting a step at the events where the step falls
to ``h`` or changes sign. All functions are vectorised over cells and import nothing of cmpsim.
"""

from __future__ import annotations

import numpy as np

__all__ = ["pressures", "rates", "advance"]


def pressures(s, f, h):
    """(p_A / P, p_B / P) of the two levels for step s = zA - zB (m), fraction f of A, contact height h (m)."""
    s, f, h = np.broadcast_arrays(*(np.asarray(v, dtype=float) for v in (s, f, h)))
    m = np.minimum(np.abs(s), h) / h
    a_up = s >= 0
    u = np.where(a_up, f, 1.0 - f)
    p_up = 1.0 + (1.0 - u) * m / u
    p_dn = 1.0 - m
    return np.where(a_up, p_up, p_dn), np.where(a_up, p_dn, p_up)


def rates(s, f, h, k_a, k_b):
    """Removal rates (R_A, R_B) in m/s of the two levels: blanket rates k_a, k_b (m/s) times p / P."""
    pa, pb = pressures(s, f, h)
    return k_a * pa, k_b * pb


def _linear_until(s0, dt, k_up, u, h):
    """Time spent in the contactless regime |s| > h before |s| reaches h (capped at dt)."""
    speed = k_up / u
    return np.minimum(dt, np.maximum(np.abs(s0) - h, 0.0) / speed)


def advance(za, zb, f, h, k_a, k_b, dt):
    """Heights (zA, zB) after polishing for dt (s) with constant blanket rates k_a, k_b (m/s), exactly.

    Arrays broadcast together; f in (0, 1) is the fraction of level A seen by the pad (the
    effective density), h > 0 the contact height (m). The removal of each level is the exact
    time integral of :func:`rates` along the exact step-height trajectory.
    """
    za, zb, f, h, k_a, k_b, dt = np.broadcast_arrays(*(np.array(v, dtype=float) for v in (za, zb, f, h, k_a, k_b, dt)))
    za, zb, left = za.copy(), zb.copy(), dt.copy()
    for _ in range(4):  # at most: contactless -> contact -> sign change -> contact
        todo = left > 0
        if not todo.any():
            break
        s = za - zb
        # at s = 0 the level that is removed more slowly becomes the upper one
        a_up = (s > 0) | ((s == 0) & (k_a <= k_b))
        u = np.where(a_up, f, 1.0 - f)
        k_up = np.where(a_up, k_a, k_b)
        k_dn = np.where(a_up, k_b, k_a)
        # regime 1: only the upper level touches the pad
        t1 = np.where(todo, _linear_until(s, left, k_up, u, h), 0.0)
        rem_up = k_up / u * t1
        za = za - np.where(a_up, rem_up, 0.0)
        zb = zb - np.where(a_up, 0.0, rem_up)
        left = left - t1
        # snap exactly onto |s| = h where the event was reached (round-off would leave it a hair above)
        hit = todo & (t1 > 0) & (left > 0)
        zb = np.where(hit & a_up, za - h, zb)
        za = np.where(hit & ~a_up, zb - h, za)
        # regime 2: both levels in contact; sigma = |s| measured from the upper level
        todo = left > 0
        if not todo.any():
            break
        # after the snap above, |zA - zB| can exceed h by an ulp of the heights (zA - (zA - h) != h
        # in floating point); a tolerance of 1e-12 h or a few ulps of the heights, whichever is
        # larger, keeps such a cell in the contact regime instead of sending it back to the
        # contactless one, where it would make no progress (a contact height of picometres under
        # heights of micrometres: the ulp of the heights is the larger)
        sig = np.abs(za - zb)
        ulps = 8.0 * np.finfo(float).eps * np.maximum(np.abs(za), np.abs(zb))
        inside = todo & (sig <= h * (1.0 + 1e-12) + ulps)
        sig = np.minimum(sig, h)
        b = (k_up * (1.0 - u) / u + k_dn) / h
        a = k_up - k_dn  # d sigma/dt = -a - b sigma
        sig_inf = -a / b
        # time to reach sigma = 0 (only if the steady state lies below zero)
        with np.errstate(divide="ignore", invalid="ignore"):
            t0 = np.where((sig_inf < 0) & (sig > 0), np.log((sig - sig_inf) / (-sig_inf)) / b, np.inf)
        t2 = np.where(inside, np.minimum(left, t0), 0.0)
        decay = -np.expm1(-b * t2)  # 1 - exp(-b t2)
        integral = sig_inf * t2 + (sig - sig_inf) * decay / b  # of sigma over t2
        rem_up = k_up * (t2 + (1.0 - u) / u * integral / h)
        rem_dn = k_dn * (t2 - integral / h)
        za = za - np.where(a_up, rem_up, rem_dn)
        zb = zb - np.where(a_up, rem_dn, rem_up)
        crossed = inside & (t0 <= left)
        # at the sign change the two levels meet: set them equal (their mean keeps the removed volume to round-off)
        meet = f * za + (1.0 - f) * zb
        za = np.where(crossed, meet, za)
        zb = np.where(crossed, meet, zb)
        left = left - t2
    if np.any(left > 0):  # cannot happen: at most one contact event and one sign change per call
        raise RuntimeError("step-height integration left time unpolished after four regime changes")
    return za, zb
