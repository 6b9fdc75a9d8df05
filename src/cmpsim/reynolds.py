"""Average-flow Reynolds equation (paper eq. 5, and its Newtonian limit) on the polar wafer grid.

In the form settled in ``docs/model.md`` (section "Reynolds equation"), with
phi = ln(p / p0) and p0 the ambient granular pressure at the wafer edge,

    div( D grad phi ) = div( q ),      phi = 0 on r = R_w,

    D = (1/6) (t/a) v Psi(h/d) h^2 Phi^p        (m^3/s, symmetric positive-definite tensor)
    q = u_m h + (sigma/2) Phi^s (u_pad - u_wafer)  (m^2/s)

with u_m the mean surface velocity and v the granular fluctuation velocity (constant B of
eq. 5). The equation is linear in phi, so one sparse solve gives the pressure for a given
film; the film enters only through the coefficients.

The Newtonian slurry (``slurry_model="newtonian"``, ``docs/model.md`` section "Newtonian
slurry and cavitation") is the same operator with the gauge pressure p (Pa) as unknown,

    div( h^3/(12 eta) Phi^p grad p ) = div( q ),      p = 0 on r = R_w,

and the flow factors at the Newtonian limit x = sqrt(w/k) h/d -> 0 of the grain-flow ones
(f = g = 3). It is exactly the x -> 0 limit of D/p above with the Haff viscosity
eta = (a/t) p d / v held constant, since Psi -> h/(2d).

Discretisation: conservative cell-centred finite volumes on :class:`cmpsim.grid.PolarGrid`;
two-point normal gradients, cross-gradient (off-diagonal tensor) terms from averaged central
differences, the Dirichlet edge at half a cell from the last centres. The observed order is
2 (``tests/test_reynolds.py``, manufactured solutions). Solved with a sparse LU
(``scipy.sparse.linalg.splu``); any callable ``solver(A) -> object with .solve(b)`` can be
injected.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import scipy.sparse as sp
import scipy.sparse.linalg as spla

from .flowfactors import RoughnessGeometry, pressure_flow_factors, regularize_pressure_tensor, shear_flow_factors
from .grainflow import grain_coefficients
from .grid import PolarGrid
from .kinematics import Kinematics

__all__ = [
    "SLURRY_MODELS",
    "NEWTONIAN_GRAIN_COEFFICIENT",
    "LubricationParameters",
    "FaceCoefficients",
    "lubrication_coefficients",
    "assemble_operator",
    "face_fluxes",
    "flux_divergence",
    "ReynoldsSystem",
    "factorize",
]


#: Slurry rheologies: Haff grain flow (the paper, solved in ln p) or a Newtonian liquid (in p).
SLURRY_MODELS = ("granular", "newtonian")

#: The grain-size coefficients f and g at x = sqrt(w/k) h/d -> 0 (eq. 18-19), used by the
#: Newtonian slurry: isotropic roughness then gives Tripp's Phi^p = 1 - 1.5 (sigma/h)^2.
NEWTONIAN_GRAIN_COEFFICIENT = 3.0


@dataclass(frozen=True)
class LubricationParameters:
    """Inputs of the Reynolds coefficients (all SI).

    Attributes
    ----------
    particle_diameter : float
        d, m.
    w_over_k : float
        Haff's w/k, dimensionless.
    t_over_a : float
        Haff's t/a, dimensionless.
    fluctuation_velocity : float
        v (the constant B of eq. 5), m/s.
    roughness : RoughnessGeometry
    kinematics : Kinematics
    flow_factor_floor : float
        Smallest eigenvalue of Phi^p allowed to reach the solver, dimensionless (> 0).
    slurry_model : {"granular", "newtonian"}
        Haff grain flow (unknown ln(p/p0), the paper) or a Newtonian liquid (unknown: gauge p).
    viscosity : float
        Newtonian viscosity eta, Pa s (> 0); used only by the Newtonian slurry.
    """

    particle_diameter: float
    w_over_k: float
    t_over_a: float
    fluctuation_velocity: float
    roughness: RoughnessGeometry
    kinematics: Kinematics
    flow_factor_floor: float = 0.05
    slurry_model: str = "granular"
    viscosity: float = 5e-3

    def __post_init__(self) -> None:
        if self.slurry_model not in SLURRY_MODELS:
            raise ValueError(f"slurry_model must be one of {SLURRY_MODELS}; got {self.slurry_model!r}")
        if not (np.isfinite(self.viscosity) and self.viscosity > 0):
            raise ValueError(f"slurry_viscosity must be finite and > 0 Pa s (valid range: (0, inf)); got {self.viscosity!r}")


@dataclass
class FaceCoefficients:
    """Diffusion tensor (D_xx, D_xy, D_yy; m^3/s) and flux vector (q_x, q_y; m^2/s) on faces.

    ``radial`` and ``angular`` hold 5-tuples (dxx, dxy, dyy, qx, qy) of arrays shaped like
    the grid; ``floored`` counts faces whose flow-factor tensor was regularised.
    """

    radial: tuple
    angular: tuple
    floored: int = 0
    n_faces: int = 0


def lubrication_coefficients(h, x, y, params: LubricationParameters):
    """Reynolds coefficients at points (x, y) with film thickness h (all m).

    Returns ``(dxx, dxy, dyy, qx, qy, floored)``: the diffusion tensor D with the regularised
    pressure flow-factor tensor (eq. 8–10), the flux vector q = u_m h + (sigma/2) Phi^s du
    (m^2/s, eq. 11–13) and the boolean mask of regularised points. For the granular slurry
    D = (1/6)(t/a) v Psi h^2 Phi^p (m^3/s, multiplies grad ln p); for the Newtonian slurry
    D = h^3/(12 eta) Phi^p (m^4/(Pa s), multiplies grad p) with f = g = 3 in the flow factors.
    Raises ValueError if any film thickness is not finite and > 0.
    """
    h = np.asarray(h, dtype=float)
    if not np.all(np.isfinite(h)) or np.any(h <= 0):
        raise ValueError("film thickness must be finite and > 0 m everywhere on the wafer (the wafer touches the pad mean plane)")
    rough = params.roughness
    hs = h / rough.sigma
    if params.slurry_model == "newtonian":
        f = g = np.full(h.shape, NEWTONIAN_GRAIN_COEFFICIENT)
    else:
        psi, f, g = grain_coefficients(h / params.particle_diameter, params.w_over_k)
    pxx, pxy, pyy = pressure_flow_factors(hs, f, g, rough)
    pxx, pxy, pyy, floored = regularize_pressure_tensor(pxx, pxy, pyy, params.flow_factor_floor)
    if params.slurry_model == "newtonian":
        c = h * h * h / (12.0 * params.viscosity)
    else:
        c = params.t_over_a * params.fluctuation_velocity * psi * h * h / 6.0
    sxx, sxy, syy = shear_flow_factors(hs, f, rough)
    umx, umy, dux, duy = params.kinematics.mean_and_relative(x, y)
    half_sigma = 0.5 * rough.sigma
    qx = umx * h + half_sigma * (sxx * dux + sxy * duy)
    qy = umy * h + half_sigma * (sxy * dux + syy * duy)
    return c * pxx, c * pxy, c * pyy, qx, qy, floored


def _polar_components(dxx, dxy, dyy, theta_n):
    """Components of D in the (n, t) frame with normal at angle theta_n: (D_nn, D_nt)."""
    c, s = np.cos(theta_n), np.sin(theta_n)
    d_nn = c * c * dxx + 2.0 * s * c * dxy + s * s * dyy
    # t = e_theta = (-s, c)
    d_nt = -s * c * dxx + (c * c - s * s) * dxy + s * c * dyy
    return d_nn, d_nt


def assemble_operator(grid: PolarGrid, coeffs: FaceCoefficients) -> sp.csr_matrix:
    """Matrix A with (A phi)_P = sum over faces of P of the outward flux -D grad(phi) . n L.

    For a symmetric positive-definite D it is an M-matrix (without cross terms), singular
    only without the Dirichlet edge. Units: m^3/s (flux per unit phi).
    """
    n_r, n_t, dr, dth = grid.n_r, grid.n_theta, grid.dr, grid.dtheta
    rows, cols, vals = [], [], []
    i = np.arange(n_r)[:, None] * np.ones((1, n_t), dtype=int)
    j = np.arange(n_t)[None, :] * np.ones((n_r, 1), dtype=int)
    P = grid.index(i, j)

    def add(p, n, col, w):
        rows.append(p.ravel())
        cols.append(col.ravel())
        vals.append(w.ravel())
        if n is not None:
            rows.append(n.ravel())
            cols.append(col.ravel())
            vals.append(-w.ravel())

    # ---- radial faces (outer face of each cell) ----
    dxx, dxy, dyy = coeffs.radial[:3]
    _, _, length = grid.radial_faces
    d_rr, d_rt = _polar_components(dxx, dxy, dyy, grid.theta)
    rf = (i + 1.0) * dr
    interior = i < n_r - 1
    Pi, Ni = P[interior], grid.index(i[interior] + 1, j[interior])
    Li, drr, drt = length[interior], d_rr[interior], d_rt[interior]
    add(Pi, Ni, Ni, -drr / dr * Li)
    add(Pi, Ni, Pi, drr / dr * Li)
    ii, jj = i[interior], j[interior]
    wt = -drt * Li / (4.0 * dth * rf[interior])
    for di in (0, 1):
        add(Pi, Ni, grid.index(ii + di, jj + 1), wt)
        add(Pi, Ni, grid.index(ii + di, jj - 1), -wt)
    edge = ~interior
    Pe = P[edge]
    add(Pe, None, Pe, d_rr[edge] * length[edge] / (0.5 * dr))

    # ---- angular faces (counter-clockwise face of each cell) ----
    dxx, dxy, dyy = coeffs.angular[:3]
    theta_f = (j + 1.0) * dth
    d_tt, d_tr = _polar_components(dxx, dxy, dyy, theta_f + 0.5 * np.pi)
    # D_tr with n = e_theta, t = -e_r: flip sign to get e_theta . D . e_r
    d_tr = -d_tr
    La = np.full(P.shape, dr)
    N = grid.index(i, j + 1)
    r_c = (i + 0.5) * dr
    add(P, N, N, -d_tt / (r_c * dth) * La)
    add(P, N, P, d_tt / (r_c * dth) * La)
    (ca, wa), (cb, wb) = grid.radial_derivative_stencil
    for jj_shift in (0, 1):
        sel = np.roll(np.arange(n_t), -jj_shift)  # cell (i, j + shift)
        for c_arr, w_arr in ((ca, wa), (cb, wb)):
            add(P, N, c_arr[:, sel], -0.5 * d_tr * w_arr[:, sel] * La)

    return _to_csr(grid, rows, cols, np.concatenate(vals))


_PATTERNS: dict = {}


def _to_csr(grid: PolarGrid, rows, cols, vals) -> sp.csr_matrix:
    """Sum the COO entries into CSR; the pattern depends on the grid only and is cached."""
    pattern = _PATTERNS.get(grid)
    if pattern is None or pattern[0] != len(vals):
        r = np.concatenate(rows)
        c = np.concatenate(cols)
        keys, inverse = np.unique(r.astype(np.int64) * grid.size + c, return_inverse=True)
        indptr = np.searchsorted(keys // grid.size, np.arange(grid.size + 1))
        pattern = (len(vals), inverse, (keys % grid.size).astype(np.int32), indptr.astype(np.int32), len(keys))
        if len(_PATTERNS) > 16:
            _PATTERNS.clear()
        _PATTERNS[grid] = pattern
    _, inverse, indices, indptr, nnz = pattern
    data = np.bincount(inverse, weights=vals, minlength=nnz)
    return sp.csr_matrix((data, indices.copy(), indptr.copy()), shape=(grid.size, grid.size))


def face_fluxes(grid: PolarGrid, coeffs: FaceCoefficients) -> tuple[np.ndarray, np.ndarray]:
    """Integrated flux q . n L through each cell's faces, m^3/s, each of shape (n_r, n_theta).

    Returns ``(fr, fa)``: ``fr[i, j]`` through the outer radial face of cell (i, j) (outward
    from it; for the last ring, out of the wafer), ``fa[i, j]`` through its counter-clockwise
    angular face (towards cell (i, j + 1)).
    """
    n_t = grid.n_theta
    qx, qy = coeffs.radial[3:5]
    # integral of the outward normal over the arc r = r_f, |theta - theta_j| < dtheta/2 is
    # 2 r_f sin(dtheta/2) e_r(theta_j): with it the normals of a cell sum exactly to zero, so
    # a uniform flux field has exactly zero divergence (free-stream preservation)
    rf = (np.arange(grid.n_r) + 1.0)[:, None] * grid.dr
    lr = 2.0 * rf * np.sin(0.5 * grid.dtheta)
    c, s = np.cos(grid.theta), np.sin(grid.theta)
    fr = (qx * c + qy * s) * lr  # outward through the outer face of (i, j)
    qx, qy = coeffs.angular[3:5]
    tf = (np.arange(n_t) + 1.0)[None, :] * grid.dtheta
    fa = (-qx * np.sin(tf) + qy * np.cos(tf)) * grid.dr  # through the ccw face of (i, j)
    return fr, fa


def flux_divergence(grid: PolarGrid, coeffs: FaceCoefficients) -> np.ndarray:
    """Sum over the faces of each cell of the outward flux q . n L, m^3/s, shape (size,)."""
    fr, fa = face_fluxes(grid, coeffs)
    div = fr.copy()
    div[1:, :] -= fr[:-1, :]
    div += fa - np.roll(fa, 1, axis=1)
    return div.ravel()


def factorize(A: sp.spmatrix):
    """Default sparse direct solver: SuperLU factorisation of A (CSC), with ``.solve(b)``.

    The operator's sparsity pattern is symmetric, so a minimum-degree ordering of A^T + A
    fills in least (3x faster than the default COLAMD on the default grid).
    """
    return spla.splu(A.tocsc(), permc_spec="MMD_AT_PLUS_A")


class ReynoldsSystem:
    """The discrete Reynolds problem A(h) phi = b(h) on a grid, for given face coefficients.

    Parameters
    ----------
    grid : PolarGrid
    coeffs : FaceCoefficients
    source : array_like, optional
        Extra integrated source per cell (m^3/s), added to the right-hand side; used by the
        manufactured-solution tests.
    solver : callable, optional
        ``solver(A)`` returning an object with ``.solve(b)``; default :func:`factorize`.
    """

    def __init__(self, grid: PolarGrid, coeffs: FaceCoefficients, source=None, solver=None):
        self.grid = grid
        self.coeffs = coeffs
        self.matrix = assemble_operator(grid, coeffs)
        rhs = -flux_divergence(grid, coeffs)
        if source is not None:
            rhs = rhs + np.asarray(source, dtype=float).ravel()
        self.rhs = rhs
        self._solver = solver or factorize
        self._factor = None

    @property
    def factor(self):
        """The factorisation of the matrix (computed once, on first use)."""
        if self._factor is None:
            self._factor = self._solver(self.matrix)
        return self._factor

    def solve(self) -> np.ndarray:
        """phi at the cell centres, shape (n_r, n_theta)."""
        phi = self.factor.solve(self.rhs)
        return np.asarray(phi).reshape(self.grid.n_r, self.grid.n_theta)

    def residual(self, phi) -> np.ndarray:
        """A phi - b for a given phi (flattened), m^3/s."""
        return self.matrix @ np.asarray(phi).ravel() - self.rhs
