"""Benchmark: vectorised asperity contact vs. per-point adaptive quadrature.

Times :func:`cmpsim.physics.contact.asperity_contact` on N separations (default 20,000, from -4 to
2.999 sigma_s) against a baseline that evaluates the same integrals point by point with
``scipy.integrate.quad`` (QAGS, epsabs=0, epsrel=1e-12): for each separation D, the load
and the area of each regime, on the bands [D, D + omega_e], [D + omega_e, D + omega_p] and
[D + omega_p, cutoff] (six integrals; the band ends are the breakpoints). Checks that both
agree to 1e-8 relative (pressure and the three area ratios), then prints the speed-up ratio
measured in this run and the largest relative difference. Exits with status 1 if the
agreement check fails. For information it also times the solver's path, a
:class:`cmpsim.physics.contact.ContactTable` of the same pad (build once, then interpolate).

Run:  python benchmarks/bench_contact.py [--points 20000] [--baseline-points N] [--model lep]

``--baseline-points`` times the baseline on an evenly spaced subset (its per-point cost is
then compared with the kernel's per-point cost on all points); by default it runs on all.
"""

from __future__ import annotations

import argparse
import datetime
import math
import platform
import sys
import time

import numpy as np
from scipy.integrate import quad
from scipy.special import ndtr

from cmpsim.physics.contact import PLASTIC_RATIO, ContactTable, PadSurface, asperity_contact

TOL = 1e-8


def baseline_point(delta: float, pad: PadSurface, model: str) -> tuple[float, float, float, float]:
    """(pressure, A_el/A_n, A_ep/A_n, A_pl/A_n) at D = delta * sigma_s by per-band scipy quad."""
    s, R, E, H = pad.sigma_s, pad.asperity_radius, pad.e_star, pad.hardness
    K = 0.454 + 0.41 * pad.poisson
    w_e = (3 * math.pi * K * H / (4 * E)) ** 2 * R
    w_p = PLASTIC_RATIO * w_e
    cut = pad.height_cutoff
    scale = pad.asperity_density / (ndtr(cut) if math.isfinite(cut) else 1.0)
    inv_sqrt_2pi = 1.0 / math.sqrt(2.0 * math.pi)

    def phi(z):
        return inv_sqrt_2pi * math.exp(-0.5 * z * z)

    def el_load(z):
        w = s * (z - delta)
        return 4.0 / 3.0 * E * math.sqrt(R) * w * math.sqrt(w) * phi(z)

    def el_area(z):
        return math.pi * R * s * (z - delta) * phi(z)

    def ep_area_law(w):
        u = (w - w_e) / (w_p - w_e)
        return math.pi * R * w * (1 - 2 * u**3 + 3 * u**2)

    def ep_area(z):
        return ep_area_law(s * (z - delta)) * phi(z)

    def ep_load(z):
        w = s * (z - delta)
        p_mean = H * (1 - (1 - K) * math.log(w_p / w) / math.log(w_p / w_e))
        return p_mean * ep_area_law(w) * phi(z)

    def pl_area(z):
        return 2 * math.pi * R * s * (z - delta) * phi(z)

    def integrate(f, a, b):
        b = min(b, cut)
        if not b > a:
            return 0.0
        if math.isinf(b):
            b = max(a, 0.0) + 40.0  # phi(40) = 1e-348: nothing beyond
        return quad(f, a, b, epsabs=0.0, epsrel=1e-12, limit=200)[0]

    if model == "elastic":
        a_el = integrate(el_area, delta, math.inf)
        return scale * integrate(el_load, delta, math.inf), scale * a_el, 0.0, 0.0
    d_e, d_p = delta + w_e / s, delta + w_p / s
    p = integrate(el_load, delta, d_e) + integrate(ep_load, d_e, d_p) + H * integrate(pl_area, d_p, math.inf)
    a_el = integrate(el_area, delta, d_e)
    a_ep = integrate(ep_area, d_e, d_p)
    a_pl = integrate(pl_area, d_p, math.inf)
    return scale * p, scale * a_el, scale * a_ep, scale * a_pl


