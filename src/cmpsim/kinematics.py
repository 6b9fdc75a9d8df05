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

__all__ = ["Kinematics", "KINEMATICS"]

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
