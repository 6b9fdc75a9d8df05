"""Removal laws (``removal_law``): the local removal rate from the fields of the solved state.

Each law says which fields it needs (:attr:`needs`, names of :data:`REMOVAL_FIELDS`) and
computes the rate (m/s) from them; its coefficients come from the Config
(:meth:`from_config`). The post-processing offers the fields and never asks which law it has.
A new law (e.g. an abrasive-particle law) adds a class here and an entry in the registry of
:mod:`cmpsim.models`. Kernels and references: :mod:`cmpsim.physics.removal`, ``docs/model.md``
("Removal rate").
"""

from __future__ import annotations

import dataclasses
import math
import warnings

import numpy as np

from ..physics.abrasion import AbrasiveContact, abrasive_removal_rate
from ..physics.kinetics import chemical_rate, flash_temperature, series_rate
from ..physics.materials import ABRASIVES, FILMS
from ..physics.removal import removal_rate, shear_power_removal_rate

__all__ = ["REMOVAL_FIELDS", "PaperRemovalLaw", "ShearPowerRemovalLaw", "AbrasiveRemovalLaw", "TwoStepKinetics", "abrasive_contact"]

#: The fields of a solved state a removal law may ask for (all at the cell centres, SI).
REMOVAL_FIELDS = {
    "normal_stress": "sigma_n = (1 - a_r) p_slurry,normal + p_c, Pa",
    "shear_stress": "(tau_x, tau_y) on the wafer (slurry, plus pad friction if removal_shear = 'total'), Pa",
    "contact_pressure": "nominal pad-summit contact pressure p_c, Pa",
    "fluid_shear_stress": "(tau_x, tau_y) of the slurry alone, (1 - a_r) tau_f, Pa",
    "relative_speed": "local sliding speed |u_pad - u_wafer|, m/s",
    "contact_area_ratio": "real over nominal contact area of the pad summits A_r/A_n (elastic + elastoplastic + plastic)",
    "film_thickness": "h, m",
    "contact_spot_density": "summits in contact per unit nominal area N (cmpsim.physics.contact.contact_spot_density), 1/m^2",
}


class PaperRemovalLaw:
    """The paper's Runnels-Eyman law RR = K sigma_n |tau| (:func:`cmpsim.physics.removal.removal_rate`)."""

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
    """The shear-power law RR = k_s (mu p_c + chi |tau_f|) |du| (:func:`cmpsim.physics.removal.shear_power_removal_rate`)."""

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


def abrasive_contact(config) -> AbrasiveContact:
    """The particles, pad and film of the abrasive law (:mod:`cmpsim.physics.abrasion`) of a Config.

    The pad presses an embedded particle with p_pad = min(H_pad, 4 E'_pad / (3 pi)), E'_pad the
    pad-particle effective modulus; the particle-film contact takes E* from both bodies and the
    hardness and K of the softer one; the film takes its Hertz compliance share of the
    interference (docs/model.md, section 13e). ``film_hardness`` > 0 replaces the table's film
    hardness; ``film_size_length`` R* makes the film's hardness grow under small particles,
    H(r) = H_0 sqrt(1 + R*/r) up to the abrasive's hardness (section 13e.8).
    """
    c = config
    a, f = ABRASIVES[c.abrasive], FILMS[c.film]
    if c.film_hardness > 0:  # a measured film hardness replaces the table's
        f = dataclasses.replace(f, hardness=c.film_hardness)
    pad_e = 1.0 / ((1.0 - c.pad_poisson**2) / c.pad_modulus + a.reduced_compliance)
    film_softer = f.hardness <= a.hardness
    soft = f if film_softer else a
    compliance = a.reduced_compliance + f.reduced_compliance
    return AbrasiveContact(
        diameter=c.particle_diameter,
        diameter_std=c.particle_size_std,
        volume_fraction=c.solid_volume_fraction,
        pad_pressure=min(c.pad_hardness, 4.0 * pad_e / (3.0 * math.pi)),
        e_star=1.0 / compliance,
        hardness=soft.hardness,
        k_factor=0.454 + 0.41 * soft.poisson,
        film_share=f.reduced_compliance / compliance,
        efficiency=c.abrasion_efficiency,
        # the film's indentation size effect, up to the abrasive's hardness (then the particle yields)
        size_length=c.film_size_length if film_softer else 0.0,
        hardness_limit=a.hardness if film_softer else float("inf"),
    )