def max_rel_diff(got: np.ndarray, ref: np.ndarray) -> float:
    """Largest relative difference; a zero reference demands an exact zero."""
    zero = ref == 0
    if np.any(got[zero] != 0):
        return math.inf
    if not np.any(~zero):
        return 0.0
    return float(np.max(np.abs(got[~zero] - ref[~zero]) / np.abs(ref[~zero])))


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--points", type=int, default=20_000)
    ap.add_argument("--baseline-points", type=int, default=None, help="subset size for the baseline (default: all)")
    ap.add_argument("--model", choices=("lep", "elastic"), default="lep")
    ap.add_argument("--repeat", type=int, default=7, help="kernel timing: best of this many runs")
    args = ap.parse_args(argv)

    pad = PadSurface(15e-6, 1e8, 50e-6, 110e6, 20e6, 0.3)  # prototype pad, 3 sigma cutoff
    delta = np.linspace(-4.0, 2.999, args.points)
    sep = delta * pad.sigma_s

    asperity_contact(sep[:100], pad, args.model)  # warm-up
    best = math.inf
    for _ in range(args.repeat):
        t0 = time.perf_counter()
        res = asperity_contact(sep, pad, args.model)
        best = min(best, time.perf_counter() - t0)
    kernel_per_point = best / args.points

    nb = args.points if args.baseline_points is None else min(args.baseline_points, args.points)
    idx = np.unique(np.linspace(0, args.points - 1, nb).round().astype(int))
    t0 = time.perf_counter()
    ref = np.array([baseline_point(float(sep[i] / pad.sigma_s), pad, args.model) for i in idx])
    base_time = time.perf_counter() - t0
    base_per_point = base_time / len(idx)

    def diffs_of(r):
        return {
            "pressure": max_rel_diff(r.pressure[idx], ref[:, 0]),
            "area_ratio_elastic": max_rel_diff(r.area_ratio_elastic[idx], ref[:, 1]),
            "area_ratio_elastoplastic": max_rel_diff(r.area_ratio_elastoplastic[idx], ref[:, 2]),
            "area_ratio_plastic": max_rel_diff(r.area_ratio_plastic[idx], ref[:, 3]),
        }

    diffs = diffs_of(res)
    worst = max(diffs.values())
    ratio = base_per_point / kernel_per_point

    t0 = time.perf_counter()
    table = ContactTable(pad, args.model)
    build = time.perf_counter() - t0
    table(sep[:100])
    t_table = math.inf
    for _ in range(args.repeat):
        t0 = time.perf_counter()
        res_t = table(sep)
        t_table = min(t_table, time.perf_counter() - t0)
    table_diff = diffs_of(res_t)["pressure"]

    print(f"cmpsim bench_contact  {datetime.date.today().isoformat()}  python {platform.python_version()}"
          f"  numpy {np.__version__}  {platform.machine()}")
    print(f"pad: sigma_s=15 um, eta=1e8 /m^2, R=50 um, E'=110 MPa, H=20 MPa, nu=0.3, cutoff 3 sigma;"
          f" model={args.model}; D/sigma in [-4, 2.999]")
    print(f"kernel   asperity_contact: {args.points} points in {best * 1e3:.2f} ms (best of {args.repeat})"
          f" = {kernel_per_point * 1e6:.3f} us/point")
    print(f"baseline scipy quad:       {len(idx)} points in {base_time:.2f} s = {base_per_point * 1e6:.1f} us/point")
    for k, v in diffs.items():
        print(f"  max rel diff {k:26s} {v:.2e}")
    print(f"info: ContactTable (solver path) build {build:.2f} s, then {t_table / args.points * 1e6:.3f} us/point"
          f" ({base_per_point / (t_table / args.points):.0f}x the baseline; {base_per_point * args.points / (build + t_table):.0f}x"
          f" with the build counted), pressure max rel diff {table_diff:.1e}")
    print(f"RESULT speed-up ratio {ratio:.0f}x (per point), max rel diff {worst:.2e}"
          f" ({'OK' if worst <= TOL else 'FAIL'}: tolerance {TOL:g})")
    return 0 if worst <= TOL else 1


if __name__ == "__main__":
    sys.exit(main())
