"""Ouma's elliptic weighting: the surface deflection of an elastic half-space under a uniform disc load.

Ouma (PhD thesis, MIT, 1998, eqs. 5.11-5.15; Ouma et al., IEEE TSM 15, 232, 2002) weights the
layout density by the deflection of an elastic half-space under a uniform pressure q on a disc
of radius a (Timoshenko & Goodier, *Theory of Elasticity*, 1951, section 126; Johnson, *Contact
Mechanics*, 1985, eq. 3.34). With E* = E / (1 - nu^2) and the complete elliptic integrals
K(m), E(m) of parameter m = k^2 (scipy's convention):

    r <= a:   w(r) = (4 q a / (pi E*)) E((r/a)^2),
    r >  a:   w(r) = (4 q r / (pi E*)) [E((a/r)^2) - (1 - (a/r)^2) K((a/r)^2)],

so w(0) = 2 q a / E* and w(a) = 4 q a / (pi E*): the weight falls to 2/pi of its peak at the
edge of the loaded disc, and the planarization length of this convention is the disc's diameter,
L = 2a. Outside, w decays as (q a^2 / E*) / r, the point-load (Boussinesq) tail, whose integral
over the plane diverges: the weighting has to be truncated to be normalised.

**Truncation (a choice; Ouma's was not read).** The kernel is cut at r_t = ``truncation`` x a and
normalised to unit integral over that disc. The default, ``truncation = 1`` (the deflection
under the load only), is the one nearest to the only evidence on Ouma's convention that we have:
his Table 5.3 (one data set, read second-hand) fits square 5.25, cylinder 5.85, elliptic 7.35 mm,
elliptic / square = 1.40; fitted to the same smoothing, our square and cylinder windows give
cylinder / square = 1.14 (his 1.11), and our elliptic kernel gives elliptic / square = 1.19 cut at
r = a, 0.87 at 1.5 a, 0.69 at 2 a, 0.49 at 3 a: a longer tail smooths more, so it needs a shorter L
and moves further from his ratio. docs/model.md section 18.2 gives the numbers.

The weighting on a die is the kernel averaged over each cell (``SUBSAMPLES`` x ``SUBSAMPLES``
points per cell), summed over the periodic images of the die (the die repeats on the wafer) and
normalised to unit sum: the mean density is kept to round-off and rho_eff stays between the
extremes of rho (the kernel is positive).
"""

from __future__ import annotations

from dataclasses import dataclass
from functools import lru_cache

import numpy as np
from scipy.integrate import quad
from scipy.optimize import brentq
from scipy.special import ellipe, ellipk, j0

from .pad import half_power_wave_number, pad_stack

__all__ = ["EllipticWeighting", "elliptic_profile", "elliptic_half_power", "planarization_length_elliptic_from_pad",
           "DEFAULT_TRUNCATION", "SUBSAMPLES"]

#: r_t / a of the default elliptic weighting (see the module docstring).
DEFAULT_TRUNCATION = 1.0
#: Points per cell and direction at which the kernel is averaged over a cell.
SUBSAMPLES = 3


def elliptic_profile(rho):
    """w(r) / w(0) of the half-space under a uniform disc load, at rho = r / a (1 at 0, 2/pi at 1, ~ 1/(2 rho) far out)."""
    rho = np.asarray(rho, dtype=float)
    out = np.empty_like(rho)
    inside = rho <= 1.0
    out[inside] = (2.0 / np.pi) * ellipe(rho[inside] ** 2)
    m = 1.0 / rho[~inside] ** 2
    out[~inside] = (2.0 / np.pi) * rho[~inside] * (ellipe(m) - (1.0 - m) * ellipk(m))
    return out


@lru_cache(maxsize=64)
def _radial_integral(truncation: float) -> float:
    """int_0^c f(rho) rho drho (f = elliptic_profile, c = truncation)."""
    f = lambda x: float(elliptic_profile(np.array([x]))[0]) * x  # noqa: E731
    inner = quad(f, 0.0, 1.0, epsabs=0, epsrel=1e-13, limit=200)[0]
    outer = quad(f, 1.0, truncation, epsabs=0, epsrel=1e-13, limit=200)[0] if truncation > 1.0 else 0.0
    return inner + outer


