"""Within-wafer uniformity: rotation-averaged profiles of a polar field, WIWNU and range.

Pure kernels (numpy only) on the cell-centred polar grid of :mod:`cmpsim.numerics.grid`: ring i
covers r_{i-1/2} <= r <= r_{i+1/2} (equally wide rings, or rings graded towards the edge)
and its cells are centred on the circle of radius r_i = (r_{i-1/2} + r_{i+1/2}) / 2 at the
equally spaced angles theta_j = (j + 1/2) dtheta.

The wafer turns under the stationary (carrier-frame) pressure field, so a point of the wafer
at radius r sees, over one turn, every angle of the circle r: what it loses is the angular
mean of the fixed-frame removal-rate map along that circle. On the grid this is the mean of
the ring's cell values (the periodic midpoint rule: exact for a trigonometric polynomial in
theta of degree below n_theta). The profile is the piecewise-constant function equal to that
mean on each ring, so its area integral is the grid's midpoint-rule integral of the map.

Within-wafer non-uniformity (WIWNU) is the area-weighted standard deviation over the mean of
that profile inside radius <= R_w - edge_exclusion (the 1-sigma / mean of CMP practice with a
metrology edge exclusion; see docs/model.md, "Within-wafer uniformity"); a ring cut by the
exclusion circle counts with the area of its part inside.
"""

from __future__ import annotations

import numpy as np

__all__ = ["ring_mean", "ring_edges", "ring_areas_inside", "weighted_std_over_mean", "weighted_range", "uniformity"]


def ring_mean(field) -> np.ndarray:
    """Rotation average of a polar cell field of shape (n_r, n_theta): the mean of each ring, shape (n_r,)."""
    f = np.asarray(field, dtype=float)
    if f.ndim != 2:
        raise ValueError(f"a polar field has shape (n_r, n_theta); got {f.shape}")
    return f.mean(axis=1)


def ring_edges(radius: float, n_r: int) -> np.ndarray:
    """Radii of the ring faces, 0, dr, ..., R_w (n_r + 1 values), m."""
    return np.linspace(0.0, radius, n_r + 1)


def ring_areas_inside(edges, limit: float) -> np.ndarray:
    """Area of each ring [edges[i], edges[i+1]] inside the disk r <= limit, m^2."""
    e = np.clip(np.asarray(edges, dtype=float), 0.0, max(float(limit), 0.0))
    return np.pi * (e[1:] ** 2 - e[:-1] ** 2)


def weighted_std_over_mean(values, weights) -> float:
    """Weighted standard deviation / weighted mean (population std; NaN if the mean is 0)."""
    v = np.asarray(values, dtype=float)
    w = np.asarray(weights, dtype=float)
    total = w.sum()
    if not total > 0:
        raise ValueError("no weight: the region is empty")
    mean = float(np.sum(w * v) / total)
    if mean == 0.0:
        return float("nan")
    std = float(np.sqrt(np.sum(w * (v - mean) ** 2) / total))
    return std / abs(mean)


def weighted_range(values, weights) -> float:
    """max - min of the values with a positive weight."""
    v = np.asarray(values, dtype=float)[np.asarray(weights) > 0]
    if v.size == 0:
        raise ValueError("no weight: the region is empty")
    return float(v.max() - v.min())


def uniformity(profile, radius: float, edge_exclusion: float, edges=None) -> tuple[float, float]:
    """(WIWNU, range) of a ring profile on a disk of ``radius`` with an ``edge_exclusion`` (m).

    ``profile`` holds the ring means (:func:`ring_mean`) of the rings between ``edges`` (the
    n_r + 1 face radii, m; default: equally wide rings). WIWNU is the area-weighted
    std / mean, the range max - min, both over r <= radius - edge_exclusion.
    """
    p = np.asarray(profile, dtype=float)
    limit = radius - edge_exclusion
    if not (0.0 <= edge_exclusion < radius):
        raise ValueError(f"edge_exclusion = {edge_exclusion:g} m leaves no wafer: valid range [0, {radius:g}) m (the wafer radius)")
    w = ring_areas_inside(ring_edges(radius, p.size) if edges is None else edges, limit)
    return weighted_std_over_mean(p, w), weighted_range(p, w)
