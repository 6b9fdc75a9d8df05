"""Which inputs a data set can calibrate: quantity kind -> candidate inputs, in order of preference.

``cmpsim calibrate DATA`` without ``--free`` asks each :class:`QuantityKind` of
:data:`QUANTITY_KINDS` for the inputs its points could identify (:class:`Candidate`, with the
reason), then keeps those the fit's Jacobian can separate (:mod:`cmpsim.calibration.identify`).
A new kind of measurement (die test structures, pad temperature, a lot's wafers) adds a
:class:`QuantityKind` and one line in :data:`QUANTITY_KINDS`; nothing else changes.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Callable

from ..inputs.config import Config
from ..physics.chemistry import input_names
from ..validation import point_config

__all__ = ["Candidate", "QuantityKind", "QUANTITY_KINDS", "kind_of", "candidates", "choose_for", "FILM_REMOVAL", "TEST_STRUCTURES",
           "PAD_HEAT", "PAD_LIFE"]


@dataclass(frozen=True)
class Candidate:
    """An input a kind of measurement could identify, the ``why`` of it, and the ``settings``
    (inputs such as ``film_chemistry = "additive"``) the model needs for the input to act."""

    name: str
    why: str
    settings: tuple = ()


@dataclass(frozen=True)
class QuantityKind:
    """A kind of measurement: its ``quantities`` and the :class:`Candidate` inputs its points could
    identify, ``candidates(points, config)`` (points: :class:`cmpsim.validation.data.DataPoint`),
    in order of preference (the first is kept when two cannot be separated)."""

    name: str
    quantities: tuple
    candidates: Callable
    #: the scale the kind calibrates: "wafer" (film removal, fitted through the wafer solve by
    #: :func:`cmpsim.calibration.calibrate`), "die" (test structures), "pad" (the pad's heat balance) or
    #: "lot" (a lot's wafers: the pad life, whose ``config`` is a :class:`cmpsim.calibration.padlife.LotSetting`)
    scale: str = "wafer"
    #: for the die and pad scales: ``jacobian(records, names, config)`` -> d(whitened residual)/d ln(input)
    #: at the start, one column per name (what :func:`cmpsim.calibration.identify.choose` reads)
    jacobian: Callable | None = None


def _film_candidates(points, config: Config) -> list[Candidate]:
    """Removal rates of each film, in order of preference: k_F (scales the mechanical rate: one point
    fixes it), R_c,F (adds a constant), B_F (adds a rate proportional to the sliding speed)."""
    by_film: dict[str, list] = {}
    for p in points:
        by_film.setdefault(p.film or config.film, []).append(p)
    out = []
    on = (("film_chemistry", "additive"),)
    for film, pts in by_film.items():
        factor, speed, rate = input_names(film)
        cfgs = [point_config(config, p.conditions) for p in pts]
        pressures = {round(c.applied_pressure, 6) for c in cfgs}
        speeds = {round(c.rotation_speed * c.centre_distance, 9) for c in cfgs}
        settings = {(round(c.applied_pressure, 6), round(c.rotation_speed * c.centre_distance, 9), round(c.particle_diameter, 12), round(c.solids_loading, 9)) for c in cfgs}
        n = f"{len(pts)} removal point(s) of {film}"
        out.append(Candidate(factor, f"{n}: k_{film} scales the mechanical rate (the physics' own shape across "
                                     f"{len(settings)} setting(s): {len(pressures)} pressure(s), {len(speeds)} sliding speed(s))", on))
        out.append(Candidate(rate, f"{n}: R_c,{film}, the chemical rate that needs no sliding, adds the same rate to every one", on))
        if len(speeds) > 1:
            out.append(Candidate(speed, f"{n} at {len(speeds)} sliding speeds: B_{film} adds a rate proportional to the speed", on))
        else:
            out.append(Candidate(speed, f"{n}, all at one sliding speed: B_{film} V is then a constant like R_c,{film}", on))
    return out


#: Removal rates, removal depths and remaining thickness of blanket films (wafer mean or profile).
FILM_REMOVAL = QuantityKind("film removal", ("removal_rate", "removal_rate_mean", "removal", "thickness"), _film_candidates)



def _structure_candidates(records, config: Config) -> list[Candidate]:
    """Test structures: the die constants their quantities approach (:func:`cmpsim.calibration.die.choose_free`)."""
    from .die import DIE_CONSTANTS, choose_free

    _, why = choose_free(records)
    return [Candidate(n, why[n]) for n in DIE_CONSTANTS if n in why]


def _structure_jacobian(records, names, config):
    from .die import start_jacobian

    return start_jacobian(records, names, config)


def _pad_candidates(records, config: Config) -> list[Candidate]:
    """Pad temperature and friction: the summit friction and the heat removal (:func:`cmpsim.calibration.thermal.choose_free`)."""
    from .thermal import choose_free

    names, why = choose_free(records)
    return [Candidate(n, why[n]) for n in names]


def _pad_jacobian(records, names, config):
    from .thermal import start_jacobian

    return start_jacobian(records, names, config)


#: Dishing, erosion and step height of test structures: the die model's constants (docs/calibrate.md).
TEST_STRUCTURES = QuantityKind("test structures", ("dishing", "erosion", "step_height"), _structure_candidates, "die", _structure_jacobian)
#: The pad's temperature rise and effective friction: the summit friction and the pad's heat removal.
PAD_HEAT = QuantityKind("pad temperature", ("pad_temperature_rise", "friction_coefficient"), _pad_candidates, "pad", _pad_jacobian)



def _lot_candidates(records, setting) -> list[Candidate]:
    """A lot's wafers: the pad life's glazing and conditioning constants (:func:`cmpsim.calibration.padlife.choose_free`)."""
    from .padlife import choose_free

    names, why = choose_free(records, setting)
    return [Candidate(n, why[n]) for n in names]


def _lot_jacobian(records, names, setting):
    from .padlife import start_jacobian

    return start_jacobian(records, names, setting)


#: Per-wafer thickness or removal of a lot (rows with a ``wafer``): the pad life's glazing and conditioning constants.
PAD_LIFE = QuantityKind("pad life", ("thickness", "removal"), _lot_candidates, "lot", _lot_jacobian)

#: The kinds of measurement that choose inputs, by name.
QUANTITY_KINDS: dict[str, QuantityKind] = {k.name: k for k in (FILM_REMOVAL, TEST_STRUCTURES, PAD_HEAT, PAD_LIFE)}


def kind_of(quantity: str, scale: str | None = None) -> QuantityKind | None:
    """The kind a quantity belongs to (None: no kind chooses inputs for it yet), of ``scale`` if given."""
    for kind in QUANTITY_KINDS.values():
        if quantity in kind.quantities and (scale is None or kind.scale == scale):
            return kind
    return None


def choose_for(kind: QuantityKind, records, config: Config, max_free: int | None = None):
    """The inputs ``records`` of a die or pad ``kind`` choose: its candidates, kept while the Jacobian at
    the start separates them, with one degree of freedom left (:class:`cmpsim.calibration.identify.Choice`)."""
    from .identify import choose_records

    cands = kind.candidates(records, config)
    return choose_records([c.name for c in cands], [c.why for c in cands], kind.jacobian, records, config, max_free, kind.name)


def candidates(datasets, config: Config) -> tuple[list[Candidate], list[str]]:
    """(candidates of every kind in the data, in order, no repeats; notes on quantities no kind takes)."""
    groups: dict[str, list] = {}
    notes = []
    for ds in datasets:
        for p in ds.points:
            kind = kind_of(p.quantity, "wafer")
            if kind is None:
                notes.append(f"{ds.name}: quantity {p.quantity!r} chooses no input (no registered kind); give --free to fit inputs to it")
                continue
            groups.setdefault(kind.name, []).append(p)
    out, seen = [], set()
    for name, pts in groups.items():
        for c in QUANTITY_KINDS[name].candidates(pts, config):
            if c.name not in seen:
                seen.add(c.name)
                out.append(c)
    return out, sorted(set(notes))
