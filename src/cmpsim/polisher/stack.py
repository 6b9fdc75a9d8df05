"""The film stack on the wafer per radius, and its removal top film first (issue 32).

The wafer turns under the head, so every point at radius r loses the rotation average of the
removal rate there (:mod:`cmpsim.results.uniformity`): the stack is a thickness per film per ring
of the solve's polar grid (ring centres ``radius``, ring areas ``areas``). Within a time step dt
each ring removes its top film at the rate of that film's material there; when the top film
clears before the end of the step, the rest of the step removes the film below at its own rate
(*carry-over*), and so on down the stack. Below the last film is the substrate, which is not
removed (the time left is reported as ``idle``). The removed volume of a step is exactly
sum_rings area_i sum_films rate_ki t_ki, t_ki the time film k was exposed on ring i within the step
(``tests/test_polish.py`` checks it against the drop of the stack's volume).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

__all__ = ["FilmStack", "Removal", "remove", "ring_areas"]


def ring_areas(ring_faces) -> np.ndarray:
    """Area of each ring between consecutive faces (m), m^2."""
    f = np.asarray(ring_faces, dtype=float)
    return np.pi * (f[1:] ** 2 - f[:-1] ** 2)


@dataclass(frozen=True)
class FilmStack:
    """Films of a wafer per ring: ``names`` and ``materials`` (top first), ``radius`` (ring centres,
    m), ``areas`` (ring areas, m^2) and ``thickness`` (films x rings, m)."""

    names: tuple
    materials: tuple
    radius: np.ndarray
    areas: np.ndarray
    thickness: np.ndarray

    @classmethod
    def uniform(cls, films, radius, ring_faces) -> "FilmStack":
        """A stack of uniform films (:class:`cmpsim.polisher.recipe.Film`) on the rings of a grid."""
        radius = np.asarray(radius, dtype=float)
        t = np.array([[f.thickness] * radius.size for f in films], dtype=float)
        return cls(tuple(f.name for f in films), tuple(f.material for f in films), radius, ring_areas(ring_faces), t)

    @property
    def wafer_area(self) -> float:
        """Area of the wafer (sum of the ring areas), m^2."""
        return float(self.areas.sum())

    def top(self) -> np.ndarray:
        """Index of the top film left on each ring (len(names) where every film is cleared)."""
        present = self.thickness > 0
        return np.where(present.any(axis=0), np.argmax(present, axis=0), len(self.names))

    def volume(self) -> np.ndarray:
        """Volume of each film on the wafer, m^3."""
        return self.thickness @ self.areas

    def cleared_fraction(self, film: int) -> float:
        """Share of the wafer area on which film ``film`` (an index, top first) and every film above it are gone."""
        gone = np.all(self.thickness[: film + 1] <= 0, axis=0)
        return float(self.areas[gone].sum() / self.areas.sum())

    def mean_thickness(self, film: int) -> float:
        """Area-mean thickness of film ``film`` over the wafer, m."""
        return float(self.thickness[film] @ self.areas / self.areas.sum())

    def to_dict(self) -> dict:
        """{"radius": [m], film name: [m], ...}: the ``thickness`` object of the JSON."""
        out = {"radius": [float(r) for r in self.radius]}
        for name, t in zip(self.names, self.thickness):
            out[name] = [float(x) for x in t]
        return out


@dataclass(frozen=True)
class Removal:
    """What one :func:`remove` did: ``exposure`` (films x rings, s) the time each film was removed on
    each ring, ``removed`` (films x rings, m) the thickness taken, ``idle`` (rings, s) the time the
    bare substrate was polished (nothing removed)."""

    exposure: np.ndarray
    removed: np.ndarray
    idle: np.ndarray

    def volume(self, areas) -> float:
        """Removed volume, m^3."""
        return float(np.sum(self.removed @ np.asarray(areas)))


def remove(stack: FilmStack, rates, dt: float) -> tuple[FilmStack, Removal]:
    """Polish ``stack`` for ``dt`` s at ``rates`` (films x rings, m/s: each film's rate on each ring).

    Top film first on every ring; a film that clears within the step hands the rest of the step to
    the film below at that film's rate (carry-over). Returns the new stack and the :class:`Removal`.
    """
    rates = np.asarray(rates, dtype=float)
    if rates.shape != stack.thickness.shape:
        raise ValueError(f"rates must have the shape of the stack (films x rings) {stack.thickness.shape}; got {rates.shape}")
    if not (np.isfinite(dt) and dt >= 0):
        raise ValueError(f"time step must be finite and >= 0 s; got {dt!r}")
    if np.any(rates < 0) or not np.all(np.isfinite(rates)):
        raise ValueError("removal rates must be finite and >= 0")
    t = stack.thickness.copy()
    left = np.full(t.shape[1], float(dt))
    exposure = np.zeros_like(t)
    removed = np.zeros_like(t)
    for k in range(t.shape[0]):
        active = (left > 0) & (t[k] > 0)
        r = rates[k]
        with np.errstate(divide="ignore"):
            need = np.where(r > 0, t[k] / np.where(r > 0, r, 1.0), np.inf)  # time to clear film k, s
        clears = active & (need <= left)
        partial = active & ~clears
        exposure[k] = np.where(clears, need, np.where(partial, left, 0.0))
        removed[k] = np.where(clears, t[k], np.where(partial, r * left, 0.0))
        t[k] = np.where(clears, 0.0, t[k] - removed[k])
        left = np.where(clears, left - need, np.where(partial, 0.0, left))
    t = np.maximum(t, 0.0)
    new = FilmStack(stack.names, stack.materials, stack.radius, stack.areas, t)
    return new, Removal(exposure, removed, left)
