"""Heat conduction in closed form, for the pad's temperature (issue 32): pure kernels, SI units.

The thermal properties of a body (effusivity, diffusivity, the Maxwell-Eucken conductivity of a
porous pad), the share of the frictional heat that enters the pad (the effusivity partition of
Blok 1937 and Jaeger 1942), and the closed forms the pad's column of :mod:`cmpsim.physics.thermal`
is verified against (Carslaw & Jaeger, Conduction of Heat in Solids, 2nd ed., 1959):

* semi-infinite body, constant surface flux (section 2.9):  T - T0 = 2 q sqrt(t / (pi k rho c));
* the same with surface loss h (section 2.7):  T - T0 = (q/h) [1 - exp(b^2) erfc(b)], b = h sqrt(alpha t)/k;
* slab 0 < x < L, flux at one face, the other adiabatic (section 3.3, eq. (3));
* a lumped capacity C behind a conductance H:  T - T0 = (q/H) (1 - exp(-H t / C)).
"""

from __future__ import annotations

import math

import numpy as np
from scipy.special import erfcx

__all__ = [
    "effusivity",
    "diffusivity",
    "maxwell_eucken",
    "partition_coefficient",
    "semi_infinite_rise",
    "semi_infinite_rise_convective",
    "slab_rise",
    "lumped_rise",
]


def effusivity(conductivity, density, heat_capacity):
    """Thermal effusivity e = sqrt(k rho c), W s^(1/2) / (m^2 K)."""
    return np.sqrt(np.asarray(conductivity) * np.asarray(density) * np.asarray(heat_capacity))


def diffusivity(conductivity, density, heat_capacity):
    """Thermal diffusivity alpha = k / (rho c), m^2/s."""
    return np.asarray(conductivity) / (np.asarray(density) * np.asarray(heat_capacity))


def maxwell_eucken(matrix_conductivity, inclusion_conductivity, inclusion_fraction):
    """Conductivity of a matrix with dispersed spherical inclusions (Maxwell–Eucken), W/(m K).

    k = k_m [2 k_m + k_d - 2 phi (k_m - k_d)] / [2 k_m + k_d + phi (k_m - k_d)] (Maxwell 1873;
    Eucken 1940; the lower bound of Hashin–Shtrikman when k_d < k_m, the upper when k_d > k_m).
    """
    km = np.asarray(matrix_conductivity, dtype=float)
    kd = np.asarray(inclusion_conductivity, dtype=float)
    phi = np.asarray(inclusion_fraction, dtype=float)
    return km * (2 * km + kd - 2 * phi * (km - kd)) / (2 * km + kd + phi * (km - kd))


def partition_coefficient(pad_effusivity, counter_effusivity, duty=1.0):
    """Share of the interface heat that enters the pad, e_p / (e_p + f e_c), dimensionless.

    Two semi-infinite bodies in perfect contact, heated at the interface from the same initial
    temperature, share the heat in the ratio of their effusivities (Blok 1937; Jaeger 1942). A
    pad point spends the share ``duty`` f of the time under the wafer while the counter-body
    (wafer/carrier) is heated all the time: the pad's track-averaged flux f q_p and the counter's
    q_c give the same surface temperature when q_p / q = e_p / (e_p + f e_c) (eq. P3 of
    ``docs/polisher.md``). With f = 1 it is the classical stationary partition.
    """
    ep = np.asarray(pad_effusivity, dtype=float)
    ec = np.asarray(counter_effusivity, dtype=float)
    return ep / (ep + np.asarray(duty, dtype=float) * ec)


def semi_infinite_rise(heat_flux, time, conductivity, density, heat_capacity):
    """Surface temperature rise of a semi-infinite body under a constant surface flux, K.

    T(0, t) - T0 = 2 q sqrt(t / (pi k rho c)) (Carslaw & Jaeger 1959, section 2.9, eq. (6) at
    x = 0). ``heat_flux`` q in W/m^2, ``time`` t in s.
    """
    q = np.asarray(heat_flux, dtype=float)
    t = np.asarray(time, dtype=float)
    return 2.0 * q * np.sqrt(t / (np.pi * conductivity * density * heat_capacity))


def semi_infinite_rise_convective(heat_flux, film_coefficient, time, conductivity, density, heat_capacity):
    """Surface rise of a semi-infinite body under flux q with surface loss h to T0, K.

    T(0, t) - T0 = (q/h) [1 - exp(b^2) erfc(b)], b = h sqrt(alpha t) / k (Carslaw & Jaeger 1959,
    section 2.7, eq. (9) at x = 0 with the flux in place of the ambient step); -> q/h as t -> inf
    and -> 2 q sqrt(t/(pi k rho c)) as h -> 0. Evaluated with erfcx (no overflow).
    """
    q = np.asarray(heat_flux, dtype=float)
    h = np.asarray(film_coefficient, dtype=float)
    t = np.asarray(time, dtype=float)
    b = h * np.sqrt(conductivity / (density * heat_capacity) * t) / conductivity
    sp = math.sqrt(math.pi)
    series = 2 * b / sp - b**2 + 4 * b**3 / (3 * sp) - b**4 / 2  # 1 - erfcx(b) for small b (no cancellation)
    return q / h * np.where(b < 1e-3, series, 1.0 - erfcx(np.maximum(b, 1e-3)))


def slab_rise(heat_flux, time, thickness, conductivity, density, heat_capacity, terms=200):
    """Heated-face rise of a slab under a constant flux, the other face adiabatic, K.

    T(face) - T0 = q t/(rho c L) + q L/(3k) - (2 q L/(k pi^2)) sum_{n>=1} exp(-alpha n^2 pi^2 t/L^2)/n^2
    (Carslaw & Jaeger 1959, section 3.3, eq. (3) at the heated face). ``terms`` terms of the sum;
    the tail left out is below 2 q L/(k pi^2 terms).
    """
    q = np.asarray(heat_flux, dtype=float)
    t = np.asarray(time, dtype=float)[..., None]
    n = np.arange(1, terms + 1)
    alpha = conductivity / (density * heat_capacity)
    tail = np.sum(np.exp(-alpha * (n * np.pi / thickness) ** 2 * t) / n**2, axis=-1)
    tt = t[..., 0]
    return q * tt / (density * heat_capacity * thickness) + q * thickness / conductivity * (1.0 / 3.0 - 2.0 / np.pi**2 * tail)


def lumped_rise(heat_flux, conductance, capacity, time):
    """Lumped body (uniform temperature) under flux q with loss H to T0: (q/H)(1 - exp(-t H/C)), K.

    ``conductance`` H in W/(m^2 K), ``capacity`` C in J/(m^2 K); time constant C/H. The limit of
    a pad column whose Biot number H L / k is small.
    """
    q = np.asarray(heat_flux, dtype=float)
    return q / conductance * -np.expm1(-np.asarray(time, dtype=float) * conductance / capacity)
