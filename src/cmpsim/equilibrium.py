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
:class:`cmpsim.cavitation.CavitationSystem`), with Gumbel on the frozen set where p > p_cav. Steps are
limited to a trust region on the change of the film and safeguarded by a backtracking line
search. The start is the contact-only equilibrium at zero tilt (or, without contact, a
bracket of the fluid-only load).
"""

from __future__ import annotations

import threading
from dataclasses import dataclass, field

import numpy as np
from scipy.optimize import brentq

from . import compliance
from .cavitation import CAVITATION_MODELS, CavitationSystem
from .contact import PadSurface, asperity_contact, contact_table
from .geometry import film_thickness
from .grid import PolarGrid
from .reynolds import (
    FaceCoefficients,
    LinearSolveStats,
    LubricationParameters,
    ReynoldsSystem,
    assemble_operator,
    factorize,
    flux_divergence,
    lubrication_coefficients,
)

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
]

MODEL_VARIANTS = ("lep", "elastic", "hydrodynamic")

#: A Newton step's Jacobian factorises its state's matrix when solving that state by iterative
#: refinement took more back-substitutions than this (the old factorisation is too far away).
JACOBIAN_REFINE_LIMIT = 10
#: The Jacobian's columns are finite differences accurate to ~1e-6: their linear solves by
#: refinement stop at this relative accuracy (the pressure solves themselves go to round-off).
JACOBIAN_RTOL = 1e-10

#: Within this factor of the tolerance, Newton keeps its last Jacobian (a chord step): the
#: Jacobian changes by about the relative size of the last step, so the chord step still
#: shrinks the residual by orders of magnitude, and a Jacobian costs more than a pressure solve.
CHORD_MERIT = 100.0

#: Gauge pressure of absolute vacuum, Pa (one standard atmosphere below ambient): the lowest
#: admissible cavitation pressure.
VACUUM_GAUGE_PRESSURE = -101325.0


class EquilibriumError(RuntimeError):
    """No equilibrium was found; the message says why and what was tried."""


@dataclass
class PressureState:
    """Everything computed at one trial position u = (h0, theta, beta).

    ``phi`` is the unknown of the discrete system: ln(p/p0) for the granular slurry, the gauge
    pressure p (Pa) for the Newtonian one, and for JFO cavitation p (Pa) on the full-film
    cells and 1 - theta on the cavitated ones. ``p_slurry`` is the absolute granular pressure
    (granular) or the gauge pressure acting on the wafer (Newtonian: p, max(p, p_cav) with
    Gumbel, the JFO p >= p_cav). ``p_fluid`` = (1 - a_r) times the gauge pressure.
    """

    u: np.ndarray
    h: np.ndarray  # film thickness at cell centres, m
    phi: np.ndarray  # unknown of the discrete system (see above)
    p_slurry: np.ndarray  # granular: absolute granular pressure; newtonian: gauge pressure acting, Pa
    p_fluid: np.ndarray  # (1 - a_r) x gauge pressure, Pa
    p_contact: np.ndarray  # Pa
    area_elastic: np.ndarray
    area_elastoplastic: np.ndarray
    area_plastic: np.ndarray
    residual: np.ndarray  # (R_F, R_y, R_x)
    system: ReynoldsSystem | CavitationSystem | None  # None on a compliant pad (see ``coupling``)
    floored_fraction: float
    fill_fraction: np.ndarray | None = None  # JFO: theta (1 on the full film); else None
    cavitated: np.ndarray | None = None  # Gumbel / JFO: cells held at p_cav; else None
    # ---- pad compliance (compliance.py); None on a rigid pad
    deflection: np.ndarray | None = None  # pad deflection w at cell centres, m
    coupling: object = None  # (CoupledLinearisation, evaluation) for the Jacobian
    # ---- set by the Jacobian of a linear (non-JFO) rigid-pad system: dphi/du, (cells, 3)
    dphi_du: np.ndarray | None = None

    @property
    def p_total(self) -> np.ndarray:
        """Total normal pressure on the wafer (gauge), Pa."""
        return self.p_fluid + self.p_contact

    @property
    def area_ratio(self) -> np.ndarray:
        return self.area_elastic + self.area_elastoplastic + self.area_plastic


@dataclass
class EquilibriumSolution:
    """Converged (or diagnosed) equilibrium."""

    state: PressureState
    converged: bool
    iterations: int
    factorizations: int
    back_substitutions: int
    history: list = field(default_factory=list)


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
    foundation : compliance.WinklerFoundation, compliance.LayeredFoundation or None
        Elastic pad stack under the asperity layer; ``None`` = rigid pad (the paper).
    solver : callable, optional
        Sparse solver of every pressure solve, passed to the Reynolds (or cavitation) system
        (``solver(A)`` returning an object with ``.solve(b)``, a sparse factorisation); default
        :func:`cmpsim.reynolds.factorize` (SuperLU).

    Notes
    -----
    Cost: the factorisation of the last matrix factorised is kept and later trial positions
    are solved by iterative refinement against it (:func:`cmpsim.reynolds.refine`), with a
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
        foundation: compliance.WinklerFoundation | compliance.LayeredFoundation | None = None,
        solver=None,
    ):
        self._init_args = dict(
            dome_height=dome_height, applied_pressure=applied_pressure, ambient_pressure=ambient_pressure,
            lubrication=lubrication, pad=pad, variant=variant, separation_offset=separation_offset,
            cavitation=cavitation, cavitation_pressure=cavitation_pressure, foundation=foundation,
        )
        if variant not in MODEL_VARIANTS:
            raise ValueError(f"model must be one of {MODEL_VARIANTS}; got {variant!r}")
        _check_cavitation(lubrication.slurry_model, cavitation, cavitation_pressure)
        if not (np.isfinite(applied_pressure) and applied_pressure > 0):
            raise ValueError(f"applied_pressure must be > 0 Pa; got {applied_pressure!r}")
        if lubrication.slurry_model == "granular" and not (np.isfinite(ambient_pressure) and ambient_pressure > 0):
            raise ValueError(f"ambient granular pressure must be > 0 Pa; got {ambient_pressure!r}")
        if variant != "hydrodynamic" and pad is None:
            raise ValueError(f"model {variant!r} needs a PadSurface")
        self.grid = grid
        self.dome_height = dome_height
        self.applied_pressure = applied_pressure
        self.p0 = ambient_pressure
        self.lub = lubrication
        self.pad = pad
        self.variant = variant
        self.separation_offset = separation_offset
        self.newtonian = lubrication.slurry_model == "newtonian"
        self.cavitation = cavitation
        self.p_cav = None if cavitation == "none" else float(cavitation_pressure)
        self._last_cavitated = None
        self.foundation = foundation
        if foundation is not None and variant == "hydrodynamic":
            raise ValueError("a compliant pad (pad_compliance = 'winkler') needs a model with contact ('lep' or 'elastic')")
        if foundation is not None and cavitation == "jfo":
            raise ValueError("a compliant pad (pad_compliance = 'winkler') does not take JFO cavitation; use 'gumbel' or 'none'")
        self.sigma = lubrication.roughness.sigma
        R = grid.radius
        self.xc, self.yc = grid.centres
        self.xr, self.yr, _ = grid.radial_faces
        self.xa, self.ya, _ = grid.angular_faces
        self.load_scale = applied_pressure * np.pi * R * R
        # scaling of the unknowns: h0 in sigma, tilts in sigma / R_w
        self.u_scale = np.array([self.sigma, self.sigma / R, self.sigma / R])
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

    @property
    def factorizations(self) -> int:
        """Sparse factorisations so far (calls of ``solver``)."""
        return self.linear.factorizations

    @factorizations.setter
    def factorizations(self, value: int) -> None:
        self.linear.factorizations = value

    @property
    def back_substitutions(self) -> int:
        """Solves with a factorisation so far (including refinement steps)."""
        return self.linear.back_substitutions

    @back_substitutions.setter
    def back_substitutions(self, value: int) -> None:
        self.linear.back_substitutions = value

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
        """Film thickness at points (x, y) for position u = (h0, theta, beta), m."""
        if self.foundation is not None:  # rigid film + pad deflection (compliance.py)
            return compliance.deformed_film(self, u, x, y)
        return film_thickness(x, y, u[0], u[1], self.dome_height, self.grid.radius, cross_tilt=u[2])

    def face_coefficients(self, u) -> FaceCoefficients:
        """Reynolds coefficients on all faces at position u."""
        if self.foundation is None:  # one evaluation on both face sets
            c = lubrication_coefficients(self.film(u, self._xf, self._yf), self._xf, self._yf, self.lub, self._vf)
            floored = int(np.count_nonzero(c[5]))
            return FaceCoefficients(tuple(a[0] for a in c[:5]), tuple(a[1] for a in c[:5]), floored, c[5].size)
        rad = lubrication_coefficients(self.film(u, self.xr, self.yr), self.xr, self.yr, self.lub)
        ang = lubrication_coefficients(self.film(u, self.xa, self.ya), self.xa, self.ya, self.lub)
        floored = int(np.count_nonzero(rad[5]) + np.count_nonzero(ang[5]))
        return FaceCoefficients(rad[:5], ang[:5], floored, rad[5].size + ang[5].size)

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
        g = self.grid
        f = g.integrate(p_total) / self.load_scale - 1.0
        my = g.integrate(p_total * self.xc) / (self.load_scale * g.radius)
        mx = g.integrate(p_total * self.yc) / (self.load_scale * g.radius)
        return np.array([f, my, mx])

    def _combine(self, h, phi, system=None, acting=None):
        """Slurry and contact pressures of the unknown ``phi`` (see :class:`PressureState`).

        ``acting`` (Gumbel only) freezes the set of cells whose own pressure acts (p > p_cav)
        for the Jacobian. Returns (p_slurry, p_fluid, p_c, a_e, a_ep, a_p, theta, cavitated).
        """
        pc, ae, aep, ap = self.contact(h)
        ar = ae + aep + ap
        theta = cav = None
        if not self.newtonian:
            p_abs = self.p0 * np.exp(phi)
            p_fluid = (1.0 - ar) * (p_abs - self.p0)
            return p_abs, p_fluid, pc, ae, aep, ap, theta, cav
        if self.cavitation == "jfo":
            p, theta = system.fields(phi)
            cav = system.cavitated.reshape(p.shape)
        elif self.cavitation == "gumbel":
            cav = phi <= self.p_cav if acting is None else ~acting
            p = np.where(cav, self.p_cav, phi)
        else:
            p = phi
        return p, (1.0 - ar) * p, pc, ae, aep, ap, theta, cav

    def _system(self, coeffs, frozen: PressureState | None = None):
        """The discrete slurry problem of these face coefficients (JFO: on ``frozen``'s set if given)."""
        if self.cavitation == "jfo":
            solver = self._counting_solver
            if frozen is not None:
                return CavitationSystem(self.grid, coeffs, self.p_cav, cavitated=frozen.system.cavitated, solver=solver)
            # start the active-set iteration from the last solved set (the solution does not depend on it)
            system = CavitationSystem(self.grid, coeffs, self.p_cav, guess=self._last_cavitated, solver=solver)
            self._last_cavitated = system.cavitated if system.cavitated.any() else None
            return system
        return ReynoldsSystem(self.grid, coeffs, solver=self.solver, reference=self._reference, stats=self.linear)

    def state(self, u, guess=None) -> PressureState:
        """Solve the Reynolds equation and evaluate contact and residuals at position u.

        ``guess`` (optional, flat, one value per cell) is where iterative refinement against
        an earlier factorisation starts (see :func:`cmpsim.reynolds.refine`): a closer start
        needs fewer back-substitutions, the converged phi is the same to round-off. It is
        ignored where the solve does not refine (JFO, compliant pad, a fresh factorisation).
        """
        if self.foundation is not None:  # film and pad deflection solved together (compliance.py)
            return compliance.coupled_state(self, u)
        u = np.asarray(u, dtype=float)
        h = self.film(u, self.xc, self.yc)
        coeffs = self.face_coefficients(u)
        system = self._system(coeffs)
        phi = system.solve(x0=guess) if isinstance(system, ReynoldsSystem) else system.solve()
        if isinstance(system, ReynoldsSystem) and system.own_factor is not None:
            self._reference = system.own_factor  # later positions refine against it
        if self.newtonian:
            if not np.all(np.isfinite(phi)):
                raise ValueError(
                    f"the slurry pressure is not finite at a minimum film of {h.min() / self.sigma:.3g} sigma; flow "
                    f"factors regularised on {100 * coeffs.floored / max(coeffs.n_faces, 1):.0f} % of the faces"
                )
        elif not np.all(np.isfinite(phi)) or phi.max() > 300.0:  # p > 1e130 p0: no physical state
            raise ValueError(
                f"the slurry pressure diverges (ln(p/p0) up to {np.nanmax(phi):.3g}) at a minimum film of "
                f"{h.min() / self.sigma:.3g} sigma; flow factors regularised on "
                f"{100 * coeffs.floored / max(coeffs.n_faces, 1):.0f} % of the faces"
            )
        p_abs, p_fluid, pc, ae, aep, ap, theta, cav = self._combine(h, phi, system)
        res = self._residual(p_fluid + pc)
        return PressureState(
            u, h, phi, p_abs, p_fluid, pc, ae, aep, ap, res, system, coeffs.floored / max(coeffs.n_faces, 1), theta, cav
        )

    def jacobian(self, st: PressureState, rel_step: float = 1e-6) -> np.ndarray:
        """d(residual)/du at a solved state: 3 coefficient re-evaluations, 3 back-substitutions.

        With cavitation the derivative is the one on the frozen set of cavitated cells (JFO:
        the reduced system of the state; Gumbel: the cells where p > p_cav), exact wherever
        the set does not change under the perturbation.
        """
        if self.foundation is not None:  # includes the pad deflection (compliance.py)
            return compliance.coupled_jacobian(self, st, rel_step)
        if isinstance(st.system, ReynoldsSystem):
            return self._film_jacobian(st, rel_step)
        J = np.empty((3, 3))
        base = st.system.residual(st.phi)
        acting = None if st.cavitated is None else ~st.cavitated
        for k in range(3):
            du = np.zeros(3)
            du[k] = rel_step * self.u_scale[k]
            u = st.u + du
            h = self.film(u, self.xc, self.yc)
            pert = self._system(self.face_coefficients(u), frozen=st)
            dr = pert.residual(st.phi) - base
            dphi = -st.system.factor.solve(dr).reshape(st.phi.shape)
            self.back_substitutions += 1
            _, p_fluid, pc, *_ = self._combine(h, st.phi + dphi, st.system, acting)
            J[:, k] = (self._residual(p_fluid + pc) - st.residual) / du[k]
        return J

    def _film_jacobian(self, st: PressureState, rel_step: float) -> np.ndarray:
        """:meth:`jacobian` for the linear (non-JFO) system on a rigid pad, in one extra
        coefficient evaluation and one extra contact evaluation.

        The face coefficients depend on the local film only (and on the fixed face position),
        so dc/du_k = dc/dh dh/du_k: one forward difference in h gives dc/dh on every face, the
        film changes dh/du_k follow from the geometry, and since A phi - b is linear in the
        coefficients its change is A(dc_k) phi + div(dc_k). Then dphi = -A^-1 dr as before
        (the three columns in one solve). The contact pressure and area likewise take
        dp_c/dh dh/du_k from one evaluation at h + eps.
        """
        J = np.empty((3, 3))
        hf = self.film(st.u, self._xf, self._yf)
        eps = rel_step * self.sigma
        c0 = st.system.coeffs
        c1 = lubrication_coefficients(hf + eps, self._xf, self._yf, self.lub, self._vf)
        dcdh = [(c1[m] - np.stack([c0.radial[m], c0.angular[m]])) / eps for m in range(5)]
        acting = None if st.cavitated is None else ~st.cavitated
        phi = st.phi.ravel()
        dr = np.empty((phi.size, 3))
        steps = []
        for k in range(3):
            du = np.zeros(3)
            du[k] = rel_step * self.u_scale[k]
            steps.append(du)
            dh = self.film(st.u + du, self._xf, self._yf) - hf
            dc = [d * dh for d in dcdh]
            dcoeffs = FaceCoefficients(tuple(a[0] for a in dc), tuple(a[1] for a in dc))
            dr[:, k] = assemble_operator(self.grid, dcoeffs) @ phi + flux_divergence(self.grid, dcoeffs)
        system = st.system
        if system.own_factor is None and system.refinement_steps > JACOBIAN_REFINE_LIMIT:
            # the state is far from the factorised position: a new LU here pays for itself
            # over the three columns and the next trial positions, which refine against it
            system.factor
            self._reference = system.own_factor
        dphis = -system.solve_linear(dr, rtol=JACOBIAN_RTOL)
        st.dphi_du = dphis / (rel_step * self.u_scale)  # the columns' steps du_k
        # contact depends on the local film only: one evaluation gives its derivative in h
        if self.variant == "hydrodynamic":
            dpc = dar = 0.0
        else:
            pc1, ae1, aep1, ap1 = self.contact(st.h + eps)
            dpc = (pc1 - st.p_contact) / eps
            dar = (ae1 + aep1 + ap1 - st.area_ratio) / eps
        for k, du in enumerate(steps):
            dphi = dphis[:, k].reshape(st.phi.shape)
            dh = self.film(st.u + du, self.xc, self.yc) - st.h
            gauge = self._gauge(st.phi + dphi, acting)
            p_total = (1.0 - (st.area_ratio + dar * dh)) * gauge + st.p_contact + dpc * dh
            J[:, k] = (self._residual(p_total) - st.residual) / du[k]
        return J

    def _gauge(self, phi, acting=None):
        """Gauge slurry pressure acting on the wafer for the unknown phi (not JFO), Pa."""
        if not self.newtonian:
            return self.p0 * np.exp(phi) - self.p0
        if self.cavitation == "gumbel":
            cav = phi <= self.p_cav if acting is None else ~acting
            return np.where(cav, self.p_cav, phi)
        return phi

    # ------------------------------------------------------------------ starts
    def contact_only_start(self) -> np.ndarray:
        """h0 at zero tilt for which the pad contact alone carries the applied load."""
        if self.foundation is not None:  # with the pad deflection (compliance.py)
            return compliance.compliant_contact_only_start(self)
        shape = self.film(np.zeros(3), self.xc, self.yc)  # h - h0 at u = 0

        def excess(h0):
            pc = self.contact(h0 + shape)[0]
            return self.grid.integrate(pc) / self.load_scale - 1.0

        h_lo = -shape.min() + 1e-3 * self.sigma  # smallest h0 with a positive film everywhere
        cutoff = self.pad.height_cutoff if np.isfinite(self.pad.height_cutoff) else 12.0
        # beyond this h0 even the lowest point of the wafer clears every summit: no contact
        h_hi = -shape.min() + self.separation_offset + cutoff * self.pad.sigma_s
        if excess(h_lo) < 0:
            raise EquilibriumError(
                "the applied load exceeds what the pad asperities can carry before the wafer "
                f"touches the pad mean plane (contact pressure at zero film is {excess(h_lo) + 1:.3g} "
                "x the applied pressure); lower applied_pressure or stiffen the pad"
            )
        h0 = _contact_root(self, shape, h_lo, h_hi)
        if h0 is None:  # the safeguarded Newton did not settle: bracket and Brent
            h0 = brentq(excess, h_lo, h_hi, xtol=1e-6 * self.sigma, rtol=1e-12)
        return np.array([h0, 0.0, 0.0])

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


def _contact_root(problem: WaferProblem, shape, h_lo: float, h_hi: float, max_iter: int = 30):
    """h0 where the contact load equals the applied load, by Newton's method on its logarithm.

    ln(load) is close to linear in h0 over the contact layer (the summit heights are nearly
    Gaussian), so Newton converges in a few steps: the first slope from one contact evaluation
    at two films (h0 and h0 + eps, stacked), the later ones secants through the last two. Steps are kept inside the bracket [h_lo, h_hi] (bisection
    otherwise). Returns None if it does not converge to 1e-6 sigma.
    """
    sigma = problem.sigma
    eps = 1e-6 * sigma
    target = np.log(problem.load_scale)
    lo, hi = h_lo, h_hi
    h0 = 0.5 * (lo + hi)
    prev = None  # (h0, g) of the last iterate: secant slope after the first step
    for _ in range(max_iter):
        if prev is None:
            pc = problem.contact(np.stack([h0 + shape, h0 + eps + shape]))[0]
            f0, f1 = problem.grid.integrate(pc[0]), problem.grid.integrate(pc[1])
        else:
            f0 = problem.grid.integrate(problem.contact(h0 + shape)[0])
        if f0 <= 0.0:  # no contact at all: the root is below
            hi = h0
            h0, prev = 0.5 * (lo + hi), None
            continue
        g = np.log(f0) - target
        if g > 0:
            lo = h0
        else:
            hi = h0
        if prev is None:
            slope = (np.log(f1) - np.log(f0)) / eps if f1 > 0 else -np.inf
        else:
            slope = (g - prev[1]) / (h0 - prev[0])
        prev = (h0, g)
        step = -g / slope if np.isfinite(slope) and slope < 0 else np.nan
        new = h0 + step
        if not (lo < new < hi):
            new = 0.5 * (lo + hi)
        if abs(new - h0) < 1e-6 * sigma or hi - lo < 1e-6 * sigma:
            return new
        h0 = new
    return None


def _check_cavitation(slurry_model: str, cavitation: str, cavitation_pressure) -> None:
    """Refuse cavitation settings that do not apply, naming the parameter and its valid range."""
    if cavitation not in CAVITATION_MODELS:
        raise ValueError(f"cavitation must be one of {CAVITATION_MODELS}; got {cavitation!r}")
    if cavitation == "none":
        return
    if slurry_model != "newtonian":
        raise ValueError(
            f"cavitation = {cavitation!r} applies to the Newtonian slurry only (slurry_model = 'newtonian'); with "
            f"slurry_model = {slurry_model!r} the valid value is 'none': the granular slurry is solved in ln p, so its "
            "gauge pressure cannot fall below -p0 (an implicit, speed-dependent cavitation pressure)"
        )
    p = cavitation_pressure
    if p is None or not (np.isfinite(p) and VACUUM_GAUGE_PRESSURE <= p <= 0.0):
        raise ValueError(
            f"cavitation_pressure must be a gauge pressure in [{VACUUM_GAUGE_PRESSURE:g}, 0] Pa (no higher than ambient, "
            f"no lower than vacuum); got {p!r}"
        )


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


def balance_load(problem: WaferProblem, u, max_expansions: int = 40) -> np.ndarray:
    """Adjust h0 at fixed tilts until the load balances (bracket + Brent); the Newton safeguard.

    Positions where the film touches the pad or the pressure diverges count as
    overloaded (residual +inf). Returns the new u; raises EquilibriumError if no bracket
    is found.
    """
    u = np.asarray(u, dtype=float)
    sigma = problem.sigma

    seen = {}  # Brent re-evaluates the bracket ends: solve each h0 once

    def load(h0):
        h0 = float(h0)
        if h0 not in seen:
            try:
                seen[h0] = problem.state([h0, u[1], u[2]]).residual[0]
            except ValueError:
                seen[h0] = np.inf
        return seen[h0]

    h0 = _secant_load(problem, u, load)
    if h0 is not None:
        return np.array([h0, u[1], u[2]])
    a, fa = u[0], load(u[0])
    step = 0.25 * sigma
    direction = 1.0 if fa > 0 else -1.0
    for _ in range(max_expansions):
        b = a + direction * step
        fb = load(b)
        if np.sign(fb) != np.sign(fa):
            break
        a, fa = b, fb
        step *= 1.6
    else:
        raise EquilibriumError(
            f"no film thickness balances the load at attack angle {u[1]:.3g} rad: the load residual keeps "
            f"the sign of {fa:.3g} from h0 = {u[0]:.4g} m to {a:.4g} m"
        )
    lo, hi = sorted((a, b))
    flo, fhi = (fa, fb) if a < b else (fb, fa)
    # shrink an infinite end with bisection so that brentq sees finite values
    for _ in range(60):
        if np.isfinite(flo) and np.isfinite(fhi):
            break
        mid = 0.5 * (lo + hi)
        fm = load(mid)
        if np.sign(fm) == np.sign(flo):
            lo, flo = mid, fm
        else:
            hi, fhi = mid, fm
    h0 = brentq(load, lo, hi, xtol=1e-6 * sigma, rtol=1e-14, maxiter=200)
    return np.array([h0, u[1], u[2]])


def _secant_load(problem: WaferProblem, u, load, max_iter: int = 12):
    """h0 balancing the load at fixed tilts by a safeguarded Newton/secant iteration on
    g = ln(1 + R_F) (the load over the applied load, in logarithm: close to linear in h0 where
    the load is steep); None if it does not converge, so that the bracket takes over.

    Its steps shrink quickly, so that after the first ones the pressure solves refine against
    the factorisation at hand instead of factorising at every bracket point.
    """
    sigma = problem.sigma

    def g(h0):
        r = load(h0)
        return np.log1p(r) if np.isfinite(r) and r > -1.0 else np.nan

    h0 = float(u[0])
    g0 = g(h0)
    if not np.isfinite(g0):
        return None
    eps = 1e-4 * sigma
    slope = (g(h0 + eps) - g0) / eps
    for _ in range(max_iter):
        if not (np.isfinite(slope) and slope < 0):
            return None
        step = float(np.clip(-g0 / slope, -0.5 * sigma, 0.5 * sigma))
        h1 = h0 + step
        g1 = g(h1)
        while not np.isfinite(g1) or abs(g1) > abs(g0):  # backtrack towards h0
            step *= 0.5
            if abs(step) < 1e-9 * sigma:
                return None
            h1 = h0 + step
            g1 = g(h1)
        if abs(step) < 1e-6 * sigma or abs(g1) < 1e-12:
            return h1
        slope = (g1 - g0) / (h1 - h0)
        h0, g0 = h1, g1
    return None


def solve_equilibrium(
    problem: WaferProblem,
    start=None,
    tol: float = 1e-9,
    max_iter: int = 40,
    max_step: float = 0.5,
    warm_start: bool | None = None,
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
        u, st, it, history = _from_start(problem, start, warm, tol, max_iter, max_step)
    except (EquilibriumError, ValueError):
        if not coarse_step:
            raise
        # the coarse grid's first step led nowhere on this grid: start again as without it
        return solve_equilibrium(problem, None, tol, max_iter, max_step, warm_start=False)
    if problem._reference is not None:
        cache = _last_factors()
        if len(cache) > 8:
            cache.clear()
        cache[problem.grid] = problem._reference
    return EquilibriumSolution(st, True, it, problem.factorizations, problem.back_substitutions, history)


def _from_start(problem: WaferProblem, start, warm: bool, tol: float, max_iter: int, max_step: float):
    """Newton from ``start`` (with the load balanced first if far off, and for a Newtonian
    slurry one restart from an attack-angle scan): (u, state, steps, history)."""
    u = np.asarray(start, dtype=float).copy()
    if warm and problem._reference is None:
        # a warm start continues a chain of neighbouring points (sweeps, `cmpsim reproduce`):
        # refine against the last factorisation made on this grid (in this thread)
        problem._reference = _last_factors().get(problem.grid)
    try:
        st = problem.state(u)
    except ValueError:
        st = None
    if st is None or abs(st.residual[0]) > 0.25:
        # far from balance (e.g. the slurry adds a large load to the contact-only start):
        # first balance the load by bracketing h0, then let Newton do the rest
        u = balance_load(problem, u)
        st = problem.state(u)
    try:
        u, st, it, history = _newton(problem, u, st, tol, max_iter, max_step)
    except EquilibriumError as first:
        if not problem.newtonian:
            raise
        # A Newtonian film at zero tilt carries almost no net load (its pressure is nearly odd
        # in x), so the contact-only start can sit in a basin of the merit function far from a
        # lift-carried equilibrium. Restart once from the best point of an attack-angle scan.
        try:
            u = _tilt_scan_start(problem, u)
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
    if problem.foundation is not None or problem.cavitation == "jfo":
        return False
    if problem.variant == "hydrodynamic":
        return problem.grid.size > WARM_START_GRIDS[0][0] * WARM_START_GRIDS[0][1]
    return problem.grid.size > _WARM_START_MIN_CELLS


#: Grid of the first Newton step of a cold start (see :func:`_coarse_first_step`).
FIRST_STEP_GRID = (8, 24)


def _use_coarse_step(problem: WaferProblem) -> bool:
    g = problem.grid
    return (
        problem.foundation is None
        and problem.cavitation != "jfo"
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


def _tilt_scan_start(problem: WaferProblem, u, n: int = 9) -> np.ndarray:
    """Balance the load at ``n`` attack angles within the admissible range and return the point
    where the moment about y changes sign (interpolated, in the bracket closest to balance;
    else where it is smallest), cross tilt 0.

    The range is +-0.9 (cutoff sigma + dome height) / R_w: tilting further would lower the
    trailing edge through the layer where the pad carries load.
    """
    cutoff = problem.pad.height_cutoff if problem.pad is not None and np.isfinite(problem.pad.height_cutoff) else 3.0
    layer = cutoff * problem.sigma + problem.dome_height
    limit = 0.9 * layer / problem.grid.radius
    thetas = np.linspace(-limit, limit, n)
    points = []
    for th in thetas:
        try:
            # bracket from above the contact layer: the thickest film that balances the load,
            # not a thin one where the sub-ambient pressure of a full-Sommerfeld film sucks
            # the wafer onto the pad
            v = balance_load(problem, [u[0] + layer, th, 0.0])
            points.append((th, v, problem.state(v).residual[1]))
        except (EquilibriumError, ValueError):
            continue
    if not points:
        raise EquilibriumError("no attack angle of the scan admits a load balance")
    # of the sign changes, the one whose ends are closest to balance (the moment is steep and
    # erratic around thin, sucked-down films)
    brackets = [(max(abs(ma), abs(mb)), va, vb, ma, mb) for (_, va, ma), (_, vb, mb) in zip(points, points[1:]) if ma * mb <= 0 and ma != mb]
    if brackets:
        _, va, vb, ma, mb = min(brackets, key=lambda q: q[0])
        w = ma / (ma - mb)
        return (1 - w) * va + w * vb
    return min(points, key=lambda q: abs(q[2]))[1]


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
        if J is None or _merit(st.residual) > CHORD_MERIT * tol or problem.foundation is not None:
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
        if problem.foundation is None and problem.variant != "hydrodynamic":
            trust = min(max_step, 2.0 * trust) if alpha == 1.0 else max(2.0 * alpha * size, 1e-6)
        # with a compliant pad or the hydrodynamic variant the radius stays at max_step: shrinking
        # it stalled the outer Newton on the default model under Thakurta's conditions and on the
        # hydrodynamic cold start at 80 rpm (coarse grid), where the fixed radius converges
        # (tests/test_validation.py, tests/test_sweeps.py)
        u, st = trial, new
        history.append((u.copy(), st.residual.copy()))
    return u, st, it, history


@dataclass
class RootScan:
    """Moment residual along a scan of attack angles, the load balanced at each (h0 by Brent).

    ``roots`` are the attack angles (rad) where the moment about y changes sign, bracketed by
    the scan and polished with Brent's method; more than one means the equilibrium is not
    unique along this line (cross tilt held at its equilibrium value).
    """

    attack_angles: np.ndarray
    moment_residuals: np.ndarray
    roots: list


def scan_moment_roots(problem: WaferProblem, solution: EquilibriumSolution, n: int = 13, span: float = 0.9) -> RootScan:
    """Look for other equilibria: scan the attack angle over +-``span`` x (h_min / R_w).

    Tilting a wafer by h_min / R_w would make its edge touch the pad mean plane, so the scan
    covers the admissible tilts. Each scan point costs one load balance (about ten pressure
    solves). Points where the load cannot be balanced are left out (NaN).
    """
    st = solution.state
    limit = span * float(st.h.min()) / problem.grid.radius
    thetas = np.linspace(-limit, limit, n)
    moments = np.full(n, np.nan)
    for k, th in enumerate(thetas):
        try:
            u = balance_load(problem, [st.u[0], th, st.u[2]])
            moments[k] = problem.state(u).residual[1]
        except (EquilibriumError, ValueError):
            continue
    def moment(th):
        u = balance_load(problem, [st.u[0], th, st.u[2]])
        return problem.state(u).residual[1]

    roots = []
    for k in range(n - 1):
        a, b = moments[k], moments[k + 1]
        if not (np.isfinite(a) and np.isfinite(b)):
            continue
        if a == 0:
            roots.append(float(thetas[k]))
        elif a * b < 0:
            # polish the bracketed root (each evaluation is one load balance)
            try:
                root = brentq(moment, thetas[k], thetas[k + 1], xtol=1e-4 * (thetas[1] - thetas[0]), maxiter=30)
            except (EquilibriumError, ValueError, RuntimeError):
                root = thetas[k] - a * (thetas[k + 1] - thetas[k]) / (b - a)
            roots.append(float(root))
    return RootScan(thetas, moments, roots)
