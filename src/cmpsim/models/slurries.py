"""Slurry models (``slurry_model``, with ``cavitation``): the pressure unknown, cavitation and shear.

A slurry model owns what depends on the slurry's rheology beyond the Reynolds coefficients
(:data:`cmpsim.operators.reynolds.RHEOLOGIES`):

- the unknown phi of the discrete system and the pressures it stands for: ln(p/p0) and the
  absolute granular pressure p0 e^phi (:class:`GranularSlurry`, the paper), or the gauge
  pressure p (:class:`NewtonianSlurry`);
- the cavitation of the film (Newtonian only): :class:`NoCavitation` (full Sommerfeld),
  :class:`GumbelCavitation` (acting pressure max(p, p_cav)) or :class:`JFOCavitation`
  (mass-conserving, the complementarity system of :mod:`cmpsim.operators.cavitation`);
- the shear stress of the slurry on the wafer (eq. 14-15; Patir & Cheng 1979) and the normal
  stress the removal law sees.

``docs/model.md`` ("Reynolds equation", "Newtonian slurry and cavitation") gives the physics.
The objects are built by name in :mod:`cmpsim.models` (the registry).
"""

from __future__ import annotations

import numpy as np

import scipy.sparse as sp

from ..operators.cavitation import CavitationSystem, upwind_couette_matrix
from ..physics.flowfactors import shear_stress_factors
from ..physics.grainflow import GrainFlow, grain_coefficients
from ..physics.removal import newtonian_shear_stress, slurry_shear_stress
from ..operators.reynolds import NEWTONIAN_GRAIN_COEFFICIENT, FaceCoefficients, assemble_operator, flux_divergence, own_face_fluxes

__all__ = ["NoCavitation", "GumbelCavitation", "JFOCavitation", "GranularSlurry", "NewtonianSlurry", "FILL_SCALE"]

#: The pressure scale s of the JFO universal variable on a compliant pad, Pa: a cell with
#: psi = p_cav - s is empty (theta = 0). One atmosphere, the scale of the cavitation pressure
#: itself, keeps the columns of the cavitated cells of the Newton matrix of the order of the others.
FILL_SCALE = 101325.0


def _floored_share(coeffs) -> float:
    """Percentage of the faces whose flow-factor tensor was regularised."""
    return 100 * coeffs.floored / max(coeffs.n_faces, 1)


# ---------------------------------------------------------------------------------- cavitation
class NoCavitation:
    """Full Sommerfeld: the gauge pressure p acts with either sign; the system is linear."""

    name = "none"
    p_cav = None
    #: The coarse-grid starts of :mod:`cmpsim.solver.equilibrium` apply (linear system).
    coarse_starts = True
    #: Can be solved coupled with a compliant pad's deflection (:mod:`cmpsim.operators.compliance`).
    couples_with_deflection = True

    def system(self, problem, coeffs, frozen=None):
        """The discrete problem of these face coefficients: the linear Reynolds system."""
        return problem.reynolds_system(coeffs)

    def acting(self, p, system=None, acting=None):
        """(pressure acting on the wafer, fill fraction or None, cavitated cells or None), Pa."""
        return p, None, None

    def gauge(self, p, acting=None):
        """Gauge pressure acting on the wafer of the unknown p (not JFO), Pa."""
        return p

    def linearised(self, p):
        """(acting pressure, its derivative in p) for the coupled Newton of a compliant pad."""
        return p, np.ones_like(p)

    def cavitated(self, p):
        """Cells held at p_cav (None: no cavitation)."""
        return None

    # ---- the coupled solve of a compliant pad (cmpsim.operators.compliance): the unknown, its residual
    def residual(self, grid, coeffs, phi):
        """(R, dR/dphi) of the Reynolds system at the unknown phi: R = A phi + div q, m^3/s (flat).

        The system is linear in phi (Gumbel clips only the pressure that acts on the wafer),
        so dR/dphi is the operator A of :func:`cmpsim.operators.reynolds.assemble_operator`.
        """
        A = assemble_operator(grid, coeffs)
        return A @ np.asarray(phi).ravel() + flux_divergence(grid, coeffs), A

    def flux_change(self, grid, coeffs, dcoeffs, phi):
        """The change of :meth:`residual` when the face coefficients change by ``dcoeffs`` at fixed phi, m^3/s.

        Linear in ``dcoeffs`` (the residual is linear in the coefficients); ``coeffs`` are the
        coefficients it is taken at (unused here: no upwinding).
        """
        return assemble_operator(grid, dcoeffs) @ np.asarray(phi).ravel() + flux_divergence(grid, dcoeffs)

    def face_flux_slopes(self, grid, coeffs, dcoeffs, phi, ops):
        """(radial, angular) slope of each cell's own outer-radial and counter-clockwise face flux
        under the face-coefficient derivatives ``dcoeffs``, m^3/s per m of film (flat, size N each).

        The system is linear in the coefficients, so each slope is the part of its own cell's row of
        :meth:`flux_change` that belongs to that face: :func:`cmpsim.operators.reynolds.own_face_fluxes`, one
        pass (``coeffs`` and ``ops`` unused here).
        """
        return own_face_fluxes(grid, dcoeffs, phi)


