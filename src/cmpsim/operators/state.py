"""The state of the wafer at one trial position, the converged equilibrium, and its error.

The vocabulary shared by the solver's rooms (:mod:`cmpsim.solver.wafer`, :mod:`cmpsim.operators.compliance`,
:mod:`cmpsim.solver.equilibrium`, the models of :mod:`cmpsim.models`): what one pressure solve at a
position u = (h0, theta, beta) gives (:class:`PressureState`), what Newton's method returns
(:class:`EquilibriumSolution`) and the error it raises (:class:`EquilibriumError`).
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

__all__ = ["PressureState", "EquilibriumSolution", "EquilibriumError"]


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
    system: object  # ReynoldsSystem or CavitationSystem; None on a compliant pad (see ``coupling``)
    floored_fraction: float
    fill_fraction: np.ndarray | None = None  # JFO: theta (1 on the full film); else None
    cavitated: np.ndarray | None = None  # Gumbel / JFO: cells held at p_cav; else None
    # ---- pad compliance (cmpsim.operators.compliance); None on a rigid pad
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
        """Nominal pad contact area over the nominal area (elastic + elastoplastic + plastic)."""
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