class TwoStepKinetics:
    """A thermally activated chemical step in series with the mechanical rate (:mod:`cmpsim.physics.kinetics`).

    RR = RR_c RR_m / (RR_c + RR_m), RR_c = c_0 exp(-(E_a/R_g)(1/T - 1/T_0)), T = T_pad + beta mu p_c |du|
    (T_pad = ``pad_temperature``, T_0 = ``slurry_temperature`` when it is 0).
    """

    def __init__(self, reference_rate: float, activation_energy: float, heating_coefficient: float, temperature: float, friction_coefficient: float,
                 pad_temperature: float | None = None):
        self.reference_rate = reference_rate
        self.activation_energy = activation_energy
        self.heating_coefficient = heating_coefficient
        self.temperature = temperature  # T_0: the reference temperature of reference_rate (slurry_temperature)
        self.friction_coefficient = friction_coefficient
        # the base of the flash temperature: the pad's surface (cmpsim polish sets it through time), else T_0
        self.pad_temperature = temperature if not pad_temperature else pad_temperature

    @classmethod
    def from_config(cls, config) -> "TwoStepKinetics":
        c = config
        return cls(c.chemical_rate, c.activation_energy, c.flash_heating_coefficient, c.slurry_temperature, c.friction_coefficient, c.pad_temperature)

    def rate(self, mechanical, contact_pressure, relative_speed) -> np.ndarray:
        """The two-step rate, m/s, from the mechanical rate (m/s) and the local friction power on a pad at ``pad_temperature``."""
        t = flash_temperature(self.pad_temperature, self.friction_coefficient, contact_pressure, relative_speed, self.heating_coefficient)
        return series_rate(chemical_rate(t, self.reference_rate, self.activation_energy, self.temperature), mechanical)


class AbrasiveRemovalLaw:
    """Abrasive particles trapped in the pad's real contact plough the film (:func:`cmpsim.physics.abrasion.abrasive_removal_rate`),
    with the chemical step in series for ``removal_kinetics = 'two_step'`` (docs/model.md, section 13e)."""

    name = "abrasive"
    needs = ("contact_pressure", "contact_area_ratio", "relative_speed", "contact_spot_density")
    #: Absolute rates (m/s); the ratio, whose reference solve costs as much as the point, on request.
    relative_by_default = False

    def __init__(self, contact: AbrasiveContact, kinetics: TwoStepKinetics | None = None):
        self.contact = contact
        self.kinetics = kinetics

    @classmethod
    def from_config(cls, config) -> "AbrasiveRemovalLaw":
        kinetics = KINETICS[config.removal_kinetics]
        return cls(abrasive_contact(config), kinetics and kinetics.from_config(config))

    def rate(self, contact_pressure, contact_area_ratio, relative_speed, contact_spot_density=None) -> np.ndarray:
        """Removal rate, m/s (0 without abrasive, with a RuntimeWarning saying so); particles counted
        summit by summit when ``contact_spot_density`` (1/m^2) is given, else its continuum limit."""
        if self.contact.volume_fraction == 0:
            warnings.warn("solids_loading = 0: no abrasive particles, so the abrasive removal law removes nothing (removal rate 0)", RuntimeWarning, stacklevel=2)
        rr = abrasive_removal_rate(contact_pressure, contact_area_ratio, relative_speed, self.contact, contact_spot_density).rate
        if self.kinetics is not None:
            rr = self.kinetics.rate(rr, contact_pressure, relative_speed)
        return rr


#: ``removal_kinetics`` -> the step in series with the mechanical rate (None: the mechanical rate alone).
KINETICS: dict[str, type | None] = {"mechanical": None, "two_step": TwoStepKinetics}