class GumbelCavitation(NoCavitation):
    """Gumbel (half-Sommerfeld): the pressure acting on the wafer is max(p, p_cav).

    Its derivatives are taken on the frozen set where p > p_cav (semismooth Newton).
    """

    name = "gumbel"

    def __init__(self, p_cav: float):
        self.p_cav = float(p_cav)

    def acting(self, p, system=None, acting=None):
        cav = p <= self.p_cav if acting is None else ~acting
        return np.where(cav, self.p_cav, p), None, cav

    def gauge(self, p, acting=None):
        cav = p <= self.p_cav if acting is None else ~acting
        return np.where(cav, self.p_cav, p)

    def linearised(self, p):
        acting = p > self.p_cav
        return np.where(acting, p, self.p_cav), acting.astype(float)

    def cavitated(self, p):
        return p <= self.p_cav


class JFOCavitation(NoCavitation):
    """Mass-conserving JFO cavitation: unknowns p and 1 - theta (:class:`cmpsim.operators.cavitation.CavitationSystem`).

    On a rigid pad the unknown is that of :class:`~cmpsim.operators.cavitation.CavitationSystem`: p on
    the full film, r = 1 - theta on the cavitated cells, solved by the primal-dual active set.
    The system is a complementarity problem, so the coarse-grid starts do not take it.

    On a compliant pad (:mod:`cmpsim.operators.compliance`) the film and the pad deflection are solved
    together by Newton's method, and the complementarity is carried by one universal variable
    psi per cell, Pa (in the spirit of Elrod's switch function; Giacopini et al. 2010 for the
    complementarity):

        p = max(psi, p_cav),    theta = 1 - max(p_cav - psi, 0) / s,    s = :data:`FILL_SCALE`,

    so that p >= p_cav, theta <= 1 and (p - p_cav)(1 - theta) = 0 hold by construction and the
    mass balance A p + B theta + c = 0 (:meth:`CavitationSystem.mass_residual`) is one smooth
    equation per cell on each side of psi = p_cav. Newton's method on it, with the derivative
    taken on the side psi is on, is the semismooth Newton (primal-dual active set) iteration
    of the rigid pad with the deflection solved in; the cavitated set is {psi < p_cav}. The
    pressure that acts on the wafer is Gumbel's max(psi, p_cav); what differs from Gumbel is
    the Reynolds residual, which conserves mass where the film ruptures.
    """

    name = "jfo"
    coarse_starts = False
    couples_with_deflection = True

    def __init__(self, p_cav: float):
        self.p_cav = float(p_cav)

    def system(self, problem, coeffs, frozen=None):
        """The JFO system; on ``frozen``'s cavitated set if given (the Jacobian's reduced system)."""
        solver = problem._counting_solver
        if frozen is not None:
            return CavitationSystem(problem.grid, coeffs, self.p_cav, cavitated=frozen.system.cavitated, solver=solver)
        # start the active-set iteration from the last solved set (the solution does not depend on it)
        system = CavitationSystem(problem.grid, coeffs, self.p_cav, guess=problem._last_cavitated, solver=solver)
        problem._last_cavitated = system.cavitated if system.cavitated.any() else None
        return system

    def acting(self, p, system=None, acting=None):
        """(p, theta, cavitated) of the unknown: that of ``system`` (rigid pad), or the
        universal variable psi of the coupled solve when ``system`` is None."""
        if system is None:
            psi = np.asarray(p)
            return np.maximum(psi, self.p_cav), self.fill_fraction(psi), psi < self.p_cav
        p, theta = system.fields(p)
        return p, theta, system.cavitated.reshape(p.shape)

    def gauge(self, p, acting=None):  # the rigid-pad JFO Jacobian goes through acting(), with the system
        raise NotImplementedError("the JFO pressure needs its system: use acting()")

    # ---- the universal variable psi of the coupled solve (class docstring)
    def fill_fraction(self, psi):
        """theta = 1 - max(p_cav - psi, 0) / s of the universal variable psi (Pa)."""
        return 1.0 - np.maximum(self.p_cav - np.asarray(psi), 0.0) / FILL_SCALE

    def linearised(self, psi):
        """(p = max(psi, p_cav), dp/dpsi): 1 on the full film, 0 on the cavitated cells."""
        psi = np.asarray(psi)
        full = psi >= self.p_cav
        return np.where(full, psi, self.p_cav), full.astype(float)

    def cavitated(self, psi):
        """Cells of the coupled solve whose film has ruptured (psi < p_cav)."""
        return np.asarray(psi) < self.p_cav

    def residual(self, grid, coeffs, psi):
        """(R, dR/dpsi): the mass balance R = A p + B theta + c per cell, m^3/s (flat), of the
        universal variable psi, with its derivative on the side of p_cav each cell is on:
        A diag(full) + B diag(cavitated) / s (:mod:`cmpsim.operators.cavitation`)."""
        psi = np.asarray(psi).ravel()
        A = assemble_operator(grid, coeffs)
        B, c = upwind_couette_matrix(grid, coeffs)
        p, dp = self.linearised(psi)
        R = A @ p + B @ self.fill_fraction(psi) + c
        return R, (A @ sp.diags(dp) + B @ sp.diags((1.0 - dp) / FILL_SCALE)).tocsr()

    def flux_change(self, grid, coeffs, dcoeffs, psi):
        """The change of :meth:`residual` under a change ``dcoeffs`` of the face coefficients
        ``coeffs`` at fixed psi: the diffusive flux of p plus the Couette flux of theta,
        upwinded as the flux of ``coeffs`` is (exact while no face flux changes sign), m^3/s."""
        psi = np.asarray(psi).ravel()
        B, c = upwind_couette_matrix(grid, dcoeffs, direction=coeffs)
        return assemble_operator(grid, dcoeffs) @ self.linearised(psi)[0] + B @ self.fill_fraction(psi) + c

    def face_flux_slopes(self, grid, coeffs, dcoeffs, psi, ops):
        """The face-flux slopes of :meth:`NoCavitation.face_flux_slopes` for the JFO mass balance.

        Its Couette flux is upwinded by the direction of ``coeffs``' flux, so the slopes are taken
        from :meth:`flux_change` on every second ring (sector) at a time: the faces of one parity
        touch disjoint cells, and each cell's change is then its own face's slope.
        """
        zero = tuple(np.zeros_like(a) for a in dcoeffs.radial)
        s_rad = np.empty(grid.size)
        s_ang = np.empty(grid.size)
        for parity in (0, 1):
            mask = ops.ring_parity == parity
            r = self.flux_change(grid, coeffs, FaceCoefficients(tuple(a * mask for a in dcoeffs.radial), zero), psi)
            s_rad[mask.ravel()] = r[mask.ravel()]
            mask = ops.sector_parity == parity
            r = self.flux_change(grid, coeffs, FaceCoefficients(zero, tuple(a * mask for a in dcoeffs.angular)), psi)
            s_ang[mask.ravel()] = r[mask.ravel()]
        return s_rad, s_ang


