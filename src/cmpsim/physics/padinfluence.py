"""Influence coefficients of a laterally coupled pad on the cells of a polar grid (pure kernels).

The deflection of the pad surface at a point x under a pressure p is w(x) = ∫ G(|x - x'|) p(x') dA'
with the radial kernel G(ρ) = (1/2π) ∫_0^∞ C(q) J0(qρ) q dq of an axisymmetric compliance C(q)
(m/Pa; ``docs/model.md``, section 13c). On a polar grid with a pressure uniform in each cell,
the deflection at the cell centre i is Σ_j K_ij p_j with K_ij = ∫_{cell j} G(|x_i - x'|) dA'
(collocation at the centres, exact cell integrals of the kernel). Three facts make that cheap:

- **The cell integral as a boundary integral.** With the radial primitive F(ρ) = ∫_0^ρ G(s) s ds
  = (ρ/2π) ∫_0^∞ C(q) J1(qρ) dq, the field (F(ρ)/ρ) ê_ρ has divergence G (ρ measured from the
  target point), so ∫_S G dA = ∮_∂S (F(ρ)/ρ) ê_ρ · n ds (divergence theorem). Splitting
  F = F_∞ + (F - F_∞), F_∞ = C(0)/2π, the first part gives 2π F_∞ = C(0) to the cell that holds
  the target and nothing to the others (the angle a closed curve subtends); only the near
  field (F - F_∞)/ρ, which decays exponentially beyond a few coupling lengths, is integrated
  numerically along the four edges of each cell (two arcs, two rays). A kernel much narrower
  than a cell then gives exactly the local (Winkler) answer K = C(0) I, and a kernel wider than
  the cells their exact overlap, on equal and on edge-graded rings alike.
- **Quadrature on the edges.** The integrand is largest where an edge passes closest to the
  target (distance δ, at least half a cell width) and falls like δ/ρ² away from there; each
  edge is split at that point and each side integrated by Gauss-Legendre in u, with the arc
  length s = δ sinh u from the closest point, which turns that peak into the smooth sech u.
- **Rotational symmetry.** The grid is the same in every sector, so K_ij depends on the two
  rings and the sector offset only (a block-circulant matrix, and symmetric in the offset):
  n_r² (n_θ/2 + 1) numbers, applied by a real FFT over the sectors and one n_r x n_r matrix
  per angular mode (:func:`angular_modes`).

F(ρ) is tabulated once by Gauss-Legendre quadrature in q (panels half an oscillation of
J1(qρ) wide) and interpolated by a cubic spline in asinh(ρ/a).
"""

from __future__ import annotations

import numpy as np

__all__ = ["radial_primitive", "ring_influence", "angular_modes", "apply_modes"]

#: Gauss-Legendre nodes on each side of the closest point of an edge: near edges (closer than
#: twice their length) and far ones.
_NEAR_NODES, _FAR_NODES = 12, 6
_GAUSS = {n: np.polynomial.legendre.leggauss(n) for n in (8, _NEAR_NODES, _FAR_NODES)}


