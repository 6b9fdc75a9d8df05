"""A layout riding along a recipe (issue 32): the die model at a few wafer sites through the steps.

The wafer is integrated per radius through the recipe (:mod:`cmpsim.polisher.engine`); a die at a
site of radius r is polished, step after step, by the die model of :mod:`cmpsim.die`
(:class:`cmpsim.die.chip.DieModel`) with that step's conditions there:

* its **blanket rate**: the rotation-averaged removal rate of the die's film (copper for a copper
  die, oxide for an oxide die) at r, from the step's wafer solve, at the pad's temperature of
  each time step, times ``rate_factor`` and the glazed pad's factor (``pad_life``): the very rate
  the film stack is polished with. Every rate of the die model is the blanket rate times a
  pressure ratio, so the die is polished exactly by the step's mean rate at r, the blanket depth
  of the step over its duration;
* its **duration** as ended: a step that stops at the end point gives the die the time it ran;
* the step's **config**: the applied pressure (the pad body's bulge into wide gaps) and the pad
  stack (the planarization length), as ``cmpsim die`` takes them from its inputs;
* its **state**: the heights of both levels of every window, the films left on the die and the
  event times are carried from step to step (:meth:`cmpsim.die.chip.DieModel.resume`).

The die's film stack follows the recipe's: a top film of copper makes a copper damascene die
whose ``copper_thickness`` is that film's (and ``barrier_thickness`` that of a barrier film right
below), an oxide top film an oxide die; ``params`` set any die input (:data:`cmpsim.die.DIE_PARAMETERS`).
The die's own films clear on the die's own schedule (its selectivities to the copper rate), not
on the wafer's.
"""

from __future__ import annotations

import math
import os
from dataclasses import dataclass, field

import numpy as np

__all__ = ["RidingDie", "Ride", "SITE_KEYS", "DIE_UNITS", "parse_sites"]

#: The keys of a site in a step's ``die`` list besides radius and duration (the die model's own, :meth:`cmpsim.die.DieResult.scalars`).
SITE_KEYS = ("time", "blanket_rate", "thickness_range", "step_height_max", "dishing_max", "erosion_max", "hotspot_count",
             "time_to_planarize", "time_to_clear")
#: The units of the ride's keys in the JSON of ``cmpsim polish --die``.
DIE_UNITS = {
    "die.radius": "m (the site's distance from the wafer centre)", "die.duration": "s (the step's, as ended)",
    "die.time": "s (the die's polishing time since the recipe's start)", "die.blanket_rate": "m/s (the step's mean at the site)",
    "die.thickness_range": "m", "die.step_height_max": "m", "die.dishing_max": "m", "die.erosion_max": "m", "die.hotspot_count": "1",
    "die.time_to_planarize": "s (from the recipe's start; null until every window planarized)",
    "die.time_to_clear": "s (from the recipe's start; null until every window cleared; null for oxide)",
    "ride.sites": "m", "ride.window": "m", "ride.planarization_length": "m",
}


def parse_sites(text) -> tuple:
    """Site radii (m) from ``"0, 70 mm, 140mm"`` (a bare number is mm) or a sequence of floats (m)."""
    from ..inputs.units import to_si

    if not isinstance(text, str):
        return tuple(float(r) for r in text)
    out = []
    for part in (p.strip() for p in text.split(",")):
        if not part:
            raise ValueError(f"--sites {text!r}: an empty radius; give radii separated by commas, e.g. 0,70mm,140mm")
        try:
            out.append(float(part) * 1e-3)
        except ValueError:
            out.append(to_si(part, "m", "--sites", "70 mm"))
    return tuple(out)