# ---------------------------------------------------------------------------------- slurries
class GranularSlurry:
    """Haff grain flow (the paper): unknown phi = ln(p/p0), p the absolute granular pressure.

    Its gauge pressure p - p0 cannot fall below -p0 (an implicit cavitation), so it takes no
    cavitation model.
    """

    name = "granular"
    unknown = "ln(p/p0)"
    #: Restart Newton from an attack-angle scan when it fails (a lift-carried film): no.
    lift_restart = False
    #: Whether a cavitation model other than "none" applies.
    takes_cavitation = False

    def __init__(self, ambient_pressure: float):
        if not (np.isfinite(ambient_pressure) and ambient_pressure > 0):
            raise ValueError(f"ambient granular pressure must be > 0 Pa; got {ambient_pressure!r}")
        self.p0 = float(ambient_pressure)
        self.cavitation = NoCavitation()

    @property
    def coarse_starts(self) -> bool:
        return self.cavitation.coarse_starts

    @property
    def couples_with_deflection(self) -> bool:
        return self.cavitation.couples_with_deflection

    def system(self, problem, coeffs, frozen=None):
        """The discrete problem of these face coefficients (see the cavitation models)."""
        return self.cavitation.system(problem, coeffs, frozen)

    def check(self, phi, h, coeffs, sigma: float) -> None:
        """Raise ValueError if the solved pressure is not a physical state."""
        if not np.all(np.isfinite(phi)) or phi.max() > 300.0:  # p > 1e130 p0: no physical state
            raise ValueError(
                f"the slurry pressure diverges (ln(p/p0) up to {np.nanmax(phi):.3g}) at a minimum film of "
                f"{h.min() / sigma:.3g} sigma; flow factors regularised on "
                f"{_floored_share(coeffs):.0f} % of the faces"
            )

    def diverges(self, phi) -> bool:
        """Whether an iterate of the coupled solve has left every physical state."""
        return not np.all(np.isfinite(phi)) or phi.max() > 300.0

    def pressures(self, phi, system=None, acting=None):
        """(p_slurry, gauge pressure acting, fill fraction, cavitated) of the unknown phi.

        p_slurry is the absolute granular pressure p0 e^phi, Pa; no fill fraction, no cavitation.
        """
        p_abs = self.p0 * np.exp(phi)
        return p_abs, p_abs - self.p0, None, None

    def gauge(self, phi, acting=None):
        """Gauge slurry pressure acting on the wafer, p0 e^phi - p0, Pa."""
        return self.p0 * np.exp(phi) - self.p0

    def linearised(self, phi):
        """(p_slurry, gauge pressure, its derivative in phi) for the coupled Newton, Pa."""
        p_abs = self.p0 * np.exp(phi)
        return p_abs, p_abs - self.p0, p_abs

    def cavitated(self, phi):
        return None

    def unknown_scale(self, applied_pressure: float) -> float:
        """The scale on which a change of the unknown counts (convergence tests): 1, ln(p/p0) is dimensionless."""
        return 1.0

    def residual(self, grid, coeffs, phi):
        """(R, dR/dphi) of the discrete slurry problem at the unknown phi (the coupled solve of a compliant pad)."""
        return self.cavitation.residual(grid, coeffs, phi)

    def flux_change(self, grid, coeffs, dcoeffs, phi):
        """The change of :meth:`residual` under a change ``dcoeffs`` of the face coefficients at fixed phi."""
        return self.cavitation.flux_change(grid, coeffs, dcoeffs, phi)

    def face_flux_slopes(self, grid, coeffs, dcoeffs, phi, ops):
        """Slopes of each cell's own face fluxes under ``dcoeffs`` (the coupled pad's Jacobian), m^3/s per m."""
        return self.cavitation.face_flux_slopes(grid, coeffs, dcoeffs, phi, ops)

    def edge_pressure(self, ambient_pressure: float) -> float:
        """The slurry pressure at the wafer edge reported as ``ambient_pressure``: p0, Pa."""
        return ambient_pressure

    def normal_pressure(self, p_slurry):
        """The slurry's normal stress in the paper's removal law: the granular pressure, Pa."""
        return p_slurry

    def shear_stress(self, st, grid, lub, du):
        """(tau_x, tau_y) of the grain flow on the wafer (eq. 14-15 with the Haff viscosity), Pa."""
        grad_phi = grid.gradient(st.phi, 0.0)
        grad_p = (st.p_slurry * grad_phi[0], st.p_slurry * grad_phi[1])
        _, f, _ = grain_coefficients(st.h / lub.particle_diameter, lub.w_over_k)
        phi_fs, phi_fp = shear_stress_factors(st.h / lub.roughness.sigma, f, lub.roughness)
        grain = GrainFlow(lub.particle_diameter, lub.w_over_k, lub.t_over_a, lub.fluctuation_velocity)
        return slurry_shear_stress(st.p_slurry, grad_p, st.h, du, grain, phi_fs=phi_fs, phi_fp=phi_fp)


