"""The wafer under a membrane head: its bending in equilibrium with the pressures on both faces.

The membrane presses the zone pressures p_b on the back of the wafer (:func:`cmpsim.plate.zone_load`),
the slurry and the pad press p(w) on its face, and the wafer, a free Kirchhoff plate
(:mod:`cmpsim.plate`), bends by w (m, positive away from the pad: the film grows by w):

    D del^4 w = p(w) - p_b,        w orthogonal to the rigid-body modes 1, x, y.

Its rigid-body motion is the carrier's (h0, attack angle, cross tilt), found by the equilibrium
solver for each bending: force and moment balance are the plate's solvability conditions, so at
the solution the plate's relief load vanishes and the bending is a bending only.

Solve (docs/model.md, "Carrier"). ``equilibrium(w)`` returns the equilibrium state (force and
moment balance) with the wafer face bent by w. The bending is the root of the preconditioned
fixed-point residual

    F(w) = (K + k) ^-1 (p(w) - p_b + k w) - w,

with K the free plate and k the load stiffness -d(mean pressure)/d(h0) measured at the rigid
equilibrium: where the pressure answers a change of film locally with about k, (K + k)^-1 is the
inverse of the linearised problem and the iteration converges at once (the classical splitting
of a plate on an elastic foundation); the remaining coupling is taken by Anderson mixing
(:func:`scipy.optimize.anderson`). A thin wafer bends over ell = (D / k)^(1/4), a few mm, so the
solve is continued in the bending stiffness: from a stiffness at which ell reaches the wafer
radius (the wafer nearly rigid, the bending small) down to D by factors of 100, each stage
starting from the last; a stage that fails is split once (factor 10).
"""

from __future__ import annotations

import warnings
from dataclasses import dataclass

import numpy as np
from scipy.optimize import anderson
from scipy.optimize import NoConvergence

from .grid import PolarGrid
from .plate import KirchhoffPlate, PlateOperator

__all__ = ["BendingSolution", "BendingError", "solve_bending"]

#: Stages of the continuation in bending stiffness: the first factor tried, and the smallest
#: before giving up.
STAGE_FACTOR = 100.0
MIN_STAGE_FACTOR = 10.0


class BendingError(RuntimeError):
    """No bent equilibrium was found; the message names the stage and the cause."""


@dataclass
class BendingSolution:
    """The bent wafer in equilibrium: ``deflection`` (m, cells), the final ``state`` of ``equilibrium``,
    the number of equilibrium solves and the continuation's stiffness factors."""

    deflection: np.ndarray
    state: object
    solves: int
    stages: list


def solve_bending(
    equilibrium,
    plate: KirchhoffPlate,
    grid: PolarGrid,
    back_pressure,
    load_stiffness: float,
    tol: float,
    start=None,
    max_iter: int = 60,
) -> BendingSolution:
    """Bending w (m) of ``plate`` on ``grid`` with the face pressure of ``equilibrium(w).p_total`` (Pa) and the back pressure ``back_pressure`` (Pa, cells).

    ``load_stiffness`` k (Pa/m, > 0) preconditions the iteration; ``tol`` (m) bounds the
    max-norm of the fixed-point residual F(w) (the change of the bending an iteration would
    still make); ``start`` is a bending to start from (warm start). Raises :class:`BendingError`.
    """
    if not (np.isfinite(load_stiffness) and load_stiffness > 0):
        raise BendingError(f"the load stiffness must be finite and > 0 Pa/m to precondition the bending; got {load_stiffness!r}")
    shape = (grid.n_r, grid.n_theta)
    pb = np.asarray(back_pressure, dtype=float).reshape(shape)
    count = {"solves": 0, "last": None}

    def evaluate(w):
        last = count["last"]
        if last is not None and np.array_equal(last[0], w):
            return last[1]
        st = equilibrium(w)
        count["solves"] += 1
        count["last"] = (np.array(w, copy=True), st)
        return st

    def stage(w0, scale):
        """The bending at ``scale`` x the plate's stiffness, from ``w0`` (raises what Anderson or the equilibrium raise)."""
        stiff = KirchhoffPlate(plate.thickness, plate.modulus * scale, plate.poisson)
        op = PlateOperator(stiff, grid, load_stiffness)

        def residual(x):
            wx = x.reshape(shape)
            st = evaluate(wx)
            return (op.deflection(np.asarray(st.p_total).reshape(shape) - pb + load_stiffness * wx) - wx).ravel()

        if np.max(np.abs(residual(w0.ravel()))) <= tol:  # already there (a warm start at the solution)
            return w0
        with warnings.catch_warnings():  # Anderson's small least-squares problems may be ill-conditioned; harmless
            warnings.simplefilter("ignore")
            return anderson(residual, w0.ravel(), alpha=1.0, M=6, f_tol=tol, maxiter=max_iter).reshape(shape)

    failures = (NoConvergence, BendingError, RuntimeError, ValueError, np.linalg.LinAlgError)
    w, stages = None, []
    if start is not None:  # a warm start goes straight to the plate's stiffness
        try:
            w = stage(np.asarray(start, dtype=float).reshape(shape), 1.0)
            stages.append(1.0)
        except failures:
            w = None
    if w is None:
        # continuation from the stiffness at which the bending length reaches the wafer radius
        first = max(1.0, load_stiffness * grid.radius**4 / plate.bending_stiffness)
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
    return BendingSolution(w, st, count["solves"], stages)
