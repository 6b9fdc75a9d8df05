"""The wafer as a Kirchhoff plate with a free edge, discretised on the polar grid.

A thin plate of bending stiffness D = E t^3 / (12 (1 - nu^2)) under a normal load q (Pa, in
the direction of the deflection w), optionally resting on a local (Winkler) foundation of
stiffness k (Pa/m), obeys (Timoshenko & Woinowsky-Krieger, *Theory of Plates and Shells*,
2nd ed. 1959, eq. 101 and sections 61-62)

    D del^4 w + k w = q,

with the free-edge conditions at the rim r = a (no bending moment, no Kirchhoff shear):

    M_r = -D [w_rr + nu (w_r / r + w_thth / r^2)] = 0,
    V_r = -D [(del^2 w)_r + (1 - nu) (1/r) d/dth (w_rth / r - w_th / r^2)] = 0.

Discretisation (docs/model.md, "Carrier"). The grid's cells are equally spaced in theta, so the
load is split into Fourier modes cos n theta, sin n theta (a real FFT over the sectors, exact);
each mode n is a radial problem solved in mixed form, m = del_n^2 w:

    del_n^2 w - m = 0,      D del_n^2 m + k w = q_n,      del_n^2 f = (r f')'/r - n^2 f / r^2,

by cell-centred finite volumes on the grid's rings (fluxes r f' on the faces, zero on the
centre face, second order). At the rim the slope s = w'(a) and the value w_a are unknowns:
w_a = w_N + (a - r_N) s, the flux of m is a m'(a) with m'(a) = (1 - nu) n^2 (a s - w_a) / a^3
(V_r = 0), and m_N + (a - r_N) m'(a) = (1 - nu)(s / a - n^2 w_a / a^2) (M_r = 0). With this
closure the sum of the m-equations weighted by r^n is exactly the load's force (n = 0) or
moment (n = 1): the free plate's solvability conditions are the discrete force and moment
balances of :mod:`cmpsim.solver.equilibrium` (sum of p dA, sum of p x dA, sum of p y dA), to round-off.

Without a foundation the free plate moves as a rigid body (w = const, w = r cos theta,
r sin theta); those modes are the carrier's unknowns (h0 and the tilts), not the plate's. The
plate therefore returns the bending part only, orthogonal to them (sum of w dA = 0, sum of
w x dA = sum of w y dA = 0), under the load minus its rigid-body part (inertia relief: the load
is balanced by the uniform and linear load that a free body's acceleration would give). That
part, the ``relief`` of :class:`PlateDeflection`, vanishes exactly when the load is in force
and moment balance.
"""

from __future__ import annotations

from dataclasses import dataclass
from functools import cached_property

import numpy as np
import scipy.sparse as sp

from .grid import PolarGrid
from ..physics.padstack import plate_bending_stiffness
from .sparse import factorize

__all__ = ["bending_stiffness", "KirchhoffPlate", "PlateDeflection", "PlateOperator", "zone_load"]


def bending_stiffness(thickness, modulus, poisson):
    """Flexural rigidity D = E t^3 / (12 (1 - nu^2)) of a thin plate, N m (t in m, E in Pa).

    Timoshenko & Woinowsky-Krieger (1959), eq. 3; the kernel :func:`cmpsim.physics.padstack.plate_bending_stiffness`.
    """
    return plate_bending_stiffness(thickness, modulus, poisson)


def zone_load(grid: PolarGrid, radii, pressures) -> np.ndarray:
    """Cell field (Pa, shape (n_r, n_theta)) of concentric pressure zones behind the wafer.

    Zone k presses ``pressures[k]`` (Pa) on R_{k-1} < r < R_k, ``radii`` = (R_1, ..., R_n) in m,
    R_0 = 0. A ring of cells cut by a zone boundary takes the area-weighted mean of the zones
    it holds (the exact overlap of the annuli), so the field's integral is the membrane's load
    sum P_k pi (R_k^2 - R_{k-1}^2) exactly, however the boundaries fall on the grid.
    """
    outer = np.asarray(grid.radial_faces[2], dtype=float)[:, 0] / grid.dtheta
    inner = np.concatenate([[0.0], outer[:-1]])
    edges = np.concatenate([[0.0], np.asarray(radii, dtype=float)])
    lo = np.maximum(inner[:, None], edges[None, :-1])
    hi = np.minimum(outer[:, None], edges[None, 1:])
    overlap = np.clip(hi * hi - lo * lo, 0.0, None)  # (rings, zones), times pi
    ring = overlap @ np.asarray(pressures, dtype=float) / (outer * outer - inner * inner)
    return np.broadcast_to(ring[:, None], (grid.n_r, grid.n_theta)).copy()


