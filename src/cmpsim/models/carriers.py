"""Carrier models (``carrier``): the wafer's unknowns and the load the carrier applies.

The paper's carrier holds the wafer as a rigid body (:class:`RigidCarrier`): three unknowns,
the film thickness h0 at the centre and the two tilts, driven by the balance of the applied
load and of the moments about the carrier's pivot at the centre of the wafer face
(eq. 30-31). A membrane head (:class:`MembraneCarrier`) presses the wafer through concentric
pressure zones and lets it bend as a free Kirchhoff plate (:mod:`cmpsim.numerics.plate`,
:mod:`cmpsim.operators.membrane`): the same three rigid-body unknowns and balances, plus the bending,
found around the rigid-body Newton solve. The carrier also says how its equilibrium is solved
(:meth:`RigidCarrier.equilibrium`), so the operating point never asks which carrier it has.
"""

from __future__ import annotations

from functools import lru_cache

import numpy as np

from ..physics.geometry import film_thickness
from ..operators.membrane import BendingError, solve_bending
from ..numerics.plate import KirchhoffPlate, zone_load
from ..operators.state import EquilibriumError

__all__ = ["RigidCarrier", "MembraneCarrier", "ring_of", "ring_table"]


#: Interpolation matrices from a grid's cells to points, by (grid, points): the faces and centres of
#: a grid are the same for every solve of a study, so every head on that grid shares them.
_INTERPOLATION: dict = {}


def ring_of(config):
    """The retaining ring of a Config: (inner radius, outer radius, pressure) in m, m, Pa, or None without ring pressure."""
    if config.retaining_ring_pressure == 0.0:
        return None
    inner = 0.5 * config.wafer_diameter + config.retaining_ring_gap
    return (inner, inner + config.retaining_ring_width, config.retaining_ring_pressure)


#: Radii of the table of the ring's pad deflection under the wafer, graded towards the edge.
RING_TABLE = 128


@lru_cache(maxsize=8)
def ring_table(foundation, radius: float, ring: tuple):
    """The pad's deflection under the retaining ring (m) as a function of the radius under the wafer (m).

    ``ring`` = (inner radius, outer radius, pressure) in m, m, Pa; ``foundation`` a laterally
    coupled pad (:meth:`cmpsim.physics.padstack.LayeredFoundation.annulus_deflection`). The Hankel
    integral is evaluated at :data:`RING_TABLE` radii r_j = R (1 - s_j^2), s_j equally spaced
    (spacing 2R/n at the centre, R/n^2 at the edge, where the deflection turns over the pad's
    coupling length), and interpolated by a cubic spline. On the 300mm preset's pad and ring the
    spline is within 6.7e-7 of the integral's largest value at 500 random radii (about 3 pm of
    4 um), where the 1024 equally spaced radii with linear interpolation it replaced were within
    2.2e-4 and cost ten times as much (tests/test_retaining_ring.py checks 1e-6). Cached: every solve of a study on the same
    pad, wafer and ring shares the table.
    """
    inner, outer, pressure = ring
    s = np.linspace(0.0, 1.0, RING_TABLE)
    edge = radius * (1.0 + 1e-9)  # the grid's outermost face points sit on the radius
    table_r = edge * (1.0 - s[::-1] ** 2)
    from scipy.interpolate import CubicSpline  # the retaining ring's table only (issue 31)

    return CubicSpline(table_r, foundation.annulus_deflection(table_r, inner, outer, pressure))


