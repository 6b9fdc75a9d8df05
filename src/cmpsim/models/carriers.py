"""Carrier models (``carrier``): the wafer's unknowns and the load the carrier applies.

The paper's carrier holds the wafer as a rigid body (:class:`RigidCarrier`): three unknowns,
the film thickness h0 at the centre and the two tilts, driven by the balance of the applied
load and of the moments about the carrier's pivot at the centre of the wafer face
(eq. 30-31). A carrier that bends the wafer (a membrane head) adds a class here and an entry
in the registry of :mod:`cmpsim.models`.
"""

from __future__ import annotations

import numpy as np

from ..geometry import film_thickness

__all__ = ["RigidCarrier"]


class RigidCarrier:
    """A rigid wafer under a uniform applied pressure, pivoting about the centre of its face.

    Unknowns u = (h0 [m], attack angle theta [rad], cross tilt beta [rad]); residuals

        R_F = (integral of p dA) / (P_applied A) - 1,
        R_y = (integral of p x dA) / (P_applied A R_w),   R_x = (integral of p y dA) / (P_applied A R_w).
    """

    name = "rigid"
    unknowns = ("h0", "attack_angle", "cross_tilt")

    def load(self, applied_pressure: float, radius: float) -> float:
        """Total applied load P_applied pi R_w^2, N."""
        return applied_pressure * np.pi * radius * radius

    def scale(self, sigma: float, radius: float) -> np.ndarray:
        """Scale of the unknowns for trust regions and finite differences: h0 in sigma, tilts in sigma / R_w."""
        return np.array([sigma, sigma / radius, sigma / radius])

    def film(self, problem, u, x, y) -> np.ndarray:
        """Film thickness over a rigid pad at points (x, y), m (eq. 30: dome, tilts, h0)."""
        return film_thickness(x, y, u[0], u[1], problem.dome_height, problem.grid.radius, cross_tilt=u[2])

    def residual(self, problem, p_total) -> np.ndarray:
        """(R_F, R_y, R_x) of a total normal pressure field on the wafer (gauge, Pa)."""
        g = problem.grid
        f = g.integrate(p_total) / problem.load_scale - 1.0
        my = g.integrate(p_total * problem.xc) / (problem.load_scale * g.radius)
        mx = g.integrate(p_total * problem.yc) / (problem.load_scale * g.radius)
        return np.array([f, my, mx])

    def residual_change(self, problem, dp) -> np.ndarray:
        """The change of (R_F, R_y, R_x) under a change dp of the pressure (the residual is affine in p)."""
        return self.residual(problem, dp) + np.array([1.0, 0.0, 0.0])
