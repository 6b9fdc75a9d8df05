"""Pad compliance: the pad stack as an elastic (Winkler) foundation under the asperity layer.

The rigid-pad model deforms only the asperity layer. Here the bulk of the pad (and an optional
subpad) deflects under the normal pressure it carries, locally, as a bed of independent springs:

    w = (p_fluid + p_contact) / k,          1/k = sum_i t_i / M_i,
    M_i = E_i (1 - nu_i) / ((1 + nu_i)(1 - 2 nu_i))     (constrained, oedometric modulus)

with w > 0 pushing the pad surface away from the wafer, so that the film and the contact
separation become h = h_rigid(u) + w. ``docs/model.md`` ("Pad compliance") gives the reasons
for the constrained modulus and for what a Winkler bed leaves out (the lateral coupling that
concentrates pressure at the wafer edge).

Coupled solve at a wafer position u = (h0, theta, beta). The unknowns are phi = ln(p/p0) and
w at the cell centres; the film on a face takes the rigid film there plus w interpolated
linearly in r from the two cells beside it (extrapolated over the last half ring at the rim;
:func:`cmpsim.numerics.grid.face_operators`). Residuals

    R(phi, w) = A(h(w)) phi - b(h(w))          (the Reynolds system of ``reynolds``)
    G(phi, w) = k w - P(phi, h(w))             (local: P = (1 - a_r)(p - p0) + p_c)

Newton's method on (phi, w) with w eliminated locally: G is diagonal in w, so
dw = (P_phi dphi - G) / (k - P_h) and dphi solves the sparse Schur system

    (A + R_w diag(P_phi / (k - P_h))) dphi = -R + R_w (G / (k - P_h)),

whose pattern is the one of A (R_w = dR/dw couples nearest neighbours only). One sparse LU per
Newton step, as for the rigid pressure solve. R_w is assembled from the derivative of each face
flux with respect to the film on that face, obtained with four assemblies of the Reynolds
operator on a colouring of the faces (radial faces of even / odd rings, angular faces of even /
odd sectors: every cell then has exactly one face of each colour). The derivative of the
equilibrium residuals with respect to u follows from the same factorisation (implicit
differentiation, three back-substitutions), and so does a tangent predictor that starts the
next solve close to its solution.

With lateral coupling (:class:`LayeredFoundation`, ``pad_compliance = "layer"``) the deflection is
w = C p with a nonlocal compliance C (the top pad as a plate on an elastic subpad layer, its
kernel integrated exactly over the polar cells: :mod:`cmpsim.numerics.padgrid`); G becomes k (w - C p),
and the Newton system is solved by GMRES preconditioned by the factorisation of the same system
with a sparse (Laplacian) stand-in for the pad's stiffness, exact for the long waves where C
tends to the bed's 1/k (:func:`cmpsim.numerics.padgrid.layer_newton_matrix`).
"""

from __future__ import annotations

import copy
import threading
from dataclasses import dataclass, field

import numpy as np
import scipy.sparse as sp

from ..numerics.grid import face_operators as _face_operators
# the pad stack's kernels moved to cmpsim.physics.padstack; re-exported here, where they were public
from ..physics.padstack import *  # noqa: F403
from ..physics.padstack import __all__ as _PADSTACK
from .coupling import coupled_newton_matrices
from ..numerics.padgrid import layer_deflection, layer_newton_matrix, pad_laplacian
from ..numerics.krylov import gmres as _gmres  # looked up at call time: benchmarks/bench_house.py swaps it
from .reynolds import FaceCoefficients, factorize, lubrication_coefficients, venting_film_matrices
from .state import PressureState

#: Relative residual of the GMRES solve of each layered-pad Newton system (an inexact Newton step:
#: the outer iterations gain about this factor per step). 1e-4 rather than the 1e-6 it was: on the
#: 300mm preset the equilibrium then costs 0.71x the CPU time (0.97 s against 1.36 s, one run), with
#: the same Newton and bending iterations and its answers within 1e-10 (relative) of the tighter solve.
LAYER_KRYLOV_RTOL = 1e-4

