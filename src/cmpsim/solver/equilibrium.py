"""Force and moment equilibrium of the wafer: solve for h0, attack angle and cross tilt.

For a trial position u = (h0, theta, beta) the film h(x, y) follows from the geometry
(eq. 30), the slurry pressure from one sparse solve of the Reynolds equation, the pad
contact pressure from the asperity kernel. The three residuals are

    R_F = (integral of p dA) / (P_applied A) - 1          (eq. 31, force)
    R_y = (integral of p x dA) / (P_applied A R_w)         (moment about the y axis)
    R_x = (integral of p y dA) / (P_applied A R_w)         (moment about the x axis)

with p = (1 - a_r) p_g + p_contact, p_g the gauge pressure of the slurry (p_slurry - p0 for
the granular slurry; for the Newtonian one p, max(p, p_cav) with Gumbel cavitation, the JFO
pressure >= p_cav), the carrier pivot at the centre of the wafer face (so friction has no
moment arm). They are driven to zero by Newton's method. The
Jacobian comes from the same discrete system, dphi/du = -A^-1 d(A phi - b)/du, where the
derivative of the residual at fixed phi is a cheap finite difference of the face
coefficients: one LU factorisation per Newton step and three back-substitutions. With JFO
cavitation the derivative is taken on the frozen cavitated set (the reduced system of
:class:`cmpsim.operators.cavitation.CavitationSystem`), with Gumbel on the frozen set where p > p_cav. Steps are
limited to a trust region on the change of the film and safeguarded by a backtracking line
search. The start is the contact-only equilibrium at zero tilt (or, without contact, a
bracket of the fluid-only load).

The problem (:class:`cmpsim.solver.wafer.WaferProblem`) and its models (:mod:`cmpsim.models`) give the
states and Jacobians; this module is the Newton driver and its starts (coarse grids, load
balance of :mod:`cmpsim.solver.loadbalance`). ``WaferProblem``, ``PressureState``,
``EquilibriumSolution``, ``EquilibriumError``, ``balance_load`` and ``scan_moment_roots`` are
re-exported here, where they have always been imported from.
"""

from __future__ import annotations

import threading

import numpy as np

from ..operators.cavitation import VACUUM_GAUGE_PRESSURE
from ..numerics.grid import PolarGrid
from .loadbalance import RootScan, balance_load, scan_moment_roots, tilt_scan_start
from ..models.pads import JACOBIAN_REFINE_LIMIT, JACOBIAN_RTOL
from ..operators.state import EquilibriumError, EquilibriumSolution, PressureState
from .wafer import MODEL_VARIANTS, WaferProblem

__all__ = [
    "WaferProblem",
    "PressureState",
    "EquilibriumSolution",
    "EquilibriumError",
    "solve_equilibrium",
    "balance_load",
    "scan_moment_roots",
    "RootScan",
    "MODEL_VARIANTS",
    "VACUUM_GAUGE_PRESSURE",
    "JACOBIAN_REFINE_LIMIT",
    "JACOBIAN_RTOL",
]

#: Within this factor of the tolerance, Newton keeps its last Jacobian (a chord step): the
#: Jacobian changes by about the relative size of the last step, so the chord step still
#: shrinks the residual by orders of magnitude, and a Jacobian costs more than a pressure solve.
CHORD_MERIT = 100.0


def _merit(r: np.ndarray) -> float:
    return float(np.max(np.abs(r)))


def _diagnosis(problem: WaferProblem, st: PressureState) -> str:
    hs = st.h.min() / problem.sigma
    text = (
        f"last position h0 = {st.u[0]:.6g} m, attack angle = {st.u[1]:.4g} rad, cross tilt = {st.u[2]:.4g} rad; "
        f"residuals (load, moment_y, moment_x) = ({st.residual[0]:.3g}, {st.residual[1]:.3g}, {st.residual[2]:.3g}); "
        f"minimum film {hs:.3g} sigma"
    )
    if st.floored_fraction > 0:
        text += (
            f"; the flow-factor tensor was regularised on {100 * st.floored_fraction:.0f} % of the faces, i.e. the film "
            "is outside the validity of the perturbation flow factors (docs/model.md)"
        )
    return text


