"""Cavitation of the Newtonian slurry: Gumbel (half-Sommerfeld) and mass-conserving JFO.

Both act on the Newtonian average-flow Reynolds equation of :mod:`cmpsim.operators.reynolds` (unknown:
the gauge pressure p, Pa; p = 0 on the wafer edge). ``docs/model.md``, section "Newtonian
slurry and cavitation", gives the equations and the reasoning.

- ``"none"`` (full Sommerfeld): A p = b, the pressure may take any sign.
- ``"gumbel"``: the same p, but the pressure acting on the wafer is max(p, p_cav). Simple, and
  it violates mass conservation where p < p_cav.
- ``"jfo"`` (Jakobsson–Floberg–Olsson; Elrod, J. Lubr. Technol. 103, 350 (1981); in the
  linear-complementarity form of Giacopini, Fowell, Dini & Strozzi, J. Tribol. 132, 041702
  (2010)): unknowns p and the fill fraction theta (share of the gap filled by liquid) with

      div( -D grad p + theta q ) = 0,   p >= p_cav,  theta <= 1,  (p - p_cav)(1 - theta) = 0,

  q = u_m h + (sigma/2) Phi^s du the Couette-type flux of :func:`cmpsim.operators.reynolds.lubrication_coefficients`.
  Finite volumes on the polar grid: the diffusive part is the matrix A of
  :func:`cmpsim.operators.reynolds.assemble_operator`, the convective part carries theta upwinded on
  each face (theta of the cell the Couette flux leaves; theta = 1 for flux entering through
  the flooded wafer edge). With r = 1 - theta the system reads

      A p - B r = b,   p - p_cav >= 0,  r >= 0,  (p - p_cav) r = 0

  where B is the upwinded Couette matrix and b = -div q the right-hand side of the
  full-film problem: with r = 0 it *is* the full-film system, so the solution is unchanged
  wherever nothing cavitates. It is solved by a primal-dual active-set (semismooth Newton on
  min(p - p_cav, r) = 0) iteration: on the cavitated set C the unknown is r (p = p_cav), on
  the rest it is p (r = 0); each step is one sparse solve with the columns of A on the full
  film and those of -B on C; C is updated from the signs and the iteration stops when C
  repeats. The mixed matrix is a Z-matrix with positive diagonal (both A, without
  cross-diffusion, and the upwind B are), for which the iteration is monotone and terminates
  in finitely many steps (Hintermüller, Ito & Kunisch, SIAM J. Optim. 13, 865 (2002)).
"""

from __future__ import annotations

import numpy as np
import scipy.sparse as sp

from ..numerics.grid import PolarGrid
from .reynolds import FaceCoefficients, assemble_operator, face_fluxes, factorize, flux_divergence

__all__ = [
    "CAVITATION_MODELS",
    "VACUUM_GAUGE_PRESSURE",
    "CavitationError",
    "upwind_couette_matrix",
    "reduced_matrix",
    "solve_complementarity",
    "CavitationSystem",
]

#: Cavitation treatments of the Newtonian slurry.
CAVITATION_MODELS = ("none", "gumbel", "jfo")

#: Gauge pressure of absolute vacuum, Pa (one standard atmosphere below ambient): the lowest
#: admissible cavitation pressure.
VACUUM_GAUGE_PRESSURE = -101325.0


class CavitationError(RuntimeError):
    """The active-set iteration of the JFO problem did not settle."""