__all__ = [
    *_PADSTACK,
    "COMPLIANCE_MODELS",
    "CoupledLinearisation",
    "coupled_state",
    "coupled_jacobian",
    "coupled_jacobian_and_pressure",
    "film_change",
    "local_deflection",
]

#: Values of the ``pad_compliance`` input (the registry is :data:`cmpsim.models.PAD_MODELS`).
COMPLIANCE_MODELS = ("rigid", "winkler", "layer")

#: Newton on (phi, w) stops when the last step moved w by less than this many sigma and phi by
#: less than this; the steps then contract by 0.05 or better, so the error left is far smaller.
_STEP_TOL = 1e-8
_MAX_INNER = 40
#: No Newton step moves w by more than this many sigma.
_MAX_DW = 0.25
#: A factorisation is reused (chord step) while its steps contract by this factor or better; a
#: factorisation from another position is tried only if its first step is below _REUSE_FIRST.
_CONTRACTION = 0.05
_REUSE_FIRST = 1e-4
#: The Jacobian of the equilibrium uses the state's factorisation only if it was built within
#: _JACOBIAN_MOVE (in units of u_scale: sigma, sigma / R_w) of the state's position and the
#: iterate has moved less than _JACOBIAN_DRIFT (sigma / phi units) since; otherwise it
#: refactorises at the state. A nearby factorisation gives a Jacobian good to about that
#: relative distance, which keeps the outer Newton superlinear.
_JACOBIAN_DRIFT = 1e-3
_JACOBIAN_MOVE = 0.05


# ---------------------------------------------------------------------------------- memory
@dataclass
class _Memory:
    """What a problem remembers between coupled solves (warm starts and deformed films)."""

    last: tuple | None = None  # (u, phi, w) of the last converged state
    tangent: tuple | None = None  # (u, phi, w, dphi/du, dw/du) of the last Jacobian
    lin: "CoupledLinearisation | None" = None  # the last factorisation (reused for chord steps)
    deflections: dict = field(default_factory=dict)  # u bytes -> w of converged states

    def remember(self, u, phi, w) -> None:
        self.last = (u.copy(), phi.copy(), w.copy())
        if len(self.deflections) >= 1024:
            self.deflections.pop(next(iter(self.deflections)))
        self.deflections[np.asarray(u, dtype=float).tobytes()] = w.copy()


def _memory(problem) -> _Memory:
    mem = problem.__dict__.get("_compliance_memory")
    if mem is None:
        mem = problem.__dict__["_compliance_memory"] = _Memory()
    return mem


_THREAD = threading.local()


def _chains() -> dict:
    """(grid, foundation, slurry, cavitation) -> the memory of the last equilibrium solved in this thread."""
    cache = getattr(_THREAD, "chains", None)
    if cache is None:
        cache = _THREAD.chains = {}
    return cache


def _chain_key(problem) -> tuple:
    return (problem.grid, problem.foundation, problem.slurry.name, problem.cavitation, problem.variant)


def resume_chain(problem) -> None:
    """A warm start continues a chain of neighbouring points (sweeps, studies; issue 23): the first
    coupled solve of ``problem`` starts from the slurry pressure and pad deflection of the last
    equilibrium solved in this thread on the same grid, pad, slurry and model, and tries that
    equilibrium's factorisation for its chord steps (accepted only while they contract, like any
    chord step). The Jacobian never uses it: it refactorises at its own state. Measured on a
    six-point pressure chain: 6 -> 3 factorisations a point, 1.6-1.8x faster (docs/performance.md)."""
    mem = _memory(problem)
    last = _chains().get(_chain_key(problem))
    if last is None or mem.last is not None:
        return
    mem.last = last.last
    if last.lin is not None:
        lin = copy.copy(last.lin)
        lin.drift = np.inf  # another problem's matrix: a chord factor only, never the Jacobian's
        mem.lin = lin


