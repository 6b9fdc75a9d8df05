"""Removal laws (``removal_law``): the local removal rate from the fields of the solved state.

Each law says which fields it needs (:attr:`needs`, names of :data:`REMOVAL_FIELDS`) and
computes the rate (m/s) from them; its coefficients come from the Config
(:meth:`from_config`). The post-processing offers the fields and never asks which law it has.
A new law (e.g. an abrasive-particle law) adds a class here and an entry in the registry of
:mod:`cmpsim.models`. Kernels and references: :mod:`cmpsim.removal`, ``docs/model.md``
("Removal rate").
"""

from __future__ import annotations

import numpy as np

from ..removal import removal_rate, shear_power_removal_rate

__all__ = ["REMOVAL_FIELDS", "PaperRemovalLaw", "ShearPowerRemovalLaw"]

#: The fields of a solved state a removal law may ask for (all at the cell centres, SI).
REMOVAL_FIELDS = {
    "normal_stress": "sigma_n = (1 - a_r) p_slurry,normal + p_c, Pa",
    "shear_stress": "(tau_x, tau_y) on the wafer (slurry, plus pad friction if removal_shear = 'total'), Pa",
    "contact_pressure": "nominal pad-summit contact pressure p_c, Pa",
    "fluid_shear_stress": "(tau_x, tau_y) of the slurry alone, (1 - a_r) tau_f, Pa",
    "relative_speed": "local sliding speed |u_pad - u_wafer|, m/s",
    "film_thickness": "h, m",
}


class PaperRemovalLaw:
    """The paper's Runnels-Eyman law RR = K sigma_n |tau| (:func:`cmpsim.removal.removal_rate`)."""

    name = "paper"
    needs = ("normal_stress", "shear_stress")
    #: The paper's Figs. 11-12 are in removal rate relative to its reference case.
    relative_by_default = True

    def __init__(self, preston_coefficient: float):
        self.preston_coefficient = preston_coefficient

    @classmethod
    def from_config(cls, config) -> "PaperRemovalLaw":
        return cls(config.preston_coefficient)

    def rate(self, normal_stress, shear_stress) -> np.ndarray:
        """Removal rate, m/s."""
        return removal_rate(normal_stress, shear_stress, self.preston_coefficient)


class ShearPowerRemovalLaw:
    """The shear-power law RR = k_s (mu p_c + chi |tau_f|) |du| (:func:`cmpsim.removal.shear_power_removal_rate`)."""

    name = "shear_power"
    needs = ("contact_pressure", "fluid_shear_stress", "relative_speed")
    #: Absolute rates (m/s); the ratio, whose reference solve costs as much as the point, on request.
    relative_by_default = False

    def __init__(self, coefficient: float, friction_coefficient: float, fluid_shear_weight: float):
        self.coefficient = coefficient
        self.friction_coefficient = friction_coefficient
        self.fluid_shear_weight = fluid_shear_weight

    @classmethod
    def from_config(cls, config) -> "ShearPowerRemovalLaw":
        return cls(config.shear_power_coefficient, config.friction_coefficient, config.fluid_shear_weight)

    def rate(self, contact_pressure, fluid_shear_stress, relative_speed) -> np.ndarray:
        """Removal rate, m/s."""
        return shear_power_removal_rate(
            contact_pressure, fluid_shear_stress, relative_speed, self.coefficient, self.friction_coefficient, self.fluid_shear_weight
        )