def solve_equilibrium(
    problem: WaferProblem,
    start=None,
    tol: float = 1e-9,
    max_iter: int = 40,
    max_step: float = 0.5,
    warm_start: bool | None = None,
    rebalance: bool = True,
) -> EquilibriumSolution:
    """Newton iteration on (h0, theta, beta) with trust region and backtracking.

    Parameters
    ----------
    problem : WaferProblem
    start : array_like, optional
        Initial (h0 [m], theta [rad], beta [rad]); default: contact-only start (or fluid
        bracket for the hydrodynamic variant).
    tol : float
        Convergence when max |R| < tol (relative load and moment residuals).
    max_iter : int
        Newton steps allowed.
    max_step : float
        Trust region: no step changes h0, or the film at the wafer edge through a tilt, by
        more than ``max_step`` sigma.
    warm_start : bool, optional
        Without ``start``, first solve the same problem on coarse grids (8x24, then 24x64)
        and start from their equilibrium: the cold-start search (bracket, trust-region-limited
        steps) then runs where each solve is cheap. Default (None): for the hydrodynamic
        variant and for grids finer than 48x128 on a rigid pad without JFO cavitation. The
        converged position is the one of this grid (to ``tol``); the coarse factorisations
        are counted in ``factorizations``. Otherwise, for the contact models on a rigid pad
        without JFO cavitation, a cold start takes its first Newton step on the 8x24 grid
        (:func:`_coarse_first_step`; ``warm_start=False`` switches that off too).
    rebalance : bool
        From a ``start`` whose load residual exceeds 0.25 (far from balance), first balance the
        load by bracketing h0 (:func:`cmpsim.solver.loadbalance.balance_load`). ``False`` refuses such a
        start instead (EquilibriumError): for a trial that a caller would rather shorten than pay
        a bracket for (the Newton steps of the membrane's bending, :mod:`cmpsim.operators.membrane`).

    Raises
    ------
    EquilibriumError
        If the film would have to touch the pad, or Newton cannot reduce the residual.
    """
    warm = start is not None
    if start is None and (_use_warm_start(problem) if warm_start is None else warm_start):
        start = _coarse_start(problem, max_iter, max_step)
    coarse_step = False
    if start is None and _use_coarse_step(problem) and warm_start is not False:
        start = _coarse_first_step(problem, max_step)
        coarse_step = start is not None
    if start is None:
        try:
            start = problem.fluid_start() if problem.variant == "hydrodynamic" else problem.contact_only_start()
        except ValueError as exc:  # a kernel refused every trial film
            raise EquilibriumError(f"no admissible start position: {exc}") from exc
    try:
        u, st, it, history = _from_start(problem, start, warm, tol, max_iter, max_step, rebalance)
    except (EquilibriumError, ValueError):
        if not coarse_step:
            raise
        # the coarse grid's first step led nowhere on this grid: start again as without it
        return solve_equilibrium(problem, None, tol, max_iter, max_step, warm_start=False)
    problem.pad_model.end_chain(problem)
    if problem._reference is not None:
        cache = _last_factors()
        if len(cache) > 8:
            cache.clear()
        cache[problem.grid] = problem._reference
    return EquilibriumSolution(st, True, it, problem.factorizations, problem.back_substitutions, history)