@dataclass(frozen=True)
class RidingDie:
    """What rides along (``cmpsim.polish(recipe, die=RidingDie(...))``, ``cmpsim polish --die``).

    ``layout``: a GDSII/OASIS file (with ``layers``, ``window`` (m), ``top``, ``pdk`` or
    ``layer_map``, as :func:`cmpsim.die.chip.layout_die`), a layout CSV, a built-in die name or a
    :class:`cmpsim.die.Layout`; ``sites``: radii (m) of the dies, default the centre, mid-radius
    and the outermost whole die (:meth:`Ride.sites`); ``process``: ``"oxide"``, ``"copper"``, a
    :class:`cmpsim.die.DieProcess` or None (from the recipe's top film); ``params``: die inputs
    with units; ``spec``: hotspot limits; the rest as :class:`cmpsim.die.chip.DieModel`.
    """

    layout: object
    layers: tuple = ()
    window: float = 20e-6
    top: str | None = None
    pdk: str | None = None
    layer_map: object = None
    sites: tuple | None = None
    process: object = None
    params: dict = field(default_factory=dict)
    spec: object = None
    weighting: str = "gaussian"
    feature_contact: str = "elastic"
    planarization_length: float | None = None

    def load(self):
        """The die :class:`~cmpsim.die.Layout`; ValueError naming the parameter for a missing file or an unknown layer."""
        from ..die.chip import is_layout_file, layout_die
        from ..die.layout import BUILTIN_LAYOUTS, Layout
        from ..die.polish import load_layout

        if isinstance(self.layout, Layout):
            return self.layout
        if isinstance(self.layout, (str, os.PathLike)) and str(self.layout) not in BUILTIN_LAYOUTS and is_layout_file(self.layout):
            if not self.layers:
                raise ValueError(f"--die {str(self.layout)!r} is a layout file: give its layers (--layer L/D, or a name with --pdk / --layer-map)")
            try:
                return layout_die(self.layout, list(self.layers), self.window, top=self.top, pdk=self.pdk, layer_map=self.layer_map)
            except ValueError as exc:
                raise ValueError(f"--die {str(self.layout)!r}: {exc}") from None
        given = [n for n, v in (("--layer", self.layers), ("--top", self.top), ("--pdk", self.pdk), ("--layer-map", self.layer_map)) if v]
        if given:
            raise ValueError(f"{', '.join(given)} {'applies' if len(given) == 1 else 'apply'} to a layout file (.gds, .gds.gz, .oas); --die {str(self.layout)!r} is a CSV grid or a built-in die")
        if str(self.layout) not in BUILTIN_LAYOUTS and not os.path.isfile(str(self.layout)):
            raise ValueError(f"--die {str(self.layout)!r}: no such file (a .gds, .gds.gz, .oas or CSV layout, or a built-in die: cmpsim die --list)")
        try:
            return load_layout(self.layout)
        except (ValueError, OSError) as exc:
            raise ValueError(f"--die {str(self.layout)!r}: {exc}") from None

    def die_process(self, recipe):
        """The die's :class:`~cmpsim.die.DieProcess`: ``process`` and ``params``, the film thicknesses from the recipe's stack."""
        from ..die.process import DieProcess

        if isinstance(self.process, DieProcess):
            if self.params:
                raise ValueError("give the die inputs either as a DieProcess or as params, not both")
            return self.process
        films = recipe.films
        kind = self.process or films[0].material
        if kind not in ("oxide", "copper"):
            raise ValueError(f"--die: the recipe's top film is {films[0].material!r}; the die model polishes an oxide or a copper "
                             "damascene die (give process = 'oxide' or 'copper')")
        values = {}
        if kind == "copper" and films[0].material == "copper":
            values["copper_thickness"] = films[0].thickness
            if len(films) > 1 and films[1].material == "barrier":
                values["barrier_thickness"] = films[1].thickness
        try:
            return DieProcess.from_values(kind, **(values | dict(self.params)))
        except ValueError as exc:
            raise ValueError(f"--die-param: {exc}") from None

    def prepare(self, recipe, configs) -> "Ride":
        """Read the layout, check the sites against the wafer of the steps: the :class:`Ride` the engine drives."""
        return Ride(self, recipe, configs)