def end_chain(problem) -> None:
    """Keep what ``problem``'s last equilibrium leaves for the next point of a chain (:func:`resume_chain`)."""
    mem = problem.__dict__.get("_compliance_memory")
    if mem is None or mem.last is None:
        return
    cache = _chains()
    if len(cache) > 8:
        cache.clear()
    cache[_chain_key(problem)] = _Memory(last=mem.last, lin=mem.lin)


# ---------------------------------------------------------------------------------- evaluation
def _rigid_film(problem, u, x, y):
    """The carrier's film over the undeformed pad, m."""
    return problem.carrier.film(problem, u, x, y)


@dataclass
class _Evaluation:
    """Residuals and everything local at one (u, phi, w)."""

    u: np.ndarray
    phi: np.ndarray  # (n_r, n_theta)
    w: np.ndarray  # (n_r, n_theta)
    h: np.ndarray  # film at the cell centres
    face_h: tuple  # (radial, angular) film on the faces
    coeffs: FaceCoefficients
    matrix: sp.csr_matrix  # dR/dphi (the slurry model's: the Reynolds operator, or the JFO mass balance's)
    R: np.ndarray  # Reynolds residual, flat
    G: np.ndarray  # k w - P, flat
    p_abs: np.ndarray  # p_slurry of PressureState (granular: absolute; Newtonian: gauge acting)
    p_fluid: np.ndarray
    contact: tuple  # (p_c, a_el, a_ep, a_pl)

    @property
    def p_total(self) -> np.ndarray:
        return self.p_fluid + self.contact[0]


def _rigid_films(problem, u) -> tuple:
    """The rigid film (m) at the cell centres, on the radial and on the angular faces at u."""
    return tuple(_rigid_film(problem, u, x, y) for x, y in ((problem.xc, problem.yc), (problem.xr, problem.yr), (problem.xa, problem.ya)))


def _face_coefficients(problem, rigid, w, ops) -> tuple:
    wf = w.ravel()
    hr = rigid[1] + (ops.interp_radial @ wf).reshape(w.shape)
    ha = rigid[2] + (ops.interp_angular @ wf).reshape(w.shape)
    return (hr, ha), _coefficients(problem, hr, ha)


def _coefficients(problem, hr, ha) -> FaceCoefficients:
    # both face sets in one evaluation, with the face kinematics the problem computed once
    c = lubrication_coefficients(np.stack([hr, ha]), problem._xf, problem._yf, problem.lub, problem._vf)
    return FaceCoefficients(
        tuple(a[0] for a in c[:5]), tuple(a[1] for a in c[:5]), int(np.count_nonzero(c[5])), c[5].size, problem.lub.groove_venting
    )


def _slurry_pressure(problem, phi):
    """(p_slurry, gauge pressure acting, its derivative in phi) of the unknown phi.

    Granular: phi = ln(p/p0), p_slurry the absolute granular pressure. Newtonian: phi is the
    gauge pressure p; with Gumbel cavitation the acting pressure is max(p, p_cav), whose
    derivative is taken on the set where p > p_cav (semismooth Newton).
    """
    return problem.slurry.linearised(phi)


def _load(problem, phi, h):
    """(p_slurry, p_fluid, contact) at a film h and phi: the pressure the pad carries is p_fluid + p_c."""
    contact = problem.contact(h)
    ar = contact[1] + contact[2] + contact[3]
    p_slurry, gauge, _ = _slurry_pressure(problem, phi)
    return p_slurry, (1.0 - ar) * gauge, contact


