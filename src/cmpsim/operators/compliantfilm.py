"""The compliant pad's contact-only start and its deformed film at any point of the wafer.

The cold start of the coupled solve of :mod:`cmpsim.operators.compliance` (the film h0 at zero tilt at
which the pad contact alone carries the load, the local balance k w = p_c(h) inverted through a
table) and the film at arbitrary points (the rigid film plus the deflection of the solved state,
interpolated from the cell centres), which the outputs ask for at the rim and the centre.
``docs/model.md``, "Pad compliance".
"""

from __future__ import annotations

import numpy as np

from ..numerics.roots import brentq
from .compliance import _memory, _rigid_film
from .state import EquilibriumError

__all__ = ["compliant_contact_only_start", "deformed_film"]


def compliant_contact_only_start(problem) -> np.ndarray:
    """h0 at zero tilt for which the pad contact alone carries the load on the compliant pad."""
    pad, sigma = problem.pad, problem.sigma
    shape = _rigid_film(problem, np.zeros(3), problem.xc, problem.yc)  # h - h0 at u = 0
    zero_film = problem.contact(np.full(1, 1e-3 * sigma))[0][0]
    if zero_film < problem.applied_pressure:
        raise EquilibriumError(
            "the applied load exceeds what the pad asperities can carry before the wafer "
            f"touches the pad mean plane (contact pressure at zero film is {zero_film / problem.applied_pressure:.3g} "
            "x the applied pressure); lower applied_pressure or stiffen the pad"
        )
    # contact only, the local balance k w = p_c(h) with h = h_rigid + w inverts explicitly:
    # h_rigid = h - p_c(h) / k is increasing in h, so a table of it gives h from h_rigid
    h_max, h_tab, hr_tab, pc_tab = _contact_only_table(problem)

    def film(h0):
        hr = h0 + shape
        return np.where(hr >= h_max, hr, np.interp(hr, hr_tab, h_tab))

    def excess(h0):
        # the contact pressure of the table's balance at each cell's rigid film: no kernel call
        return problem.grid.integrate(np.interp(h0 + shape, hr_tab, pc_tab)) / problem.load_scale - 1.0

    h_hi = -shape.min() + h_max  # no contact even undeflected
    h_lo = -shape.max() + hr_tab[0]  # the film closes somewhere below this
    if excess(h_lo) <= 0:
        raise EquilibriumError("no film balances the contact load on the compliant pad")
    h0 = brentq(excess, h_lo, h_hi, xtol=1e-6 * sigma, rtol=1e-12)
    u = np.array([h0, 0.0, 0.0])
    # the deflection of the table (the coupled solve's start balances it to round-off: :func:`_start`)
    _memory(problem).last = (u, np.zeros_like(shape), film(h0) - (h0 + shape))
    return u


_CONTACT_ONLY_TABLES: dict = {}


def _contact_only_table(problem) -> tuple:
    """(h_max, h, h_rigid, p_c) of the contact-only local balance: the film h (m) on 4001 points
    up to h_max, where the contact ends, the rigid film h - p_c(h) / k (m) it stands on and the
    contact pressure p_c(h) (Pa); built once per pad surface, contact model, offset and bed
    stiffness (a cold start on every point of a sweep would otherwise build it again)."""
    pad, sigma = problem.pad, problem.sigma
    key = (pad, problem.variant, problem.separation_offset, problem.foundation.stiffness, sigma)
    table = _CONTACT_ONLY_TABLES.get(key)
    if table is None:
        cutoff = pad.height_cutoff if np.isfinite(pad.height_cutoff) else 12.0
        h_max = problem.separation_offset + cutoff * pad.sigma_s  # no contact beyond
        h_tab = np.linspace(1e-3 * sigma, h_max, 4001)
        pc_tab = problem.contact(h_tab)[0]
        hr_tab = h_tab - pc_tab / problem.foundation.stiffness
        if len(_CONTACT_ONLY_TABLES) >= 64:
            _CONTACT_ONLY_TABLES.clear()
        table = _CONTACT_ONLY_TABLES[key] = (h_max, h_tab, hr_tab, pc_tab)
    return table


def deformed_film(problem, u, x, y) -> np.ndarray:
    """Film thickness at points (x, y) of the wafer at position u on the compliant pad, m.

    The rigid film plus the pad deflection of the coupled solution at u, interpolated from the
    cell centres (solved first if u is not a position solved before).
    """
    u = np.asarray(u, dtype=float)
    w = _memory(problem).deflections.get(u.tobytes())
    if w is None:
        w = problem.state(u).deflection
    x, y = np.broadcast_arrays(np.asarray(x, dtype=float), np.asarray(y, dtype=float))
    return _rigid_film(problem, u, x, y) + (_interpolation(problem.grid, x, y) @ w.ravel()).reshape(x.shape)


_INTERPOLATIONS: dict = {}


def _interpolation(grid, x, y):
    """:meth:`cmpsim.numerics.grid.PolarGrid.interpolation_matrix` of ``grid`` at the points (x, y), built
    once per grid and points (the outputs ask for the film at the rim and the centre of every
    solve)."""
    key = (grid, x.shape, x.tobytes(), y.tobytes())
    m = _INTERPOLATIONS.get(key)
    if m is None:
        if len(_INTERPOLATIONS) >= 32:
            _INTERPOLATIONS.clear()
        m = _INTERPOLATIONS[key] = grid.interpolation_matrix(x.ravel(), y.ravel())
    return m
