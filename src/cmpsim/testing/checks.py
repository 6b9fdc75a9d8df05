"""Verification helpers shared by the tests: manufactured solutions on the polar grid and
central-difference Jacobians of an equilibrium problem.

Used by the tests only; nothing in the solver depends on this module.
"""

from __future__ import annotations

import numpy as np

from ..numerics.grid import PolarGrid
from ..operators.reynolds import FaceCoefficients, ReynoldsSystem

__all__ = ["manufactured_errors", "central_difference_jacobian"]


def manufactured_errors(fun, grid: PolarGrid, venting: float = 0.0) -> tuple[float, float]:
    """(max, L2) error of the polar Reynolds solve of a manufactured solution, in the units of phi.

    ``fun(x, y)`` returns ``[dxx, dxy, dyy, source, phi]`` at points (m): the diffusion tensor,
    the source -div(D grad phi) (+ the grooves' sink g kappa^2 phi if ``venting`` = kappa^2 > 0,
    1/m^2) per unit area and the exact solution, 0 on the rim. The L2 error is area-weighted
    over the wafer.
    """

    def coeffs(x, y):
        dxx, dxy, dyy, _, _ = fun(x, y)
        z = np.zeros_like(x)
        return (dxx + z, dxy + z, dyy + z, z, z)

    xr, yr, _ = grid.radial_faces
    xa, ya, _ = grid.angular_faces
    c = FaceCoefficients(coeffs(xr, yr), coeffs(xa, ya), venting=venting)
    xc, yc = grid.centres
    phi = ReynoldsSystem(grid, c, source=fun(xc, yc)[3] * grid.area).solve()
    err = phi - fun(xc, yc)[4]
    return float(np.max(np.abs(err))), float(np.sqrt(grid.integrate(err**2) / (np.pi * grid.radius**2)))


def central_difference_jacobian(problem, u, rel_step: float = 1e-4) -> np.ndarray:
    """d(balance residuals)/du (3 x 3) of ``problem`` at position u by central differences of its
    states, steps ``rel_step`` times ``problem.u_scale``."""
    fd = np.empty((3, 3))
    for k in range(3):
        du = np.zeros(3)
        du[k] = rel_step * problem.u_scale[k]
        fd[:, k] = (problem.state(u + du).residual - problem.state(u - du).residual) / (2 * du[k])
    return fd