def _evaluate(problem, u, phi, w, ops, rigid=None) -> _Evaluation:
    """Residuals at (u, phi, w); ``rigid`` is :func:`_rigid_films` at u if already computed."""
    k = problem.foundation.stiffness
    rigid = _rigid_films(problem, u) if rigid is None else rigid
    face_h, coeffs = _face_coefficients(problem, rigid, w, ops)
    h = rigid[0] + w
    R, A = problem.slurry.residual(problem.grid, coeffs, phi)
    p_abs, p_fluid, contact = _load(problem, phi, h)
    f = problem.foundation
    if f.local:
        G = (k * w - p_fluid - contact[0]).ravel()
    else:  # k (w - C p): the same scale as on the Winkler bed, to which it reduces when C = 1/k
        G = k * (w.ravel() - layer_deflection(f, p_fluid + contact[0], problem.grid).ravel())
    return _Evaluation(u, phi, w, h, face_h, coeffs, A, R, G, p_abs, p_fluid, contact)


def _load_derivative_h(problem, phi, h):
    """dP/dh at fixed phi (central difference of the contact table), Pa/m."""
    dh = 1e-6 * problem.sigma
    h = np.asarray(h, dtype=float)
    phi = np.broadcast_to(phi, h.shape)
    # both sides in one evaluation (elementwise: the same values as two)
    _, p_fluid, contact = _load(problem, np.stack([phi, phi]), np.stack([h + dh, h - dh]))
    total = p_fluid + contact[0]
    return (total[0] - total[1]) / (2.0 * dh)


@dataclass
class CoupledLinearisation:
    """Newton matrix of the coupled (phi, w) system with w eliminated, factorised once.

    ``factor`` solves S = A + R_w diag(P_phi / K); K = k - P_h (Winkler bed), or, on a layered pad,
    the 2N (dphi, v) matrix of :func:`cmpsim.numerics.padgrid.layer_newton_matrix`. All vectors flat (cell order).
    """

    factor: object
    R_w: sp.csr_matrix
    P_phi: np.ndarray
    P_h: np.ndarray
    K: np.ndarray
    u: np.ndarray  # position where it was built
    drift: float = 0.0  # how far the iterate moved since (max |dw| / sigma, |dphi|), summed
    # ---- layered pad (nonlocal compliance): the system is solved by GMRES, preconditioned by the
    # factorisation above of the (dphi, v) system with the sparse stand-in stiffness (cmpsim.numerics.padgrid)
    A: sp.csr_matrix | None = None
    layer: object = None  # (k, deflection: callable pressure -> deflection, sigma, g, c_loc) or None
    krylov_iterations: int = 0
    # d(face flux)/d(face film) on the radial and angular faces (flat): R_w, and dR/du in the Jacobian
    face_slopes: tuple | None = None
    # a grooved pad's (V_r, V_a) of cmpsim.operators.reynolds.venting_film_matrices, or None
    venting: tuple | None = None
    # the cavitated cells it was linearised on (Gumbel, JFO), or None
    cavitated: np.ndarray | None = None

    def solve(self, R, G):
        """(dphi, dw) of the Newton system (dphi, dw) = -J^-1 (R, G).

        Winkler bed: J = [A R_w; -P_phi K], solved exactly with the factorisation. Layered pad:
        the second row is k (dw - C (P_phi dphi + P_h dw)) with the nonlocal C; GMRES on the
        system left-preconditioned by the same system with a sparse stand-in for the pad's
        stiffness (:mod:`cmpsim.numerics.padgrid`).
        """
        if self.layer is None:
            return self._solve_local(R, G)
        return self._solve_layer(R, G)

    def _solve_local(self, R, G):
        dphi = np.asarray(self.factor.solve(-R + self.R_w @ (G / self.K)))
        dw = (self.P_phi * dphi - G) / self.K
        return dphi, dw

    def approximate_step(self, R, G):
        """The Newton step of the factorised system: exact on a Winkler bed, the preconditioner's on a layered pad."""
        if self.layer is None:
            return self._solve_local(R, G)
        dphi, dw = self._precondition(-R, -G)
        return dphi, dw

    def _precondition(self, r1, r2):
        """(dphi, dw) solving the sparse stand-in J_p (dphi, dw) = (r1, r2) of the layered system
        (pad stiffness k0 - b L; :func:`cmpsim.numerics.padgrid.layer_newton_matrix`)."""
        k, _, _, g, c_loc = self.layer
        n = r1.size
        z = r2 / k
        x = np.asarray(self.factor.solve(np.concatenate([r1 - self.R_w @ (g * z), g * self.P_h * z])))
        dphi, v = x[:n], x[n:]
        p = g * (self.P_phi * dphi + self.P_h * (v + z))
        return dphi, v + c_loc * p + z

    def deflection(self, pressure):
        """C p (m) for a flat cell field (Pa): p / k on a Winkler bed."""
        if self.layer is None:
            return pressure / (self.K + self.P_h)
        return self.layer[1](pressure)

    def _solve_layer(self, R, G):
        k, deflect, sigma = self.layer[:3]
        n = R.size

        def precondition(r1, r2):
            a, b = self._precondition(r1, r2)
            return np.concatenate([a, b / sigma])

        def matvec(x):
            self.krylov_iterations += 1
            dphi, dw = x[:n], x[n:] * sigma
            r1 = self.A @ dphi + self.R_w @ dw
            r2 = k * (dw - deflect(self.P_phi * dphi + self.P_h * dw))
            return precondition(r1, r2)

        rhs = precondition(-R, -G)  # the preconditioner's step
        if not np.any(rhs):
            return np.zeros(n), np.zeros(n)
        x = _gmres(matvec, rhs, x0=rhs, rtol=LAYER_KRYLOV_RTOL, max_iter=200)
        return x[:n], x[n:] * sigma