def _from_start(problem: WaferProblem, start, warm: bool, tol: float, max_iter: int, max_step: float, rebalance: bool = True):
    """Newton from ``start`` (with the load balanced first if far off, or refused without ``rebalance``, and for
    a Newtonian slurry one restart from an attack-angle scan): (u, state, steps, history)."""
    u = np.asarray(start, dtype=float).copy()
    if warm and problem._reference is None:
        # a warm start continues a chain of neighbouring points (sweeps, `cmpsim reproduce`):
        # refine against the last factorisation made on this grid (in this thread)
        problem._reference = _last_factors().get(problem.grid)
    if warm:
        problem.pad_model.resume_chain(problem)
    joint = problem.pad_model.joint_newton(problem, u, tol, max_iter, max_step)
    if joint is not None:
        return joint
    try:
        st = problem.state(u)
    except ValueError:
        st = None
    if not rebalance and (st is None or abs(st.residual[0]) > 0.25):
        raise EquilibriumError(
            "the start is far from load balance (load residual "
            + ("undefined: no admissible film" if st is None else f"{st.residual[0]:.3g}")
            + ") and rebalancing was not asked for"
        )
    if st is None or abs(st.residual[0]) > 0.25:
        # far from balance (e.g. the slurry adds a large load to the contact-only start):
        # first balance the load by bracketing h0, then let Newton do the rest
        u = balance_load(problem, u)
        st = problem.state(u)
    try:
        u, st, it, history = _newton(problem, u, st, tol, max_iter, max_step)
    except EquilibriumError as first:
        if not problem.slurry.lift_restart:
            raise
        # A Newtonian film at zero tilt carries almost no net load (its pressure is nearly odd
        # in x), so the contact-only start can sit in a basin of the merit function far from a
        # lift-carried equilibrium. Restart once from the best point of an attack-angle scan.
        try:
            u = tilt_scan_start(problem, u)
            st = problem.state(u)
            u, st, it, history = _newton(problem, u, st, tol, max_iter, max_step)
        except (EquilibriumError, ValueError) as second:
            raise EquilibriumError(f"{first}; a restart from an attack-angle scan failed too: {second}") from first
    return u, st, it, history


_THREAD = threading.local()


def _last_factors() -> dict:
    """Grid -> the last factorisation of an equilibrium solved on it in this thread."""
    cache = getattr(_THREAD, "factors", None)
    if cache is None:
        cache = _THREAD.factors = {}
    return cache


#: Coarse grids of the warm start, coarsest first.
WARM_START_GRIDS = ((8, 24), (24, 64))
#: Default warm start for contact models from this many cells on (48x128).
_WARM_START_MIN_CELLS = 48 * 128


def _use_warm_start(problem: WaferProblem) -> bool:
    if not (problem.pad_model.coarse_starts and problem.slurry.coarse_starts):
        return False
    if problem.variant == "hydrodynamic":
        return problem.grid.size > WARM_START_GRIDS[0][0] * WARM_START_GRIDS[0][1]
    return problem.grid.size > _WARM_START_MIN_CELLS


#: Grid of the first Newton step of a cold start (see :func:`_coarse_first_step`).
FIRST_STEP_GRID = (8, 24)


def _use_coarse_step(problem: WaferProblem) -> bool:
    g = problem.grid
    return (
        problem.pad_model.coarse_starts
        and problem.slurry.coarse_starts
        and problem.variant != "hydrodynamic"
        and g.size > 2 * FIRST_STEP_GRID[0] * FIRST_STEP_GRID[1]
        and g.n_r >= FIRST_STEP_GRID[0]
        and g.n_theta >= FIRST_STEP_GRID[1]
    )


def _coarse_first_step(problem: WaferProblem, max_step: float):
    """The first Newton step of a cold start, taken on the coarse grid :data:`FIRST_STEP_GRID`:
    the contact-only start and the Newton step from it (zero tilt to the tilt the moments
    ask for) there, where a solve is cheap; None if that fails (the caller starts on its own
    grid). The target grid then needs one factorisation less: its first matrix is already
    near the equilibrium, and later positions refine against it."""
    coarse = problem.on_grid(PolarGrid(problem.grid.radius, *FIRST_STEP_GRID))
    try:
        u = coarse.contact_only_start()
        st = coarse.state(u)
        step = -np.linalg.solve(coarse.jacobian(st), st.residual)
    except (EquilibriumError, ValueError, np.linalg.LinAlgError):
        return None
    finally:
        problem.factorizations += coarse.factorizations
        problem.back_substitutions += coarse.back_substitutions
    scaled = float(np.max(np.abs(step) / problem.u_scale))
    if not np.isfinite(scaled):
        return None
    if scaled > max_step:
        step *= max_step / scaled
    return u + step


