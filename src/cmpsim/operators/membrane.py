"""The wafer under a membrane head: its bending in equilibrium with the pressures on both faces.

The membrane presses the zone pressures p_b on the back of the wafer (:func:`cmpsim.numerics.plate.zone_load`),
the slurry and the pad press p(w) on its face, and the wafer, a free Kirchhoff plate
(:mod:`cmpsim.numerics.plate`), bends by w (m, positive away from the pad: the film grows by w):

    D del^4 w = p(w) - p_b,        w orthogonal to the rigid-body modes 1, x, y.

Its rigid-body motion is the carrier's (h0, attack angle, cross tilt), found by the equilibrium
solver for each bending: force and moment balance are the plate's solvability conditions, so at
the solution the plate's relief load vanishes and the bending is a bending only.

Solve (docs/model.md, "Carrier"). ``equilibrium(w)`` returns the equilibrium state (force and
moment balance) with the wafer face bent by w; ``response(w, dw)`` the linear change of its face
pressure under a change dw of the bending, the rigid-body position re-balanced (implicit
differentiation of the equilibrium at w). The bending is the root of the preconditioned residual

    F(w) = (K + k) ^-1 (p(w) - p_b + k w) - w,

with K the free plate and k the load stiffness -d(mean pressure)/d(h0) measured at the rigid
equilibrium: where the pressure answers a change of film locally with about k, (K + k)^-1 is the
inverse of the linearised problem (the classical splitting of a plate on an elastic foundation).
The root is found by Newton's method on F whose linear systems

    F'(w) dw = (K + k)^-1 (response(w, dw) + k dw) - dw = -F(w)

are solved by GMRES (a Newton-Krylov method, Knoll & Keyes 2004): every Krylov vector costs one
back-substitution of the state's factorisation and one plate solve, not an equilibrium, and each
Newton step one equilibrium. A step that does not lower |F| is halved; if four halvings do not
lower it, or the Newton step is over 100 times longer than F (a nearly singular linearisation:
GMRES then returns metres for a residual of picometres), the fixed-point step F is tried and
halved in its place (near the root F contracts by the splitting's factor). If Newton fails from the
start (a thin wafer whose bending is far from linear), the solve is continued in the bending
stiffness: from a stiffness at which the bending length ell = (D / k)^(1/4) reaches the wafer
radius (the wafer nearly rigid, the bending small) down to D by factors of 100, each stage
starting from the last; a stage that fails is split.
"""

from __future__ import annotations

import logging
import warnings
from dataclasses import dataclass
from functools import lru_cache

import numpy as np

from ..numerics.grid import PolarGrid
from ..numerics.krylov import gmres
from ..numerics.plate import KirchhoffPlate, PlateOperator

__all__ = ["BendingSolution", "BendingError", "solve_bending"]

#: Each Newton step of the bending at DEBUG level: residual, Krylov iterations, trial residuals.
log = logging.getLogger(__name__)

#: Stages of the continuation in bending stiffness: the first factor tried, and the smallest
#: before giving up.
STAGE_FACTOR = 100.0
MIN_STAGE_FACTOR = 10.0
#: Relative residual of the Krylov solve of each Newton step (an inexact Newton step: the outer
#: iteration then gains about this factor per step on top of its quadratic rate).
KRYLOV_RTOL = 1e-4
KRYLOV_MAX_ITER = 50
#: Halvings of a Newton step that does not lower the residual, before the fixed-point step is tried
#: (and halved as often) and then the stage given up.
MAX_HALVINGS = 4
#: A Newton step longer than this many times the fixed-point step |F| is not trusted (see solve_bending).
MAX_STEP_RATIO = 100.0


def plate_operator(plate: KirchhoffPlate, grid: PolarGrid, load_stiffness: float) -> PlateOperator:
    """The preconditioner (K + k) of ``plate`` on ``grid``, k the load stiffness (Pa/m) rounded to 1/16 of an
    octave: the operator is built once (one LU of its Fourier modes) and kept for the warm-started solves of
    a study, whose load stiffness barely moves (a preconditioner; the bending it converges to does not
    depend on k)."""
    octave = round(16.0 * np.log2(load_stiffness)) / 16.0
    return _plate_operator(plate, grid, float(2.0**octave))


@lru_cache(maxsize=16)
def _plate_operator(plate: KirchhoffPlate, grid: PolarGrid, k: float) -> PlateOperator:
    return PlateOperator(plate, grid, k)


class BendingError(RuntimeError):
    """No bent equilibrium was found; the message names the stage and the cause."""


@dataclass
class BendingSolution:
    """The bent wafer in equilibrium: ``deflection`` (m, cells), the final ``state`` of ``equilibrium``,
    the number of equilibrium solves, the continuation's stiffness factors (``[1.0]`` when none was
    needed) and the Krylov iterations (linearised pressure responses) of the Newton steps."""

    deflection: np.ndarray
    state: object
    solves: int
    stages: list
    krylov: int = 0


