"""The protocols of the four model axes: what the solver and the post-processing ask a model.

Each axis is a small family of classes behind one protocol, picked by name in one place (the
registry of :mod:`cmpsim.models`, as ``scipy.integrate.solve_ivp(method=...)`` maps a name to
an ``OdeSolver`` subclass). The Newton driver (:mod:`cmpsim.solver.equilibrium`), the wafer problem
(:mod:`cmpsim.solver.wafer`), the coupled pad solve (:mod:`cmpsim.operators.compliance`) and the
post-processing (:mod:`cmpsim.solver.postprocess`) only call these methods; none of them tests an
option's name (``tests/test_house.py`` checks that).
"""

from __future__ import annotations

from typing import Protocol, runtime_checkable

import numpy as np

__all__ = ["PadModel", "SlurryModel", "CavitationModel", "RemovalLaw", "CarrierModel", "FilmChemistry"]


@runtime_checkable
class PadModel(Protocol):
    """The pad under the asperity layer (``pad_compliance``): owns the deflection, its part of the
    linearisation and the cold start. Implementations: :mod:`cmpsim.models.pads`."""

    name: str
    #: The elastic stack (:mod:`cmpsim.physics.padstack`), or None for a pad that does not deflect.
    foundation: object
    #: Newton may reuse its Jacobian near convergence (chord steps).
    chord_steps: bool
    #: Newton shrinks its trust radius after a cut step and regrows it after a full one.
    adaptive_trust: bool
    #: The coarse-grid warm start and first step of :mod:`cmpsim.solver.equilibrium` apply.
    coarse_starts: bool

    def check(self, variant: str, slurry: "SlurryModel") -> None:
        """Raise ValueError (naming the input) for a model variant or slurry this pad cannot take."""

    def film(self, problem, u, x, y) -> np.ndarray:
        """Film thickness at points (x, y) for the wafer's unknowns u, m (with the pad's deflection)."""

    def face_coefficients(self, problem, u):
        """The Reynolds :class:`~cmpsim.operators.reynolds.FaceCoefficients` at u."""

    def state(self, problem, u, guess=None):
        """The :class:`~cmpsim.operators.state.PressureState` at u (raises ValueError if the film closes or the pressure diverges)."""

    def jacobian(self, problem, st, rel_step: float = 1e-6) -> np.ndarray:
        """d(residual)/du at a solved state."""

    def contact_only_start(self, problem) -> np.ndarray:
        """The cold start: u at zero tilt where the pad contact alone carries the load."""

    def resume_chain(self, problem) -> None:
        """A warm start continues a chain of points: start from what the last equilibrium left."""

    def end_chain(self, problem) -> None:
        """Keep what this equilibrium leaves for the next point of a chain."""


@runtime_checkable
class CavitationModel(Protocol):
    """Cavitation of a film solved in the gauge pressure p (``cavitation``). Implementations:
    :mod:`cmpsim.models.slurries`."""

    name: str
    p_cav: float | None
    coarse_starts: bool
    couples_with_deflection: bool

    def system(self, problem, coeffs, frozen=None):
        """The discrete problem (``.solve``, ``.residual``) of these face coefficients."""

    def acting(self, p, system=None, acting=None):
        """(pressure acting on the wafer, fill fraction or None, cavitated cells or None), Pa."""

    def gauge(self, p, acting=None):
        """Acting gauge pressure of a linear system's unknown, Pa."""

    def linearised(self, p):
        """(acting pressure, its derivative in p), for the coupled Newton of a compliant pad."""

    def cavitated(self, p):
        """Cells held at p_cav, or None."""

    def residual(self, grid, coeffs, phi):
        """(R, dR/dphi): the discrete slurry problem's residual at the unknown phi of the coupled
        solve of a compliant pad (flat, m^3/s) and its sparse derivative."""

    def flux_change(self, grid, coeffs, dcoeffs, phi):
        """The change of :meth:`residual` under a change ``dcoeffs`` of the face coefficients at fixed phi."""


