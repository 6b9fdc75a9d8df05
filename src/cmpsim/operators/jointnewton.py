"""The Winkler pad's equilibrium by one Newton iteration on slurry pressure, deflection and position.

The nested solve of :mod:`cmpsim.operators.compliance` converges the film and the pad deflection (phi, w)
at every trial position u of the equilibrium's Newton on u, and factorises once more at each
converged state for the Jacobian (a cold default equilibrium on 24x64: 3 coupled states, 16
residual evaluations, 5 LU). Here the balance residuals join the coupled Newton system as a
border, so that one iteration moves (phi, w, u) together: 2 LU and 7 residual evaluations for
the same equilibrium (``docs/model.md``, "Pad compliance", and ``docs/performance.md``, issue 23).
The nested solve stays the fall-back and the layered pad's solve.
"""

from __future__ import annotations

import numpy as np

from .compliance import (
    _CONTRACTION,
    CoupledLinearisation,
    _Evaluation,
    _MAX_DW,
    _REUSE_FIRST,
    _STEP_TOL,
    _converged_state,
    _evaluate,
    _face_operators,
    _linearise,
    _memory,
    _position_columns,
    _rigid_film,
    _start,
)

__all__ = ["joint_equilibrium"]

#: The joint iteration hands over to the nested solve after this many factorisations: where the
#: slurry lifts the wafer far from the contact-only start (a stiff pad near hydroplaning) its
#: steps, without the nested solve's load bracketing and line search, may crawl or cycle. Over
#: 36 points (1-7 psi, 20-120 rpm, subpad 0.5-50 MPa) the converged ones took 1-32 LU, 2 on the
#: default stack; the five that did not converge spent 40 before this bound (docs/performance.md).
_MAX_FACTORISATIONS = 12