@dataclass(frozen=True)
class EllipticWeighting:
    """Ouma's elliptic weighting of planarization length L = 2a (m), cut at ``truncation`` x a, unit integral."""

    length: float
    truncation: float = DEFAULT_TRUNCATION

    def __post_init__(self) -> None:
        if not (np.isfinite(self.length) and self.length > 0):
            raise ValueError(f"planarization_length must be > 0 m; got {self.length!r}")
        if not (np.isfinite(self.truncation) and 1.0 <= self.truncation <= 100.0):
            raise ValueError(f"the elliptic weighting's truncation r_t / a must lie in [1, 100]; got {self.truncation!r}")

    @property
    def radius(self) -> float:
        """a = L / 2, the radius of the loaded disc (m)."""
        return 0.5 * self.length

    @property
    def normalisation(self) -> float:
        """int w_raw dA over r <= r_t, with w_raw = elliptic_profile(r / a) (m^2)."""
        return 2.0 * np.pi * self.radius**2 * _radial_integral(float(self.truncation))

    def weight(self, r):
        """w(r) (1/m^2): unit integral over the plane, zero beyond r_t."""
        rho = np.asarray(r, dtype=float) / self.radius
        return np.where(rho <= self.truncation, elliptic_profile(rho), 0.0) / self.normalisation

    def transfer(self, q):
        """Hankel transform 2 pi int w(r) J0(q r) r dr (1 at q = 0), by adaptive quadrature (slow: for scalars and tests)."""
        q = np.atleast_1d(np.asarray(q, dtype=float))
        a, c = self.radius, float(self.truncation)
        out = np.empty_like(q)
        for i, qi in enumerate(q):
            g = lambda x: float(elliptic_profile(np.array([x]))[0]) * x * j0(qi * a * x)  # noqa: E731
            lim = 200 + int(qi * a * c)
            val = quad(g, 0.0, 1.0, epsabs=0, epsrel=1e-12, limit=lim)[0]
            if c > 1.0:
                val += quad(g, 1.0, c, epsabs=0, epsrel=1e-12, limit=lim)[0]
            out[i] = val / _radial_integral(c)
        return out

    def grid_transfer(self, shape: tuple[int, int], cell_size: float) -> np.ndarray:
        """The rfft2 of the cell-averaged, periodically wrapped, unit-sum kernel on a die of ``shape`` cells."""
        ny, nx = shape
        py, px = ny * cell_size, nx * cell_size
        rt = self.truncation * self.radius
        sub = (np.arange(SUBSAMPLES) + 0.5) / SUBSAMPLES - 0.5
        # offsets of the cell centres from the kernel centre at cell (0, 0), wrapped into one period
        dx = (np.arange(nx) * cell_size + 0.5 * px) % px - 0.5 * px
        dy = (np.arange(ny) * cell_size + 0.5 * py) % py - 0.5 * py
        kern = np.zeros(shape)
        mx = int(np.ceil((rt + cell_size) / px))
        my = int(np.ceil((rt + cell_size) / py))
        for iy in range(-my, my + 1):
            for ix in range(-mx, mx + 1):
                yy = dy + iy * py
                xx = dx + ix * px
                if np.min(np.abs(yy)) > rt + cell_size or np.min(np.abs(xx)) > rt + cell_size:
                    continue
                for sy in sub:
                    for sx in sub:
                        r = np.hypot((yy + sy * cell_size)[:, None], (xx + sx * cell_size)[None, :])
                        kern += self.weight(r)
        kern /= kern.sum()
        return np.fft.rfft2(kern)


@lru_cache(maxsize=64)
def elliptic_half_power(truncation: float = DEFAULT_TRUNCATION) -> float:
    """q_half L of the elliptic weighting: the wave number x L at which its transfer falls to 1/2."""
    w = EllipticWeighting(1.0, truncation)
    return float(brentq(lambda q: float(w.transfer(q)[0]) - 0.5, 0.05, 5.0 / w.radius, xtol=1e-12, rtol=1e-12))


def planarization_length_elliptic_from_pad(config, truncation: float = DEFAULT_TRUNCATION) -> float:
    """Planarization length (m) of the elliptic weighting implied by the pad stack of ``config``.

    The same half-power argument as the Gaussian's (:mod:`cmpsim.die.pad`): L is chosen so that
    the elliptic weighting passes half its power at the wave number where the pad stack's
    compliance has halved, L = (q_half L)_elliptic / q_half(pad).
    """
    return elliptic_half_power(float(truncation)) / half_power_wave_number(pad_stack(config))
