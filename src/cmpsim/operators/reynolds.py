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

Discretisation: conservative cell-centred finite volumes on :class:`cmpsim.numerics.grid.PolarGrid`;
two-point normal gradients, cross-gradient (off-diagonal tensor) terms from averaged central
differences, the Dirichlet edge at half a cell from the last centres. The observed order is
2 (``tests/test_reynolds.py``, manufactured solutions). Solved with a sparse LU
(:func:`cmpsim.numerics.sparse.factorize`); any callable ``solver(A) -> object with .solve(b)`` can be
injected.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import scipy.sparse as sp

from ..physics.flowfactors import RoughnessGeometry, pressure_flow_factors, regularize_pressure_tensor, shear_flow_factors
from ..physics.grainflow import grain_coefficients
from ..numerics.grid import PolarGrid
from ..physics.kinematics import Kinematics
from ..numerics.fvassembly import FaceCoefficients, assemble_operator, assembly_map, face_fluxes, flux_divergence, own_face_fluxes, venting_film_matrices, venting_map
from ..numerics.sparse import factorize as guarded_factorize

__all__ = [
    "SLURRY_MODELS",
    "RHEOLOGIES",
    "GrainFlowRheology",
    "NewtonianRheology",
    "NEWTONIAN_GRAIN_COEFFICIENT",
    "LubricationParameters",
    "FaceCoefficients",
    "lubrication_coefficients",
    "assemble_operator",
    "face_fluxes",
    "flux_divergence",
    "own_face_fluxes",
    "ReynoldsSystem",
    "LinearSolveStats",
    "refine",
    "assembly_map",
    "venting_map",
    "venting_film_matrices",
    "factorize",
]


#: The grain-size coefficients f and g at x = sqrt(w/k) h/d -> 0 (eq. 18-19), used by the
#: Newtonian slurry: isotropic roughness then gives Tripp's Phi^p = 1 - 1.5 (sigma/h)^2.
NEWTONIAN_GRAIN_COEFFICIENT = 3.0


class GrainFlowRheology:
    """Haff grain flow (the paper, eq. 5): unknown ln(p/p0), D = (1/6)(t/a) v Psi h^2 Phi^p."""

    name = "granular"

    @staticmethod
    def film_coefficients(h, params: "LubricationParameters"):
        """(c, f, g) at film h (m): D = c Phi^p (m^3/s), f and g the grain-size coefficients (eq. 18-19)."""
        psi, f, g = grain_coefficients(h / params.particle_diameter, params.w_over_k)
        return params.t_over_a * params.fluctuation_velocity * psi * h * h / 6.0, f, g


class NewtonianRheology:
    """A Newtonian liquid: unknown the gauge pressure p, D = h^3/(12 eta) Phi^p with f = g = 3."""

    name = "newtonian"

    @staticmethod
    def film_coefficients(h, params: "LubricationParameters"):
        """(c, f, g) at film h (m): D = c Phi^p (m^4/(Pa s)), f = g = 3 (the x -> 0 limit)."""
        f = g = np.full(h.shape, NEWTONIAN_GRAIN_COEFFICIENT)
        return h * h * h / (12.0 * params.viscosity), f, g


