"""Brent's root finder on a bracket, for the solver's one-dimensional balances.

:func:`brentq` is Brent's method (Brent 1973, *Algorithms for Minimization without
Derivatives*, ch. 4: inverse quadratic interpolation or the secant step when it stays well
inside the bracket, bisection otherwise), in the variant of ``scipy.optimize.brentq``: the same
steps, tolerances, iteration count and errors, so the same root to the last bit
(``tests/test_roots.py`` checks identical roots and function-call counts on thousands of
brackets).

Written here, not imported, because the load balance of every operating point needs one root
and loading ``scipy.optimize`` for it cost about a fifth of the whole ``cmpsim run`` of the base
case (``benchmarks/bench_import.py``; issue 31). The studies that need the rest of
``scipy.optimize`` (calibration, zone tuning) import it where they use it, and the test
references (:mod:`cmpsim.testing`) keep scipy's own.
"""

from __future__ import annotations

import math
from typing import Callable

__all__ = ["brentq", "RTOL_MIN"]

#: The smallest relative tolerance accepted (4 machine epsilons, as scipy).
RTOL_MIN = 4.0 * 2.220446049250313e-16


def brentq(f: Callable[[float], float], a: float, b: float, xtol: float = 2e-12, rtol: float = RTOL_MIN, maxiter: int = 100) -> float:
    """A root of ``f`` in the bracket [a, b] (f(a) and f(b) of opposite signs), in the unit of a.

    Converged when half the bracket is below (xtol + rtol |x|) / 2, or f is exactly 0.
    Raises ValueError for tolerances out of range, a bracket without a sign change or a NaN
    value of f (naming x), RuntimeError after ``maxiter`` iterations without convergence.
    """
    if not xtol > 0:
        raise ValueError(f"xtol too small ({xtol:g} <= 0)")
    if not rtol >= RTOL_MIN:
        raise ValueError(f"rtol too small ({rtol:g} < {RTOL_MIN:g})")

    def value(x: float) -> float:
        v = float(f(x))
        if math.isnan(v):
            raise ValueError(f"The function value at x={x:f} is NaN; solver cannot continue.")
        return v

    xpre, xcur = float(a), float(b)
    xblk = fblk = spre = scur = 0.0
    fpre, fcur = value(xpre), value(xcur)
    if fpre == 0:
        return xpre
    if fcur == 0:
        return xcur
    if math.copysign(1.0, fpre) == math.copysign(1.0, fcur):
        raise ValueError("f(a) and f(b) must have different signs")
    for _ in range(maxiter):
        if fpre != 0 and fcur != 0 and math.copysign(1.0, fpre) != math.copysign(1.0, fcur):
            xblk, fblk = xpre, fpre  # the bracket's other end
            spre = scur = xcur - xpre
        if abs(fblk) < abs(fcur):  # the best point is the current one
            xpre, xcur, xblk = xcur, xblk, xcur
            fpre, fcur, fblk = fcur, fblk, fcur
        delta = (xtol + rtol * abs(xcur)) / 2
        sbis = (xblk - xcur) / 2
        if fcur == 0 or abs(sbis) < delta:
            return xcur
        if abs(spre) > delta and abs(fcur) < abs(fpre):
            if xpre == xblk:  # secant
                stry = -fcur * (xcur - xpre) / (fcur - fpre)
            else:  # inverse quadratic interpolation
                dpre = (fpre - fcur) / (xpre - xcur)
                dblk = (fblk - fcur) / (xblk - xcur)
                stry = -fcur * (fblk * dblk - fpre * dpre) / (dblk * dpre * (fblk - fpre))
            if 2 * abs(stry) < min(abs(spre), 3 * abs(sbis) - delta):
                spre, scur = scur, stry  # a good short step
            else:
                spre = scur = sbis
        else:
            spre = scur = sbis
        xpre, fpre = xcur, fcur
        xcur += scur if abs(scur) > delta else (delta if sbis > 0 else -delta)
        fcur = value(xcur)
    raise RuntimeError(f"Failed to converge after {maxiter} iterations, value is {xcur}")
