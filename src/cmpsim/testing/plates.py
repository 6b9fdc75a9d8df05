"""Closed-form solutions of the free circular Kirchhoff plate, for the tests of :mod:`cmpsim.numerics.plate`.

Both satisfy D del^4 w + k w = q on r < a with the free-edge conditions M_r = V_r = 0
(Timoshenko & Woinowsky-Krieger, *Theory of Plates and Shells*, 1959, sections 61-62; Leissa,
*Vibration of Plates*, NASA SP-160, 1969, eq. 2.15 for the conditions on w = f(r) cos n theta):

    f'' + nu (f' / a - n^2 f / a^2) = 0,      (del_n^2 f)' - (1 - nu) n^2 (a f' - f) / a^3 = 0.

* :func:`winkler_bessel_mode`: a plate on a Winkler foundation k under q = q0 J_n(beta r) cos n theta.
  Particular solution q0 J_n(beta r) / (D beta^4 + k); the regular homogeneous solutions are
  the real and imaginary parts of J_n(kappa r), kappa = exp(i pi / 4) / ell, ell = (D / k)^(1/4)
  (the Kelvin functions ber_n, bei_n), since del^4 J_n(kappa r) = kappa^4 J_n = -J_n / ell^4.
  Evaluated with mpmath at 30 digits.
* :func:`winkler_step_load`: a plate on a Winkler foundation k under the axisymmetric step load q on
  r < b (a membrane zone, or every zone inside a boundary, raised by q): the circular-plate form of
  Hetenyi's beam under a load on a half-line (M. Hetenyi, *Beams on Elastic Foundation*, 1946;
  Timoshenko & Woinowsky-Krieger, ch. 8, for plates on a foundation). w = q/k + c J_0(kappa r) for
  r < b, c1 J_0(kappa r) + c2 Y_0(kappa r) for b < r < a (real parts, complex c: the Kelvin
  functions ber, bei, ker, kei); w, w', del^2 w and (del^2 w)' continuous at b (the load jumps,
  the plate's shear does not), M_r = V_r = 0 at a. Far from both b and a the foundation pressure
  k w falls across b as Hetenyi's 1 - exp(-lambda x) cos(lambda x) / 2, lambda = 1/(sqrt(2) ell),
  whose 10-90 % width is :func:`hetenyi_step_width`. Evaluated with mpmath at 30 digits.
* :func:`free_plate_balanced_load`: a free plate without foundation under the self-balanced load
  q = p0 (1 - 2 r^2 / a^2), a polynomial: w = p0/D (r^4/64 - r^6/(288 a^2)) + C r^2 + c0, C from
  M_r(a) = 0 (V_r = 0 holds because the load has no net force), c0 such that w has no mean.
"""

from __future__ import annotations

import numpy as np

__all__ = ["winkler_bessel_mode", "winkler_step_load", "hetenyi_step_width", "free_plate_balanced_load"]


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


def winkler_step_load(r, load_radius: float, q: float, radius: float, bending_stiffness: float, poisson: float, foundation_stiffness: float) -> np.ndarray:
    """Deflection w(r) (m) of a free circular plate on a Winkler bed under q (Pa) on r < ``load_radius``.

    ``r``, ``load_radius`` b and ``radius`` a in m, ``bending_stiffness`` D in N m,
    ``foundation_stiffness`` k in Pa/m (> 0). The foundation pressure is k w; b >= a gives the
    uniform q/k (the free plate then does not bend), b <= 0 no deflection.
    """
    r = np.asarray(r, dtype=float)
    if load_radius >= radius:
        return np.full(r.shape, q / foundation_stiffness)
    if load_radius <= 0:
        return np.zeros(r.shape)
    import mpmath as mp

    with mp.workdps(30):
        nu, a, b, k = (mp.mpf(v) for v in (poisson, radius, load_radius, foundation_stiffness))
        kappa = mp.exp(1j * mp.pi / 4) / (mp.mpf(bending_stiffness) / k) ** mp.mpf(0.25)
        kinds = (mp.besselj, mp.bessely)

        def columns(kind, x):
            """(w, w', del^2 w, (del^2 w)') of Re(c Z_0(kappa x)) for c = 1 and c = i (del^2 Z_0(kappa r) = -kappa^2 Z_0)."""
            z0, z1 = kinds[kind](0, kappa * x), kinds[kind](1, kappa * x)
            values = (z0, -kappa * z1, -(kappa**2) * z0, kappa**3 * z1)
            return [mp.re(v) for v in values], [-mp.im(v) for v in values]

        # unknowns: c (J_0 inside), c1 (J_0 outside), c2 (Y_0 outside), each as (Re, Im)
        m, rhs = mp.zeros(6, 6), mp.zeros(6, 1)
        for col, (kind, sign) in enumerate(((0, 1), (0, -1), (1, -1))):
            for part, values in enumerate(columns(kind, b)):
                for row in range(4):
                    m[row, 2 * col + part] = sign * values[row]
        rhs[0] = -mp.mpf(q) / k  # the particular solution q/k inside
        for col, kind in ((1, 0), (2, 1)):
            for part, (_, w1, lap, lap1) in enumerate(columns(kind, a)):
                m[4, 2 * col + part] = lap - (1 - nu) * w1 / a  # M_r = 0: w'' + nu w'/a = del^2 w - (1 - nu) w'/a
                m[5, 2 * col + part] = lap1  # V_r = 0 (axisymmetric)
        c = mp.lu_solve(m, rhs)
        inner, outer_j, outer_y = (c[0] + 1j * c[1]), (c[2] + 1j * c[3]), (c[4] + 1j * c[5])
        out = []
        for ri in r.ravel():
            x = mp.mpf(ri)
            if x < b:
                out.append(float(mp.mpf(q) / k + mp.re(inner * mp.besselj(0, kappa * x))))
            else:
                out.append(float(mp.re(outer_j * mp.besselj(0, kappa * x) + outer_y * mp.bessely(0, kappa * x))))
    return np.array(out).reshape(r.shape)


def hetenyi_step_width(bending_stiffness: float, foundation_stiffness: float, level: float = 0.1) -> float:
    """The distance (m) over which the foundation pressure under a step load falls from 1 - level to level of the step.

    Hetenyi's infinite beam (or plate strip) on a Winkler bed under q on x < 0: k w / q =
    1 - exp(lambda x) cos(lambda x) / 2 for x < 0 and exp(-lambda x) cos(lambda x) / 2 for x > 0,
    lambda = (k / 4 D)^(1/4); both levels are reached at |x| = y / lambda with exp(-y) cos(y) =
    2 level, so the width is 2 y / lambda (10-90 %: y = 0.9976, width 2.822 (D/k)^(1/4)).
    """
    from scipy.optimize import brentq

    y = brentq(lambda t: np.exp(-t) * np.cos(t) - 2.0 * level, 0.0, np.pi / 2)
    return 2.0 * y / (foundation_stiffness / (4.0 * bending_stiffness)) ** 0.25


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
