"""The models of cmpsim, picked by name in one place: the registry of the four model axes.

Each input that chooses physics maps its value to a class here, as
``scipy.integrate.solve_ivp(method=...)`` maps a name to an ``OdeSolver`` subclass:

========================  ==============================================  =====================================
input                     values -> class                                  protocol (:mod:`cmpsim.models.base`)
========================  ==============================================  =====================================
``pad_compliance``        :data:`PAD_MODELS` (rigid, winkler, layer)       :class:`~cmpsim.models.base.PadModel`
``slurry_model``          :data:`SLURRY_MODELS` (granular, newtonian)      :class:`~cmpsim.models.base.SlurryModel`
``cavitation``            :data:`CAVITATION_MODELS` (none, gumbel, jfo)    :class:`~cmpsim.models.base.CavitationModel`
``removal_law``           :data:`REMOVAL_LAWS` (paper, ..., abrasive)      :class:`~cmpsim.models.base.RemovalLaw`
``carrier``               :data:`CARRIERS` (rigid, membrane)               :class:`~cmpsim.models.base.CarrierModel`
``film_chemistry``        :data:`FILM_CHEMISTRIES` (none, additive)        :class:`~cmpsim.models.base.FilmChemistry`
========================  ==============================================  =====================================

:mod:`cmpsim.solver.setup` builds the models of a Config with the functions below; the solver and
the post-processing only ask the objects. New physics adds a class and an entry here.
"""

from __future__ import annotations

import numpy as np

from ..operators.cavitation import VACUUM_GAUGE_PRESSURE
from .base import CarrierModel, CavitationModel, FilmChemistry, PadModel, RemovalLaw, SlurryModel
from .carriers import MembraneCarrier, RigidCarrier
from .chemistry import AdditiveChemistry, NoChemistry
from .pads import LayerPad, RigidPad, WinklerPad
from .removal_laws import AbrasiveRemovalLaw, PaperRemovalLaw, ShearPowerRemovalLaw
from .slurries import GranularSlurry, GumbelCavitation, JFOCavitation, NewtonianSlurry, NoCavitation

__all__ = [
    "PAD_MODELS",
    "SLURRY_MODELS",
    "CAVITATION_MODELS",
    "REMOVAL_LAWS",
    "CARRIERS",
    "FILM_CHEMISTRIES",
    "pad_model",
    "pad_for_foundation",
    "slurry_model",
    "removal_law",
    "carrier",
    "film_chemistry",
    "PadModel",
    "SlurryModel",
    "CavitationModel",
    "RemovalLaw",
    "CarrierModel",
    "FilmChemistry",
]

#: ``pad_compliance`` -> pad model class.
PAD_MODELS: dict[str, type] = {"rigid": RigidPad, "winkler": WinklerPad, "layer": LayerPad}
#: ``slurry_model`` -> slurry model class.
SLURRY_MODELS: dict[str, type] = {"granular": GranularSlurry, "newtonian": NewtonianSlurry}
#: ``cavitation`` -> cavitation model class (of the Newtonian slurry).
CAVITATION_MODELS: dict[str, type] = {"none": NoCavitation, "gumbel": GumbelCavitation, "jfo": JFOCavitation}
#: ``removal_law`` -> removal law class.
REMOVAL_LAWS: dict[str, type] = {"paper": PaperRemovalLaw, "shear_power": ShearPowerRemovalLaw, "abrasive": AbrasiveRemovalLaw}
#: ``carrier`` -> carrier model class.
CARRIERS: dict[str, type] = {"rigid": RigidCarrier, "membrane": MembraneCarrier}
#: ``film_chemistry`` -> film chemistry class (what the slurry's chemistry adds to the mechanical rate).
FILM_CHEMISTRIES: dict[str, type] = {"none": NoChemistry, "additive": AdditiveChemistry}


def _pick(registry: dict, option: str, name: str) -> type:
    try:
        return registry[name]
    except (KeyError, TypeError):
        raise ValueError(f"{option} must be one of {tuple(registry)}; got {name!r}") from None


def pad_model(config) -> PadModel:
    """The pad model of a Config (``pad_compliance``, with its stack from the pad inputs)."""
    return _pick(PAD_MODELS, "pad_compliance", config.pad_compliance).from_config(config)


def pad_for_foundation(foundation) -> PadModel:
    """The pad model that solves with an elastic stack of :mod:`cmpsim.physics.padstack` (None: rigid)."""
    for cls in PAD_MODELS.values():
        if type(foundation) is cls.foundation_type:
            return cls(foundation)
    raise ValueError(f"foundation must be None, a WinklerFoundation or a LayeredFoundation; got {foundation!r}")


def slurry_model(name: str, cavitation: str = "none", cavitation_pressure=None, ambient_pressure: float = 1.0) -> SlurryModel:
    """The slurry model ``name`` with its cavitation, refusing settings that do not apply.

    ``ambient_pressure`` is the granular pressure p0 at the wafer edge, Pa; ``cavitation_pressure``
    the gauge p_cav in [-101325, 0] Pa, required unless ``cavitation == "none"``.
    """
    cls = _pick(SLURRY_MODELS, "slurry_model", name)
    cav_cls = _pick(CAVITATION_MODELS, "cavitation", cavitation)
    if cav_cls is NoCavitation:
        return cls(ambient_pressure)
    if not cls.takes_cavitation:
        raise ValueError(
            f"cavitation = {cavitation!r} applies to the Newtonian slurry only (slurry_model = 'newtonian'); with "
            f"slurry_model = {name!r} the valid value is 'none': the granular slurry is solved in ln p, so its "
            "gauge pressure cannot fall below -p0 (an implicit, speed-dependent cavitation pressure)"
        )
    p = cavitation_pressure
    if p is None or not (np.isfinite(p) and VACUUM_GAUGE_PRESSURE <= p <= 0.0):
        raise ValueError(
            f"cavitation_pressure must be a gauge pressure in [{VACUUM_GAUGE_PRESSURE:g}, 0] Pa (no higher than ambient, "
            f"no lower than vacuum); got {p!r}"
        )
    return cls(ambient_pressure, cav_cls(p))


def removal_law(config) -> RemovalLaw:
    """The removal law of a Config (``removal_law``, with its coefficients), with the film chemistry
    of ``film_chemistry`` added for the film ``film`` (``"none"``: the mechanical law itself)."""
    law = _pick(REMOVAL_LAWS, "removal_law", config.removal_law).from_config(config)
    return film_chemistry(config).wrap(law)


def film_chemistry(config) -> FilmChemistry:
    """The film chemistry of a Config (``film_chemistry``, with the constants of its ``film``)."""
    return _pick(FILM_CHEMISTRIES, "film_chemistry", config.film_chemistry).from_config(config)


def carrier(config="rigid") -> CarrierModel:
    """The carrier model of a Config (``carrier``, with its zones and wafer plate), or a carrier that takes no inputs by name (``"rigid"``)."""
    if isinstance(config, str):
        cls = _pick(CARRIERS, "carrier", config)
        try:
            return cls()
        except TypeError:
            raise ValueError(f"carrier {config!r} needs its inputs: build it from a Config, cmpsim.models.carrier(config)") from None
    return _pick(CARRIERS, "carrier", config.carrier).from_config(config)