class NewtonianSlurry(GranularSlurry):
    """A Newtonian liquid: unknown the gauge pressure p (Pa, 0 at the edge), with a cavitation model."""

    name = "newtonian"
    unknown = "p"
    #: A Newtonian film at zero tilt carries almost no net load (its pressure is nearly odd in
    #: x): when Newton fails from the contact-only start, restart from an attack-angle scan.
    lift_restart = True
    takes_cavitation = True

    def __init__(self, ambient_pressure: float, cavitation=None):
        self.p0 = float(ambient_pressure)
        self.cavitation = cavitation or NoCavitation()

    def check(self, phi, h, coeffs, sigma: float) -> None:
        if not np.all(np.isfinite(phi)):
            raise ValueError(
                f"the slurry pressure is not finite at a minimum film of {h.min() / sigma:.3g} sigma; flow "
                f"factors regularised on {_floored_share(coeffs):.0f} % of the faces"
            )

    def diverges(self, phi) -> bool:
        return not np.all(np.isfinite(phi))

    def pressures(self, phi, system=None, acting=None):
        """(p_slurry, gauge pressure acting, fill fraction, cavitated): p_slurry is the acting gauge pressure."""
        p, theta, cav = self.cavitation.acting(phi, system, acting)
        return p, p, theta, cav

    def gauge(self, phi, acting=None):
        return self.cavitation.gauge(phi, acting)

    def linearised(self, phi):
        p, dp = self.cavitation.linearised(phi)
        return p, p, dp

    def cavitated(self, phi):
        return self.cavitation.cavitated(phi)

    def unknown_scale(self, applied_pressure: float) -> float:
        """The scale on which a change of the unknown counts (convergence tests): the applied pressure, Pa."""
        return applied_pressure

    def edge_pressure(self, ambient_pressure: float) -> float:
        """Ambient: 0 Pa gauge."""
        return 0.0

    def normal_pressure(self, p_slurry):
        """The compressive part max(p, 0) of the gauge pressure (docs/model.md, "Newtonian slurry and cavitation"), Pa."""
        return np.maximum(p_slurry, 0.0)

    def shear_stress(self, st, grid, lub, du):
        """(tau_x, tau_y) of the Newtonian film on the wafer, Couette part weighted by the fill fraction, Pa."""
        grad_p = grid.gradient(st.p_slurry, 0.0)
        f = np.full(st.h.shape, NEWTONIAN_GRAIN_COEFFICIENT)
        phi_fs, phi_fp = shear_stress_factors(st.h / lub.roughness.sigma, f, lub.roughness)
        theta = 1.0 if st.fill_fraction is None else st.fill_fraction
        return newtonian_shear_stress(grad_p, st.h, du, lub.viscosity, phi_fs, phi_fp, theta)