class Ride:
    """The dies of a :class:`RidingDie` through a recipe: ``radii`` (m), ``dies`` (the die at each site now, a DieResult)."""

    def __init__(self, riding: RidingDie, recipe, configs):
        from ..die.hotspots import parse_spec

        self.riding = riding
        self.layout = riding.load()
        self.process = riding.die_process(recipe)
        self.spec = parse_spec(riding.spec)
        self.materials = (self.process.kind,)  # the die's film: "oxide" or "copper", the name of its blanket rate's film
        cfg = configs[0]
        radius = 0.5 * float(cfg.wafer_diameter)
        self.radii = self.sites(cfg) if riding.sites is None else np.asarray(riding.sites, dtype=float)
        if self.radii.ndim != 1 or self.radii.size == 0:
            raise ValueError("--sites: give at least one radius")
        for r in self.radii:
            if not (math.isfinite(r) and 0.0 <= r <= radius):
                raise ValueError(f"--sites: {r * 1e3:g} mm is outside the wafer (radius {radius * 1e3:g} mm); give radii from 0 to {radius * 1e3:g} mm")
        self._models: dict = {}
        self.model(cfg)  # the die inputs, weighting and feature contact checked before any solve
        self.dies = None

    def sites(self, config) -> np.ndarray:
        """The default sites (m): the centre, mid-radius and the outermost whole die (its far corner at the edge exclusion)."""
        radius = 0.5 * float(config.wafer_diameter)
        edge = max(radius - float(config.edge_exclusion) - 0.5 * math.hypot(*self.layout.size), 0.0)
        return np.array([0.0, 0.5 * radius, edge])

    def model(self, config):
        """The :class:`~cmpsim.die.chip.DieModel` of a step's config (one per distinct config; its rate is set per site)."""
        from ..die.chip import DieModel

        key = config.key()
        if key not in self._models:
            r = self.riding
            self._models[key] = DieModel(config, self.process, blanket_rate=1.0, planarization_length=r.planarization_length,
                                         weighting=r.weighting, feature_contact=r.feature_contact, spec=self.spec)
        return self._models[key]

    def step(self, config, ring_radius, result) -> list:
        """Polish the die at every site through one step (a :class:`~cmpsim.polisher.engine.StepResult` with ``blanket_removal``);
        returns the step's ``die`` list, one dict per site (SI)."""
        model = self.model(config)
        depth = np.interp(self.radii, np.asarray(ring_radius, dtype=float), result.blanket_removal[self.process.kind])
        duration = float(result.duration)
        if self.dies is None:
            self.dies = [model.start(self.layout)] * len(self.radii)  # one start for all: resume leaves it as it was
        out = []
        for k, (r, d) in enumerate(zip(self.radii, depth)):
            if duration > 0 and d > 0:
                self.dies[k] = model.resume(self.dies[k], duration, blanket_rate=d / duration)
            elif duration > 0:
                raise ValueError(f"step {result.name!r}: the {self.process.kind} rate at the site r = {r * 1e3:g} mm is zero: nothing polishes the die")
            out.append({"radius": float(r), "duration": duration} | self.dies[k].scalars()
                       | {"blanket_rate": d / duration if duration > 0 else 0.0})
        return out

    def to_dict(self) -> dict:
        """The top-level ``ride`` object of ``cmpsim polish --die --json`` and the units of its keys (the recipe's own units are the engine's)."""
        lay = self.layout
        die = self.dies[0] if self.dies else None
        ride = {"layout": lay.name, "process": self.process.kind, "sites": [float(r) for r in self.radii], "window": lay.cell_size,
                "inputs": self.process.to_dict(), "spec": dict(self.spec), "weighting": self.riding.weighting,
                "feature_contact": self.riding.feature_contact,
                "planarization_length": die.planarization_length if die is not None else None}
        if lay.windowed:
            ride["layers"] = [f"{a}/{b}" for a, b in lay.layers]
        return {"ride": ride, "units": dict(DIE_UNITS)}
