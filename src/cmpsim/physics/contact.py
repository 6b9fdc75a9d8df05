"""Statistical asperity contact of the rough pad on the smooth wafer (paper eq. 20–29, corrected).

Asperity summits of the pad have a common radius R, an areal density eta_a and Gaussian
heights z of standard deviation sigma_s, measured from the mean plane of the summit heights.
An asperity with interference ``omega = z - D`` (D = separation of the wafer from that plane)
deforms

* elastically (Hertz, Greenwood–Williamson) for omega < omega_e,
* elastoplastically (Zhao–Maietta–Chang, ZMC) for omega_e <= omega < omega_p = 54 omega_e,
* fully plastically (Abbott–Firestone) for omega >= omega_p,

with omega_e = (3 pi K H / (4 E'))^2 R (eq. 27) and K = 0.454 + 0.41 nu. The per-asperity
laws (``docs/model.md``, "Asperity contact") are

    elastic:       A = pi R omega,                     P = (4/3) E' R^1/2 omega^3/2
    elastoplastic: A = pi R omega [1 - 2u^3 + 3u^2],   P = H [1 - (1-K) ln(omega_p/omega)/ln(omega_p/omega_e)] A
    plastic:       A = 2 pi R omega,                   P = H A

with u = (omega - omega_e)/(omega_p - omega_e); A and P are continuous at omega_e and omega_p.

The paper counts contact only where the clearance is below 3 R_q. Here that statement is
honoured by the height distribution itself: summit heights follow a Gaussian truncated at
``height_cutoff`` * sigma_s (3 by default) and renormalised. No summit reaches beyond the
cutoff, so there is no contact at larger clearance, and, unlike a hard switch on the
pressure, the load is a continuous function of the separation (it vanishes like
(cutoff - D)^(5/2)).

Integrals over the height distribution use fixed Gauss–Legendre quadrature (after the
substitution z = D + t^2 for the omega^(3/2) law, whose derivative is singular at z = D),
so the kernel is fully vectorised; ``tests/test_contact.py`` checks it against adaptive
mpmath quadrature to 1e-8 relative.
"""

from __future__ import annotations

from dataclasses import dataclass
from functools import cached_property, lru_cache

import numpy as np
from scipy.special import ndtr

__all__ = ["PadSurface", "ContactResult", "ContactTable", "contact_table", "asperity_contact", "asperity_laws", "contact_spot_density", "MODELS"]

MODELS = ("lep", "elastic")

#: omega_p / omega_e (Johnson; ZMC), paper text after eq. 27.
PLASTIC_RATIO = 54.0
#: Each band is integrated only where phi is within exp(-40) of its largest value on the
#: band (at most _WINDOW standardised heights away from it; see _window).
_WINDOW = 10.0
_NODES = 32
#: Points per block in asperity_contact.
_BLOCK = 512
_GL_X, _GL_W = np.polynomial.legendre.leggauss(_NODES)
_INV_SQRT_2PI = 1.0 / np.sqrt(2.0 * np.pi)


def _finite_positive(name: str, value: float, unit: str) -> None:
    if not (np.isfinite(value) and value > 0):
        raise ValueError(f"{name} must be finite and > 0 {unit} (valid range: (0, inf)); got {value!r}")


