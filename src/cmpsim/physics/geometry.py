"""Film thickness of a domed (convex), tilted wafer over a flat pad (paper eq. 30).

The wafer face is a spherical cap of radius R_c through the wafer rim, bulging a dome
height delta_d towards the pad at its centre. ``h0`` is the height above the pad mean plane
of the centre of the rim chord (the point about which the wafer tilts); the wafer centre O
then sits at about h0 - delta_d. A positive attack angle theta lowers the +x side (the
trailing side for a pad moving in +x relative to the wafer) and so makes the film converge
along the sliding direction; the cross tilt beta does the same along +y.

Eq. 30 as printed, ``h0 + a - sqrt(B)`` with ``a ~ R_c`` (about 145 m for a 5 um dome on a
3-inch wafer), loses about 3e-14 m to cancellation. Both functions here use the
algebraically equal form ``h0 + (a^2 - B) / (a + sqrt(B))`` in which ``a^2 - B`` is formed
without subtracting large numbers.
"""

from __future__ import annotations

import numpy as np

__all__ = ["curvature_radius", "film_thickness_1d", "film_thickness", "check_geometry"]


def check_geometry(dome_height: float, wafer_radius: float) -> None:
    """Raise ValueError unless 0 <= dome_height < wafer_radius and wafer_radius > 0 (m)."""
    if not (np.isfinite(wafer_radius) and wafer_radius > 0):
        raise ValueError(f"wafer_radius must be finite and > 0 m (valid range: (0, inf)); got {wafer_radius!r}")
    if not (np.isfinite(dome_height) and 0 <= dome_height < wafer_radius):
        raise ValueError(
            f"dome_height must be in [0, wafer_radius) m (convex wafers; 0 = flat); got {dome_height!r}"
        )


def curvature_radius(dome_height: float, wafer_radius: float) -> float:
    """Radius of curvature R_c of the wafer face from its dome height and radius, m.

    Sagitta relation R_c = (R_w^2 + delta_d^2) / (2 delta_d); infinite for a flat wafer.
    """
    check_geometry(dome_height, wafer_radius)
    if dome_height == 0:
        return np.inf
    return (wafer_radius**2 + dome_height**2) / (2.0 * dome_height)


def film_thickness_1d(x, h0, attack_angle, dome_height, wafer_radius):
    """Film thickness along the sliding direction through the wafer centre, eq. 30, m.

    h(x) = h0 + (R_c - delta_d) cos(theta) - sqrt([(R_c - delta_d) cos(theta) + x sin(theta)]^2 + R_w^2 - x^2),
    evaluated in the cancellation-free form. ``x`` in m (|x| <= R_w), ``h0`` in m, the
    attack angle theta in rad, ``dome_height`` delta_d and ``wafer_radius`` R_w in m.
    """
    check_geometry(dome_height, wafer_radius)
    x = np.asarray(x, dtype=float)
    th = np.asarray(attack_angle, dtype=float)
    if dome_height == 0:
        return h0 - x * np.tan(th)
    rc = curvature_radius(dome_height, wafer_radius)
    a = (rc - dome_height) * np.cos(th)
    st = np.sin(th)
    num = x * x * np.cos(th) ** 2 - wafer_radius**2 - 2.0 * a * x * st  # = a^2 - B
    b = (a + x * st) ** 2 + wafer_radius**2 - x * x
    return h0 + num / (a + np.sqrt(b))


def film_thickness(x, y, h0, attack_angle, dome_height, wafer_radius, cross_tilt=0.0):
    """Film thickness over the 2-D wafer disk (eq. 30 generalised to a spherical cap), m.

    The cap of radius R_c is rotated rigidly about the centre of its rim chord, at height
    h0, so that its axis has direction (sin theta, sin beta, sqrt(1 - sin^2 theta -
    sin^2 beta)). On y = 0 with beta = 0 it agrees with :func:`film_thickness_1d` to
    O(theta^2 x) (the printed eq. 30 is not an exact rotation), and exactly at theta = 0.

    Parameters
    ----------
    x, y : array_like
        Position on the wafer relative to its centre, m; x along the sliding direction.
    h0 : float or array_like
        Height of the rim-chord centre above the pad mean plane, m.
    attack_angle : float
        theta, rad (tilt about the y axis; positive = film converging towards +x).
    dome_height, wafer_radius : float
        delta_d and R_w, m.
    cross_tilt : float
        beta, rad (tilt about the x axis; positive = film converging towards +y).
    """
    check_geometry(dome_height, wafer_radius)
    x = np.asarray(x, dtype=float)
    y = np.asarray(y, dtype=float)
    nx, ny = np.sin(attack_angle), np.sin(cross_tilt)
    tilt = nx * nx + ny * ny
    if not np.all(tilt < 1.0):  # NaN too: no wafer axis for these angles
        raise ValueError(
            f"attack_angle and cross_tilt must satisfy sin^2 + sin^2 < 1 (a wafer axis); got {attack_angle!r} rad and {cross_tilt!r} rad"
        )
    nz = np.sqrt(1.0 - tilt)
    if dome_height == 0:
        return h0 - (nx * x + ny * y) / nz
    rc = curvature_radius(dome_height, wafer_radius)
    arm = rc - dome_height
    a = arm * nz
    num = x * x + y * y - wafer_radius**2 - 2.0 * arm * (nx * x + ny * y)  # = a^2 - B
    return h0 + num / (a + np.sqrt(a * a - num))