def solve_bending(
    equilibrium,
    plate: KirchhoffPlate,
    grid: PolarGrid,
    back_pressure,
    load_stiffness: float,
    tol: float,
    response,
    start=None,
    max_iter: int = 30,
    trial=None,
) -> BendingSolution:
    """Bending w (m) of ``plate`` on ``grid`` with the face pressure of ``equilibrium(w).p_total`` (Pa) and the back pressure ``back_pressure`` (Pa, cells).

    ``response(w, dw)`` is the linear change (Pa, cells) of the face pressure of the
    equilibrium at the bending w (the last one ``equilibrium`` solved) under a change ``dw`` (m)
    of the bending. ``load_stiffness`` k (Pa/m, > 0) preconditions the Newton-Krylov iteration;
    ``tol`` (m) bounds the max-norm of the residual F(w) (the change of the bending a fixed-point
    iteration would still make); ``start`` is a bending to start from (warm start);
    ``max_iter`` bounds the Newton steps of each stage; ``trial(w)``, if given, is the equilibrium
    at the trial bendings of the Newton steps (the others, at each stage's start, are
    ``equilibrium(w)``): one that fails where ``equilibrium`` would search further (a position far
    from balance), so that a step too long is halved rather than paid for. Raises :class:`BendingError`.
    """
    if not (np.isfinite(load_stiffness) and load_stiffness > 0):
        raise BendingError(f"the load stiffness must be finite and > 0 Pa/m to precondition the bending; got {load_stiffness!r}")
    shape = (grid.n_r, grid.n_theta)
    pb = np.asarray(back_pressure, dtype=float).reshape(shape)
    k = load_stiffness
    count = {"solves": 0, "last": None, "krylov": 0}
    trial_solver = equilibrium if trial is None else trial

    def evaluate(w, solver=equilibrium):
        last = count["last"]
        if last is not None and np.array_equal(last[0], w):
            return last[1]
        st = solver(w)
        count["solves"] += 1
        count["last"] = (np.array(w, copy=True), st)
        return st

    failures = (BendingError, RuntimeError, ValueError, np.linalg.LinAlgError)

    def stage(w, scale):
        """The bending at ``scale`` x the plate's stiffness, from ``w`` (raises BendingError, or what the equilibrium raises)."""
        stiff = KirchhoffPlate(plate.thickness, plate.modulus * scale, plate.poisson)
        op = plate_operator(stiff, grid, k)
        k_op = op.k  # the preconditioner's stiffness (k to 1/16 of an octave)

        def residual(wx, solver=equilibrium):
            return op.deflection(np.asarray(evaluate(wx, solver).p_total).reshape(shape) - pb + k_op * wx) - wx

        f = residual(w)
        size = np.max(np.abs(f))
        for _ in range(max_iter):
            if size <= tol:
                return w
            evaluate(w)  # the state the response linearises (already the last one solved)

            def matvec(x, w=w):
                count["krylov"] += 1
                dw = x.reshape(shape)
                return (op.deflection(np.asarray(response(w, dw)).reshape(shape) + k_op * dw) - dw).ravel()

            try:  # from the fixed-point step dw = F, the Newton step of a purely local pressure response
                newton = gmres(matvec, -f.ravel(), x0=f.ravel(), rtol=KRYLOV_RTOL, max_iter=KRYLOV_MAX_ITER).reshape(shape)
            except ValueError:  # no Newton step: the fixed-point step alone
                newton = None
            # The preconditioner is the linearised problem of a local pressure response, so the Newton step is of
            # the size of the fixed-point step F; a step orders of magnitude longer comes from a nearly singular
            # linearisation (a cell at a kink of the pressure's response), not from the problem: take F instead.
            candidates = [("fixed-point", f)]
            if newton is not None and np.all(np.isfinite(newton)) and np.max(np.abs(newton)) <= MAX_STEP_RATIO * size:
                candidates.insert(0, ("Newton", newton))
            for kind, step in candidates:
                for _ in range(MAX_HALVINGS + 1):
                    w_trial = w + step
                    try:
                        f_trial = residual(w_trial, trial_solver)
                    except failures:  # no equilibrium at the trial bending: a step too far, as one that does not lower |F|
                        f_trial = np.full(shape, np.inf)
                    size_trial = np.max(np.abs(f_trial))
                    log.debug(
                        "bending x%g: |F| %.3g m, %s step %.3g m, Krylov %d, trial |F| %.3g m",
                        scale, size, kind, np.max(np.abs(step)), count["krylov"], size_trial,
                    )
                    if size_trial < size:
                        break
                    step = 0.5 * step
                else:
                    continue
                break
            else:
                raise BendingError(f"no Newton or fixed-point step of the bending lowers its residual ({size:.3g} m)")
            w, f, size = w_trial, f_trial, size_trial
        if size <= tol:
            return w
        raise BendingError(f"the bending did not converge in {max_iter} Newton steps (residual {size:.3g} m against {tol:.3g} m)")

    w, stages = None, []
    w0 = np.zeros(shape) if start is None else np.asarray(start, dtype=float).reshape(shape)
    try:  # straight to the plate's stiffness (from the warm start, or flat)
        w = stage(w0, 1.0)
        stages.append(1.0)
    except failures:
        w = None
    if w is None:
        # continuation from the stiffness at which the bending length reaches the wafer radius
        first = max(1.0, k * grid.radius**4 / plate.bending_stiffness)
        w, done, scale = np.zeros(shape), first * STAGE_FACTOR, first
        while True:
            try:
                w = stage(w, scale)
            except failures as exc:
                factor = done / scale
                if factor <= MIN_STAGE_FACTOR:
                    raise BendingError(
                        f"the bending of the wafer did not converge at {scale:.3g} x its stiffness ({type(exc).__name__}: {exc}); "
                        f"stages done (stiffness factors): {', '.join(f'{s:.3g}' for s in stages) or 'none'}"
                    ) from exc
                scale = max(1.0, done / np.sqrt(factor))  # split the stage
                continue
            stages.append(scale)
            if scale == 1.0:
                break
            done, scale = scale, max(1.0, scale / STAGE_FACTOR)
    st = evaluate(w)  # the equilibrium at the converged bending (force and moment balance to the solver's tolerance)
    return BendingSolution(w, st, count["solves"], stages, count["krylov"])
