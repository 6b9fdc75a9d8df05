"""The wafer on the pad at one operating point: the problem the equilibrium solver takes.

:class:`WaferProblem` holds the grid, the load and the four models of the operating point
(pad, slurry with its cavitation, carrier; :mod:`cmpsim.models`) and answers, for a trial
position u of the wafer, the film, the Reynolds coefficients, the asperity contact and the
balance residuals; the pressure solve and its Jacobian are the pad model's. Newton's method
on u is :func:`cmpsim.solver.equilibrium.solve_equilibrium`.
"""

from __future__ import annotations

import numpy as np

from .. import models
from ..physics.contact import PadSurface, asperity_contact, contact_table
from ..numerics.grid import PolarGrid
from ..operators.reynolds import FaceCoefficients, LinearSolveStats, LubricationParameters, ReynoldsSystem, factorize
from ..operators.state import PressureState

__all__ = ["WaferProblem", "MODEL_VARIANTS"]

MODEL_VARIANTS = ("lep", "elastic", "hydrodynamic")


def _linear_count(name: str, doc: str) -> property:
    """A counter of the problem's :class:`~cmpsim.operators.reynolds.LinearSolveStats` (``self.linear``), readable and settable."""
    return property(lambda self: getattr(self.linear, name), lambda self, value: setattr(self.linear, name, value), doc=doc)