class RigidCarrier:
    """A rigid wafer under a uniform applied pressure, pivoting about the centre of its face.

    Unknowns u = (h0 [m], attack angle theta [rad], cross tilt beta [rad]); residuals

        R_F = (integral of p dA) / (P_applied A) - 1,
        R_y = (integral of p x dA) / (P_applied A R_w),   R_x = (integral of p y dA) / (P_applied A R_w).
    """

    name = "rigid"
    unknowns = ("h0", "attack_angle", "cross_tilt")
    #: The carrier presses in zones whose pressures can be tuned (:func:`cmpsim.tune_zones`).
    has_zones = False
    def __init__(self, ring=None):
        #: The retaining ring: (inner radius, outer radius, pressure) in m, m, Pa, or None.
        self.ring = None if ring is None or ring[2] == 0.0 else tuple(float(v) for v in ring)

    @classmethod
    def from_config(cls, config) -> "RigidCarrier":
        """The rigid carrier with the retaining ring of a Config (``retaining_ring_*``; none at zero pressure)."""
        return cls(ring=ring_of(config))

    def ring_deflection(self, problem, r) -> np.ndarray:
        """The pad's deflection (m, away from the wafer) at radii ``r`` under the retaining ring's load.

        The ring presses ``retaining_ring_pressure`` on the annulus from wafer radius + gap to
        + gap + width; the laterally coupled pad carries it to the wafer's edge
        (:meth:`cmpsim.physics.padstack.LayeredFoundation.annulus_deflection`), tabulated once per pad,
        wafer and ring (:func:`ring_table`) and interpolated by a cubic spline.
        """
        return ring_table(problem.foundation, problem.grid.radius, self.ring)(r)

    def equilibrium(self, problem, solve, start=None, **options):
        """The equilibrium of ``problem``: ``solve(problem, start=start, **options)``, Newton on the
        rigid-body unknowns (:func:`cmpsim.solver.equilibrium.solve_equilibrium`)."""
        return solve(problem, start=start, **options)

    def bending_field(self, problem) -> np.ndarray:
        """The wafer's bending at the cell centres of ``problem``'s grid, m: none for a rigid wafer."""
        return np.zeros((problem.grid.n_r, problem.grid.n_theta))

    def load(self, applied_pressure: float, radius: float) -> float:
        """Total applied load P_applied pi R_w^2, N."""
        return applied_pressure * np.pi * radius * radius

    def scale(self, sigma: float, radius: float) -> np.ndarray:
        """Scale of the unknowns for trust regions and finite differences: h0 in sigma, tilts in sigma / R_w."""
        return np.array([sigma, sigma / radius, sigma / radius])

    def film(self, problem, u, x, y) -> np.ndarray:
        """Film thickness over the undeformed pad at points (x, y), m (eq. 30: dome, tilts, h0), plus the
        pad's deflection under the retaining ring if there is one."""
        h = film_thickness(x, y, u[0], u[1], problem.dome_height, problem.grid.radius, cross_tilt=u[2])
        if self.ring is None:
            return h
        return h + self.ring_deflection(problem, np.hypot(x, y))

    def residual(self, problem, p_total) -> np.ndarray:
        """(R_F, R_y, R_x) of a total normal pressure field on the wafer (gauge, Pa)."""
        g = problem.grid
        f = g.integrate(p_total) / problem.load_scale - 1.0
        my = g.integrate(p_total * problem.xc) / (problem.load_scale * g.radius)
        mx = g.integrate(p_total * problem.yc) / (problem.load_scale * g.radius)
        return np.array([f, my, mx])

    def residual_change(self, problem, dp) -> np.ndarray:
        """The change of (R_F, R_y, R_x) under a change dp of the pressure (the residual is affine in p)."""
        return self.residual(problem, dp) + np.array([1.0, 0.0, 0.0])