def _linearise(problem, ev: _Evaluation, ops) -> CoupledLinearisation:
    grid = problem.grid
    k = problem.foundation.stiffness
    phi = ev.phi.ravel()
    # derivative of every face flux with respect to the film on that face
    eps = 1e-7 * problem.sigma
    hr, ha = ev.face_h
    plus = _coefficients(problem, hr + eps, ha + eps)
    d_rad = tuple((a - b) / eps for a, b in zip(plus.radial, ev.coeffs.radial))
    d_ang = tuple((a - b) / eps for a, b in zip(plus.angular, ev.coeffs.angular))
    # each face's flux slope: the slurry model knows how its residual depends on the coefficients
    s_rad, s_ang = problem.slurry.face_flux_slopes(grid, ev.coeffs, FaceCoefficients(d_rad, d_ang), phi, ops)
    ar = ev.contact[1] + ev.contact[2] + ev.contact[3]
    P_phi = ((1.0 - ar) * _slurry_pressure(problem, ev.phi)[2]).ravel()
    P_h = _load_derivative_h(problem, ev.phi, ev.h).ravel()
    K = k - P_h
    R_w, S = coupled_newton_matrices(grid, ev.matrix, s_rad, s_ang, P_phi / K)
    venting = None
    if problem.lub.groove_venting:  # a grooved pad's sink is a cell term, not a face flux: its film slope apart
        venting = venting_film_matrices(grid, FaceCoefficients(d_rad, d_ang), phi, problem.lub.groove_venting)
        R_v = (venting[0] @ ops.interp_radial + venting[1] @ ops.interp_angular).tocsr()
        R_w = (R_w + R_v).tocsr()
        S = (S + R_v @ sp.diags(P_phi / K)).tocsr()
    f = problem.foundation
    if not f.local:  # the layered pad: factorise the preconditioner's sparse system instead
        S, g = layer_newton_matrix(ev.matrix, R_w, P_phi, P_h, f.local_compliance, f.stiffness_quadratic(), pad_laplacian(grid, f.coupling_length))
    factor = (problem.solver or factorize)(S)
    problem.factorizations += 1
    lin = CoupledLinearisation(factor, R_w, P_phi, P_h, K, ev.u.copy())
    lin.face_slopes = (s_rad, s_ang)
    lin.venting = venting
    lin.cavitated = problem.slurry.cavitated(ev.phi)
    if not f.local:
        lin.A = ev.matrix
        lin.layer = (k, lambda p: layer_deflection(f, p.reshape(grid.n_r, grid.n_theta), grid).ravel(), problem.sigma, g, f.local_compliance)
    return lin


