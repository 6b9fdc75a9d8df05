"""Reference solutions for verifying the Newtonian lubrication and cavitation solvers.

Analytic and semi-analytic (closed-form integrals plus a scalar root) solutions of the
one-dimensional Reynolds equation for a plane (linear-film) slider, with one surface moving
at speed U over a stationary one (mean velocity U/2), viscosity eta, and ambient (gauge
zero) pressure at both ends x = 0 and x = L:

    d/dx( h^3/(12 eta) dp/dx ) = (U/2) dh/dx,    h(x) = h_1 + (h_2 - h_1) x / L.

- :func:`plane_slider_pressure`, :func:`plane_slider_load`: the classical converging slider
  (Hamrock, *Fundamentals of Fluid Film Lubrication*, McGraw-Hill 1994, ch. 8, the
  fixed-incline slider: P = 6 m X (1 - X) / ((2 + m)(1 + m - m X)^2),
  W = 6/m^2 [ln(1 + m) - 2m/(2 + m)], m = h_i/h_o - 1).
- :func:`linear_film_pressure`: the same in the general form of any slope sign (full
  Sommerfeld); :func:`gumbel_load`: its Gumbel (half-Sommerfeld for p_cav = 0) load.
- :func:`jfo_diverging_slider`: the mass-conserving (JFO) solution of a diverging slider,
  whose full-Sommerfeld pressure falls below p_cav: full film from the inlet to the rupture
  point x_c (p = p_cav and dp/dx = 0 there, so the flux is Q = U h(x_c)/2), a cavitated zone
  of fill fraction theta = h(x_c)/h(x) up to the reformation point x_r, and a full film from
  x_r (p = p_cav) to the outlet (p = 0) carrying the same flux Q.
- :func:`strip_problem`: the one-dimensional analogue of the wafer discretisation (the same
  face-coefficient kernel :func:`cmpsim.operators.reynolds.lubrication_coefficients`, two-point
  fluxes, Dirichlet ends half a cell from the last centres, upwinded fill fraction), so that
  the complementarity solver can be compared with the references above.

Used by the tests only; nothing in the solver depends on this module.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import scipy.sparse as sp
from scipy.integrate import quad
from scipy.optimize import brentq

from ..operators.reynolds import LubricationParameters, lubrication_coefficients

__all__ = [
    "plane_slider_pressure",
    "plane_slider_load",
    "linear_film_pressure",
    "gumbel_load",
    "JFOSlider",
    "jfo_diverging_slider",
    "StripProblem",
    "strip_problem",
]


def plane_slider_pressure(x, length, h_inlet, h_outlet, viscosity, speed):
    """Pressure of the converging plane slider (Hamrock ch. 8), Pa.

    ``x`` from the inlet (m, 0..length), film h_inlet at x = 0 falling linearly to h_outlet
    (m), ``viscosity`` (Pa s), ``speed`` U of the moving surface (m/s, towards the outlet).
    """
    m = h_inlet / h_outlet - 1.0
    X = np.asarray(x, dtype=float) / length
    P = 6.0 * m * X * (1.0 - X) / ((2.0 + m) * (1.0 + m - m * X) ** 2)
    return P * viscosity * speed * length / h_outlet**2


def plane_slider_load(length, h_inlet, h_outlet, viscosity, speed):
    """Load per unit width of the converging plane slider (Hamrock ch. 8), N/m."""
    m = h_inlet / h_outlet - 1.0
    W = 6.0 / m**2 * (np.log1p(m) - 2.0 * m / (2.0 + m))
    return W * viscosity * speed * length**2 / h_outlet**2


def _integrals(h1, s, a, b):
    """(int_a^b dx/h^2, int_a^b dx/h^3) for h = h1 + s x."""
    ha, hb = h1 + s * a, h1 + s * b
    return (1.0 / ha - 1.0 / hb) / s, 0.5 * (1.0 / ha**2 - 1.0 / hb**2) / s


def linear_film_pressure(x, length, h1, h2, viscosity, speed):
    """Full-Sommerfeld pressure of a linear film h1 -> h2 (either slope sign), p = 0 at both ends, Pa.

    p(x) = 12 eta [(U/2) int_0^x dx/h^2 - Q int_0^x dx/h^3], Q = (U/2) I2(0, L) / I3(0, L).
    """
    s = (h2 - h1) / length
    i2, i3 = _integrals(h1, s, 0.0, length)
    q = 0.5 * speed * i2 / i3
    x = np.asarray(x, dtype=float)
    j2, j3 = _integrals(h1, s, 0.0, x)
    return 12.0 * viscosity * (0.5 * speed * j2 - q * j3)


def gumbel_load(length, h1, h2, viscosity, speed, p_cav):
    """Load per unit width of max(p, p_cav) with the full-Sommerfeld p of a linear film, N/m."""
    s = (h2 - h1) / length
    i2, i3 = _integrals(h1, s, 0.0, length)
    h_m = 2.0 * (0.5 * speed * i2 / i3) / speed  # film where dp/dx = 0 (pressure extremum)
    x_m = (h_m - h1) / s

    def p(x):
        return float(linear_film_pressure(x, length, h1, h2, viscosity, speed)) - p_cav

    if p(x_m) >= 0:  # the pressure never falls below p_cav
        return quad(lambda x: p(x) + p_cav, 0.0, length, epsabs=0, epsrel=1e-13, limit=200)[0]
    a = brentq(p, 0.0, x_m, xtol=1e-15 * length, rtol=1e-15)
    b = brentq(p, x_m, length, xtol=1e-15 * length, rtol=1e-15)
    left = quad(lambda x: p(x) + p_cav, 0.0, a, epsabs=0, epsrel=1e-13, limit=200)[0]
    right = quad(lambda x: p(x) + p_cav, b, length, epsabs=0, epsrel=1e-13, limit=200)[0]
    return left + p_cav * (b - a) + right


@dataclass(frozen=True)
class JFOSlider:
    """JFO solution of the diverging plane slider (see :func:`jfo_diverging_slider`)."""

    length: float
    h1: float
    h2: float
    viscosity: float
    speed: float
    p_cav: float
    rupture: float  # x_c, m
    reformation: float  # x_r, m
    flux: float  # Q = U h(x_c) / 2, m^2/s

    def film(self, x):
        return self.h1 + (self.h2 - self.h1) * np.asarray(x, dtype=float) / self.length

    def pressure(self, x):
        """p(x), Pa: full film before x_c and after x_r, p_cav between."""
        x = np.asarray(x, dtype=float)
        s = (self.h2 - self.h1) / self.length
        j2, j3 = _integrals(self.h1, s, 0.0, x)
        first = 12.0 * self.viscosity * (0.5 * self.speed * j2 - self.flux * j3)
        k2, k3 = _integrals(self.h1, s, self.reformation, x)
        last = self.p_cav + 12.0 * self.viscosity * (0.5 * self.speed * k2 - self.flux * k3)
        return np.where(x <= self.rupture, first, np.where(x < self.reformation, self.p_cav, last))

    def fill_fraction(self, x):
        """theta(x): h(x_c)/h(x) in the cavitated zone, 1 elsewhere."""
        x = np.asarray(x, dtype=float)
        cav = (x > self.rupture) & (x < self.reformation)
        return np.where(cav, 2.0 * self.flux / (self.speed * self.film(x)), 1.0)

    def load(self) -> float:
        """Integral of p over the slider, N/m (closed form per zone)."""
        s = (self.h2 - self.h1) / self.length
        eta, u, q, h1 = self.viscosity, self.speed, self.flux, self.h1

        def full(a, b, p_a):
            # int_a^b [p_a + 12 eta ((U/2) int_a^x h^-2 - Q int_a^x h^-3)] dx with h = h1 + s x
            ha = h1 + s * a
            ln = np.log((h1 + s * b) / ha)
            hb = h1 + s * b
            k2 = ((b - a) / ha - ln / s) / s  # int_a^b int_a^x h^-2
            k3 = 0.5 * ((b - a) / ha**2 - (1.0 / ha - 1.0 / hb) / s) / s  # int_a^b int_a^x h^-3
            return p_a * (b - a) + 12.0 * eta * (0.5 * u * k2 - q * k3)

        return full(0.0, self.rupture, 0.0) + self.p_cav * (self.reformation - self.rupture) + full(self.reformation, self.length, self.p_cav)


def jfo_diverging_slider(length, h1, h2, viscosity, speed, p_cav) -> JFOSlider:
    """Mass-conserving (JFO) solution of a diverging plane slider h1 < h2 with p = 0 at both ends.

    Rupture x_c: 12 eta [(U/2) I2(0, x_c) - (U h(x_c)/2) I3(0, x_c)] = p_cav (p = p_cav and
    dp/dx = 0). Reformation x_r: 12 eta [(U/2) I2(x_r, L) - Q I3(x_r, L)] = -p_cav. Both by
    Brent's method on closed-form integrals. Raises ValueError if the full-Sommerfeld
    pressure does not reach p_cav (nothing cavitates).
    """
    if not h2 > h1:
        raise ValueError("the JFO reference is for a diverging slider (h2 > h1)")
    s = (h2 - h1) / length

    def rupture(x):
        i2, i3 = _integrals(h1, s, 0.0, x)
        return 12.0 * viscosity * (0.5 * speed * i2 - 0.5 * speed * (h1 + s * x) * i3) - p_cav

    if rupture(length) > 0:
        raise ValueError("the pressure does not reach p_cav: nothing cavitates")
    x_c = brentq(rupture, 1e-12 * length, length, xtol=1e-15 * length, rtol=1e-15)
    q = 0.5 * speed * (h1 + s * x_c)

    def reform(x):
        i2, i3 = _integrals(h1, s, x, length)
        return 12.0 * viscosity * (0.5 * speed * i2 - q * i3) + p_cav

    x_r = brentq(reform, x_c, length * (1 - 1e-14), xtol=1e-15 * length, rtol=1e-15)
    return JFOSlider(length, h1, h2, viscosity, speed, p_cav, x_c, x_r, q)


@dataclass
class StripProblem:
    """The discrete 1-D slider: diffusion A (per Pa), upwinded Couette matrix B and edge term c
    (B theta + c = net outward Couette flux), the full-film right-hand side b = -(B 1 + c),
    cell centres x and width dx (m)."""

    x: np.ndarray
    dx: float
    A: sp.csr_matrix
    B: sp.csr_matrix
    c: np.ndarray
    rhs: np.ndarray


def strip_problem(n: int, length: float, h1: float, h2: float, params: LubricationParameters) -> StripProblem:
    """1-D finite volumes of the Newtonian slider on n cells, with the wafer solver's kernels.

    ``params`` must be Newtonian with ``kinematics.mode == "sliding"`` (the pad moves in +x
    at U under a still wafer); the face coefficients come from
    :func:`cmpsim.operators.reynolds.lubrication_coefficients` at the n + 1 faces.
    """
    dx = length / n
    xf = np.arange(n + 1) * dx
    hf = h1 + (h2 - h1) * xf / length
    dxx, _, _, qx, _, _ = lubrication_coefficients(hf, xf, np.zeros_like(xf), params)
    a = dxx / dx
    a[0] *= 2.0  # Dirichlet ends half a cell from the centres
    a[-1] *= 2.0
    i = np.arange(n)
    A = sp.diags(a[:-1] + a[1:]) - sp.diags(a[1:-1], 1) - sp.diags(a[1:-1], -1)
    rows, cols, vals = [], [], []
    for k in range(1, n):  # interior face between cells k-1 and k; flux qx[k] in +x
        up = k - 1 if qx[k] > 0 else k
        rows += [k - 1, k]
        cols += [up, up]
        vals += [qx[k], -qx[k]]
    c = np.zeros(n)
    for cell, out in ((0, -qx[0]), (n - 1, qx[n])):  # outward Couette flux through the ends
        if out > 0:
            rows.append(cell)
            cols.append(cell)
            vals.append(out)
        else:
            c[cell] += out
    B = sp.csr_matrix((vals, (rows, cols)), shape=(n, n))
    rhs = -(qx[1:] - qx[:-1])
    return StripProblem((i + 0.5) * dx, dx, A.tocsr(), B, c, rhs)