@dataclass(frozen=True)
class PadSurface:
    """Greenwood–Williamson description of the pad surface and its material.

    Parameters
    ----------
    sigma_s : float
        Standard deviation of the summit heights, m (> 0).
    asperity_density : float
        Areal density of summits eta_a, 1/m^2 (> 0).
    asperity_radius : float
        Summit radius of curvature R, m (> 0).
    e_star : float
        Effective modulus E' of eq. 22, Pa (> 0).
    hardness : float
        Pad hardness H, Pa (> 0).
    poisson : float
        Pad Poisson ratio nu, in [0, 0.5]; sets K = 0.454 + 0.41 nu.
    height_cutoff : float
        Summit heights are truncated at ``height_cutoff * sigma_s`` (paper: contact only
        below 3 R_q); ``numpy.inf`` for the untruncated Gaussian. Must be >= 0.5.
    """

    sigma_s: float
    asperity_density: float
    asperity_radius: float
    e_star: float
    hardness: float
    poisson: float
    height_cutoff: float = 3.0

    def __post_init__(self) -> None:
        _finite_positive("sigma_s", self.sigma_s, "m")
        _finite_positive("asperity_density", self.asperity_density, "1/m^2")
        _finite_positive("asperity_radius", self.asperity_radius, "m")
        _finite_positive("e_star", self.e_star, "Pa")
        _finite_positive("hardness", self.hardness, "Pa")
        if not (np.isfinite(self.poisson) and 0.0 <= self.poisson <= 0.5):
            raise ValueError(f"poisson must be in [0, 0.5]; got {self.poisson!r}")
        if not (self.height_cutoff >= 0.5):  # also rejects NaN; inf allowed
            raise ValueError(f"height_cutoff must be >= 0.5 (in units of sigma_s, inf allowed); got {self.height_cutoff!r}")

    @property
    def k_factor(self) -> float:
        """Maximum-contact-pressure factor K = 0.454 + 0.41 nu (Chang–Etsion–Bogy), dimensionless."""
        return 0.454 + 0.41 * self.poisson

    @property
    def omega_e(self) -> float:
        """Critical interference at initial yield, eq. 27: (3 pi K H / (4 E'))^2 R, m."""
        return (3.0 * np.pi * self.k_factor * self.hardness / (4.0 * self.e_star)) ** 2 * self.asperity_radius

    @property
    def omega_p(self) -> float:
        """Interference of fully plastic flow, omega_p = 54 omega_e, m."""
        return PLASTIC_RATIO * self.omega_e

    @cached_property
    def _normaliser(self) -> float:
        return float(ndtr(self.height_cutoff)) if np.isfinite(self.height_cutoff) else 1.0

    @property
    def plasticity_index(self) -> float:
        """Greenwood–Williamson plasticity index (E'/H) sqrt(sigma_s/R), dimensionless."""
        return self.e_star / self.hardness * np.sqrt(self.sigma_s / self.asperity_radius)


def asperity_laws(omega, pad: PadSurface, model: str = "lep"):
    """Per-asperity contact area (m^2), load (N) and regime of one summit.

    ``omega`` is the interference in m (>= 0 for contact; negative gives zero).
    Returns ``(area, load, regime)`` with regime 0 = none, 1 = elastic, 2 = elastoplastic,
    3 = plastic. Used by the tests for continuity at omega_e and omega_p.
    """
    w = np.asarray(omega, dtype=float)
    R = pad.asperity_radius
    area = np.zeros_like(w)
    load = np.zeros_like(w)
    regime = np.zeros(w.shape, dtype=int)
    on = w > 0
    wp = np.where(on, w, 1.0)
    if model == "elastic":
        area = np.where(on, np.pi * R * wp, 0.0)
        load = np.where(on, 4.0 / 3.0 * pad.e_star * np.sqrt(R) * wp**1.5, 0.0)
        return area, load, np.where(on, 1, 0)
    _check_model(model)
    we, wpl = pad.omega_e, pad.omega_p
    el = on & (w < we)
    ep = on & (w >= we) & (w < wpl)
    pl = on & (w >= wpl)
    u = (wp - we) / (wpl - we)
    a_ep = np.pi * R * wp * (1.0 - 2.0 * u**3 + 3.0 * u**2)
    pm = pad.hardness * (1.0 - (1.0 - pad.k_factor) * np.log(wpl / np.where(ep, wp, wpl)) / np.log(PLASTIC_RATIO))
    area = np.select([el, ep, pl], [np.pi * R * wp, a_ep, 2.0 * np.pi * R * wp], 0.0)
    load = np.select(
        [el, ep, pl],
        [4.0 / 3.0 * pad.e_star * np.sqrt(R) * wp**1.5, pm * a_ep, pad.hardness * 2.0 * np.pi * R * wp],
        0.0,
    )
    regime = np.select([el, ep, pl], [1, 2, 3], 0)
    return area, load, regime