# ---------------------------------------------------------------------------------- local solve
def local_deflection(problem, h_rigid, phi, w0=None, tol: float = 1e-12, max_iter: int = 60):
    """Deflection w solving k w = P(phi, h_rigid + w) cell by cell (phi fixed), m.

    The residual is increasing in w (the contact pressure falls as the film opens), so a
    Newton iteration whose steps are limited to a quarter sigma and keep the film positive
    converges from any start. Raises ValueError if it does not.
    """
    k = problem.foundation.stiffness
    sigma = problem.sigma
    h_rigid = np.asarray(h_rigid, dtype=float)
    phi = np.broadcast_to(np.asarray(phi, dtype=float), h_rigid.shape)
    floor = -h_rigid + 1e-3 * sigma  # smallest w with a positive film
    w = np.maximum(np.zeros_like(h_rigid) if w0 is None else np.asarray(w0, dtype=float).copy(), floor)
    for _ in range(max_iter):
        h = h_rigid + w
        _, p_fluid, contact = _load(problem, phi, h)
        g = k * w - p_fluid - contact[0]
        dg = k - _load_derivative_h(problem, phi, h)
        step = -g / dg
        step = np.clip(step, -_MAX_DW * sigma, _MAX_DW * sigma)
        w_new = np.maximum(w + step, 0.5 * (w + floor))
        done = np.max(np.abs(w_new - w)) < tol * sigma
        w = w_new
        if done:
            return w
    raise ValueError("the local pad deflection did not converge (film at the limit of the contact model)")


# ---------------------------------------------------------------------------------- coupled state
def _start(problem, u, mem: _Memory):
    """Initial (phi, w) at u: the tangent predictor, or the last state with w re-balanced locally (on a
    layered pad: moved by the local balance's change, keeping its nonlocal shape; docs/limitations.md)."""
    if mem.tangent is not None:
        ut, phi_t, w_t, dphi, dw = mem.tangent
        du = u - ut
        if np.all(np.abs(du) <= 50.0 * problem.u_scale):
            return phi_t + dphi @ du, w_t + dw @ du
    shape = (problem.grid.n_r, problem.grid.n_theta)
    phi = mem.last[1] if mem.last is not None else np.zeros(shape)
    w0 = mem.last[2] if mem.last is not None else None
    h_rigid = _rigid_film(problem, u, problem.xc, problem.yc)
    if w0 is None or problem.foundation.local:
        return phi, local_deflection(problem, h_rigid, phi, w0)
    h_last = _rigid_film(problem, mem.last[0], problem.xc, problem.yc)
    return phi, w0 + local_deflection(problem, h_rigid, phi, w0) - local_deflection(problem, h_last, phi, w0)


