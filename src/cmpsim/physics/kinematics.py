"""Surface velocities of pad and wafer on a rotary polisher.

Frame: origin at the wafer centre, fixed to the carrier (not rotating with the wafer), x
along the relative sliding velocity at the wafer centre, z from the pad towards the wafer.
The pad (angular speed Omega_p) turns about its centre at (0, e); the wafer (Omega_w) turns
about the origin; both turn counter-clockwise seen from the wafer, as on common polishers.

    u_pad(x, y)   = Omega_p (e - y, x)
    u_wafer(x, y) = Omega_w (-y, x)

so the relative velocity u_pad - u_wafer = ((Omega_p - Omega_w)(-y) + Omega_p e, (Omega_p - Omega_w) x)
is uniform, Omega e along x, when the two speeds are equal (the paper's single "relative
rotation speed"). The mean velocity (u_pad + u_wafer)/2 is then a rotation about the
midpoint between the centres, not uniform. ``kinematics="sliding"`` replaces both by the
paper's 1-D idealisation: the pad translates at U = Omega_p e in x under a wafer that does
not move.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

__all__ = ["Kinematics", "KINEMATICS", "head_sweep_nodes"]

KINEMATICS = ("rotating", "sliding")


@dataclass(frozen=True)
class Kinematics:
    """Rigid-body motion of pad and wafer.

    Attributes
    ----------
    pad_speed, wafer_speed : float
        Angular speeds Omega_p, Omega_w of pad and wafer, rad/s (> 0).
    centre_distance : float
        Distance e between the pad centre and the wafer centre, m (> 0).
    mode : {"rotating", "sliding"}
        Full rigid rotations, or uniform translation of the pad (see module docstring).
    """

    pad_speed: float
    wafer_speed: float
    centre_distance: float
    mode: str = "rotating"

    def __post_init__(self) -> None:
        for name, unit in (("pad_speed", "rad/s"), ("wafer_speed", "rad/s"), ("centre_distance", "m")):
            v = getattr(self, name)
            if not (np.isfinite(v) and v > 0):
                raise ValueError(f"{name} must be finite and > 0 {unit} (valid range: (0, inf)); got {v!r}")
        if self.mode not in KINEMATICS:
            raise ValueError(f"kinematics must be one of {KINEMATICS}; got {self.mode!r}")

    @property
    def sliding_speed(self) -> float:
        """Relative sliding speed at the wafer centre U = Omega_p e, m/s."""
        return self.pad_speed * self.centre_distance

    def velocities(self, x, y):
        """Pad and wafer surface velocities at (x, y) (m), each as a pair of arrays (m/s).

        Returns ``(upx, upy, uwx, uwy)``.
        """
        x = np.asarray(x, dtype=float)
        y = np.asarray(y, dtype=float)
        if self.mode == "sliding":
            z = np.zeros(np.broadcast(x, y).shape)
            return z + self.sliding_speed, z.copy(), z.copy(), z.copy()
        wp, ww, e = self.pad_speed, self.wafer_speed, self.centre_distance
        return wp * (e - y), wp * x, -ww * y, ww * x

    def mean_and_relative(self, x, y):
        """Mean velocity (u_pad + u_wafer)/2 and relative velocity u_pad - u_wafer, m/s.

        Returns ``(umx, umy, dux, duy)``.
        """
        upx, upy, uwx, uwy = self.velocities(x, y)
        return 0.5 * (upx + uwx), 0.5 * (upy + uwy), upx - uwx, upy - uwy


def head_sweep_nodes(centre_distance: float, amplitude: float, n: int):
    """Centre distances and weights that average a quantity over one cycle of the head's sweep.

    The head oscillates across the pad, e(t) = e_0 + A sin(2 pi t / T): the time average over a
    cycle of a quantity f(e) that follows the head quasi-statically is

        (1/T) int_0^T f(e(t)) dt = (1/pi) int_0^pi f(e_0 + A cos phi) dphi,

    the integral of f against the arcsine (Chebyshev) density of the time spent at each e. The
    n-point Gauss-Chebyshev rule of the first kind gives it with nodes
    e_k = e_0 + A cos((2k - 1) pi / (2n)) and equal weights 1/n, exact for f a polynomial in e of
    degree below 2n (Abramowitz & Stegun 25.4.38).

    Parameters
    ----------
    centre_distance : float
        Mean pad-centre to wafer-centre distance e_0, m (> 0).
    amplitude : float
        Sweep amplitude A, m (0 <= A < e_0: the wafer centre never crosses the pad centre).
    n : int
        Number of nodes (>= 1).

    Returns
    -------
    distances : numpy.ndarray
        e_k, m, from the outermost to the innermost.
    weights : numpy.ndarray
        1/n each (they sum to 1).
    """
    if not (np.isfinite(centre_distance) and centre_distance > 0):
        raise ValueError(f"centre_distance must be finite and > 0 m (valid range: (0, inf)); got {centre_distance!r}")
    if not (np.isfinite(amplitude) and 0 <= amplitude < centre_distance):
        raise ValueError(
            f"amplitude must be in [0, centre_distance) = [0, {centre_distance:g}) m (the wafer centre may not cross "
            f"the pad centre); got {amplitude!r}"
        )
    if int(n) != n or n < 1:
        raise ValueError(f"nodes must be an integer >= 1; got {n!r}")
    n = int(n)
    k = np.arange(1, n + 1)
    return centre_distance + amplitude * np.cos((2 * k - 1) * np.pi / (2 * n)), np.full(n, 1.0 / n)