@dataclass(frozen=True)
class ContactResult:
    """Nominal contact pressure and real-contact-area ratios at each separation.

    All arrays are shaped like the ``separation`` passed to :func:`asperity_contact`.

    Attributes
    ----------
    pressure : numpy.ndarray
        Nominal contact pressure F_total / A_n (eq. 28), Pa.
    pressure_elastic, pressure_elastoplastic, pressure_plastic : numpy.ndarray
        Its parts carried by elastic (eq. 20), elastoplastic (eq. 25) and plastic (eq. 23)
        summits, Pa.
    area_ratio_elastic, area_ratio_elastoplastic, area_ratio_plastic : numpy.ndarray
        Real contact area over nominal area of each regime (eq. 21/29, 26, 24), dimensionless.
    """

    pressure: np.ndarray
    pressure_elastic: np.ndarray
    pressure_elastoplastic: np.ndarray
    pressure_plastic: np.ndarray
    area_ratio_elastic: np.ndarray
    area_ratio_elastoplastic: np.ndarray
    area_ratio_plastic: np.ndarray

    @property
    def area_ratio(self) -> np.ndarray:
        """Total real contact area ratio A_r / A_n (eq. 29), dimensionless."""
        return self.area_ratio_elastic + self.area_ratio_elastoplastic + self.area_ratio_plastic


def _check_model(model: str) -> None:
    if model not in MODELS:
        raise ValueError(f"model must be one of {MODELS}; got {model!r}")


def _gauss(a: np.ndarray, b: np.ndarray):
    """Gauss–Legendre nodes and weights mapped to [a, b] (rows per point); empty if b <= a."""
    width = np.maximum(b - a, 0.0)
    nodes = a[..., None] + 0.5 * width[..., None] * (_GL_X + 1.0)
    weights = 0.5 * width[..., None] * _GL_W
    return nodes, weights


def _window(a: np.ndarray, b: np.ndarray):
    """The part of the band [a, b] that carries its Gaussian weight.

    phi peaks on [a, b] at m, the point nearest 0; beyond |zeta - m| = min(10, 40/|m|) it is
    below exp(-40) (relative) of phi(m). Clipping there keeps each band a few Gaussian widths
    wide, so one Gauss-Legendre panel resolves it whatever the separation or cutoff.
    """
    m = np.minimum(np.maximum(a, 0.0), b)
    with np.errstate(divide="ignore"):
        half = np.minimum(_WINDOW, 40.0 / np.abs(m))
    return np.maximum(a, m - half), np.minimum(b, m + half)


def _pdf(zeta: np.ndarray) -> np.ndarray:
    return _INV_SQRT_2PI * np.exp(-0.5 * zeta * zeta)


def asperity_contact(separation, pad: PadSurface, model: str = "lep") -> ContactResult:
    """Contact pressure and real-area ratios of the pad at a given separation (eq. 20–29).

    Parameters
    ----------
    separation : array_like
        Distance D from the mean plane of the summit heights to the wafer, m. Any finite
        value (negative means the wafer is below the mean summit height).
    pad : PadSurface
    model : {"lep", "elastic"}
        ``"lep"``: elastic–elastoplastic–plastic (Hertz / ZMC / Abbott–Firestone), the
        paper's model; ``"elastic"``: every summit Hertzian (Greenwood–Williamson), the
        earlier elastic model of the same group.

    Returns
    -------
    ContactResult
    """
    _check_model(model)
    if not isinstance(pad, PadSurface):
        raise ValueError(f"pad must be a PadSurface; got {type(pad).__name__}")
    d = np.asarray(separation, dtype=float)
    if not np.all(np.isfinite(d)):
        raise ValueError("separation must be finite (m)")
    shape = d.shape
    flat = d.reshape(-1)
    # blocks of _BLOCK points keep the (points x nodes) temporaries in cache (2x faster)
    parts = [_contact_block(flat[i : i + _BLOCK], pad, model) for i in range(0, max(flat.size, 1), _BLOCK)]
    fields_ = {k: np.concatenate([p[k] for p in parts]).reshape(shape) for k in parts[0]}
    return ContactResult(**fields_)


def contact_spot_density(separation, pad: PadSurface) -> np.ndarray:
    """Summits in contact per unit nominal area at the separation D, 1/m^2.

    eta_a / Phi(cutoff) * (Phi(cutoff) - Phi(D / sigma_s)): the summits whose height exceeds D
    (Greenwood & Williamson, Proc. R. Soc. A 295, 300 (1966), eq. 7, with the paper's
    truncation of the heights at ``height_cutoff`` sigma_s); 0 where D is above the cutoff.
    With :func:`asperity_contact` it gives the mean summit contact, area (A_r/A_n)/N and load
    p_c/N, used by the abrasive removal law (docs/model.md, 13e.1).
    """
    d = np.asarray(separation, dtype=float) / pad.sigma_s
    cut = pad.height_cutoff
    # upper tail difference, Phi(cut) - Phi(d) = Phi(-d) - Phi(-cut) (no cancellation for d > 0)
    mass = ndtr(-d) - (ndtr(-cut) if np.isfinite(cut) else 0.0)
    return pad.asperity_density / pad._normaliser * np.maximum(mass, 0.0)


