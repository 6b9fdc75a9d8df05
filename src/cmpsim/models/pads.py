"""Pad models (``pad_compliance``): the pad's deflection, its part of the linearisation, its cold start.

- :class:`RigidPad` (the paper): only the asperity layer deforms; the film is the wafer's
  (:mod:`cmpsim.models.carriers`), one sparse Reynolds solve per position, the Jacobian from
  one extra coefficient evaluation (dc/dh times the geometric dh/du).
- :class:`WinklerPad`: the pad stack as a local elastic bed (:class:`cmpsim.physics.padstack.WinklerFoundation`);
- :class:`LayerPad`: elastic layers with lateral coupling (:class:`cmpsim.physics.padstack.LayeredFoundation`).

The two compliant pads solve the film and the deflection together (:mod:`cmpsim.operators.compliance`).
Every model answers the same questions of :class:`cmpsim.models.base.PadModel`; the
equilibrium solver asks them and never tests which pad it has. A new pad model subclasses
one of these (or implements the protocol) and adds an entry to :data:`cmpsim.models.PAD_MODELS`
(``docs/developer.md`` has a worked example).
"""

from __future__ import annotations

import numpy as np

from ..numerics.roots import brentq
from ..operators import compliance, compliantfilm, jointnewton, sensitivity
from ..physics.padstack import LayeredFoundation, PadLayer, WinklerFoundation
from ..operators.reynolds import FaceCoefficients, ReynoldsSystem, assemble_operator, flux_divergence, lubrication_coefficients
from ..operators.state import EquilibriumError, PressureState

__all__ = ["RigidPad", "WinklerPad", "LayerPad", "pad_layers"]

#: A Newton step's Jacobian factorises its state's matrix when solving that state by iterative
#: refinement took more back-substitutions than this (the old factorisation is too far away).
JACOBIAN_REFINE_LIMIT = 10
#: The Jacobian's columns are finite differences accurate to ~1e-6: their linear solves by
#: refinement stop at this relative accuracy (the pressure solves themselves go to round-off).
JACOBIAN_RTOL = 1e-10


def pad_layers(config) -> list:
    """The :class:`~cmpsim.physics.padstack.PadLayer` stack of a Config: top pad, then the subpad if any."""
    layers = [PadLayer(config.pad_thickness, config.pad_bulk_modulus, config.pad_poisson)]
    if config.subpad_thickness > 0:
        layers.append(PadLayer(config.subpad_thickness, config.subpad_modulus, config.subpad_poisson))
    return layers


