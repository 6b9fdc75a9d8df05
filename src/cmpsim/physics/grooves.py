"""Grooved pad: the homogenised venting of the slurry film by grooves at ambient pressure.

A pad with concentric grooves (IC1000 is sold K-grooved) holds, in each groove deep compared with
the film, the slurry at ambient pressure. Over a land of length L = pitch - width between two
grooves the film pressure obeys the Reynolds equation with p = p_a at both ends; on the
wafer's scale, much longer than the pitch, the pressure averaged over one pitch obeys the
screened Reynolds equation (``docs/model.md``, "Grooved pad: venting of the film")

    div( g grad p ) - g kappa^2 (p - p_a) = div( q ),      kappa^2 = 12 pitch / L^3,

with g the film's conductance (h^3 / (12 eta) Phi^p for the Newtonian slurry) and q its
Couette flux. The coefficient is the one that makes the pitch mean of the exact land
solution, p = S x (x - L) / (2 g) for a uniform source S, mean -S L^3 / (12 g pitch) (the
groove at p_a), the homogenised answer -S / (g kappa^2); the land's lowest decay mode,
kappa^2 = pi^2 / L^2, would under-vent: 12 / pi^2 = 1.216 times the exact land mean
(``tests/test_grooves.py``).
The same holds for the granular slurry in its unknown ln(p/p0), which is 0 at the grooves.
"""

from __future__ import annotations

import math

__all__ = ["groove_venting", "LAND_MEAN_FACTOR"]

#: The pitch mean of the parabolic land pressure is -S L^2 / (LAND_MEAN_FACTOR g) times
#: L / pitch: the 1 / 12 of the mean of x (L - x) / 2 over (0, L) in units of L^2.
LAND_MEAN_FACTOR = 12.0


def groove_venting(pitch: float, width: float) -> float:
    """The venting coefficient kappa^2 = 12 pitch / (pitch - width)^3 of a grooved pad, 1/m^2.

    ``pitch`` (m): groove pitch, 0 for an ungrooved pad (returns 0.0); ``width`` (m): groove
    width, 0 <= width < pitch. The homogenised pitch-mean pressure of lands of length
    L = pitch - width between grooves at ambient pressure (derived in ``docs/model.md``,
    "Grooved pad: venting of the film", from the exact land solution).
    Raises ValueError if the inputs are not finite, negative, or width >= pitch > 0.
    """
    if not (math.isfinite(pitch) and math.isfinite(width) and pitch >= 0 and width >= 0):
        raise ValueError(f"pad_groove_pitch and pad_groove_width must be finite and >= 0 m; got {pitch!r}, {width!r}")
    if pitch == 0:
        if width != 0:
            raise ValueError(f"pad_groove_width = {width:g} m needs pad_groove_pitch > 0 (got 0: an ungrooved pad)")
        return 0.0
    if width >= pitch:
        raise ValueError(f"pad_groove_width must be in [0, pad_groove_pitch) = [0, {pitch:g}) m; got {width:g} m")
    land = pitch - width
    return LAND_MEAN_FACTOR * pitch / land**3