@runtime_checkable
class SlurryModel(Protocol):
    """The slurry (``slurry_model`` with its ``cavitation``): owns its pressure unknown, its
    cavitation and its shear. Implementations: :mod:`cmpsim.models.slurries`."""

    name: str
    #: The unknown of the discrete system: "ln(p/p0)" or "p".
    unknown: str
    cavitation: CavitationModel
    #: Restart Newton once from an attack-angle scan when it fails from the cold start.
    lift_restart: bool
    coarse_starts: bool
    couples_with_deflection: bool

    def system(self, problem, coeffs, frozen=None): ...

    def check(self, phi, h, coeffs, sigma: float) -> None:
        """Raise ValueError if a solved unknown is not a physical state."""

    def diverges(self, phi) -> bool: ...

    def pressures(self, phi, system=None, acting=None):
        """(p_slurry, acting gauge pressure, fill fraction, cavitated) of the unknown phi."""

    def gauge(self, phi, acting=None): ...

    def linearised(self, phi):
        """(p_slurry, acting gauge pressure, its derivative in phi)."""

    def cavitated(self, phi): ...

    def unknown_scale(self, applied_pressure: float) -> float:
        """The scale of the unknown for convergence tests (1 for ln(p/p0), Pa for p)."""

    def residual(self, grid, coeffs, phi): ...

    def flux_change(self, grid, coeffs, dcoeffs, phi): ...

    def edge_pressure(self, ambient_pressure: float) -> float:
        """The slurry pressure at the wafer edge (output ``ambient_pressure``), Pa."""

    def normal_pressure(self, p_slurry):
        """The slurry's normal stress in the removal law, Pa."""

    def shear_stress(self, st, grid, lub, du):
        """(tau_x, tau_y) of the slurry on the wafer, Pa."""


@runtime_checkable
class RemovalLaw(Protocol):
    """The removal law (``removal_law``): owns its rate and says which fields it needs.
    Implementations: :mod:`cmpsim.models.removal_laws`."""

    name: str
    #: Names of :data:`cmpsim.models.removal_laws.REMOVAL_FIELDS` passed to :meth:`rate` as keywords.
    needs: tuple
    #: Whether ``cmpsim.solve`` gives ``removal_rate_relative`` (and solves its reference case)
    #: unless told (issue 23).
    relative_by_default: bool

    def rate(self, **fields) -> np.ndarray:
        """Local removal rate, m/s."""


@runtime_checkable
class CarrierModel(Protocol):
    """The carrier (``carrier``): owns the wafer's unknowns and the load it applies.
    Implementations: :mod:`cmpsim.models.carriers`."""

    name: str
    #: Names of the unknowns u.
    unknowns: tuple
    #: Whether the carrier presses in zones whose pressures can be tuned.
    has_zones: bool

    def load(self, applied_pressure: float, radius: float) -> float:
        """Total applied load, N."""

    def scale(self, sigma: float, radius: float) -> np.ndarray:
        """Scale of each unknown (trust region, finite differences)."""

    def film(self, problem, u, x, y) -> np.ndarray:
        """Film over the undeformed pad at points (x, y), m."""

    def residual(self, problem, p_total) -> np.ndarray:
        """The balance residuals of a total pressure field on the wafer (dimensionless)."""

    def residual_change(self, problem, dp) -> np.ndarray:
        """The change of the residuals under a pressure change dp."""

    def bending_field(self, problem) -> np.ndarray:
        """The wafer's bending at the cell centres (m), zero for a rigid wafer."""

    def equilibrium(self, problem, solve, start=None, **options):
        """The :class:`~cmpsim.operators.state.EquilibriumSolution` of ``problem``, with ``solve`` (Newton on the
        rigid-body unknowns, :func:`cmpsim.solver.equilibrium.solve_equilibrium`) doing the rigid-body part."""


@runtime_checkable
class FilmChemistry(Protocol):
    """What the slurry's chemistry adds to the mechanical removal rate of the film (``film_chemistry``).
    Implementations: :mod:`cmpsim.models.chemistry`."""

    name: str

    def wrap(self, law: RemovalLaw) -> RemovalLaw:
        """The removal law with this chemistry (the same protocol); ``law`` itself when it adds nothing."""