def _contact_block(d: np.ndarray, pad: PadSurface, model: str) -> dict:
    """:func:`asperity_contact` on a 1-D block of separations (m); returns the fields as a dict."""
    s = pad.sigma_s
    delta = d / s
    upper = np.full_like(delta, pad.height_cutoff)  # may be inf: _window bounds every band
    scale = pad.asperity_density / pad._normaliser
    R = pad.asperity_radius
    if model == "elastic":
        we = np.inf
        wpl = np.inf
    else:
        we = pad.omega_e / s
        wpl = pad.omega_p / s

    # --- elastic summits: omega in [0, omega_e), z in [D, min(D + omega_e, cutoff)] ---
    b_el = np.minimum(delta + we, upper)
    # on [D, D + 1], z = D + t^2 removes the omega^(1/2) singularity of the load's
    # derivative at z = D; the rest (only if omega_e > sigma) is smooth in z
    b_sing = np.minimum(b_el, delta + 1.0)
    t, wt = _gauss(np.zeros_like(delta), np.sqrt(np.maximum(b_sing - delta, 0.0)))
    wgt = wt * 2.0 * t * _pdf(delta[:, None] + t * t)  # dz = 2 t dt
    t2 = t * t  # = omega / sigma
    sum_p, sum_a = np.sum(wgt * t2 * t, axis=1), np.sum(wgt * t2, axis=1)
    if we > 1.0:
        z, wz = _gauss(*_window(delta + 1.0, np.maximum(b_el, delta + 1.0)))
        w = z - delta[:, None]
        wgt = wz * _pdf(z)
        sum_p, sum_a = sum_p + np.sum(wgt * w**1.5, axis=1), sum_a + np.sum(wgt * w, axis=1)
    p_el = scale * 4.0 / 3.0 * pad.e_star * np.sqrt(R) * s**1.5 * sum_p
    a_r_el = scale * np.pi * R * s * sum_a

    zero = np.zeros_like(delta)
    if model == "elastic":
        p_ep = a_r_ep = p_pl = a_r_pl = zero
    else:
        # --- elastoplastic summits (ZMC) ---
        a_ep_lim = delta + we
        b_ep = np.minimum(delta + wpl, upper)
        z, wz = _gauss(*_window(a_ep_lim, np.maximum(b_ep, a_ep_lim)))
        w = np.maximum(z - delta[:, None], we)  # clamp only guards round-off at the lower end
        u = (w - we) / (wpl - we)
        area = np.pi * R * s * w * (1.0 + u * u * (3.0 - 2.0 * u))  # 1 - 2u^3 + 3u^2
        pm = pad.hardness * (1.0 - (1.0 - pad.k_factor) * np.log(wpl / w) / np.log(PLASTIC_RATIO))
        wgt = wz * _pdf(z)
        a_r_ep = scale * np.sum(wgt * area, axis=1)
        p_ep = scale * np.sum(wgt * area * pm, axis=1)
        # --- fully plastic summits (Abbott–Firestone), closed form ---
        a_pl = delta + wpl
        b_pl = np.maximum(upper, a_pl)
        # int_a^b (zeta - delta) pdf dzeta = pdf(a) - pdf(b) - delta (Phi(b) - Phi(a)), with
        # Phi(b) - Phi(a) from the upper tail when a > 0 (1 - 1 would lose every digit)
        mass = np.where(a_pl > 0, ndtr(-a_pl) - ndtr(-b_pl), ndtr(b_pl) - ndtr(a_pl))
        first = _pdf(a_pl) - _pdf(b_pl) - delta * mass
        first = np.where(b_pl > a_pl, first, 0.0)
        a_r_pl = scale * 2.0 * np.pi * R * s * first
        p_pl = pad.hardness * a_r_pl

    return {
        "pressure": p_el + p_ep + p_pl,
        "pressure_elastic": p_el,
        "pressure_elastoplastic": p_ep,
        "pressure_plastic": p_pl,
        "area_ratio_elastic": a_r_el,
        "area_ratio_elastoplastic": a_r_ep,
        "area_ratio_plastic": a_r_pl,
    }