class RigidPad:
    """The paper's pad: a rigid bulk under the asperity layer (no deflection)."""

    name = "rigid"
    #: The elastic stack under the asperities (None: rigid).
    foundation = None
    #: Newton may keep its Jacobian near convergence (chord steps) and adapt its trust radius;
    #: the coarse-grid starts apply.
    chord_steps = True
    adaptive_trust = True
    coarse_starts = True
    #: The type of the elastic stack this model solves with (the registry maps a stack to its model).
    foundation_type = type(None)

    def __init__(self, foundation=None):
        if foundation is not None:
            raise ValueError("a rigid pad has no elastic foundation (pad_compliance = 'rigid')")

    @classmethod
    def from_config(cls, config) -> "RigidPad":
        return cls()

    def check(self, variant: str, slurry) -> None:
        """Refuse a model or slurry this pad cannot be solved with (ValueError naming the input)."""

    # ------------------------------------------------------------------ film
    def film(self, problem, u, x, y) -> np.ndarray:
        """Film thickness at points (x, y) for position u, m: the carrier's film over the undeformed pad."""
        return problem.carrier.film(problem, u, x, y)

    def face_coefficients(self, problem, u) -> FaceCoefficients:
        """Reynolds coefficients on all faces at position u (one evaluation on both face sets)."""
        c = lubrication_coefficients(self.film(problem, u, problem._xf, problem._yf), problem._xf, problem._yf, problem.lub, problem._vf)
        floored = int(np.count_nonzero(c[5]))
        return FaceCoefficients(tuple(a[0] for a in c[:5]), tuple(a[1] for a in c[:5]), floored, c[5].size, problem.lub.groove_venting)

    # ------------------------------------------------------------------ state
    def state(self, problem, u, guess=None) -> PressureState:
        """Solve the Reynolds equation and evaluate contact and residuals at position u (see WaferProblem.state)."""
        u = np.asarray(u, dtype=float)
        h = self.film(problem, u, problem.xc, problem.yc)
        coeffs = self.face_coefficients(problem, u)
        system = problem._system(coeffs)
        linear = isinstance(system, ReynoldsSystem)
        phi = system.solve(x0=guess) if linear else system.solve()
        if linear and system.own_factor is not None:
            problem._reference = system.own_factor  # later positions refine against it
        problem.slurry.check(phi, h, coeffs, problem.sigma)
        p_abs, p_fluid, pc, ae, aep, ap, theta, cav = problem._combine(h, phi, system)
        res = problem._residual(p_fluid + pc)
        return PressureState(
            u, h, phi, p_abs, p_fluid, pc, ae, aep, ap, res, system, coeffs.floored / max(coeffs.n_faces, 1), theta, cav
        )

    # ------------------------------------------------------------------ Jacobian
    def jacobian(self, problem, st: PressureState, rel_step: float = 1e-6) -> np.ndarray:
        """d(residual)/du at a solved state: 3 coefficient re-evaluations, 3 back-substitutions.

        With cavitation the derivative is the one on the frozen set of cavitated cells (JFO:
        the reduced system of the state; Gumbel: the cells where p > p_cav), exact wherever
        the set does not change under the perturbation.
        """
        if isinstance(st.system, ReynoldsSystem):
            return self._film_jacobian(problem, st, rel_step)
        J = np.empty((3, 3))
        base = st.system.residual(st.phi)
        acting = None if st.cavitated is None else ~st.cavitated
        for k in range(3):
            du = np.zeros(3)
            du[k] = rel_step * problem.u_scale[k]
            u = st.u + du
            h = self.film(problem, u, problem.xc, problem.yc)
            pert = problem._system(self.face_coefficients(problem, u), frozen=st)
            dr = pert.residual(st.phi) - base
            dphi = -st.system.factor.solve(dr).reshape(st.phi.shape)
            problem.back_substitutions += 1
            _, p_fluid, pc, *_ = problem._combine(h, st.phi + dphi, st.system, acting)
            J[:, k] = (problem._residual(p_fluid + pc) - st.residual) / du[k]
        return J

    def _film_jacobian(self, problem, st: PressureState, rel_step: float) -> np.ndarray:
        """:meth:`jacobian` for the linear (non-JFO) system, in one extra coefficient evaluation
        and one extra contact evaluation.

        The face coefficients depend on the local film only (and on the fixed face position),
        so dc/du_k = dc/dh dh/du_k: one forward difference in h gives dc/dh on every face, the
        film changes dh/du_k follow from the geometry, and since A phi - b is linear in the
        coefficients its change is A(dc_k) phi + div(dc_k). Then dphi = -A^-1 dr as before
        (the three columns in one solve). The contact pressure and area likewise take
        dp_c/dh dh/du_k from one evaluation at h + eps.
        """
        J = np.empty((3, 3))
        hf = self.film(problem, st.u, problem._xf, problem._yf)
        eps = rel_step * problem.sigma
        c0 = st.system.coeffs
        c1 = lubrication_coefficients(hf + eps, problem._xf, problem._yf, problem.lub, problem._vf)
        dcdh = [(c1[m] - np.stack([c0.radial[m], c0.angular[m]])) / eps for m in range(5)]
        acting = None if st.cavitated is None else ~st.cavitated
        phi = st.phi.ravel()
        dr = np.empty((phi.size, 3))
        steps = []
        for k in range(3):
            du = np.zeros(3)
            du[k] = rel_step * problem.u_scale[k]
            steps.append(du)
            dh = self.film(problem, st.u + du, problem._xf, problem._yf) - hf
            dc = [d * dh for d in dcdh]
            # the sink of a grooved pad is linear in the coefficients too: its change is in A(dc_k) phi
            dcoeffs = FaceCoefficients(tuple(a[0] for a in dc), tuple(a[1] for a in dc), venting=problem.lub.groove_venting)
            dr[:, k] = assemble_operator(problem.grid, dcoeffs) @ phi + flux_divergence(problem.grid, dcoeffs)
        system = st.system
        if system.own_factor is None and system.refinement_steps > JACOBIAN_REFINE_LIMIT:
            # the state is far from the factorised position: a new LU here pays for itself
            # over the three columns and the next trial positions, which refine against it
            system.factor
            problem._reference = system.own_factor
        dphis = -system.solve_linear(dr, rtol=JACOBIAN_RTOL)
        st.dphi_du = dphis / (rel_step * problem.u_scale)  # the columns' steps du_k
        # contact depends on the local film only: one evaluation gives its derivative in h
        pc1, ae1, aep1, ap1 = problem.contact(st.h + eps)
        dpc = (pc1 - st.p_contact) / eps
        dar = (ae1 + aep1 + ap1 - st.area_ratio) / eps
        for k, du in enumerate(steps):
            dphi = dphis[:, k].reshape(st.phi.shape)
            dh = self.film(problem, st.u + du, problem.xc, problem.yc) - st.h
            gauge = problem.slurry.gauge(st.phi + dphi, acting)
            p_total = (1.0 - (st.area_ratio + dar * dh)) * gauge + st.p_contact + dpc * dh
            J[:, k] = (problem._residual(p_total) - st.residual) / du[k]
        return J

    # ------------------------------------------------------------------ cold start
    def contact_only_start(self, problem) -> np.ndarray:
        """h0 at zero tilt for which the pad contact alone carries the applied load."""
        shape = self.film(problem, np.zeros(3), problem.xc, problem.yc)  # h - h0 at u = 0

        def excess(h0):
            pc = problem.contact(h0 + shape)[0]
            return problem.grid.integrate(pc) / problem.load_scale - 1.0

        h_lo = -shape.min() + 1e-3 * problem.sigma  # smallest h0 with a positive film everywhere
        cutoff = problem.pad.height_cutoff if np.isfinite(problem.pad.height_cutoff) else 12.0
        # beyond this h0 even the lowest point of the wafer clears every summit: no contact
        h_hi = -shape.min() + problem.separation_offset + cutoff * problem.pad.sigma_s
        if excess(h_lo) < 0:
            raise EquilibriumError(
                "the applied load exceeds what the pad asperities can carry before the wafer "
                f"touches the pad mean plane (contact pressure at zero film is {excess(h_lo) + 1:.3g} "
                "x the applied pressure); lower applied_pressure or stiffen the pad"
            )
        h0 = _contact_root(problem, shape, h_lo, h_hi)
        if h0 is None:  # the safeguarded Newton did not settle: bracket and Brent
            h0 = brentq(excess, h_lo, h_hi, xtol=1e-6 * problem.sigma, rtol=1e-12)
        return np.array([h0, 0.0, 0.0])

    # ------------------------------------------------------------------ joint Newton
    def joint_newton(self, problem, u, tol: float, max_iter: int, max_step: float):
        """The equilibrium by one Newton iteration on the position and the pad's own unknowns, or
        None: the rigid pad has none, the driver's Newton on u alone solves it."""
        return None

    # ------------------------------------------------------------------ chains of points
    def resume_chain(self, problem) -> None:
        """Nothing to carry: the rigid solve refines against the chain's last LU (:mod:`cmpsim.solver.equilibrium`)."""

    def end_chain(self, problem) -> None:
        """Nothing to keep beyond the chain's last LU (kept by :mod:`cmpsim.solver.equilibrium`)."""


