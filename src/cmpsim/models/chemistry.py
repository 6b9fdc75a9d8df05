"""Film chemistry (``film_chemistry``): what the slurry's chemistry adds to the mechanical removal rate.

Each model wraps the mechanical removal law of :mod:`cmpsim.models.removal_laws` (``wrap``):

* ``"none"`` (:class:`NoChemistry`, the default): the mechanical law itself, unchanged, so an
  uncalibrated configuration gives the rates it always gave, bit for bit;
* ``"additive"`` (:class:`AdditiveChemistry`): eq. 13h.2 of ``cmpsim.physics.chemistry``,
  RR = k_F RR_m + B_F |du| + R_c,F with the constants of the film being polished (``film``).

A new chemistry adds a class here and an entry in the registry of :mod:`cmpsim.models`.
docs/model.md, section 13h.
"""

from __future__ import annotations

import numpy as np

from ..physics.chemistry import additive_rate, additive_sensitivities, input_names

__all__ = ["NoChemistry", "AdditiveChemistry", "ChemicalRemovalLaw"]


class NoChemistry:
    """No film chemistry: the removal law alone."""

    name = "none"

    @classmethod
    def from_config(cls, config) -> "NoChemistry":
        return cls()

    def wrap(self, law):
        """The mechanical law itself (no object in between: the rates are the same numbers)."""
        return law


class AdditiveChemistry:
    """The additive chemistry of one film (eq. 13h.2): ``factor`` k_F (1), ``speed_coefficient``
    B_F (m/m), ``chemical_rate`` R_c,F (m/s), and the ``inputs`` that hold them."""

    name = "additive"

    def __init__(self, film: str, factor: float, speed_coefficient: float, chemical_rate: float):
        self.film = film
        self.factor = float(factor)
        self.speed_coefficient = float(speed_coefficient)
        self.chemical_rate = float(chemical_rate)
        self.inputs = input_names(film)

    @classmethod
    def from_config(cls, config) -> "AdditiveChemistry":
        film = config.film
        return cls(film, *(getattr(config, n) for n in input_names(film)))

    def wrap(self, law):
        return ChemicalRemovalLaw(law, self)


class ChemicalRemovalLaw:
    """A mechanical removal law with the film chemistry added (eq. 13h.2): the same protocol
    (:class:`cmpsim.models.base.RemovalLaw`), the local sliding speed added to what it needs."""

    def __init__(self, mechanical, chemistry: AdditiveChemistry):
        self.mechanical = mechanical
        self.chemistry = chemistry
        self.name = mechanical.name
        self.relative_by_default = mechanical.relative_by_default
        self.needs = tuple(mechanical.needs) + (() if "relative_speed" in mechanical.needs else ("relative_speed",))
        # a chemical step in series inside the mechanical law (two-step kinetics) still follows the pad's temperature
        self.kinetics = getattr(mechanical, "kinetics", None)

    def _mechanical(self, fields) -> np.ndarray:
        return self.mechanical.rate(**{n: fields[n] for n in self.mechanical.needs})

    def rate(self, **fields) -> np.ndarray:
        """Removal rate, m/s (eq. 13h.2)."""
        c = self.chemistry
        return additive_rate(self._mechanical(fields), fields["relative_speed"], c.factor, c.speed_coefficient, c.chemical_rate)

    def sensitivities(self, **fields) -> dict:
        """{input name: d(rate)/d(input)} of the film's three constants, fields on the cells (m/s per unit of the input)."""
        return dict(zip(self.chemistry.inputs, additive_sensitivities(self._mechanical(fields), fields["relative_speed"])))