def joint_equilibrium(problem, u, tol: float = 1e-9, max_iter: int = 40, max_step: float = 0.5):
    """Film, pad deflection and wafer position by one Newton iteration: (u, state, steps, history), or None.

    The nested solve (:func:`cmpsim.operators.compliance.coupled_state` at every trial position of the
    equilibrium's Newton on u, :func:`cmpsim.operators.compliance.coupled_jacobian` at each converged
    state) converges (phi, w) at positions far from the equilibrium and factorises once more
    for each Jacobian. Here the balance residuals F(phi, w, u) (eq. 31 and the moments, see
    :mod:`cmpsim.solver.equilibrium`) join the coupled Newton system as a border:

        A dphi + R_w dw + R_u du = -R
        -P_phi dphi + (k - P_h) dw + G_u du = -G
        F_phi dphi + F_w dw = -F,

    solved with the factorisation of the coupled matrix and four back-substitutions (the step
    at fixed u and the three columns d(phi, w)/du of the equilibrium's Jacobian), du from the
    3 x 3 Schur complement J. A factorisation is kept (a chord step) while the steps contract
    by 0.05; a warm start first tries the last equilibrium's factorisation (its first step
    must be below 1e-4). Steps are limited like the nested ones and scaled together: du to
    ``max_step`` (units of ``problem.u_scale``), the deflection to 0.25 sigma, the film to
    half its thickness. Converged at the iterate whose balances are below ``tol`` (max |F|)
    and whose Newton step is below 1e-8 (w in sigma, u in ``u_scale``, phi in the slurry's
    ``unknown_scale``): the nested solve's solution to its tolerances.

    Parameters
    ----------
    problem : cmpsim.solver.wafer.WaferProblem
        On a local (Winkler) bed.
    u : array_like
        Start (h0 [m], attack angle [rad], cross tilt [rad]); the start of (phi, w) is the
        problem's memory (the contact-only start, a chain's last equilibrium, a tangent).
    tol, max_iter, max_step
        As :func:`cmpsim.solver.equilibrium.solve_equilibrium`'s (``max_iter`` counts joint steps).

    Returns
    -------
    tuple or None
        (u, :class:`~cmpsim.operators.state.PressureState`, steps, history of (u, F)); None (the
        problem's memory left as it was found) if it does not converge in ``max_iter`` steps
        or a step leaves the admissible films: the caller then solves nested.
    """
    ops = _face_operators(problem.grid)
    mem = _memory(problem)
    saved = (mem.last, mem.tangent, mem.lin)
    sigma = problem.sigma
    u = np.asarray(u, dtype=float).copy()
    try:
        if mem.tangent is None and mem.last is not None and np.array_equal(mem.last[0], u):
            # the contact-only start (or a state solved here): no local balance first, Newton balances w
            phi, w = mem.last[1], mem.last[2]
        else:
            phi, w = _start(problem, u, mem)
        # a warm start first tries the factorisation of the last equilibrium (of its chain, or of
        # this problem), as a chord step accepted only if its first step is below _REUSE_FIRST
        lin = mem.lin if mem.lin is not None and mem.lin.layer is None else None
        cols = None if lin is None else _position_columns(problem, lin, u, ops)
        prev = None  # size of the last full step: a chord step must contract on it
        factorised = 0
        history = []
        for it in range(max_iter + 1):
            ev = _evaluate(problem, u, phi, w, ops)
            F = problem._residual(ev.p_total)
            history.append((u.copy(), F.copy()))
            if not np.all(np.isfinite(F)):
                break
            if prev is not None and prev < _STEP_TOL and np.max(np.abs(F)) < tol:
                return _converged(problem, ev, lin, cols, it, history)
            if it == max_iter:
                break
            step = None
            if lin is not None and (prev is not None or it == 0):  # chord step with the last factorisation
                step = _joint_step(problem, ev, F, lin, cols)
                if _joint_size(problem, step) > (_REUSE_FIRST if it == 0 else _CONTRACTION * prev):
                    step = None
            if step is None:
                factorised += 1
                if factorised > _MAX_FACTORISATIONS:
                    break
                lin = _linearise(problem, ev, ops)
                cols = _position_columns(problem, lin, u, ops)
                step = _joint_step(problem, ev, F, lin, cols)
            size = _joint_size(problem, step)
            if it == 0 and size < _STEP_TOL and np.max(np.abs(F)) < tol:
                # the start is an equilibrium already (a point solved again from its own): kept as it is
                return _converged(problem, ev, lin, cols, it, history)
            du, dphi, dw = step
            # the trust region of the position, the nested solve's limits on the deflection and film
            scale = min(1.0, max_step / max(float(np.max(np.abs(du) / problem.u_scale)), 1e-300))
            scale = min(scale, _MAX_DW * sigma / max(float(np.max(np.abs(dw))), 1e-300))
            dh = dw.reshape(w.shape) + _rigid_film(problem, u + du, problem.xc, problem.yc) - (ev.h - w)
            shrink = dh < -0.5 * ev.h
            if np.any(shrink):
                scale = min(scale, float(np.min(-0.5 * ev.h[shrink] / dh[shrink])))
            u = u + scale * du
            phi = phi + scale * dphi.reshape(phi.shape)
            w = w + scale * dw.reshape(w.shape)
            lin.drift += scale * size
            prev = size if scale == 1.0 else None
            if problem.slurry.diverges(phi):
                break
    except (ValueError, np.linalg.LinAlgError, FloatingPointError):
        pass
    mem.last, mem.tangent, mem.lin = saved
    return None


def _converged(problem, ev: _Evaluation, lin: CoupledLinearisation, cols, steps: int, history: list):
    """(u, state, steps, history) of the converged evaluation ``ev``; the tangent d(phi, w)/du kept for the next start."""
    st = _converged_state(problem, ev, lin)
    _, dphi_du, dw_du, _ = cols
    shape = ev.phi.shape
    _memory(problem).tangent = (ev.u.copy(), ev.phi.copy(), ev.w.copy(), dphi_du.reshape(shape + (3,)), dw_du.reshape(shape + (3,)))
    return ev.u, st, steps, history


def _joint_step(problem, ev: _Evaluation, F, lin: CoupledLinearisation, cols):
    """(du, dphi, dw) of the bordered Newton system of :func:`joint_equilibrium`."""
    J, dphi_du, dw_du, _ = cols
    dphi0, dw0 = lin.solve(ev.R, ev.G)
    dP0 = lin.P_phi * dphi0 + lin.P_h * dw0
    du = -np.linalg.solve(J, F + problem.carrier.residual_change(problem, dP0.reshape(ev.phi.shape)))
    return du, dphi0 + dphi_du @ du, dw0 + dw_du @ du


def _joint_size(problem, step) -> float:
    """Size of a joint step: the largest change of w (sigma), phi (in the slurry's
    ``unknown_scale``: the applied pressure for p) and u (in ``u_scale``)."""
    du, dphi, dw = step
    phi_scale = problem.slurry.unknown_scale(problem.applied_pressure)
    return max(
        float(np.max(np.abs(dw))) / problem.sigma,
        float(np.max(np.abs(dphi))) / phi_scale,
        float(np.max(np.abs(du) / problem.u_scale)),
    )