@dataclass(frozen=True)
class KirchhoffPlate:
    """A thin elastic plate: thickness (m), Young's modulus (Pa), Poisson ratio."""

    thickness: float
    modulus: float
    poisson: float

    def __post_init__(self) -> None:
        t, e, nu = self.thickness, self.modulus, self.poisson
        for name, value, valid, ok in (
            ("wafer_thickness", t, "finite and > 0 m", np.isfinite(t) and t > 0),
            ("wafer_modulus", e, "finite and > 0 Pa", np.isfinite(e) and e > 0),
            ("wafer_poisson", nu, "in [0, 0.5)", 0.0 <= nu < 0.5),
        ):
            if not ok:
                raise ValueError(f"{name} must be {valid}; got {value!r}")

    @property
    def bending_stiffness(self) -> float:
        """D = E t^3 / (12 (1 - nu^2)), N m."""
        return float(bending_stiffness(self.thickness, self.modulus, self.poisson))

    def bending_length(self, foundation_stiffness: float) -> float:
        """ell = (D / k)^(1/4), m: the length over which the plate on a foundation k (Pa/m) bends."""
        return (self.bending_stiffness / foundation_stiffness) ** 0.25


@dataclass(frozen=True)
class PlateDeflection:
    """The plate's answer to one load: cell fields of shape (n_r, n_theta).

    ``deflection`` w (m), in the direction of the load. Without a foundation it is the bending
    alone (no mean, no mean tilt) and ``relief`` (Pa) is the rigid-body part of the load that
    was taken away: c0 + c1 x + c2 y, the least-squares fit of the load by uniform and linear
    loads, zero when the load is in force and moment balance. On a foundation ``relief`` is 0.
    """

    deflection: np.ndarray
    relief: np.ndarray


