"""Haff grain-flow kernels: granular constitutive laws and the grain-size coefficients.

Everything here is a pure, vectorised function of numpy arrays in SI units.

The grain-flow function Psi and the grain-size coefficients f and g of the paper
(eq. 6, 7, 18, 19) are written in terms of the damping-length ratio
``x = sqrt(w/k) * h/d``. With ``R1 = 2 sinh x`` and ``R2 = 2 cosh x`` (eq. 7) they reduce to

    Psi = sqrt(k/w) * tanh(x/2)
    f   = 2 + x / sinh x
    g   = 1 + 2 x / sinh x - x**2 / (4 cosh**2(x/2))

(see ``docs/model.md`` for the algebra). These forms are evaluated with ``exp(-x)`` only,
so they neither overflow for large x nor lose digits to cancellation for small x.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

__all__ = [
    "GrainFlow",
    "damping_ratio",
    "grain_coefficients",
    "granular_pressure",
    "granular_viscosity",
]


def _check_positive(name: str, value: np.ndarray) -> None:
    if not np.all(np.isfinite(value)) or np.any(value <= 0):
        raise ValueError(f"{name} must be finite and > 0 (valid range: (0, inf)); got {value!r}")


def damping_ratio(h_over_d, w_over_k):
    """Haff's damping-length ratio ``x = sqrt(w/k) * h/d`` (argument of eq. 7), dimensionless."""
    h_over_d = np.asarray(h_over_d, dtype=float)
    w_over_k = np.asarray(w_over_k, dtype=float)
    _check_positive("h_over_d", h_over_d)
    _check_positive("w_over_k", w_over_k)
    return np.sqrt(w_over_k) * h_over_d


#: Above this x every e^-x term of f and g is below 1e-296 and is dropped (no underflow).
_X_FAR = 700.0


def _x_over_sinh(x: np.ndarray) -> np.ndarray:
    """x / sinh(x) = 2 x e^-x / (1 - e^-2x), stable for x in (0, inf).

    Capped at its supremum 1, which the rounded quotient exceeds by an ulp for x < 1e-4
    (that ulp pushed f and g above their bound 3).
    """
    return np.minimum(2.0 * x * np.exp(-x) / (-np.expm1(-2.0 * x)), 1.0)


def grain_coefficients(h_over_d, w_over_k):
    """Grain-flow function Psi and grain-size coefficients f, g (paper eq. 6, 7, 18, 19).

    Parameters
    ----------
    h_over_d : array_like
        Film-particle ratio H_p = h/d (film thickness over particle diameter), > 0, dimensionless.
    w_over_k : array_like
        Ratio of Haff's dissipation constant w = 1 - e**2 to his conductivity constant k, > 0,
        dimensionless (paper base case 4e-6, see ``docs/model.md`` on w/k vs k/w).

    Returns
    -------
    psi, f, g : numpy.ndarray
        Psi (eq. 6, dimensionless; tends to h/(2d) as x -> 0), f (eq. 18; 3 at x -> 0, 2 at
        x -> inf) and g (eq. 19; 3 at x -> 0, 1 at x -> inf), broadcast to a common shape.

    Raises
    ------
    ValueError
        If an argument is not finite and strictly positive.
    """
    x = damping_ratio(h_over_d, w_over_k)
    w_over_k = np.asarray(w_over_k, dtype=float)
    psi = np.tanh(0.5 * x) / np.sqrt(w_over_k)
    # Beyond _X_FAR the e^-x terms are < 1e-296 (f = 2, g = 1 to the last bit): drop them
    # there instead of letting exp(-x) underflow (and x*x overflow for x > 1e154).
    far = x > _X_FAR
    xn = np.where(far, 1.0, x)
    em = np.exp(-xn)
    xs = np.where(far, 0.0, _x_over_sinh(xn))
    f = 2.0 + xs
    # x^2 / (4 cosh^2(x/2)) = x^2 e^-x / (1 + e^-x)^2
    g = 1.0 + 2.0 * xs - np.where(far, 0.0, xn * xn * em / (1.0 + em) ** 2)
    psi, f, g = np.broadcast_arrays(psi, f, g)
    return psi.copy(), f.copy(), g.copy()


def granular_pressure(bulk_density, separation_ratio, fluctuation_velocity, *, t=1.0):
    """Haff granular pressure ``p = t d rho v^2 / s = t rho (d/s) v^2`` (eq. 1), in Pa.

    ``bulk_density`` rho in kg/m^3; ``separation_ratio`` d/s, the particle diameter over the
    mean gap between grains (dimensionless): the diameter enters only through it;
    ``fluctuation_velocity`` v in m/s; ``t`` Haff's pressure constant (keyword).
    """
    return t * np.asarray(bulk_density) * np.asarray(separation_ratio) * np.asarray(fluctuation_velocity) ** 2


def granular_viscosity(pressure, particle_diameter, fluctuation_velocity, t_over_a=1.0):
    """Haff granular viscosity ``eta = a d^2 rho v / s = (a/t) p d / v`` (eq. 1), in Pa s."""
    return np.asarray(pressure) * np.asarray(particle_diameter) / (t_over_a * np.asarray(fluctuation_velocity))


@dataclass(frozen=True)
class GrainFlow:
    """Haff's granular fluid of one slurry (Haff, J. Fluid Mech. 134, 401 (1983), doi:10.1017/S0022112083003419).

    Its constants, and its laws as methods: :meth:`pressure` and :meth:`viscosity` (eq. 1),
    :meth:`coefficients` (Psi, f, g of eq. 6, 7, 18, 19).

    Attributes
    ----------
    particle_diameter : float
        d, m.
    w_over_k : float
        Haff's dissipation over conductivity constant w/k, dimensionless.
    t_over_a : float
        Haff's pressure over viscosity constant t/a, dimensionless.
    fluctuation_velocity : float
        Granular fluctuation velocity v, m/s.
    """

    particle_diameter: float
    w_over_k: float
    t_over_a: float
    fluctuation_velocity: float

    def pressure(self, bulk_density, separation_ratio, t: float = 1.0):
        """Granular pressure p = t rho (d/s) v^2 at bulk density rho and d/s (eq. 1), Pa."""
        return granular_pressure(bulk_density, separation_ratio, self.fluctuation_velocity, t=t)

    def viscosity(self, pressure):
        """Granular viscosity eta = (a/t) p d / v at absolute granular pressure p (eq. 1), Pa s."""
        return granular_viscosity(pressure, self.particle_diameter, self.fluctuation_velocity, self.t_over_a)

    def coefficients(self, h):
        """Psi, f, g (eq. 6, 18, 19) at film thickness h (m): :func:`grain_coefficients` of h/d."""
        return grain_coefficients(np.asarray(h) / self.particle_diameter, self.w_over_k)