def _coarse_start(problem: WaferProblem, max_iter: int, max_step: float):
    """Equilibrium position on the coarse grids of :data:`WARM_START_GRIDS` (None if it fails)."""
    g = problem.grid
    u = None
    for n_r, n_t in WARM_START_GRIDS:
        if n_r * n_t >= g.size or n_r > g.n_r or n_t > g.n_theta:
            break
        coarse = problem.on_grid(PolarGrid(g.radius, n_r, n_t))
        try:
            sol = solve_equilibrium(coarse, start=u, tol=1e-8, max_iter=max_iter, max_step=max_step, warm_start=False)
        except (EquilibriumError, ValueError):
            sol = None
        problem.factorizations += coarse.factorizations
        problem.back_substitutions += coarse.back_substitutions
        if sol is None:
            break
        u = sol.state.u.copy()
    return u



def _newton(problem: WaferProblem, u, st: PressureState, tol: float, max_iter: int, max_step: float):
    """The safeguarded Newton loop of :func:`solve_equilibrium`: (u, state, steps, history)."""
    history = [(u.copy(), st.residual.copy())]
    it = 0
    J = st_j = None
    # trust radius (sigma): on a rigid pad with contact shrunk to twice the step the line search accepted,
    # regrown by 2 on every full step, so that a step that had to be cut is not retried from max_step
    trust = max_step
    while _merit(st.residual) >= tol:
        if it >= max_iter:
            raise EquilibriumError(f"Newton did not converge in {max_iter} steps; {_diagnosis(problem, st)}")
        it += 1
        if J is None or _merit(st.residual) > CHORD_MERIT * tol or not problem.pad_model.chord_steps:
            with np.errstate(over="ignore", invalid="ignore"):  # judged just below, by name
                J = problem.jacobian(st)
            if not np.all(np.isfinite(J)):
                raise EquilibriumError(
                    f"the Jacobian is not finite at h0 = {u[0]:.6g} m, attack angle {u[1]:.4g} rad (the slurry pressure "
                    f"of a perturbed position overflows); {_diagnosis(problem, st)}"
                )
            st_j = st
        elif st.dphi_du is None and st_j.dphi_du is not None:
            # the chord step: the last Jacobian (and its dphi/du for the refinement start)
            st.dphi_du = st_j.dphi_du
        try:
            step = -np.linalg.solve(J, st.residual)
        except np.linalg.LinAlgError as exc:
            raise EquilibriumError(f"singular Jacobian at h0 = {u[0]:.6g} m: {exc}") from exc
        scaled = np.abs(step) / problem.u_scale
        if scaled.max() > trust:
            step *= trust / scaled.max()
        size = min(scaled.max(), trust)
        alpha = 1.0
        reason = ""
        for _ in range(30):
            trial = u + alpha * step
            # the linearised pressure at the trial position: where refinement starts
            guess = None if st.dphi_du is None else st.phi.ravel() + st.dphi_du @ (alpha * step)
            try:
                new = problem.state(trial, guess=guess)
            except ValueError as exc:
                reason = f" ({exc})"
                alpha *= 0.5
                continue
            if np.linalg.norm(new.residual) < (1.0 - 1e-4 * alpha) * np.linalg.norm(st.residual):
                break
            alpha *= 0.5
        else:
            raise EquilibriumError(
                "line search failed: no step along the Newton direction lowers the residual; the "
                f"equilibrium may not exist for these inputs{reason}; {_diagnosis(problem, st)}"
            )
        if problem.pad_model.adaptive_trust and problem.variant != "hydrodynamic":
            trust = min(max_step, 2.0 * trust) if alpha == 1.0 else max(2.0 * alpha * size, 1e-6)
        # with a compliant pad or the hydrodynamic variant the radius stays at max_step: shrinking
        # it stalled the outer Newton on the default model under Thakurta's conditions and on the
        # hydrodynamic cold start at 80 rpm (coarse grid), where the fixed radius converges
        # (tests/test_validation.py, tests/test_sweeps.py)
        u, st = trial, new
        history.append((u.copy(), st.residual.copy()))
    return u, st, it, history