def radial_primitive(compliance, q_max: float, rho_max: float, length: float, tail: float = 0.0, n: int = 400, decayed: float = 1e-9):
    """The near field of the kernel's radial primitive: (near, reach) with near(ρ) = (F(ρ) - F_∞)/ρ, m/Pa/m.

    ``compliance(q)`` is C(q) (m/Pa, q in rad/m); F(ρ) = (ρ/2π) ∫_0^∞ C(q) J1(qρ) dq is tabulated
    on n points 0 <= ρ <= ``rho_max`` spaced like a sinh (``length``/8 near 0, geometric beyond
    ``length``), by Gauss-Legendre over 0 <= q <= ``q_max`` plus, for a compliance that goes like
    ``tail``/q beyond ``q_max`` (a layer on its own: 2/E*), that tail in closed form,
    (ρ tail/2π) ∫_X^∞ J1(x)/x dx = (ρ tail/2π)(1 - ∫_0^X J0 + J1(X)), X = q_max ρ; F_∞ = C(0)/2π.
    ``reach`` (m) is the radius beyond which |F - F_∞| < ``decayed`` F_∞ on the table (or
    ``rho_max``); near(ρ) is zero beyond it.
    """
    from scipy.interpolate import CubicSpline
    from scipy.special import itj0y0, j1

    a = length / 8.0
    xi = np.linspace(0.0, np.arcsinh(rho_max / a), n)
    rho = a * np.sinh(xi)
    f_inf = float(compliance(np.array([0.0]))[0]) / (2.0 * np.pi)
    x, wx = _GAUSS[8]
    F = np.zeros(n)
    # nodes in blocks of similar radius: each block takes panels half a period of its largest rho wide (8 nodes each)
    for start in range(1, n, 40):
        block = slice(start, min(start + 40, n))
        width = min(np.pi / rho[block][-1], 0.5 / length)
        edges = np.linspace(0.0, q_max, int(np.ceil(q_max / width)) + 1)
        half = 0.5 * np.diff(edges)
        q = (0.5 * (edges[1:] + edges[:-1]))[:, None] + half[:, None] * x[None, :]
        wq = (half[:, None] * wx[None, :]).ravel()
        q = q.ravel()
        F[block] = rho[block] * (j1(np.outer(rho[block], q)) @ (compliance(q) * wq)) / (2.0 * np.pi)
    if tail:
        X = q_max * rho
        F += rho * tail * (1.0 - itj0y0(X)[0] + j1(X)) / (2.0 * np.pi)
    spline = CubicSpline(xi, F - f_inf)
    far = np.abs(F - f_inf) > decayed * f_inf
    reach = float(min(rho_max, rho[np.flatnonzero(far)[-1] + 1])) if far[-1] == 0 else float(rho_max)

    def near(r):
        r = np.asarray(r, dtype=float)
        return np.where(r < reach, spline(np.arcsinh(r / a)) / r, 0.0)

    return near, reach


def _edge_integral(near, delta, before, after, weight):
    """∫ near(ρ) (ê_ρ · n) ds along edges, each split at its closest point to the target.

    ``delta`` (m): distance of the closest point; ``before``/``after`` (m): arc length from the
    closest point to the two ends; ``weight(s)`` -> (ρ, ê_ρ · n) at the signed arc length s from
    the closest point (arrays of shape (edges, nodes)). Both sides by Gauss-Legendre in u,
    s = ± δ sinh u.
    """
    total = np.zeros(delta.shape)
    for side, length in ((-1.0, before), (1.0, after)):
        short = length < 2.0 * delta  # seen from afar: the integrand is smooth along it
        for nodes, pick in ((_FAR_NODES, short), (_NEAR_NODES, ~short)):
            idx = np.flatnonzero(pick & (length > 0))
            if idx.size == 0:
                continue
            x, wx = _GAUSS[nodes]
            top = np.arcsinh(length[idx] / delta[idx])[:, None]
            u = 0.5 * top * (x[None, :] + 1.0)
            d = delta[idx][:, None]
            s = side * d * np.sinh(u)
            rho, normal = weight(idx, s)
            total[idx] += np.sum(near(rho) * normal * d * np.cosh(u) * 0.5 * top * wx[None, :], axis=1)
    return total