class MembraneCarrier(RigidCarrier):
    """A multi-zone membrane head pressing a wafer that bends as a free Kirchhoff plate.

    Zone k presses ``pressures[k]`` (Pa) behind the wafer out to ``radii[k]`` (m); the wafer
    (``plate``: thickness, Young's modulus, Poisson ratio) bends by w under the zone pressures
    behind and the slurry and pad pressures in front (:mod:`cmpsim.operators.membrane`). The rigid-body
    unknowns, the load (the zones' total, ``applied_pressure`` being their area mean) and the
    balances are the rigid carrier's; the film adds the bending:

        h(x, y) = h_rigid(u; x, y) + w(x, y)       (eq. 30 plus the plate's deflection).

    The bending lives on the grid of the first equilibrium solved and is interpolated
    (:meth:`cmpsim.numerics.grid.PolarGrid.interpolate`, second order) to every point the solver asks,
    on that grid or a coarser one.
    """

    name = "membrane"
    has_zones = True
    #: Shares of the zones' departure from their mean applied in turn on a cold start that Newton
    #: could not take in one go (continuation).
    ZONE_RAMP = (0.0, 0.25, 0.5, 0.75, 1.0)

    def __init__(self, radii, pressures, plate: KirchhoffPlate, ring=None):
        super().__init__(ring)
        if len(radii) != len(pressures) or not len(radii):
            raise ValueError(f"a membrane head needs one pressure per zone; got {len(pressures)} pressures for {len(radii)} zones")
        self.radii = tuple(float(r) for r in radii)
        self.pressures = tuple(float(p) for p in pressures)
        self.plate = plate
        self.bending = None  # (grid, cell field of w, m) once solved
        #: A bending (m, cells of the problem's grid) to start the next equilibrium from (a warm start), or None.
        self.initial_bending = None
        #: Equilibria solved at a new bending after the first (rigid-body) one, and the Krylov vectors
        #: (linearised pressure responses) of the bending's Newton steps, in the last equilibrium.
        self.bending_solves = 0
        self.krylov_iterations = 0

    @classmethod
    def from_config(cls, config) -> "MembraneCarrier":
        """The membrane head of a Config: ``zone_radii`` / ``zone_pressures`` (or ``applied_pressure`` in
        every zone), the wafer plate from ``wafer_thickness``, ``wafer_modulus``, ``wafer_poisson``."""
        plate = KirchhoffPlate(config.wafer_thickness, config.wafer_modulus, config.wafer_poisson)
        return cls(config.zone_outer_radii, config.zone_pressure_values, plate, ring=ring_of(config))

    def _bend_matrix(self, grid, x, y):
        """The (cached) matrix that interpolates a cell field of ``grid`` to the points (x, y)."""
        x, y = np.broadcast_arrays(np.asarray(x, dtype=float), np.asarray(y, dtype=float))
        key = (grid, x.shape, hash(x.tobytes()), hash(y.tobytes()))
        m = _INTERPOLATION.get(key)
        if m is None:
            if len(_INTERPOLATION) > 32:
                _INTERPOLATION.clear()
            m = _INTERPOLATION[key] = grid.interpolation_matrix(x.ravel(), y.ravel())
        return m

    def _bend(self, x, y) -> np.ndarray:
        grid, w = self.bending
        shape = np.broadcast_shapes(np.shape(x), np.shape(y))
        return (self._bend_matrix(grid, x, y) @ w.ravel()).reshape(shape)

    def film(self, problem, u, x, y) -> np.ndarray:
        """The rigid carrier's film plus the wafer's bending at points (x, y), m."""
        h = super().film(problem, u, x, y)
        if self.bending is None:
            return h
        return h + self._bend(x, y)

    def bending_field(self, problem) -> np.ndarray:
        """The wafer's bending w (m, away from the pad) at the cell centres of ``problem``'s grid (0 before a solve)."""
        if self.bending is None:
            return super().bending_field(problem)
        return self._bend(problem.xc, problem.yc)

    def back_pressure(self, grid) -> np.ndarray:
        """The zone pressures behind the wafer as a cell field on ``grid``, Pa (:func:`cmpsim.numerics.plate.zone_load`)."""
        return zone_load(grid, self.radii, self.pressures)

    def equilibrium(self, problem, solve, start=None, **options):
        """Rigid-body equilibrium of the flat-backed wafer (or of :attr:`initial_bending`, a warm start),
        then the bending found around it (:func:`cmpsim.operators.membrane.solve_bending`): each Newton step of
        the bending is one ``solve``, warm-started at the rigid-body position the linearised balance
        predicts, and its Krylov vectors are linearised pressure responses of the pad model
        (``film_response``, ``sensitivity``: one back-substitution each).

        The load stiffness that preconditions the bending is -d(load)/d(h0) / area at the
        rigid-body equilibrium (from its sensitivity: three back-substitutions). A cold start whose
        zones Newton cannot reach from the flat wafer ramps them from their mean
        (:attr:`ZONE_RAMP`). Raises EquilibriumError if the bending does not converge.
        """
        grid = problem.grid
        warm = self.initial_bending
        self.bending = None if warm is None else (grid, np.array(warm, dtype=float).reshape(grid.n_r, grid.n_theta))
        sol = solve(problem, start=start, **options)
        pad = problem.pad_model
        # the last equilibrium solved, the bending it was solved at, and its linearisation (J, dP/du) once asked for
        flat = np.zeros((grid.n_r, grid.n_theta)) if self.bending is None else self.bending[1]
        last = {"sol": sol, "iterations": sol.iterations, "w": flat, "lin": pad.sensitivity(problem, sol.state), "solves": 0}
        # the load stiffness: -d(mean pressure)/d(h0) at the rigid-body equilibrium
        stiffness = -grid.integrate(last["lin"][1][..., 0]) / grid.integrate(np.ones_like(sol.state.h))
        shape = (grid.n_r, grid.n_theta)

        def balanced_response(dw, expect=False):
            """(dP, du): the linear change of the face pressure (Pa, cells) and of u under a bending change dw at
            the last state (with ``expect``, the next coupled solve starts from the film it predicts)."""
            state = last["sol"].state
            if last["lin"] is None:
                last["lin"] = pad.sensitivity(problem, state)
            J, dP_du = last["lin"]
            flat = dw.ravel()
            films = (flat, self._bend_matrix(grid, problem.xr, problem.yr) @ flat, self._bend_matrix(grid, problem.xa, problem.ya) @ flat)
            dP = (pad.expect_film_change if expect else pad.film_response)(problem, state, *films).reshape(shape)
            du = -np.linalg.solve(J, self.residual_change(problem, dP))  # the rigid body re-balanced
            return dP + dP_du @ du, du

        def equilibrium(w, rebalance=True):
            w = np.array(w, dtype=float, copy=True)
            if np.array_equal(w, last["w"]):  # the bending of the last equilibrium (the start): solved already
                return last["sol"].state
            guess = last["sol"].state.u
            if last["lin"] is not None:  # the position the linearised balance predicts for this bending
                guess = guess + balanced_response(w - last["w"], expect=True)[1]
            self.bending = (grid, w)
            last["solves"] += 1
            last["sol"] = solve(problem, start=guess, rebalance=rebalance, **options)
            last["iterations"] += last["sol"].iterations
            last["w"], last["lin"] = w, None
            return last["sol"].state

        def response(w, dw):
            return balanced_response(np.asarray(dw, dtype=float).reshape(shape))[0]

        def trial(w):
            """The equilibrium at a trial bending of a Newton step: a position the linearised balance puts far
            from load balance means a step too long for the linearisation, cheaper halved than bracketed."""
            return equilibrium(w, rebalance=False)

        tol = 1e3 * options.get("tol", 1e-9) * problem.sigma
        target = self.back_pressure(grid)
        mean = grid.integrate(target) / grid.integrate(np.ones_like(target))
        uniform = np.allclose(target, mean, rtol=1e-12, atol=0.0)
        w, krylov = (None if warm is None else self.bending[1]), 0

        def bend(ramp, w):
            nonlocal krylov
            for share in ramp:
                bent = solve_bending(equilibrium, self.plate, grid, mean + share * (target - mean), stiffness, tol, response, start=w, trial=trial)
                w, krylov = bent.deflection, krylov + bent.krylov
            return w

        try:
            try:  # straight to the zones' pressures
                w = bend((1.0,), w)
            except BendingError:
                if warm is not None or uniform:
                    raise
                # a cold start of strongly non-uniform zones: bend the wafer under uniform zones first, then ramp
                w = bend(self.ZONE_RAMP, None)
        except BendingError as exc:
            raise EquilibriumError(f"membrane carrier: {exc}") from exc
        self.bending = (grid, w)
        self.bending_solves = last["solves"]  # equilibria solved at a new bending, after the first
        self.krylov_iterations = krylov
        last["sol"].iterations = last["iterations"]  # Newton steps of every rigid-body solve of the bending
        return last["sol"]