def coupled_state(problem, u):
    """The :class:`~cmpsim.solver.equilibrium.PressureState` at u with the pad deflection solved in.

    Raises ValueError (like the rigid state) when the film closes or the pressure diverges.
    """
    u = np.asarray(u, dtype=float)
    ops = _face_operators(problem.grid)
    mem = _memory(problem)
    sigma = problem.sigma
    phi, w = _start(problem, u, mem)
    rigid = _rigid_films(problem, u)  # fixed while (phi, w) are solved at this u
    ev = _evaluate(problem, u, phi, w, ops, rigid)
    lin, prev = mem.lin, None
    for _ in range(_MAX_INNER):
        dphi = dw = None
        if lin is not None:  # chord step with the factorisation at hand
            # (on a layered pad, judge by the preconditioner's cheap step before paying for GMRES)
            dphi, dw = lin.approximate_step(ev.R, ev.G)
            size = _step_size(problem, dphi, dw)
            if size > (_REUSE_FIRST if prev is None else _CONTRACTION * prev):
                dphi = None
            elif lin.layer is not None:
                dphi, dw = lin.solve(ev.R, ev.G)
                size = _step_size(problem, dphi, dw)
        if dphi is None:  # Newton step: factorise at the current iterate
            lin = _linearise(problem, ev, ops)
            dphi, dw = lin.solve(ev.R, ev.G)
            size = _step_size(problem, dphi, dw)
        dphi = dphi.reshape(phi.shape)
        dw = dw.reshape(w.shape)
        # keep the film positive and the step inside a trust region
        h = ev.h
        scale = min(1.0, _MAX_DW * sigma / max(np.max(np.abs(dw)), 1e-300))
        shrink = dw < -0.5 * h
        if np.any(shrink):
            scale = min(scale, float(np.min(-0.5 * h[shrink] / dw[shrink])))
        phi = phi + scale * dphi
        w = w + scale * dw
        lin.drift += scale * size
        if problem.slurry.diverges(phi):
            raise ValueError(
                f"the slurry pressure diverges (unknown up to {np.nanmax(phi):.3g}) on the compliant pad at a minimum "
                f"film of {h.min() / sigma:.3g} sigma"
            )
        ev = _evaluate(problem, u, phi, w, ops, rigid)
        if scale == 1.0 and size < _STEP_TOL:
            break
        prev = size if scale == 1.0 else None
    else:
        raise ValueError(f"the coupled film and pad deflection did not converge in {_MAX_INNER} Newton steps")
    return _converged_state(problem, ev, lin)


def _step_size(problem, dphi, dw) -> float:
    """Largest change of w (sigma) and of phi (slurry's ``unknown_scale``), as the joint Newton's."""
    phi_scale = problem.slurry.unknown_scale(problem.applied_pressure)
    return max(float(np.max(np.abs(dw))) / problem.sigma, float(np.max(np.abs(dphi))) / phi_scale)


def _converged_state(problem, ev: _Evaluation, lin: CoupledLinearisation) -> PressureState:
    """The :class:`PressureState` of a converged evaluation, remembered for the deformed film and warm starts."""
    u, phi, w = ev.u, ev.phi, ev.w
    mem = _memory(problem)
    res = problem._residual(ev.p_total)
    mem.remember(u, phi, w)
    mem.lin = lin
    pc, ae, aep, ap = ev.contact
    floored = ev.coeffs.floored / max(ev.coeffs.n_faces, 1)
    _, _, theta, cavitated = problem.slurry.pressures(phi)  # JFO: the fill fraction of the universal variable
    return PressureState(
        u, ev.h, phi, ev.p_abs, ev.p_fluid, pc, ae, aep, ap, res, None, floored,
        fill_fraction=theta, cavitated=cavitated, deflection=w, coupling=(lin, ev),
    )


def coupled_jacobian(problem, st, rel_step: float = 1e-6) -> np.ndarray:
    """d(residual)/du at a solved compliant state: implicit differentiation of (phi, w).

    :func:`coupled_jacobian_and_pressure` without the pressure columns.
    """
    return coupled_jacobian_and_pressure(problem, st, rel_step)[0]