def ring_influence(near, reach: float, centre_value: float, faces, n_theta: int) -> np.ndarray:
    """K[i, i', d] (m/Pa): deflection at the centre of cell (i, 0) per unit pressure on cell (i', d).

    ``faces``: the ring faces 0 = f_0 < ... < f_{n_r} = R (m); ``n_theta`` sectors; cell centres at
    the middle radius of their ring and the middle angle of their sector. ``near(ρ)`` is
    :func:`radial_primitive`'s near field, zero beyond ``reach`` (m); ``centre_value`` = C(0).
    Returns shape (n_r, n_r, n_theta), symmetric in d -> n_theta - d.
    """
    faces = np.asarray(faces, dtype=float)
    n_r = faces.size - 1
    r = 0.5 * (faces[1:] + faces[:-1])
    dth = 2.0 * np.pi / n_theta
    half = n_theta // 2
    d = np.arange(half + 1)
    K = np.zeros((n_r, n_r, half + 1))
    for i in range(n_r):  # one target ring at a time: arrays of edges x nodes stay small
        ri = r[i]
        # arcs: face k (1..n_r) of sector d, angles (d - 1/2) dth .. (d + 1/2) dth; normal e_r
        a = faces[1:, None] * np.ones((1, half + 1))
        lo = (d[None, :] - 0.5) * dth * np.ones((n_r, 1))
        hi = lo + dth
        centre = d[None, :] == 0
        psi0 = np.where(centre, 0.0, lo)  # closest point: psi = 0 on the target's sector, else the near end
        delta = np.sqrt(np.maximum(a * a + ri * ri - 2.0 * a * ri * np.cos(psi0), 0.0))
        keep = delta < reach
        ak, p0 = a[keep], psi0[keep]

        def arc(idx, s, ak=ak, p0=p0):
            psi = p0[idx][:, None] + s / ak[idx][:, None]
            rho = np.sqrt(np.maximum(ak[idx][:, None] ** 2 + ri * ri - 2.0 * ak[idx][:, None] * ri * np.cos(psi), 1e-300))
            return rho, (ak[idx][:, None] - ri * np.cos(psi)) / rho

        arcs = np.zeros(a.shape)
        arcs[keep] = _edge_integral(near, delta[keep], (ak * (p0 - lo[keep])), (ak * (hi[keep] - p0)), arc)
        # rays: angle (d + 1/2) dth (d = 0..half - 1), radius faces[k] .. faces[k+1]; normal e_psi
        psi = ((d[:-1] + 0.5) * dth)[None, :] * np.ones((n_r, 1))
        s_lo = faces[:-1, None] * np.ones((1, half))
        s_hi = faces[1:, None] * np.ones((1, half))
        s0 = np.clip(ri * np.cos(psi), s_lo, s_hi)
        delta = np.hypot(s0 * np.cos(psi) - ri, s0 * np.sin(psi))
        keep = delta < reach
        sk, ps = s0[keep], psi[keep]

        def ray(idx, s, sk=sk, ps=ps):
            t = sk[idx][:, None] + s
            c, sn = np.cos(ps[idx])[:, None], np.sin(ps[idx])[:, None]
            rho = np.sqrt(np.maximum(t * t + ri * ri - 2.0 * t * ri * c, 1e-300))
            return rho, ri * sn / rho

        rays = np.zeros(psi.shape)
        rays[keep] = _edge_integral(near, delta[keep], sk - s_lo[keep], s_hi[keep] - sk, ray)
        # cell (i', d): outer arc - inner arc + ray at (d + 1/2) dth - ray at (d - 1/2) dth
        inner = np.vstack([np.zeros((1, half + 1)), arcs[:-1]])
        ray_hi = np.hstack([rays, -rays[:, -1:]])  # the ray beyond the half turn mirrors the last one
        ray_lo = np.hstack([-rays[:, :1], rays])  # d = 0: its lower ray is the mirror of its upper
        K[i] = arcs - inner + ray_hi - ray_lo
        K[i, i, 0] += centre_value
    return np.concatenate([K, K[:, :, half - 1:0:-1]], axis=2)


def angular_modes(K: np.ndarray) -> np.ndarray:
    """The n_theta/2 + 1 angular modes of a block-circulant, offset-symmetric K[i, i', d]: real
    n_r x n_r matrices M_m = Σ_d K[:, :, d] cos(2π m d / n_theta), shape (modes, n_r, n_r)."""
    return np.ascontiguousarray(np.fft.rfft(K, axis=2).real.transpose(2, 0, 1))


def apply_modes(modes: np.ndarray, p: np.ndarray) -> np.ndarray:
    """w[i, j] = Σ_{i', d} K[i, i', d] p[i', j + d] of a cell field p (n_r, n_theta) by FFT over sectors."""
    n_theta = p.shape[-1]
    ph = np.fft.rfft(p, axis=-1).T[:, :, None]  # (modes, n_r, 1)
    wh = np.matmul(modes, ph)[:, :, 0].T
    return np.fft.irfft(wh, n=n_theta, axis=-1)