class PlateOperator:
    """The discrete free-edge plate of ``plate`` on ``grid``, on a foundation of ``foundation_stiffness`` (Pa/m, 0 = none).

    Built once (one sparse LU of all the Fourier modes' radial systems); :meth:`solve` costs
    one real FFT over the sectors and one back-substitution.
    """

    def __init__(self, plate: KirchhoffPlate, grid: PolarGrid, foundation_stiffness: float = 0.0):
        if not (np.isfinite(foundation_stiffness) and foundation_stiffness >= 0):
            raise ValueError(f"foundation stiffness must be finite and >= 0 Pa/m; got {foundation_stiffness!r}")
        self.plate, self.grid, self.k = plate, grid, float(foundation_stiffness)
        self.d = plate.bending_stiffness
        n_r = grid.n_r
        self.r = np.asarray(grid.r, dtype=float).ravel()  # cell centres
        self.faces = np.asarray(grid.radial_faces[2], dtype=float)[:, 0] / grid.dtheta  # outer face radii
        self.a = float(self.faces[-1])
        self.area = np.asarray(grid.area, dtype=float)[:, 0] / grid.dtheta  # per unit angle, r dr
        self.modes = np.arange(grid.n_theta // 2 + 1)
        blocks, self.offsets = [], []
        offset = 0
        for n in self.modes:
            block = self._mode_matrix(int(n))
            blocks.append(block)
            self.offsets.append(offset)
            offset += block.shape[0]
        self.size = offset
        self._lu = factorize(sp.block_diag(blocks, format="csc"))  # cmpsim's one guarded sparse LU
        self._n_r = n_r

    # ------------------------------------------------------------------ assembly
    def _relieved(self, n: int) -> bool:
        return self.k == 0.0 and n <= 1

    def _mode_matrix(self, n: int) -> sp.csr_matrix:
        """Radial system of mode n: unknowns [w_0..w_N-1, m_0..m_N-1, w_a, s(, lambda)], rows likewise."""
        N, r, rf, A, a = self.grid.n_r, self.r, self.faces, self.area, self.a
        nu = self.plate.poisson
        iw, im, ia, isl = np.arange(N), N + np.arange(N), 2 * N, 2 * N + 1
        size = 2 * N + 2 + (1 if self._relieved(n) else 0)
        rows, cols, vals = [], [], []

        def add(i, j, v):
            i, j, v = np.broadcast_arrays(np.atleast_1d(i), np.atleast_1d(j), np.asarray(v, dtype=float))
            rows.append(i.ravel())
            cols.append(j.ravel())
            vals.append(v.ravel())

        # interior face fluxes r_f (f_{i+1} - f_i) / (r_{i+1} - r_i) of both fields
        coef = rf[:-1] / (r[1:] - r[:-1])
        for base in (iw, im):
            lo, hi = base[:-1], base[1:]
            add(lo, hi, coef)
            add(lo, lo, -coef)
            add(hi, lo, coef)
            add(hi, hi, -coef)
            add(base, base, -n * n * A / r**2)
        # w-rows: integral of del^2 w - m; rim flux a s
        add(iw, im, -A)
        add(iw[-1], isl, a)
        # m-rows: integral of del^2 m + (k / D) w = q / D; rim flux a m'(a), m'(a) = g (a s - w_a)
        g = (1.0 - nu) * n * n / a**3
        add(im[-1], isl, a * g * a)
        add(im[-1], ia, -a * g)
        if self.k:
            add(im, iw, self.k / self.d * A)
        # rim value: w_a = w_N + (a - r_N) s
        add(ia, iw[-1], 1.0)
        add(ia, isl, a - r[-1])
        add(ia, ia, -1.0)
        # M_r = 0: m_N + (a - r_N) m'(a) - (1 - nu)(s / a - n^2 w_a / a^2) = 0
        add(isl, im[-1], 1.0)
        add(isl, isl, (a - r[-1]) * g * a - (1.0 - nu) / a)
        add(isl, ia, -(a - r[-1]) * g + (1.0 - nu) * n * n / a**2)
        if self._relieved(n):  # inertia relief: load shape r^n A on the m-rows, w orthogonal to r^n
            il = 2 * N + 2
            shape = A * r**n
            add(im, il, shape)
            add(il, iw, shape)
        return sp.csr_matrix((np.concatenate(vals), (np.concatenate(rows), np.concatenate(cols))), shape=(size, size))

    # ------------------------------------------------------------------ solve
    def solve(self, load) -> PlateDeflection:
        """Deflection (m) and removed rigid-body load (Pa) under a cell load field ``load`` (Pa, shape (n_r, n_theta))."""
        q = np.asarray(load, dtype=float).reshape(self.grid.n_r, self.grid.n_theta)
        n_t, N = self.grid.n_theta, self.grid.n_r
        qhat = np.fft.rfft(q, axis=1)  # (N, modes)
        rhs = np.zeros((self.size, 2))
        for n, off in zip(self.modes, self.offsets):
            b = qhat[:, n] * self.area / self.d
            rhs[off + N : off + 2 * N, 0] = b.real
            rhs[off + N : off + 2 * N, 1] = b.imag
        x = self._lu.solve(rhs)
        what = np.empty((N, len(self.modes)), dtype=complex)
        lam = np.zeros(2, dtype=complex)
        for n, off in zip(self.modes, self.offsets):
            what[:, n] = x[off : off + N, 0] + 1j * x[off : off + N, 1]
            if self._relieved(int(n)):
                lam[n] = (x[off + 2 * N + 2, 0] + 1j * x[off + 2 * N + 2, 1]) * self.d
        w = np.fft.irfft(what, n=n_t, axis=1)
        relief = np.zeros_like(q)
        if self.k == 0.0:
            rhat = np.zeros((N, len(self.modes)), dtype=complex)
            rhat[:, 0] = lam[0]
            rhat[:, 1] = lam[1] * self.r
            relief = np.fft.irfft(rhat, n=n_t, axis=1)
        return PlateDeflection(w, relief)

    def deflection(self, load) -> np.ndarray:
        """The deflection (m) of :meth:`solve` alone."""
        return self.solve(load).deflection

    @cached_property
    def rigid_modes(self) -> np.ndarray:
        """The plate's rigid-body modes 1, x, y at the cell centres, shape (3, n_r, n_theta)."""
        x, y = self.grid.centres
        return np.stack([np.ones_like(x), x, y])