class _NotAKnotSpline:
    """The not-a-knot cubic spline through (x_i, y_i) (columns of ``y`` interpolated together),
    the spline of ``scipy.interpolate.CubicSpline(x, y, axis=0)`` computed as it computes it.

    Written here because loading ``scipy.interpolate`` (which loads ``scipy.optimize``) cost a
    fifth of the wall time of ``cmpsim run`` on the base case, for this one table
    (``benchmarks/bench_import.py``; issue 31). The slopes s_i solve the tridiagonal system of
    C2 continuity with the not-a-knot ends (third derivative continuous at x_1 and x_{n-2}) by
    ``scipy.linalg.solve_banded`` (loaded with the sparse solvers anyway); each interval holds
    the Hermite cubic y_i + s_i t + c1 t^2 + c0 t^3, t = x - x_i, evaluated by powers of t, as
    scipy's ``PPoly`` does. ``tests/test_contact.py`` checks it against ``CubicSpline`` (equal to
    round-off; bit for bit with the scipy of this release's tests).
    """

    def __init__(self, x, y):
        from scipy.linalg import solve_banded

        x = np.asarray(x, dtype=float)
        y = np.asarray(y, dtype=float)
        n = len(x)
        if n < 4 or y.shape[0] != n or not np.all(np.diff(x) > 0):
            raise ValueError("_NotAKnotSpline needs >= 4 strictly increasing nodes and one row of y per node")
        dx = np.diff(x)
        dxr = dx.reshape((n - 1,) + (1,) * (y.ndim - 1))
        slope = np.diff(y, axis=0) / dxr
        band = np.zeros((3, n))
        rhs = np.empty(y.shape)
        band[1, 1:-1] = 2 * (dx[:-1] + dx[1:])
        band[0, 2:] = dx[:-1]
        band[-1, :-2] = dx[1:]
        rhs[1:-1] = 3 * (dxr[1:] * slope[:-1] + dxr[:-1] * slope[1:])
        d = x[2] - x[0]  # not-a-knot at the start
        band[1, 0], band[0, 1] = dx[1], d
        rhs[0] = ((dxr[0] + 2 * d) * dxr[1] * slope[0] + dxr[0] ** 2 * slope[1]) / d
        d = x[-1] - x[-3]  # and at the end
        band[1, -1], band[-1, -2] = dx[-2], d
        rhs[-1] = (dxr[-1] ** 2 * slope[-2] + (2 * d + dxr[-1]) * dxr[-2] * slope[-1]) / d
        s = solve_banded((1, 1), band, rhs.reshape(n, -1), overwrite_ab=True, overwrite_b=True, check_finite=False).reshape(y.shape)
        t = (s[:-1] + s[1:] - 2 * slope) / dxr
        self.x = x
        self.c = np.stack((t / dxr, (slope - s[:-1]) / dxr - t, s[:-1], y[:-1]))

    def __call__(self, xq):
        """The spline at ``xq`` (1-D), one row per point; the end intervals extend beyond the nodes."""
        xq = np.asarray(xq, dtype=float)
        i = np.clip(np.searchsorted(self.x, xq, side="right") - 1, 0, len(self.x) - 2)
        t = (xq - self.x[i]).reshape((-1,) + (1,) * (self.c.ndim - 2))
        c0, c1, c2, c3 = self.c[:, i]
        t2 = t * t
        return ((0.0 + c3) + c2 * t) + c1 * t2 + c0 * (t2 * t)


@lru_cache(maxsize=64)
def contact_table(pad: PadSurface, model: str = "lep") -> "ContactTable":
    """The :class:`ContactTable` of a pad, built once and cached (pads are immutable)."""
    return ContactTable(pad, model)


