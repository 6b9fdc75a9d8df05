"""Closed-form solutions of the free circular Kirchhoff plate, for the tests of :mod:`cmpsim.plate`.

Both satisfy D del^4 w + k w = q on r < a with the free-edge conditions M_r = V_r = 0
(Timoshenko & Woinowsky-Krieger, *Theory of Plates and Shells*, 1959, sections 61-62; Leissa,
*Vibration of Plates*, NASA SP-160, 1969, eq. 2.15 for the conditions on w = f(r) cos n theta):

    f'' + nu (f' / a - n^2 f / a^2) = 0,      (del_n^2 f)' - (1 - nu) n^2 (a f' - f) / a^3 = 0.

* :func:`winkler_bessel_mode`: a plate on a Winkler foundation k under q = q0 J_n(beta r) cos n theta.
  Particular solution q0 J_n(beta r) / (D beta^4 + k); the regular homogeneous solutions are
  the real and imaginary parts of J_n(kappa r), kappa = exp(i pi / 4) / ell, ell = (D / k)^(1/4)
  (the Kelvin functions ber_n, bei_n), since del^4 J_n(kappa r) = kappa^4 J_n = -J_n / ell^4.
  Evaluated with mpmath at 30 digits.
* :func:`free_plate_balanced_load`: a free plate without foundation under the self-balanced load
  q = p0 (1 - 2 r^2 / a^2), a polynomial: w = p0/D (r^4/64 - r^6/(288 a^2)) + C r^2 + c0, C from
  M_r(a) = 0 (V_r = 0 holds because the load has no net force), c0 such that w has no mean.
"""

from __future__ import annotations

import numpy as np

__all__ = ["winkler_bessel_mode", "free_plate_balanced_load"]


def winkler_bessel_mode(r, n: int, beta: float, q0: float, radius: float, bending_stiffness: float, poisson: float, foundation_stiffness: float) -> np.ndarray:
    """Radial factor f(r) (m) of w = f(r) cos n theta for the load q0 J_n(beta r) cos n theta (Pa) on a free plate on a Winkler bed.

    ``r`` in m, ``beta`` in 1/m, ``radius`` a in m, ``bending_stiffness`` D in N m,
    ``foundation_stiffness`` k in Pa/m (> 0).
    """
    import mpmath as mp

    with mp.workdps(30):
        nu, d, k, a, b = (mp.mpf(v) for v in (poisson, bending_stiffness, foundation_stiffness, radius, beta))
        kappa = mp.exp(1j * mp.pi / 4) / (d / k) ** mp.mpf(0.25)

        def j(x):
            return mp.besselj(n, x)

        def jp(x):
            return (mp.besselj(n - 1, x) - mp.besselj(n + 1, x)) / 2

        def jpp(x):  # Bessel's equation
            return -jp(x) / x - (1 - mp.mpf(n) ** 2 / x**2) * j(x)

        def edge(kk, c):  # (M_r, V_r) conditions of c J_n(kk r) at r = a
            f, f1, f2, lap1 = c * j(kk * a), c * kk * jp(kk * a), c * kk**2 * jpp(kk * a), -c * kk**3 * jp(kk * a)
            return f2 + nu * (f1 / a - n**2 * f / a**2), lap1 - (1 - nu) * n**2 * (a * f1 - f) / a**3

        cp = mp.mpf(q0) / (d * b**4 + k)
        mq, vq = edge(b, cp)
        mh, vh = edge(kappa, 1)
        coef = mp.lu_solve(mp.matrix([[mp.re(mh), mp.im(mh)], [mp.re(vh), mp.im(vh)]]), mp.matrix([-mq, -vq]))
        out = []
        for ri in np.asarray(r, dtype=float).ravel():
            h = j(kappa * mp.mpf(ri))
            out.append(float(cp * j(b * mp.mpf(ri)) + coef[0] * mp.re(h) + coef[1] * mp.im(h)))
    return np.array(out).reshape(np.shape(r))


def free_plate_balanced_load(r, p0: float, radius: float, bending_stiffness: float, poisson: float) -> np.ndarray:
    """Deflection w(r) (m, no mean) of a free plate under q = p0 (1 - 2 r^2 / a^2) (Pa), no foundation."""
    a, d, nu = radius, bending_stiffness, poisson
    f1 = a**3 / 16 - a**3 / 48  # f'(a) of f = r^4/64 - r^6/(288 a^2)
    f2 = 3 * a**2 / 16 - 5 * a**2 / 48  # f''(a)
    c = -(p0 / d) * (f2 + nu * f1 / a) / (2 * (1 + nu))  # M_r(a) = 0 with the r^2 term (w'' + nu w'/r = 2C(1 + nu))

    def shape(x):
        return p0 / d * (x**4 / 64 - x**6 / (288 * a**2)) + c * x**2

    # mean over the disk: integral of shape(r) r dr / (a^2 / 2), in closed form
    mean = (p0 / d * (a**6 / 384 - a**6 / 2304) + c * a**4 / 4) / (a**2 / 2)
    return shape(np.asarray(r, dtype=float)) - mean