#: The rheology of the Reynolds coefficients of each ``slurry_model`` (the slurry models of
#: :mod:`cmpsim.models.slurries` own the rest: unknown, cavitation, shear). The public
#: :class:`LubricationParameters` takes the name, so the discretisation resolves it here.
RHEOLOGIES = {r.name: r for r in (GrainFlowRheology, NewtonianRheology)}
#: Slurry rheologies: Haff grain flow (the paper, solved in ln p) or a Newtonian liquid (in p).
SLURRY_MODELS = tuple(RHEOLOGIES)


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
    flow_factor_continuation : float
        Eigenvalue of Phi^p below which eq. 8-10 are continued by a C1 power law in the film,
        dimensionless, in [0, 1) (0: none, the floor alone;
        :func:`cmpsim.physics.flowfactors.continue_pressure_eigenvalues`).
    slurry_model : {"granular", "newtonian"}
        Haff grain flow (unknown ln(p/p0), the paper) or a Newtonian liquid (unknown: gauge p).
    viscosity : float
        Newtonian viscosity eta, Pa s (> 0); used only by the Newtonian slurry.
    groove_venting : float
        kappa^2 of a grooved pad, 1/m^2 (:func:`cmpsim.physics.grooves.groove_venting`; 0 = ungrooved):
        the sink g kappa^2 phi of the screened Reynolds equation, carried by the face coefficients.
    """

    particle_diameter: float
    w_over_k: float
    t_over_a: float
    fluctuation_velocity: float
    roughness: RoughnessGeometry
    kinematics: Kinematics
    flow_factor_floor: float = 0.05
    flow_factor_continuation: float = 0.0
    slurry_model: str = "granular"
    viscosity: float = 5e-3
    groove_venting: float = 0.0

    def __post_init__(self) -> None:
        if self.slurry_model not in SLURRY_MODELS:
            raise ValueError(f"slurry_model must be one of {SLURRY_MODELS}; got {self.slurry_model!r}")
        if not (np.isfinite(self.flow_factor_continuation) and 0.0 <= self.flow_factor_continuation < 1.0):
            raise ValueError(
                f"flow_factor_continuation must be finite and in [0, 1) (valid range: [0, 1)); got {self.flow_factor_continuation!r}"
            )
        if not (np.isfinite(self.viscosity) and self.viscosity > 0):
            raise ValueError(f"slurry_viscosity must be finite and > 0 Pa s (valid range: (0, inf)); got {self.viscosity!r}")
        if not (np.isfinite(self.groove_venting) and self.groove_venting >= 0):
            raise ValueError(f"groove_venting must be finite and >= 0 1/m^2 (valid range: [0, inf)); got {self.groove_venting!r}")

    @property
    def rheology(self):
        """The :data:`RHEOLOGIES` entry of ``slurry_model`` (its Reynolds coefficients)."""
        return RHEOLOGIES[self.slurry_model]


def lubrication_coefficients(h, x, y, params: LubricationParameters, velocities=None):
    """Reynolds coefficients at points (x, y) with film thickness h (all m).

    Returns ``(dxx, dxy, dyy, qx, qy, floored)``: the diffusion tensor D with the regularised
    pressure flow-factor tensor (eq. 8–10), the flux vector q = u_m h + (sigma/2) Phi^s du
    (m^2/s, eq. 11–13) and the boolean mask of regularised points. For the granular slurry
    D = (1/6)(t/a) v Psi h^2 Phi^p (m^3/s, multiplies grad ln p); for the Newtonian slurry
    D = h^3/(12 eta) Phi^p (m^4/(Pa s), multiplies grad p) with f = g = 3 in the flow factors.
    ``velocities``, if given, is ``params.kinematics.mean_and_relative(x, y)`` computed before
    (it depends on the points only). Raises ValueError if any film thickness is not finite and > 0.
    """
    h = np.asarray(h, dtype=float)
    if not np.all(np.isfinite(h)) or np.any(h <= 0):
        raise ValueError("film thickness must be finite and > 0 m everywhere on the wafer (the wafer touches the pad mean plane)")
    rough = params.roughness
    hs = h / rough.sigma
    c, f, g = params.rheology.film_coefficients(h, params)
    pxx, pxy, pyy = pressure_flow_factors(hs, f, g, rough)
    pxx, pxy, pyy, floored = regularize_pressure_tensor(pxx, pxy, pyy, params.flow_factor_floor, params.flow_factor_continuation)
    sxx, sxy, syy = shear_flow_factors(hs, f, rough)
    umx, umy, dux, duy = params.kinematics.mean_and_relative(x, y) if velocities is None else velocities
    half_sigma = 0.5 * rough.sigma
    qx = umx * h + half_sigma * (sxx * dux + sxy * duy)
    qy = umy * h + half_sigma * (sxy * dux + syy * duy)
    return c * pxx, c * pxy, c * pyy, qx, qy, floored


def factorize(A: sp.spmatrix):
    """Default sparse direct solver, :func:`cmpsim.numerics.sparse.factorize` (SuperLU keeping the
    minimum-degree ordering, residual-guarded; ``docs/model.md``, "Sparse factorisation")."""
    return guarded_factorize(A)


class LinearSolveStats:
    """Counts of the sparse work: ``factorizations`` (real ``splu`` calls), ``back_substitutions``."""

    def __init__(self):
        self.factorizations = 0
        self.back_substitutions = 0
        self.last_refinement = 0  # back-substitutions of the last call of refine()


#: Iterative refinement against another matrix's factorisation stops when the correction is
#: below this times the largest |phi| (the fresh-LU answer is reproduced to round-off) ...
REFINE_RTOL = 1e-13
#: ... and is abandoned for a fresh factorisation when it has not got there in this many
#: back-substitutions, or when successive corrections shrink by less than this factor.
REFINE_MAX = 10
REFINE_CONTRACTION = 0.5
#: Corrections that stop shrinking below this times max |phi| are round-off: converged.
REFINE_STAGNATION = 1e-12


def refine(matrix, factor, rhs, x0=None, rtol: float = REFINE_RTOL, max_iter: int = REFINE_MAX, stats=None):
    """Solve ``matrix @ x = rhs`` by iterative refinement with the factorisation of a nearby matrix.

    x_{k+1} = x_k + F^-1 (rhs - matrix x_k), with F = ``factor`` (any object with ``.solve``);
    ``rhs`` may hold several columns (each is judged on its own scale). Returns x, or None if
    the corrections do not shrink below ``rtol * max|x|`` within ``max_iter`` corrections at a
    rate of at least ``REFINE_CONTRACTION`` (then the caller factorises ``matrix`` itself).
    Corrections that stagnate below ``REFINE_STAGNATION * max|x|`` are round-off: converged.
    ``stats.back_substitutions`` counts one per solve call (all columns at once).
    """
    x = np.asarray(factor.solve(rhs)) if x0 is None else np.array(x0, dtype=float)
    n_solves = 1 if x0 is None else 0
    prev = np.inf
    ok = False
    for _ in range(max_iter):
        dx = np.asarray(factor.solve(rhs - matrix @ x))
        n_solves += 1
        x += dx
        # largest correction relative to its own column's scale
        size = float(np.max(np.max(np.abs(dx), axis=0) / np.maximum(np.max(np.abs(x), axis=0), 1e-300)))
        if not np.isfinite(size):
            break
        if size <= rtol:
            ok = True
            break
        if size < prev and np.isfinite(prev):
            # at this rate, would it converge in the corrections left?
            needed = np.log(rtol / size) / np.log(size / prev)
            if needed > max_iter - n_solves + 1 and size > REFINE_STAGNATION:
                break
        if size > REFINE_CONTRACTION * prev:
            # stagnation at round-off (what a fresh factorisation would leave too): converged
            ok = prev <= REFINE_STAGNATION
            break
        prev = size
    if stats is not None:
        stats.back_substitutions += n_solves
        stats.last_refinement = n_solves
    return x if ok else None


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
    reference : object with ``.solve(b)``, optional
        Factorisation of a nearby matrix (e.g. that of the previous trial position). Solves
        then use iterative refinement against it (:func:`refine`) and factorise this system's
        own matrix only if the refinement stalls: the answer is the same to round-off.
    stats : LinearSolveStats, optional
        Where to count factorisations and back-substitutions (a new one by default).

    Notes
    -----
    ``factorizations`` (0 or 1) says whether this system called the solver.
    """

    def __init__(self, grid: PolarGrid, coeffs: FaceCoefficients, source=None, solver=None, reference=None, stats=None):
        self.grid = grid
        self.coeffs = coeffs
        self.matrix = assemble_operator(grid, coeffs)
        rhs = -flux_divergence(grid, coeffs)
        if source is not None:
            rhs = rhs + np.asarray(source, dtype=float).ravel()
        self.rhs = rhs
        self._solver = solver or factorize
        self._factor = None
        self.reference = reference
        self.stats = stats if stats is not None else LinearSolveStats()
        self.factorizations = 0
        self.refinement_steps = 0  # back-substitutions of the last solve by refinement (0: none)

    @property
    def factor(self):
        """The factorisation of the matrix (computed once, on first use)."""
        if self._factor is None:
            self._factor = self._solver(self.matrix)
            self.factorizations += 1
            self.stats.factorizations += 1
        return self._factor

    @property
    def own_factor(self):
        """This matrix's own factorisation if one was computed, else None."""
        return self._factor

    def solve_linear(self, rhs, x0=None, rtol: float = REFINE_RTOL) -> np.ndarray:
        """x with ``matrix @ x = rhs`` (flat, or columns (N, k)): refinement against the reference if any
        (to ``rtol`` relative, see :func:`refine`), else this matrix's own factorisation."""
        rhs = np.asarray(rhs, dtype=float)
        if rhs.ndim == 1 or rhs.shape[0] != self.grid.size:
            rhs = rhs.ravel()
        if self._factor is None and self.reference is not None:
            x = refine(self.matrix, self.reference, rhs, x0=x0, rtol=rtol, stats=self.stats)
            self.refinement_steps = self.stats.last_refinement
            if x is not None:
                return x
        x = np.asarray(self.factor.solve(rhs))
        self.stats.back_substitutions += 1
        return x

    def solve(self, x0=None) -> np.ndarray:
        """phi at the cell centres, shape (n_r, n_theta); ``x0`` (flat) starts the iterative
        refinement, if any (see :meth:`solve_linear`)."""
        phi = self.solve_linear(self.rhs, x0=x0)
        return np.asarray(phi).reshape(self.grid.n_r, self.grid.n_theta)

    def residual(self, phi) -> np.ndarray:
        """A phi - b for a given phi (flattened), m^3/s."""
        return self.matrix @ np.asarray(phi).ravel() - self.rhs