class WaferProblem:
    """One operating point of the wafer on the polar grid.

    Parameters
    ----------
    grid : PolarGrid
        Grid on the wafer disk (its radius is R_w).
    dome_height : float
        delta_d, m.
    applied_pressure : float
        Applied load over wafer area, Pa (> 0).
    ambient_pressure : float
        Granular pressure p0 at the wafer edge, Pa (> 0).
    lubrication : LubricationParameters
    pad : PadSurface or None
        Asperity description; ``None`` only for the hydrodynamic variant.
    variant : {"lep", "elastic", "hydrodynamic"}
    separation_offset : float
        Subtracted from the film to give the summit separation, m.
    cavitation : {"none", "gumbel", "jfo"}
        Cavitation of the Newtonian slurry (``lubrication.slurry_model == "newtonian"``):
        full Sommerfeld, Gumbel (acting pressure max(p, p_cav)) or mass-conserving JFO.
        The granular slurry takes only "none" (its gauge pressure is bounded below by -p0).
    cavitation_pressure : float, optional
        p_cav, gauge, Pa, in [-101325, 0]; required unless ``cavitation == "none"``.
    foundation : cmpsim.physics.padstack.WinklerFoundation, cmpsim.physics.padstack.LayeredFoundation or None
        Elastic pad stack under the asperity layer; ``None`` = rigid pad (the paper). Picks
        the pad model (:func:`cmpsim.models.pad_for_foundation`) unless ``pad_model`` is given.
    solver : callable, optional
        Sparse solver of every pressure solve, passed to the Reynolds (or cavitation) system
        (``solver(A)`` returning an object with ``.solve(b)``, a sparse factorisation); default
        :func:`cmpsim.operators.reynolds.factorize` (SuperLU).
    pad_model, slurry, carrier : optional
        The model objects (:mod:`cmpsim.models`), as :func:`cmpsim.solver.setup.build_problem` builds
        them from a Config; by default built from ``foundation``, ``lubrication.slurry_model``
        with ``cavitation``, and the rigid carrier.

    Notes
    -----
    Cost: the factorisation of the last matrix factorised is kept and later trial positions
    are solved by iterative refinement against it (:func:`cmpsim.operators.reynolds.refine`), with a
    new factorisation only when the refinement stalls. ``factorizations`` counts the calls of
    ``solver`` (real factorisations), ``back_substitutions`` the solves with them.
    """


    def __init__(
        self,
        grid: PolarGrid,
        dome_height: float,
        applied_pressure: float,
        ambient_pressure: float,
        lubrication: LubricationParameters,
        pad: PadSurface | None,
        variant: str = "lep",
        separation_offset: float = 0.0,
        cavitation: str = "none",
        cavitation_pressure: float | None = None,
        foundation=None,
        solver=None,
        pad_model=None,
        slurry=None,
        carrier=None,
    ):
        self._init_args = dict(
            dome_height=dome_height, applied_pressure=applied_pressure, ambient_pressure=ambient_pressure,
            lubrication=lubrication, pad=pad, variant=variant, separation_offset=separation_offset,
            cavitation=cavitation, cavitation_pressure=cavitation_pressure, foundation=foundation,
            pad_model=pad_model, slurry=slurry, carrier=carrier,
        )
        if variant not in MODEL_VARIANTS:
            raise ValueError(f"model must be one of {MODEL_VARIANTS}; got {variant!r}")
        if slurry is None:
            slurry = models.slurry_model(lubrication.slurry_model, cavitation, cavitation_pressure, ambient_pressure)
        if not (np.isfinite(applied_pressure) and applied_pressure > 0):
            raise ValueError(f"applied_pressure must be > 0 Pa; got {applied_pressure!r}")
        if variant != "hydrodynamic" and pad is None:
            raise ValueError(f"model {variant!r} needs a PadSurface")
        # the inputs as attributes (the same shape as any constructor's, e.g. calibration's _Problem)
        self.grid = grid
        self.dome_height = dome_height
        self.applied_pressure = applied_pressure
        self.p0 = ambient_pressure
        self.lub = lubrication
        self.pad = pad
        self.variant = variant
        self.separation_offset = separation_offset
        #: The models of this operating point (cmpsim.models): asked, never tested by name.
        self.slurry = slurry
        self.pad_model = pad_model if pad_model is not None else models.pad_for_foundation(foundation)
        self.carrier = carrier if carrier is not None else models.carrier()
        self.pad_model.check(variant, slurry)
        self.cavitation = slurry.cavitation.name
        self.p_cav = slurry.cavitation.p_cav
        self.foundation = self.pad_model.foundation
        self._last_cavitated = None
        self.sigma = lubrication.roughness.sigma
        R = grid.radius
        self.xc, self.yc = grid.centres
        self.xr, self.yr, _ = grid.radial_faces
        self.xa, self.ya, _ = grid.angular_faces
        self.load_scale = self.carrier.load(applied_pressure, R)
        # scaling of the unknowns: h0 in sigma, tilts in sigma / R_w
        self.u_scale = self.carrier.scale(self.sigma, R)
        self.solver = solver or factorize
        self.linear = LinearSolveStats()
        self._reference = None  # the last factorisation: later positions refine against it
        # all faces stacked (radial, angular) for one coefficient evaluation; kinematics cached
        self._xf = np.stack([self.xr, self.xa])
        self._yf = np.stack([self.yr, self.ya])
        self._vf = lubrication.kinematics.mean_and_relative(self._xf, self._yf)
        # contact depends on the separation alone: tabulate it once (error < 1e-8, see ContactTable)
        self._contact_table = None
        if variant != "hydrodynamic" and np.isfinite(pad.height_cutoff):
            self._contact_table = contact_table(pad, variant)

    factorizations = _linear_count("factorizations", "Sparse factorisations so far (calls of ``solver``).")
    back_substitutions = _linear_count("back_substitutions", "Solves with a factorisation so far (including refinement steps).")

    def _counting_solver(self, A):
        self.linear.factorizations += 1
        return self.solver(A)

    def on_grid(self, grid: PolarGrid) -> "WaferProblem":
        """The same operating point on another grid (for coarse-grid warm starts)."""
        other = WaferProblem(grid, solver=self.solver, **self._init_args)
        other._contact_table = self._contact_table
        return other

    # ------------------------------------------------------------------ geometry
    def film(self, u, x, y) -> np.ndarray:
        """Film thickness at points (x, y) for position u = (h0, theta, beta), m (the pad model's)."""
        return self.pad_model.film(self, u, x, y)

    def face_coefficients(self, u) -> FaceCoefficients:
        """Reynolds coefficients on all faces at position u."""
        return self.pad_model.face_coefficients(self, u)

    def contact(self, h):
        """Asperity contact at film thickness h (zero for the hydrodynamic variant)."""
        if self.variant == "hydrodynamic":
            z = np.zeros_like(h)
            return z, z, z, z
        d = h - self.separation_offset
        c = self._contact_table(d) if self._contact_table is not None else asperity_contact(d, self.pad, model=self.variant)
        return c.pressure, c.area_ratio_elastic, c.area_ratio_elastoplastic, c.area_ratio_plastic

    # ------------------------------------------------------------------ residuals
    def _residual(self, p_total) -> np.ndarray:
        """The carrier's balance residuals (R_F, R_y, R_x) of a total pressure field."""
        return self.carrier.residual(self, p_total)

    def _combine(self, h, phi, system=None, acting=None):
        """Slurry and contact pressures of the unknown ``phi`` (see :class:`PressureState`).

        ``acting`` (Gumbel only) freezes the set of cells whose own pressure acts (p > p_cav)
        for the Jacobian. Returns (p_slurry, p_fluid, p_c, a_e, a_ep, a_p, theta, cavitated).
        """
        pc, ae, aep, ap = self.contact(h)
        ar = ae + aep + ap
        p_slurry, gauge, theta, cav = self.slurry.pressures(phi, system, acting)
        return p_slurry, (1.0 - ar) * gauge, pc, ae, aep, ap, theta, cav

    def _system(self, coeffs, frozen: PressureState | None = None):
        """The discrete slurry problem of these face coefficients (JFO: on ``frozen``'s set if given)."""
        return self.slurry.system(self, coeffs, frozen)

    def reynolds_system(self, coeffs) -> ReynoldsSystem:
        """The linear Reynolds system of these coefficients, refining against the last factorisation."""
        return ReynoldsSystem(self.grid, coeffs, solver=self.solver, reference=self._reference, stats=self.linear)

    def state(self, u, guess=None) -> PressureState:
        """Solve the Reynolds equation and evaluate contact and residuals at position u.

        ``guess`` (optional, flat, one value per cell) is where iterative refinement against
        an earlier factorisation starts (see :func:`cmpsim.operators.reynolds.refine`): a closer start
        needs fewer back-substitutions, the converged phi is the same to round-off. It is
        ignored where the solve does not refine (JFO, compliant pad, a fresh factorisation).
        On a compliant pad the film and the pad deflection are solved together.
        """
        return self.pad_model.state(self, u, guess)

    def jacobian(self, st: PressureState, rel_step: float = 1e-6) -> np.ndarray:
        """d(residual)/du at a solved state (the pad model's linearisation).

        With cavitation the derivative is the one on the frozen set of cavitated cells (JFO:
        the reduced system of the state; Gumbel: the cells where p > p_cav), exact wherever
        the set does not change under the perturbation.
        """
        return self.pad_model.jacobian(self, st, rel_step)

    # ------------------------------------------------------------------ starts
    def contact_only_start(self) -> np.ndarray:
        """h0 at zero tilt for which the pad contact alone carries the applied load (the pad model's)."""
        return self.pad_model.contact_only_start(self)

    def fluid_start(self) -> np.ndarray:
        """h0 at zero tilt bracketing the fluid-only load (hydrodynamic variant)."""
        shape = self.film(np.zeros(3), self.xc, self.yc)
        h_lo = -shape.min() + 0.5 * self.sigma
        vals = []
        for factor in (1.0, 1.5, 2.0, 3.0, 5.0, 8.0):
            h0 = h_lo * factor + (factor - 1.0) * self.sigma
            try:
                vals.append((h0, self.state([h0, 0.0, 0.0]).residual[0]))
            except ValueError:  # diverging pressure at a thin film: overloaded
                vals.append((h0, np.inf))
            if len(vals) > 1 and (vals[-2][1] > 0 >= vals[-1][1] or vals[-2][1] < 0 <= vals[-1][1]):
                break  # the first sign change is the bracket taken below: no need to probe further
        for (a, fa), (b, fb) in zip(vals, vals[1:]):
            if fa > 0 >= fb or fa < 0 <= fb:
                if not np.isfinite(fa):
                    return np.array([b, 0.0, 0.0])
                return np.array([a + (b - a) * fa / (fa - fb), 0.0, 0.0])
        best = min(vals, key=lambda v: abs(v[1]))
        return np.array([best[0], 0.0, 0.0])