class ContactTable:
    """Piecewise cubic-spline tabulation of :func:`asperity_contact` for one pad.

    The contact outputs depend on the separation D alone, so an equilibrium that needs them
    at every grid node of every Newton step interpolates them from one table built with the
    quadrature kernel. The outputs are smooth in D except where a regime boundary of the
    summit laws meets the height cutoff c: at D = c - omega_p and D = c - omega_e (the
    per-summit load is only continuous there, so the integrals are C^1), and at D = c, where
    they vanish like (c - D)^(5/2) (loads) and (c - D)^2 (areas). The table therefore has
    its breakpoints exactly at those separations, and on the last piece it interpolates the
    outputs divided by those powers of (c - D), which are smooth.

    Separations below ``lower * sigma_s`` fall back to the kernel; at and beyond the cutoff
    the contact is exactly zero. :attr:`error_bound` is the largest interpolation error found
    at the midpoints between nodes, relative to the contact pressure at zero separation.
    """

    _POWERS = {"pressure": 2.5, "pressure_elastic": 2.5, "pressure_elastoplastic": 2.5, "pressure_plastic": 2.5}

    def __init__(self, pad: PadSurface, model: str = "lep", nodes_per_piece: int = 600, lower: float = -6.0):
        _check_model(model)
        if not np.isfinite(pad.height_cutoff):
            raise ValueError("ContactTable needs a finite height_cutoff; use asperity_contact directly")
        self.pad, self.model = pad, model
        s = pad.sigma_s
        self.cutoff = pad.height_cutoff * s
        self.d_min = lower * s
        breaks = [self.d_min]
        if model == "lep":
            breaks += [b for b in (self.cutoff - pad.omega_p, self.cutoff - pad.omega_e) if self.d_min < b < self.cutoff]
        breaks.append(self.cutoff)
        self._breaks = np.array(breaks)
        self._names = list(ContactResult.__dataclass_fields__)
        self._pieces = []
        worst = 0.0
        scale = float(asperity_contact(np.array([0.0]), pad, model).pressure[0])
        area_scale = max(float(asperity_contact(np.array([0.0]), pad, model).area_ratio[0]), 1e-300)
        for k, (a, b) in enumerate(zip(self._breaks[:-1], self._breaks[1:])):
            last = k == len(self._breaks) - 2
            # cluster nodes towards the ends (Chebyshev-like) for the singular behaviour there
            t = 0.5 * (1.0 - np.cos(np.linspace(0.0, np.pi, nodes_per_piece)))
            x = a + (b - a) * t
            if last:
                x = x[:-1]  # the cutoff itself is a zero of the weight
            exact = asperity_contact(x, pad, model)
            # one spline through all outputs at once (columns in the order of self._names)
            cols = [getattr(exact, name) / (self._weight(name, x) if last else 1.0) for name in self._names]
            self._pieces.append((a, b, last, _NotAKnotSpline(x, np.stack(cols, axis=1))))
            mid = 0.5 * (x[1:] + x[:-1])
            ref = asperity_contact(mid, pad, model)
            got = self._evaluate_piece(self._pieces[-1], mid)
            worst = max(
                worst,
                float(np.max(np.abs(got["pressure"] - ref.pressure))) / scale,
                float(np.max(np.abs(got["area_ratio_elastic"] + got["area_ratio_elastoplastic"] + got["area_ratio_plastic"] - ref.area_ratio))) / area_scale,
            )
        self.error_bound = worst

    def _weight(self, name, x):
        return (self.cutoff - x) ** self._POWERS.get(name, 2.0)

    def _evaluate_piece(self, piece, x):
        a, b, last, spline = piece
        v = spline(x)
        return {
            name: (v[:, k] * self._weight(name, x) if last else v[:, k]) for k, name in enumerate(self._names)
        }

    def __call__(self, separation) -> ContactResult:
        """Contact at ``separation`` (m), like :func:`asperity_contact`."""
        d = np.asarray(separation, dtype=float)
        out = {k: np.zeros(d.shape) for k in self._names}
        below = d < self.d_min
        if np.any(below):
            direct = asperity_contact(d[below], self.pad, self.model)
            for k in self._names:
                out[k][below] = getattr(direct, k)
        for piece in self._pieces:
            a, b = piece[0], piece[1]
            sel = (d >= a) & (d < b)
            if np.any(sel):
                vals = self._evaluate_piece(piece, d[sel])
                for k in self._names:
                    out[k][sel] = vals[k]
        return ContactResult(**out)
