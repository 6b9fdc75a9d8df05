"""The planarization length from the pad stack (docs/model.md, section 18.3).

The pad averages a pattern over the length over which its surface couples laterally. For the
stack of cmpsim's layered pad model (a top pad bending as a thin plate over a soft subpad,
:class:`cmpsim.physics.padstack.LayeredFoundation`) the deflection per pressure at wave number q is

    C(q) = t1/M1 + 1 / (D1 q^4 + K2(q)),   D1 = E1 t1^3 / 12 (1 - nu1^2),

a low-pass filter: long waves deflect the stack like a Winkler bed of stiffness k = 1/C(0),
waves shorter than the bending length (D1/k2)^(1/4) are carried by the plate. The
planarization length L of the Gaussian weighting (:class:`cmpsim.die.density.GaussianWeighting`)
is chosen so that both filters pass half their power at the same wave number:

    C(q_half) / C(0) = 1/2,      exp(-q_half^2 L^2 / (4 pi)) = 1/2   =>   L = sqrt(4 pi ln 2) / q_half.

For a plate on a Winkler subpad q_half = 1/l with l = (D1/k2)^(1/4), so L = 2.95 l.
"""

from __future__ import annotations

import numpy as np
from scipy.optimize import brentq

from ..physics.padstack import LayeredFoundation, PadLayer, plate_bending_stiffness

__all__ = ["pad_stack", "top_layer", "bending_length", "half_power_wave_number", "planarization_length_from_pad", "GAUSSIAN_HALF_POWER"]

#: q_half L of the Gaussian weighting: sqrt(4 pi ln 2).
GAUSSIAN_HALF_POWER = float(np.sqrt(4.0 * np.pi * np.log(2.0)))


def pad_stack(config) -> LayeredFoundation:
    """The layered pad stack of a :class:`cmpsim.Config` (top pad, then subpad if its thickness > 0)."""
    layers = [PadLayer(config.pad_thickness, config.pad_bulk_modulus, config.pad_poisson)]
    if config.subpad_thickness > 0:
        layers.append(PadLayer(config.subpad_thickness, config.subpad_modulus, config.subpad_poisson))
    return LayeredFoundation(tuple(layers))


def bending_length(stack: LayeredFoundation) -> float:
    """(D1 / k2)^(1/4) of the top pad on the subpad (m); the stack thickness for a single layer."""
    if len(stack.layers) == 1:
        return stack.layers[0].thickness
    top, sub = stack.layers
    return (plate_bending_stiffness(top.thickness, top.modulus, top.poisson) * sub.compliance) ** 0.25


def half_power_wave_number(stack: LayeredFoundation) -> float:
    """The wave number q (rad/m) at which C(q) = C(0) / 2 (found by Brent's method)."""
    c0 = float(stack.compliance(np.array([0.0]))[0])

    def excess(log_q):
        return float(stack.compliance(np.array([np.exp(log_q)]))[0]) / c0 - 0.5

    lo = np.log(1e-3 / bending_length(stack))
    hi = np.log(1e3 / bending_length(stack))
    if excess(hi) >= 0:
        raise ValueError("the pad stack never halves its compliance: its top layer's local compliance holds more than half of it")
    return float(np.exp(brentq(excess, lo, hi, xtol=1e-14, rtol=1e-14)))


def planarization_length_from_pad(config) -> float:
    """Planarization length (m) of the Gaussian weighting implied by the pad stack of ``config``."""
    return GAUSSIAN_HALF_POWER / half_power_wave_number(pad_stack(config))


def top_layer(config) -> LayeredFoundation:
    """The top pad alone, bonded to a rigid base: its C(q) is the pad body at the scale of a line array (:mod:`cmpsim.die.reach`)."""
    return LayeredFoundation((PadLayer(config.pad_thickness, config.pad_bulk_modulus, config.pad_poisson),))
