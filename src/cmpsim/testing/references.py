"""Reference solutions: independent evaluations that the kernels are tested and benchmarked against.

As ContactMechanics keeps its Hertz and Greenwood-Tripp references, cmpsim keeps here

* :func:`contact_reference_mp`: the statistical asperity contact (paper eq. 20-29, corrected)
  re-implemented in mpmath from the per-asperity laws (Hertz; Zhao, Maietta & Chang,
  doi:10.1115/1.555332; Abbott & Firestone) and integrated with adaptive mpmath quadrature
  over the truncated Gaussian summit heights (Greenwood & Williamson, doi:10.1098/rspa.1966.0242);
* :func:`printed_forms_mp`: the grain-flow function and grain-size coefficients exactly as
  the paper prints them (eq. 6, 7, 18, 19; Haff, doi:10.1017/S0022112083003419), in 50 digits;
* :func:`printed_flow_factors`: the average-flow factors exactly as printed (eq. 8-17;
  Patir & Cheng, doi:10.1115/1.3453103; Tripp, doi:10.1115/1.3254640);
* the lubrication references live in :mod:`cmpsim.testing.lubrication`: the closed-form
  tilted (plane inclined) slider of Reynolds' equation (Hamrock, *Fundamentals of Fluid Film
  Lubrication*, ch. 8), its Gumbel and mass-conserving (JFO) cavitated forms, and the 1-D
  strip problem built from the wafer's kernels; :func:`tilted_slider_pressure` is the first.

None of them calls the kernel it checks. The module needs mpmath, a test dependency
(``pip install cmpsim[test]``); ``import cmpsim`` never imports it.
"""

from __future__ import annotations

import contextlib
import math

import mpmath as mp

from .lubrication import plane_slider_pressure as tilted_slider_pressure

__all__ = [
    "contact_reference_mp",
    "laws_mp",
    "gaussian_breakpoints",
    "printed_forms_mp",
    "printed_flow_factors",
    "omega_eq16",
    "psi_eq17",
    "tilted_slider_pressure",
]

# --- asperity contact (eq. 20-29) ------------------------------------------------------------
def _mp_pad(pad):
    """Pad constants in mpmath, from the raw inputs (eq. 27; omega_p = 54 omega_e)."""
    R, E, H = mp.mpf(pad.asperity_radius), mp.mpf(pad.e_star), mp.mpf(pad.hardness)
    K = mp.mpf("0.454") + mp.mpf("0.41") * mp.mpf(pad.poisson)
    w_e = (3 * mp.pi * K * H / (4 * E)) ** 2 * R
    w_p = 54 * w_e
    return dict(R=R, E=E, H=H, K=K, w_e=w_e, w_p=w_p, ln_wp=mp.log(w_p), ln_span=mp.log(w_p) - mp.log(w_e))


def _laws(omega, c: dict, model: str):
    if omega <= 0:
        return mp.mpf(0), mp.mpf(0), 0
    R, E, H, K, w_e, w_p = c["R"], c["E"], c["H"], c["K"], c["w_e"], c["w_p"]
    if model == "elastic" or omega < w_e:  # Hertz / Greenwood-Williamson
        return mp.pi * R * omega, mp.mpf(4) / 3 * E * mp.sqrt(R) * omega * mp.sqrt(omega), 1
    if omega < w_p:  # Zhao-Maietta-Chang
        u = (omega - w_e) / (w_p - w_e)
        area = mp.pi * R * omega * (1 - 2 * u**3 + 3 * u**2)
        p_mean = H * (1 - (1 - K) * (c["ln_wp"] - mp.log(omega)) / c["ln_span"])
        return area, p_mean * area, 2
    area = 2 * mp.pi * R * omega  # Abbott-Firestone
    return area, H * area, 3


def laws_mp(omega, pad, model: str):
    """Per-asperity (area m^2, load N, regime) of one summit with interference ``omega`` (m), in mpmath."""
    return _laws(mp.mpf(omega), _mp_pad(pad), model)


def gaussian_breakpoints(lo, hi):
    """Breakpoints for integrating smooth(zeta) * phi(zeta) over [lo, hi] (hi may be inf).

    Tanh-sinh quadrature over a Gaussian tail is unreliable (mp.quad over [14, inf] of
    (zeta - 3) phi is off by 4e-5), so the band is split at the peak m of phi on it and at
    m +- k / max(|m|, 1), k = 2, 8: each piece then sees phi vary by a bounded factor.
    An infinite end is cut at m + 64 / max(|m|, 1), beyond which phi / phi(m) < exp(-64).
    """
    m = min(max(lo, mp.mpf(0)), hi)
    scale = 1 / max(abs(m), mp.mpf(1))
    hi = min(hi, m + 64 * scale)
    pts = {lo, hi}
    for k in (2, 8):
        for p in (m - k * scale, m + k * scale):
            if lo < p < hi:
                pts.add(p)
    return sorted(pts)


