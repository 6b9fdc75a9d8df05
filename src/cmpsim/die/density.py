"""Effective pattern density: the layout density averaged by the pad over the planarization length.

The pad does not see the local density of a cell but a weighted average of the density around
it (Stine et al., IEEE TSM 11, 129, 1998: square window; Ouma et al., IEEE TSM 15, 232, 2002:
elliptic weighting function): rho_eff = w * rho, a 2-D convolution done here by FFT. The die is
taken as **periodic**: on the wafer a die is surrounded by copies of itself (step and repeat),
so the density just beyond one edge is that of the opposite edge of the next die.

Two weighting functions, picked by name (:data:`WEIGHTINGS`), both normalised to unit integral:

* ``"gaussian"`` (default): w(r) = exp(-pi r^2 / L^2) / L^2 with L the planarization length.
  Its peak weight and its total weight equal those of Stine's square window of side L (the
  original definition of L), it is positive (rho_eff stays between the extremes of rho) and its
  Fourier transform is exact, exp(-q^2 L^2 / (4 pi)).
* ``"pad"``: the pad stack's own normalised response C(q) / C(0) (top pad bending over the
  subpad, :mod:`cmpsim.die.pad`): the weighting the layered pad model implies, with the
  negative side lobes of a bending plate.
* ``"elliptic"``: Ouma's elliptic weighting (:mod:`cmpsim.die.elliptic`), the deflection of an
  elastic half-space under a uniform disc of diameter L: the convention in which the published
  planarization lengths were fitted.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from .elliptic import EllipticWeighting

__all__ = ["GaussianWeighting", "PadWeighting", "WEIGHTINGS", "wave_numbers", "effective_density"]


def wave_numbers(shape: tuple[int, int], cell_size: float) -> np.ndarray:
    """|q| (rad/m) of the periodic FFT grid of ``shape`` (ny, nx) cells of ``cell_size`` (m)."""
    ny, nx = shape
    qy = 2.0 * np.pi * np.fft.fftfreq(ny, d=cell_size)
    qx = 2.0 * np.pi * np.fft.rfftfreq(nx, d=cell_size)
    return np.hypot(qy[:, None], qx[None, :])


@dataclass(frozen=True)
class GaussianWeighting:
    """Gaussian weighting of planarization length L (m): w(r) = exp(-pi r^2/L^2)/L^2, unit integral."""

    length: float

    def __post_init__(self) -> None:
        if not (np.isfinite(self.length) and self.length > 0):
            raise ValueError(f"planarization_length must be > 0 m; got {self.length!r}")

    def transfer(self, q):
        """Fourier transform of the weighting at wave number q (rad/m); 1 at q = 0."""
        q = np.asarray(q, dtype=float)
        return np.exp(-(q * self.length) ** 2 / (4.0 * np.pi))

    def weight(self, r):
        """w(r), 1/m^2."""
        r = np.asarray(r, dtype=float)
        return np.exp(-np.pi * (r / self.length) ** 2) / self.length**2


@dataclass(frozen=True)
class PadWeighting:
    """The pad stack's normalised compliance C(q)/C(0) as the weighting (``foundation``: a LayeredFoundation)."""

    foundation: object
    length: float  # the planarization length quoted for it (m), see cmpsim.die.pad

    def transfer(self, q):
        """C(q) / C(0) of the pad stack at wave number q (rad/m)."""
        q = np.asarray(q, dtype=float)
        c0 = float(self.foundation.compliance(np.array([0.0]))[0])
        return self.foundation.compliance(q) / c0


#: The weighting functions by name.
WEIGHTINGS = {"gaussian": GaussianWeighting, "pad": PadWeighting, "elliptic": EllipticWeighting}


def effective_density(density, cell_size: float, weighting) -> np.ndarray:
    """rho_eff = w * rho on the periodic die (FFT); ``density`` (ny, nx) in [0, 1], ``cell_size`` in m."""
    rho = np.asarray(density, dtype=float)
    if hasattr(weighting, "grid_transfer"):  # a kernel sampled on the die's cells (elliptic)
        transfer = weighting.grid_transfer(rho.shape, cell_size)
    else:
        transfer = weighting.transfer(wave_numbers(rho.shape, cell_size))
    out = np.fft.irfft2(np.fft.rfft2(rho) * transfer, s=rho.shape)
    return out
