"""Load balance at fixed tilts, the attack-angle scan, and the search for other moment roots.

The safeguards and starts of Newton's method on the wafer position
(:func:`cmpsim.solver.equilibrium.solve_equilibrium`): :func:`balance_load` brackets h0 at fixed tilts
until the slurry and contact pressures carry the applied load (eq. 31); the attack-angle scan
restarts a Newtonian film from where the moment about y changes sign; :func:`scan_moment_roots`
looks for other equilibria along the attack angle.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ..numerics.roots import brentq
from ..operators.state import EquilibriumError, EquilibriumSolution
from .wafer import WaferProblem

__all__ = ["balance_load", "scan_moment_roots", "RootScan", "tilt_scan_start"]


def balance_load(problem: WaferProblem, u, max_expansions: int = 40) -> np.ndarray:
    """Adjust h0 at fixed tilts until the load balances (bracket + Brent); the Newton safeguard.

    Positions where the film touches the pad or the pressure diverges count as
    overloaded (residual +inf). Returns the new u; raises EquilibriumError if no bracket
    is found.
    """
    u = np.asarray(u, dtype=float)
    sigma = problem.sigma

    seen = {}  # Brent re-evaluates the bracket ends: solve each h0 once

    def load(h0):
        h0 = float(h0)
        if h0 not in seen:
            try:
                seen[h0] = problem.state([h0, u[1], u[2]]).residual[0]
            except ValueError:
                seen[h0] = np.inf
        return seen[h0]

    h0 = _secant_load(problem, u, load)
    if h0 is not None:
        return np.array([h0, u[1], u[2]])
    a, fa = u[0], load(u[0])
    step = 0.25 * sigma
    direction = 1.0 if fa > 0 else -1.0
    for _ in range(max_expansions):
        b = a + direction * step
        fb = load(b)
        if np.sign(fb) != np.sign(fa):
            break
        a, fa = b, fb
        step *= 1.6
    else:
        raise EquilibriumError(
            f"no film thickness balances the load at attack angle {u[1]:.3g} rad: the load residual keeps "
            f"the sign of {fa:.3g} from h0 = {u[0]:.4g} m to {a:.4g} m"
        )
    lo, hi = sorted((a, b))
    flo, fhi = (fa, fb) if a < b else (fb, fa)
    # shrink an infinite end with bisection so that brentq sees finite values
    for _ in range(60):
        if np.isfinite(flo) and np.isfinite(fhi):
            break
        mid = 0.5 * (lo + hi)
        fm = load(mid)
        if np.sign(fm) == np.sign(flo):
            lo, flo = mid, fm
        else:
            hi, fhi = mid, fm
    h0 = brentq(load, lo, hi, xtol=1e-6 * sigma, rtol=1e-14, maxiter=200)
    return np.array([h0, u[1], u[2]])


def _secant_load(problem: WaferProblem, u, load, max_iter: int = 12):
    """h0 balancing the load at fixed tilts by a safeguarded Newton/secant iteration on
    g = ln(1 + R_F) (the load over the applied load, in logarithm: close to linear in h0 where
    the load is steep); None if it does not converge, so that the bracket takes over.

    Its steps shrink quickly, so that after the first ones the pressure solves refine against
    the factorisation at hand instead of factorising at every bracket point.
    """
    sigma = problem.sigma

    def g(h0):
        r = load(h0)
        return np.log1p(r) if np.isfinite(r) and r > -1.0 else np.nan

    h0 = float(u[0])
    g0 = g(h0)
    if not np.isfinite(g0):
        return None
    eps = 1e-4 * sigma
    slope = (g(h0 + eps) - g0) / eps
    for _ in range(max_iter):
        if not (np.isfinite(slope) and slope < 0):
            return None
        step = float(np.clip(-g0 / slope, -0.5 * sigma, 0.5 * sigma))
        h1 = h0 + step
        g1 = g(h1)
        while not np.isfinite(g1) or abs(g1) > abs(g0):  # backtrack towards h0
            step *= 0.5
            if abs(step) < 1e-9 * sigma:
                return None
            h1 = h0 + step
            g1 = g(h1)
        if abs(step) < 1e-6 * sigma or abs(g1) < 1e-12:
            return h1
        slope = (g1 - g0) / (h1 - h0)
        h0, g0 = h1, g1
    return None



def tilt_scan_start(problem: WaferProblem, u, n: int = 9) -> np.ndarray:
    """Balance the load at ``n`` attack angles within the admissible range and return the point
    where the moment about y changes sign (interpolated, in the bracket closest to balance;
    else where it is smallest), cross tilt 0.

    The range is +-0.9 (cutoff sigma + dome height) / R_w: tilting further would lower the
    trailing edge through the layer where the pad carries load.
    """
    cutoff = problem.pad.height_cutoff if problem.pad is not None and np.isfinite(problem.pad.height_cutoff) else 3.0
    layer = cutoff * problem.sigma + problem.dome_height
    limit = 0.9 * layer / problem.grid.radius
    thetas = np.linspace(-limit, limit, n)
    points = []
    for th in thetas:
        try:
            # bracket from above the contact layer: the thickest film that balances the load,
            # not a thin one where the sub-ambient pressure of a full-Sommerfeld film sucks
            # the wafer onto the pad
            v = balance_load(problem, [u[0] + layer, th, 0.0])
            points.append((th, v, problem.state(v).residual[1]))
        except (EquilibriumError, ValueError):
            continue
    if not points:
        raise EquilibriumError("no attack angle of the scan admits a load balance")
    # of the sign changes, the one whose ends are closest to balance (the moment is steep and
    # erratic around thin, sucked-down films)
    brackets = [(max(abs(ma), abs(mb)), va, vb, ma, mb) for (_, va, ma), (_, vb, mb) in zip(points, points[1:]) if ma * mb <= 0 and ma != mb]
    if brackets:
        _, va, vb, ma, mb = min(brackets, key=lambda q: q[0])
        w = ma / (ma - mb)
        return (1 - w) * va + w * vb
    return min(points, key=lambda q: abs(q[2]))[1]



@dataclass
class RootScan:
    """Moment residual along a scan of attack angles, the load balanced at each (h0 by Brent).

    ``roots`` are the attack angles (rad) where the moment about y changes sign, bracketed by
    the scan and polished with Brent's method; more than one means the equilibrium is not
    unique along this line (cross tilt held at its equilibrium value).
    """

    attack_angles: np.ndarray
    moment_residuals: np.ndarray
    roots: list


def scan_moment_roots(problem: WaferProblem, solution: EquilibriumSolution, n: int = 13, span: float = 0.9) -> RootScan:
    """Look for other equilibria: scan the attack angle over +-``span`` x (h_min / R_w).

    Tilting a wafer by h_min / R_w would make its edge touch the pad mean plane, so the scan
    covers the admissible tilts. Each scan point costs one load balance (about ten pressure
    solves). Points where the load cannot be balanced are left out (NaN).
    """
    st = solution.state
    limit = span * float(st.h.min()) / problem.grid.radius
    thetas = np.linspace(-limit, limit, n)
    moments = np.full(n, np.nan)
    for k, th in enumerate(thetas):
        try:
            u = balance_load(problem, [st.u[0], th, st.u[2]])
            moments[k] = problem.state(u).residual[1]
        except (EquilibriumError, ValueError):
            continue
    def moment(th):
        u = balance_load(problem, [st.u[0], th, st.u[2]])
        return problem.state(u).residual[1]

    roots = []
    for k in range(n - 1):
        a, b = moments[k], moments[k + 1]
        if not (np.isfinite(a) and np.isfinite(b)):
            continue
        if a == 0:
            roots.append(float(thetas[k]))
        elif a * b < 0:
            # polish the bracketed root (each evaluation is one load balance)
            try:
                root = brentq(moment, thetas[k], thetas[k + 1], xtol=1e-4 * (thetas[1] - thetas[0]), maxiter=30)
            except (EquilibriumError, ValueError, RuntimeError):
                root = thetas[k] - a * (thetas[k + 1] - thetas[k]) / (b - a)
            roots.append(float(root))
    return RootScan(thetas, moments, roots)