def upwind_couette_matrix(grid: PolarGrid, coeffs: FaceCoefficients, direction: FaceCoefficients | None = None) -> tuple[sp.csr_matrix, np.ndarray]:
    """The Couette flux of the fill fraction theta, upwinded: ``(B, c)`` with B theta + c, m^3/s.

    ``(B @ theta + c)[P]`` is the sum over the faces of cell P of the outward Couette flux
    (q . n L from :func:`cmpsim.operators.reynolds.face_fluxes`) times theta upwind: theta of P where
    the flux leaves P, of the neighbour where it enters. Through the wafer edge, flux that
    enters carries theta = 1 (the edge is flooded), which is the constant vector ``c``.
    With theta = 1 everywhere, ``B @ 1 + c`` is :func:`cmpsim.operators.reynolds.flux_divergence` (to
    round-off: the same face fluxes summed in another order).

    ``direction`` (optional): the face coefficients whose flux signs choose the upwind cell
    (default ``coeffs``). With it, ``(B, c)`` is linear in ``coeffs``: the derivative of the
    upwinded flux of ``direction`` in the direction ``coeffs``, exact wherever no face flux
    changes sign (used by the coupled solve of a compliant pad, :mod:`cmpsim.operators.compliance`).
    """
    n_r, n_t = grid.n_r, grid.n_theta
    fr, fa = face_fluxes(grid, coeffs)
    sr, sa = (fr, fa) if direction is None else face_fluxes(grid, direction)
    i = np.arange(n_r)[:, None] * np.ones((1, n_t), dtype=int)
    j = np.arange(n_t)[None, :] * np.ones((n_r, 1), dtype=int)
    P = grid.index(i, j)
    rows, cols, vals = [], [], []

    def face(p, n, flux, sign_flux):
        # flux > 0 leaves p towards n: carried by theta_p; else by theta_n
        up = np.where(sign_flux > 0, p, n)
        for row, sign in ((p, 1.0), (n, -1.0)):
            rows.append(row.ravel())
            cols.append(up.ravel())
            vals.append(sign * flux.ravel())

    interior = i < n_r - 1
    face(P[interior], grid.index(i[interior] + 1, j[interior]), fr[interior], sr[interior])
    face(P, grid.index(i, j + 1), fa, sa)
    edge = ~interior
    leaves = sr[edge] > 0
    rows.append(P[edge].ravel())
    cols.append(P[edge].ravel())
    vals.append(np.where(leaves, fr[edge], 0.0).ravel())
    c = np.zeros(grid.size)
    c[P[edge].ravel()] = np.where(leaves, 0.0, fr[edge]).ravel()
    B = sp.csr_matrix((np.concatenate(vals), (np.concatenate(rows), np.concatenate(cols))), shape=(grid.size, grid.size))
    return B, c


def reduced_matrix(A: sp.spmatrix, B: sp.spmatrix, cavitated: np.ndarray) -> sp.csr_matrix:
    """Columns of A on the full-film cells and of -B on the cavitated ones (``cavitated`` mask)."""
    cav = np.asarray(cavitated, dtype=float).ravel()
    return (A @ sp.diags(1.0 - cav) - B @ sp.diags(cav)).tocsr()


def solve_complementarity(A, B, rhs, p_cav: float, cavitated=None, max_iter: int = 200, solver=None):
    """Primal-dual active-set solution of A p - B r = rhs, p >= p_cav, r >= 0, (p - p_cav) r = 0.

    Parameters
    ----------
    A, B : sparse matrices (N x N)
        Diffusion operator (per Pa) and upwinded Couette matrix of the fill fraction
        (:func:`upwind_couette_matrix`), m^3/(Pa s) and m^3/s.
    rhs : array (N,)
        Right-hand side of the full-film problem A p = rhs, m^3/s.
    p_cav : float
        Cavitation pressure (gauge), Pa.
    cavitated : bool array (N,), optional
        Initial cavitated set; default: where the full-film solution is below p_cav.
    max_iter : int
        Active-set updates allowed.
    solver : callable, optional
        ``solver(M)`` returning an object with ``.solve(b)``; default
        :func:`cmpsim.operators.reynolds.factorize`.

    Returns
    -------
    p, r : numpy.ndarray
        Pressure (Pa, exactly p_cav on the cavitated set) and 1 - theta (exactly 0 off it).
    cavitated : numpy.ndarray of bool
        The final cavitated set C.
    factor
        Factorisation of the final reduced matrix (:func:`reduced_matrix`), for sensitivities.
    iterations : int
        Sparse solves used.

    Raises
    ------
    CavitationError
        If the set has not settled after ``max_iter`` updates (it cycles).
    """
    solver = solver or factorize
    rhs = np.asarray(rhs, dtype=float).ravel()
    n = rhs.size
    seen = set()
    if cavitated is None:
        factor = solver(A)
        p = factor.solve(rhs)
        cav = p < p_cav
        if not cav.any():
            return p, np.zeros(n), cav, factor, 1
        it = 1
    else:
        cav = np.asarray(cavitated, dtype=bool).ravel().copy()
        it = 0
    while True:
        key = cav.tobytes()
        if key in seen or it > max_iter:
            raise CavitationError(
                f"the cavitated set of the JFO problem did not settle after {it} active-set steps "
                f"({int(cav.sum())} of {n} cells cavitated)"
            )
        seen.add(key)
        M = reduced_matrix(A, B, cav)
        factor = solver(M)
        w = factor.solve(rhs - A @ np.where(cav, p_cav, 0.0))
        it += 1
        p = np.where(cav, p_cav, w)
        r = np.where(cav, w, 0.0)
        new = np.where(cav, r > 0.0, p < p_cav)
        if np.array_equal(new, cav):
            return p, r, cav, factor, it
        cav = new


