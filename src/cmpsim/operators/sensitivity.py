"""The linear response of a solved pad-coupled state: its pressure under a change of the carrier's film.

A state of the compliant pad (:func:`cmpsim.operators.compliance.coupled_state`, or the joint Newton's) solves
the Reynolds residual R(phi, w) = 0 and the pad's balance G(phi, w) = 0 at a film h = h_carrier + w.
A change dh of the carrier's film (a change of the wafer position u, or of the wafer's bending on a
membrane head, :mod:`cmpsim.operators.membrane`) moves the slurry unknown and the pad deflection by the
solution of the coupled Newton system at the state (implicit differentiation, one back-substitution
with the state's factorisation; :func:`cmpsim.operators.compliance.film_change`), and the total pressure by

    dP = P_phi dphi + P_h (dh + dw).

This module gives that response for the membrane carrier's Newton-Krylov bending: the pressure
response to a film change (:func:`film_response`), the same with the next coupled solve started from
the film and deflection it predicts (:func:`expect_film_change`), and the balances' Jacobian with the
pressure change per unit of each position component (:func:`coupled_sensitivity`).
"""

from __future__ import annotations

import numpy as np

from .compliance import _face_operators, _memory, coupled_jacobian_and_pressure, film_change

__all__ = ["film_response", "expect_film_change", "coupled_sensitivity"]


def film_response(problem, st, dh, dhr, dha):
    """The linear change at the solved compliant state ``st`` under a change of the carrier's film at fixed u.

    ``dh``, ``dhr``, ``dha`` (m, flat): the change of the film at the cell centres and on the
    radial and angular faces. Returns (dP, dphi, dw): the change of the total pressure (Pa, flat),
    of the slurry unknown and of the pad deflection (m), through the factorisation of the state's
    Jacobian: take :func:`coupled_sensitivity` (or the Jacobian) at ``st`` first, which refactorises
    a state that converged on another position's factorisation.
    """
    return film_change(problem, st.coupling[0], dh, dhr, dha, _face_operators(problem.grid))


def expect_film_change(problem, st, dh, dhr, dha) -> np.ndarray:
    """:func:`film_response`, and the next coupled solve starts where the film change is expected to lead.

    If the problem's tangent predictor was taken at ``st`` (by :func:`coupled_sensitivity` or a
    Jacobian there), its base moves from st's (phi, w) by the linear change, so that the next
    solve starts from the film change's prediction plus the tangent's own change with u. Returns
    the change of the total pressure (Pa, flat).
    """
    dP, dphi, dw = film_response(problem, st, dh, dhr, dha)
    mem = _memory(problem)
    if mem.tangent is not None and np.array_equal(mem.tangent[0], st.u):
        ut, _, _, dphi_du, dw_du = mem.tangent
        mem.tangent = (ut, st.phi + dphi.reshape(st.phi.shape), st.deflection + dw.reshape(st.phi.shape), dphi_du, dw_du)
    return dP


def coupled_sensitivity(problem, st, rel_step: float = 1e-6):
    """(J, dP/du) at the solved compliant state ``st``.

    J (3 x 3) is d(balance residuals)/du of :func:`cmpsim.operators.compliance.coupled_jacobian` (which also
    keeps the tangent d(phi, w)/du for the next start); dP/du (Pa per unit of each component of u,
    shape (n_r, n_theta, 3)) the change of the total pressure along the same solution,
    P_phi dphi/du + P_h (dh/du + dw/du), with dh/du the rigid film's: the columns the Jacobian's
    back-substitutions give (:func:`cmpsim.operators.compliance.coupled_jacobian_and_pressure`).
    """
    return coupled_jacobian_and_pressure(problem, st, rel_step)