def coupled_jacobian_and_pressure(problem, st, rel_step: float = 1e-6):
    """(J, dP/du) at a solved compliant state: implicit differentiation of (phi, w).

    For each component of u the Reynolds residual and the local balance are differentiated at
    fixed (phi, w), and the coupled system is solved with the state's factorisation: three
    back-substitutions. The face coefficients depend on u only through the film on each face,
    so dR/du is the face-flux slopes of the linearisation times d(rigid film)/du on the faces
    (a finite difference of the geometry alone: no coefficient evaluation, no assembly).
    J (3 x 3) is d(balance residuals)/du; dP/du (Pa per unit of each component of u, shape
    (n_r, n_theta, 3)) the change of the total pressure along the same solution.
    """
    ops = _face_operators(problem.grid)
    lin, ev = st.coupling
    moved = np.max(np.abs(st.u - lin.u) / problem.u_scale) if lin is not None else np.inf
    # a factorisation taken on another cavitated set linearises the other side of p_cav
    other_set = lin is not None and not _same_set(lin.cavitated, st.cavitated)
    if lin is None or moved > _JACOBIAN_MOVE or lin.drift > _JACOBIAN_DRIFT or other_set:
        lin = _linearise(problem, ev, ops)  # the state converged on another position's factorisation
        st.coupling = (lin, ev)
        _memory(problem).lin = lin
    J, dphi_du, dw_du, dP_du = _position_columns(problem, lin, st.u, ops, rel_step)
    shape = st.phi.shape
    _memory(problem).tangent = (
        st.u.copy(), st.phi.copy(), st.deflection.copy(),
        dphi_du.reshape(shape + (3,)), dw_du.reshape(shape + (3,)),
    )
    return J, dP_du.reshape(shape + (3,))


def film_change(problem, lin: CoupledLinearisation, dh, dhr, dha, ops):
    """(dP, dphi, dw): the linear change of total pressure (Pa), slurry unknown and pad deflection (m) under a
    change of the carrier's film at fixed u (``dh``, ``dhr``, ``dha``, m, flat: centres, faces), one back-substitution."""
    s_rad, s_ang = lin.face_slopes
    dR = ops.div_radial @ (s_rad * dhr) + ops.div_angular @ (s_ang * dha)
    if lin.venting is not None:
        dR = dR + lin.venting[0] @ dhr + lin.venting[1] @ dha
    dG = -lin.P_h * dh if lin.layer is None else -lin.layer[0] * lin.deflection(lin.P_h * dh)
    dphi, dw = lin.solve(dR, dG)
    problem.back_substitutions += 1
    return lin.P_phi * dphi + lin.P_h * (dh + dw), dphi, dw


def _position_columns(problem, lin: CoupledLinearisation, u, ops, rel_step: float = 1e-6):
    """(J, dphi/du, dw/du, dP/du) of the coupled system linearised in ``lin``, at position u.

    For each component of u the Reynolds residual and the local balance are differentiated at
    fixed (phi, w) (the face-flux slopes of ``lin`` times d(rigid film)/du on the faces: a
    finite difference of the geometry alone) and the coupled system is solved with ``lin``'s
    factorisation: three back-substitutions. J (3 x 3) is d(balance residuals)/du along the
    solution; dphi/du, dw/du and the total pressure's dP/du (Pa) are (cells, 3).
    """
    n = lin.P_phi.size
    J = np.empty((3, 3))
    dphi_du = np.empty((n, 3))
    dw_du = np.empty((n, 3))
    dP_du = np.empty((n, 3))
    points = ((problem.xc, problem.yc), (problem.xr, problem.yr), (problem.xa, problem.ya))
    base = [_rigid_film(problem, u, x, y) for x, y in points]
    for k in range(3):
        du = np.zeros(3)
        du[k] = rel_step * problem.u_scale[k]
        dh, dhr, dha = (((_rigid_film(problem, u + du, x, y) - b) / du[k]).ravel() for (x, y), b in zip(points, base))
        dP_du[:, k], dphi_du[:, k], dw_du[:, k] = film_change(problem, lin, dh, dhr, dha, ops)
        J[:, k] = problem.carrier.residual_change(problem, dP_du[:, k].reshape(base[0].shape))
    return J, dphi_du, dw_du, dP_du


def _same_set(a, b) -> bool:
    """Whether two cavitated sets (bool arrays, or None for none) are the same."""
    if a is None or b is None:
        return a is None and b is None
    return bool(np.array_equal(np.asarray(a).ravel(), np.asarray(b).ravel()))
