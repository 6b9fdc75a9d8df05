"""The film stacks of the die model, one class each behind one protocol, picked by name in :data:`STACKS`.

A stack says what the two levels of a cell are (:mod:`cmpsim.die.stepheight`: level A, the
level whose area fraction the layout's density sets, and level B), where they start, how fast
the pad removes level A at each depth, where its material changes and what the outputs
(dishing, erosion, clearing) mean. :class:`cmpsim.die.evolution.DieEvolution` asks the stack and
never the stack's name. Heights are measured from the original top of the field oxide (m).
"""

from __future__ import annotations

from typing import Protocol

import numpy as np

__all__ = ["FilmStack", "OxideStack", "CopperStack", "STACKS", "film_stack"]


class FilmStack(Protocol):
    """What the die evolution needs from a film stack."""

    #: True where metal lines are polished: the stack reports dishing, erosion and a clearing time.
    metal: bool
    #: The film whose blanket rate drives the stack (the wafer solve's ``film`` input).
    film: str

    def levels(self, density, width, space):
        """(local fraction of level A, whether the effective density is that of A (True) or of B, gap width of the lower level (m), zA, zB).

        ``width`` and ``space`` (m) are the line width and space of every cell, NaN where a cell has none.
        """

    def field_rate(self, za, rate):
        """Blanket rate (m/s) of level A at height za, given the stack's base blanket rate."""

    def boundary(self, za):
        """The height at which level A changes material next (-inf: never)."""

    def planarizing(self, za):
        """Whether a cell at za is in the stage whose planarity is tracked."""

    def end_depth(self) -> float:
        """A depth (m) of the order of the removal to the end point, for the step of the end-point search."""


class OxideStack:
    """Oxide ILD/STI: A = oxide over the lines (fraction rho), B = oxide over the spaces, ``step_height`` lower; one material."""

    metal = False
    film = "oxide"

    def __init__(self, process):
        self.p = process

    def levels(self, density, width, space):
        gap = np.asarray(space, dtype=float)  # the spaces between the lines
        return density, True, gap, np.zeros(density.shape), np.full(density.shape, -self.p.step_height)

    def field_rate(self, za, rate):
        return np.full(np.shape(za), rate)

    def boundary(self, za):
        return np.full(np.shape(za), -np.inf)

    def planarizing(self, za):
        return np.ones(np.shape(za), dtype=bool)

    def end_depth(self) -> float:
        return self.p.step_height


class CopperStack:
    """Copper damascene: A = the field (fraction 1 - rho: copper on barrier on oxide), B = the copper lines.

    Conformal plating closes trenches narrower than twice the plated thickness; wider ones print
    the trench depth. The field is removed at the copper rate, then at ``barrier_selectivity`` and
    ``oxide_selectivity`` times it; the lines at the copper rate.
    """

    metal = True
    film = "copper"

    def __init__(self, process):
        self.p = process

    def levels(self, density, width, space):
        p = self.p
        top = p.barrier_thickness + p.copper_thickness
        closed = ~(np.isfinite(width) & (width > 2.0 * p.copper_thickness))
        za = np.full(density.shape, top)
        return 1.0 - density, False, width, za, np.where(closed, top, top - p.trench_depth)

    def field_rate(self, za, rate):
        p = self.p
        return rate * np.where(za > p.barrier_thickness, 1.0, np.where(za > 0.0, p.barrier_selectivity, p.oxide_selectivity))

    def boundary(self, za):
        tb = self.p.barrier_thickness
        return np.where(za > tb, tb, np.where(za > 0.0, 0.0, -np.inf))

    def planarizing(self, za):
        return za > self.p.barrier_thickness  # the bulk copper stage

    def end_depth(self) -> float:
        return self.p.copper_thickness + self.p.barrier_thickness / self.p.barrier_selectivity


#: The film stacks by name (``DieProcess.kind``).
STACKS = {"oxide": OxideStack, "copper": CopperStack}


def film_stack(process) -> FilmStack:
    """The film stack of a :class:`~cmpsim.die.process.DieProcess`."""
    return STACKS[process.kind](process)
