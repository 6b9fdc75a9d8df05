"""The end point as a tool sees it: the reflectance of the wafer at 650 nm, and the platen's friction torque (issue 32).

**Reflectance** (the signal that stops a step). Each ring of the stack (:mod:`cmpsim.polisher.stack`)
reflects what its top films show at 650 nm (:mod:`cmpsim.physics.films`):

- a metal film (copper, barrier) of thickness t over what lies below (reflectance R_b):
  R = R_b + (R_m - R_b) min(t / t_o, 1), R_m the opaque film's reflectance, t_o its opacity thickness
  (40 nm: Tian et al. 2023 [T]; the linear blend below t_o is an assumption, stated in docs/polisher.md);
- an oxide film on the silicon substrate: Airy's thin-film reflectance (:func:`cmpsim.physics.films.film_reflectance`);
  whatever lies under the oxide is taken as silicon;
- the bare substrate: silicon (:func:`cmpsim.physics.films.interface_reflectance`).

The sensor sees the area-mean reflectance of the wafer (:func:`reflectance_signal`; an in-platen
sensor sweeps the wafer every turn and the tool averages the sweeps: taken as the area mean). An
end-pointed step clears its top film onto the film below: at its start the signal is S_0; with the
top film gone everywhere (the rest of the stack as it is now) it would be S_next
(:func:`cleared_level`). The :class:`EndpointDetector` stops the step at the first sample where the
signal has settled within the tolerance (1 - f)|S_0 - S_next| of S_next, f the step's
``endpoint_fraction``: with reflectances that mix by area, that is the top film cleared on about the
fraction f of the wafer (metal thinner than t_o already shows the film below, so the signal runs a
little ahead of the cleared area; the cleared fraction at that moment is reported).

**Torque.** The platen's motor supplies the torque T = (1 / Omega_p) int tau . u_pad dA (the friction
power the pad delivers over its angular speed), from the solved shear field (:func:`platen_torque`).
The trace is reported; it does not detect the end point in this model: the wafer equilibrium does
not depend on the film (the film enters only the removal law) and no film-specific friction
coefficient is sourced (:mod:`cmpsim.physics.films`), so the torque changes only with the step's inputs.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from ..physics.films import FILM_CONSTANTS, SILICON_INDEX_650, film_reflectance, interface_reflectance
from .stack import FilmStack

__all__ = ["ring_reflectance", "reflectance_signal", "cleared_level", "platen_torque", "EndpointDetector", "EndpointTrace", "WATER_INDEX"]

#: Refractive index of the slurry's water through which the sensor looks (films.film_reflectance's default).
WATER_INDEX = 1.333


def ring_reflectance(stack: FilmStack) -> np.ndarray:
    """Reflectance at 650 nm of each ring of ``stack`` (dimensionless), from the substrate up."""
    n_r = stack.thickness.shape[1]
    below = np.full(n_r, float(interface_reflectance(WATER_INDEX, SILICON_INDEX_650)))
    for k in range(len(stack.materials) - 1, -1, -1):
        c = FILM_CONSTANTS[stack.materials[k]]
        t = stack.thickness[k]
        if c.reflectance_650 is not None:  # a metal: opaque above opaque_thickness
            w = np.clip(t / c.opaque_thickness, 0.0, 1.0)
            below = below + (c.reflectance_650 - below) * w
        elif c.refractive_index_650 is not None:  # a transparent film on silicon
            below = np.where(t > 0, film_reflectance(t, film_index=c.refractive_index_650, ambient_index=WATER_INDEX), below)
        else:
            raise ValueError(f"film {stack.materials[k]!r} has no optical constants at 650 nm: no reflectance end point")
    return below


def reflectance_signal(stack: FilmStack) -> float:
    """The area-mean reflectance of the wafer at 650 nm (dimensionless): the end-point signal."""
    return float(ring_reflectance(stack) @ stack.areas / stack.areas.sum())


def cleared_level(stack: FilmStack, film: int) -> float:
    """The signal with film ``film`` (and every film above it) gone from the whole wafer, the rest as it is."""
    t = stack.thickness.copy()
    t[: film + 1] = 0.0
    return reflectance_signal(FilmStack(stack.names, stack.materials, stack.radius, stack.areas, t))


def platen_torque(shear_stress, pad_velocity, areas, pad_speed: float) -> float:
    """Torque on the platen, N m: (1 / Omega_p) sum tau . u_pad dA over the wafer.

    ``shear_stress`` (tau_x, tau_y) and ``pad_velocity`` (u_x, u_y) on the cells (Pa, m/s),
    ``areas`` the cell areas (m^2), ``pad_speed`` Omega_p (rad/s)."""
    (tx, ty), (ux, uy) = shear_stress, pad_velocity
    return float(np.sum((tx * ux + ty * uy) * areas) / pad_speed)


@dataclass
class EndpointTrace:
    """The signals of a step through time: ``time`` (s, from the recipe's start), ``reflectance``
    (the area-mean reflectance at 650 nm), ``torque`` (N m), ``cleared_fraction`` (of the step's top
    film, share of the wafer area)."""

    time: list = field(default_factory=list)
    reflectance: list = field(default_factory=list)
    torque: list = field(default_factory=list)
    cleared_fraction: list = field(default_factory=list)

    def append(self, time: float, reflectance: float, torque: float, cleared: float) -> None:
        self.time.append(float(time))
        self.reflectance.append(float(reflectance))
        self.torque.append(float(torque))
        self.cleared_fraction.append(float(cleared))

    def to_dict(self) -> dict:
        return {"time": list(self.time), "reflectance": list(self.reflectance), "torque": list(self.torque), "cleared_fraction": list(self.cleared_fraction)}


@dataclass(frozen=True)
class EndpointDetector:
    """Stops an end-pointed step: the signal has settled to the cleared level ``target`` within
    ``(1 - fraction) |start - target|`` (``start``: the signal at the step's start)."""

    start: float
    target: float
    fraction: float

    #: Smallest change of the signal a tool can see (reflectance units): below it the end point is refused.
    RESOLUTION = 1e-3

    def __post_init__(self) -> None:
        if abs(self.start - self.target) < self.RESOLUTION:
            raise ValueError(
                f"the reflectance at 650 nm would change by only {abs(self.start - self.target):.2g} when the top film clears "
                f"(from {self.start:.4f} to {self.target:.4f}): the end point cannot see it"
            )

    @property
    def tolerance(self) -> float:
        """How close to the cleared level the signal must come (reflectance units)."""
        return (1.0 - self.fraction) * abs(self.start - self.target)

    def progress(self, signal: float) -> float:
        """Share of the way from the start level to the cleared level (0 at the start, 1 cleared)."""
        return (self.start - signal) / (self.start - self.target)

    def reached(self, signal: float) -> bool:
        """True once the signal lies within the tolerance of the cleared level."""
        return abs(signal - self.target) <= self.tolerance + 1e-12