def contact_reference_mp(separation: float, pad, model: str = "lep", dps: int = 20):
    """Nominal pressure (Pa) and the three area ratios at separation D (m), adaptive mpmath.

    Summit heights zeta = z / sigma_s follow phi(zeta) / Phi(c) on (-inf, c], c the cutoff.
    """
    with mp.workdps(dps):
        s = mp.mpf(pad.sigma_s)
        eta = mp.mpf(pad.asperity_density)
        consts = _mp_pad(pad)
        w_e, w_p = consts["w_e"], consts["w_p"]
        cut = mp.inf if math.isinf(pad.height_cutoff) else mp.mpf(pad.height_cutoff)
        norm = mp.ncdf(cut) if cut != mp.inf else mp.mpf(1)
        delta = mp.mpf(separation) / s

        def integral(lo, hi, which):
            hi = min(hi, cut)
            if hi <= lo:
                return mp.mpf(0)

            pick = 0 if which == "area" else 1

            def integrand(zeta):
                return _laws(s * (zeta - delta), consts, model)[pick] * mp.npdf(zeta)

            pts = gaussian_breakpoints(lo, hi)
            # mp.quad's tolerance is absolute: scale the integrand to O(1) at the largest of
            # its values at the breakpoints (interior points of the first and last pieces
            # stand in for the ends, where the law may vanish)
            probes = pts[1:-1] + [(pts[0] + pts[1]) / 2, (pts[-2] + pts[-1]) / 2]
            ref = max(integrand(z) for z in probes)

            return eta / norm * ref * mp.quad(lambda z: integrand(z) / ref, pts)

        if model == "elastic":
            bands = {"el": (delta, cut), "ep": None, "pl": None}
        else:
            bands = {
                "el": (delta, delta + w_e / s),
                "ep": (delta + w_e / s, delta + w_p / s),
                "pl": (delta + w_p / s, cut),
            }
        out = {"pressure": mp.mpf(0)}
        for band, name in (("el", "elastic"), ("ep", "elastoplastic"), ("pl", "plastic")):
            lim = bands[band]
            out[f"area_ratio_{name}"] = integral(*lim, "area") if lim else mp.mpf(0)
            out["pressure"] += integral(*lim, "load") if lim else mp.mpf(0)
        return out


# --- grain flow (eq. 6, 7, 18, 19) -----------------------------------------------------------
def printed_forms_mp(h_over_d, w_over_k, dps: int | None = 50):
    """Psi, f, g of eq. 6, 18, 19 exactly as printed, in ``dps``-digit arithmetic.

    ``dps=None`` keeps the caller's working precision (needed inside ``mp.diff``).
    """
    with mp.workdps(dps) if dps else contextlib.nullcontext():
        hd, wk = mp.mpf(h_over_d), mp.mpf(w_over_k)
        x = mp.sqrt(wk) * hd
        r1 = mp.exp(x) - mp.exp(-x)
        r2 = mp.exp(x) + mp.exp(-x)
        psi = mp.sqrt(1 / wk) * (r2 - 2) / r1
        bracket = r1 / (r2 - 2) - r2 / r1
        f = 2 + x * bracket
        g = 1 + 2 * x * bracket + wk * hd**2 * ((r2 / r1) ** 2 - (r2 - 1) / (r2 - 2))
        return psi, f, g


# --- flow factors (eq. 8-17) -----------------------------------------------------------------
def omega_eq16(theta, gamma):
    return math.cos(theta) ** 2 / (gamma + 1) + math.sin(theta) ** 2 * gamma / (gamma + 1)


def psi_eq17(theta, gamma):
    return math.sin(theta) * math.cos(theta) * (1 - gamma) / (gamma + 1)


def printed_flow_factors(hs, f, g, s1, s2, g1, g2, t1, t2):
    """Eq. 8-15 as printed; returns a dict of every factor."""
    s = math.sqrt(s1 * s1 + s2 * s2)
    w1, w2 = (s1 / s) ** 2, (s2 / s) ** 2
    e = 1.0 / hs

    def pxx(t1, t2):  # eq. 8
        return 1 + e**2 * g * (1 - f**2 / g * (w2 * omega_eq16(t2, g2) + w1 * omega_eq16(t1, g1)))

    def sxx(t1, t2):  # eq. 11
        return -e * f * (w2 * omega_eq16(t2, g2) - w1 * omega_eq16(t1, g1))

    p2, p1 = psi_eq17(t2, g2), psi_eq17(t1, g1)
    r = 0.5 * math.pi
    return {
        "p_xx": pxx(t1, t2),
        "p_xy": -(e**2) * f**2 * (w2 * p2 + w1 * p1),  # eq. 9
        "p_yy": pxx(r - t1, r - t2),  # eq. 10
        "s_xx": sxx(t1, t2),
        "s_xy": -e * f * (w2 * p2 - w1 * p1),  # eq. 12
        "s_yy": sxx(r - t1, r - t2),  # eq. 13
        "fs": -3 * e**2 * (w2 * p2 - w1 * p1),  # eq. 14
        "fp": 1 - e**2 * f * (w2 * p2 + w1 * p1),  # eq. 15
    }