class CavitationSystem:
    """The discrete JFO problem on a grid for given face coefficients (Newtonian slurry).

    The unknown vector w holds p (Pa) on the full-film cells and r = 1 - theta on the
    cavitated ones. Constructed with ``cavitated=None`` it solves the complementarity
    problem (:func:`solve_complementarity`); with a given set it only builds the reduced
    linear system on that frozen set (used by the equilibrium Jacobian: the derivative of the
    solution at fixed set is dw = -M^-1 (M' w - b')).

    Parameters
    ----------
    grid : PolarGrid
    coeffs : FaceCoefficients
        Newtonian face coefficients (:func:`cmpsim.operators.reynolds.lubrication_coefficients`).
    p_cav : float
        Cavitation pressure (gauge), Pa (<= 0).
    cavitated : bool array, optional
        Frozen cavitated set (flattened or shaped like the grid).
    solver : callable, optional
        ``solver(A)`` returning an object with ``.solve(b)``.
    guess : bool array, optional
        Starting cavitated set of the active-set iteration (e.g. that of a neighbouring film);
        the solution does not depend on it, the cost does. If the iteration does not settle
        from it, it is restarted from the full-film solution.
    """

    def __init__(self, grid: PolarGrid, coeffs: FaceCoefficients, p_cav: float, cavitated=None, solver=None, guess=None):
        self.grid = grid
        self.coeffs = coeffs
        self.p_cav = float(p_cav)
        self.diffusion = assemble_operator(grid, coeffs)
        self.couette, self.edge_inflow = upwind_couette_matrix(grid, coeffs)
        self.full_film_rhs = -flux_divergence(grid, coeffs)
        self._solver = solver or factorize
        self._factor = None
        self.iterations = 0
        self._w = None
        if cavitated is None:
            args = (self.diffusion, self.couette, self.full_film_rhs, self.p_cav)
            try:
                p, r, cav, factor, it = solve_complementarity(*args, cavitated=guess, solver=self._solver)
            except CavitationError:
                if guess is None:
                    raise
                p, r, cav, factor, it = solve_complementarity(*args, solver=self._solver)
            self._factor, self.iterations = factor, it
            self._w = np.where(cav, r, p)
        else:
            cav = np.asarray(cavitated, dtype=bool).ravel()
        self.cavitated = cav
        self.matrix = reduced_matrix(self.diffusion, self.couette, cav)
        self.rhs = self.full_film_rhs - self.diffusion @ np.where(cav, self.p_cav, 0.0)

    @property
    def factor(self):
        """Factorisation of the reduced matrix (computed on first use if not already)."""
        if self._factor is None:
            self._factor = self._solver(self.matrix)
            self.iterations += 1
        return self._factor

    def solve(self) -> np.ndarray:
        """The unknown w (p on the full film, 1 - theta on the cavitated set), shape (n_r, n_theta)."""
        if self._w is None:
            self._w = self.factor.solve(self.rhs)
        return np.asarray(self._w).reshape(self.grid.n_r, self.grid.n_theta)

    def residual(self, w) -> np.ndarray:
        """M w - b on the frozen set, m^3/s."""
        return self.matrix @ np.asarray(w).ravel() - self.rhs

    def fields(self, w) -> tuple[np.ndarray, np.ndarray]:
        """Pressure p (Pa) and fill fraction theta of an unknown vector w, shaped like the grid."""
        w = np.asarray(w).reshape(self.grid.n_r, self.grid.n_theta)
        cav = self.cavitated.reshape(w.shape)
        return np.where(cav, self.p_cav, w), np.where(cav, 1.0 - w, 1.0)

    def mass_residual(self, p, theta) -> np.ndarray:
        """Net outward mass flux of each cell, A p + B theta + c, m^3/s (0 at a solution)."""
        return self.diffusion @ np.asarray(p).ravel() + self.couette @ np.asarray(theta).ravel() + self.edge_inflow

    def boundary_flux(self, p, theta) -> float:
        """Net volume flux out through the wafer edge, m^3/s: the sum of :meth:`mass_residual`
        (interior faces cancel), 0 for a mass-conserving solution."""
        return float(np.sum(self.mass_residual(p, theta)))