def _contact_root(problem, shape, h_lo: float, h_hi: float, max_iter: int = 30):
    """h0 where the contact load equals the applied load, by Newton's method on its logarithm.

    ln(load) is close to linear in h0 over the contact layer (the summit heights are nearly
    Gaussian), so Newton converges in a few steps: the first slope from one contact evaluation
    at two films (h0 and h0 + eps, stacked), the later ones secants through the last two. Steps
    are kept inside the bracket [h_lo, h_hi] (bisection otherwise). Returns None if it does not
    converge to 1e-6 sigma.
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


class WinklerPad(RigidPad):
    """The pad stack as a local elastic (Winkler) bed under the asperities: w = p / k.

    Film and deflection are solved together at every position (:func:`cmpsim.operators.compliance.coupled_state`);
    the Jacobian is the implicit derivative of that solve (:func:`cmpsim.operators.compliance.coupled_jacobian`).
    Newton takes a fresh Jacobian at every step and keeps its trust radius: shrinking it stalled
    the outer Newton on the default model under Thakurta's conditions (tests/test_validation.py).
    """

    name = "winkler"
    #: Solve the film, the deflection and the position in one Newton iteration (the local bed's
    #: coupled matrix is factorised; the layered pad's is solved by GMRES, nested).
    joint = True
    chord_steps = False
    adaptive_trust = False
    coarse_starts = False
    foundation_type = WinklerFoundation

    def __init__(self, foundation):
        self.foundation = foundation

    @classmethod
    def from_config(cls, config) -> "WinklerPad":
        return cls(WinklerFoundation.from_layers(pad_layers(config)))

    def check(self, variant: str, slurry) -> None:
        if variant == "hydrodynamic":
            raise ValueError(f"a compliant pad (pad_compliance = {self.name!r}) needs a model with contact ('lep' or 'elastic')")
        if not slurry.couples_with_deflection:
            raise ValueError(
                f"a compliant pad (pad_compliance = {self.name!r}) does not take {slurry.cavitation.name.upper()} cavitation; use 'gumbel' or 'none'"
            )

    def film(self, problem, u, x, y) -> np.ndarray:
        """Film at points (x, y): the carrier's film plus the pad deflection of the coupled solution at u, m."""
        return compliantfilm.deformed_film(problem, u, x, y)

    def face_coefficients(self, problem, u) -> FaceCoefficients:
        """Reynolds coefficients on the faces of the deformed film at position u."""
        rad = lubrication_coefficients(self.film(problem, u, problem.xr, problem.yr), problem.xr, problem.yr, problem.lub)
        ang = lubrication_coefficients(self.film(problem, u, problem.xa, problem.ya), problem.xa, problem.ya, problem.lub)
        floored = int(np.count_nonzero(rad[5]) + np.count_nonzero(ang[5]))
        return FaceCoefficients(rad[:5], ang[:5], floored, rad[5].size + ang[5].size, problem.lub.groove_venting)

    def state(self, problem, u, guess=None) -> PressureState:
        return compliance.coupled_state(problem, u)

    def jacobian(self, problem, st: PressureState, rel_step: float = 1e-6) -> np.ndarray:
        return compliance.coupled_jacobian(problem, st, rel_step)

    def sensitivity(self, problem, st: PressureState, rel_step: float = 1e-6):
        """(d(residual)/du, d(total pressure)/du) at a solved state (:func:`cmpsim.operators.sensitivity.coupled_sensitivity`)."""
        return sensitivity.coupled_sensitivity(problem, st, rel_step)

    def film_response(self, problem, st: PressureState, dh, dhr, dha) -> np.ndarray:
        """The linear change of the total pressure (Pa, flat) at a solved state under a change of the carrier's
        film at fixed u: ``dh``, ``dhr``, ``dha`` (m, flat) at the cell centres, radial and angular faces
        (:func:`cmpsim.operators.sensitivity.film_response`)."""
        return sensitivity.film_response(problem, st, dh, dhr, dha)[0]

    def expect_film_change(self, problem, st: PressureState, dh, dhr, dha) -> np.ndarray:
        """:meth:`film_response`, and the next coupled solve starts from the film and deflection it predicts
        (:func:`cmpsim.operators.sensitivity.expect_film_change`)."""
        return sensitivity.expect_film_change(problem, st, dh, dhr, dha)

    def contact_only_start(self, problem) -> np.ndarray:
        return compliantfilm.compliant_contact_only_start(problem)

    def joint_newton(self, problem, u, tol: float, max_iter: int, max_step: float):
        """(u, state, steps, history) of Newton on (slurry pressure, deflection, position) together
        (:func:`cmpsim.operators.jointnewton.joint_equilibrium`), or None if it does not converge."""
        if not self.joint:
            return None
        return jointnewton.joint_equilibrium(problem, u, tol=tol, max_iter=max_iter, max_step=max_step)

    def resume_chain(self, problem) -> None:
        compliance.resume_chain(problem)

    def end_chain(self, problem) -> None:
        compliance.end_chain(problem)


class LayerPad(WinklerPad):
    """Elastic layers with lateral coupling (top pad as a plate on an elastic subpad layer, by FFT).

    The coupled solve is the Winkler one with the nonlocal compliance C(q) in the balance of
    the pad; its Newton system is solved by GMRES preconditioned by the Winkler bed of the same stack.
    """

    name = "layer"
    joint = False
    foundation_type = LayeredFoundation

    @classmethod
    def from_config(cls, config) -> "LayerPad":
        return cls(LayeredFoundation(tuple(pad_layers(config))))
