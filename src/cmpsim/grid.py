"""Cell-centred polar finite-volume grid on the wafer disk.

The disk of radius R_w is cut into ``n_r`` rings of width dr = R_w / n_r and ``n_theta``
sectors of width dtheta = 2 pi / n_theta. Cell (i, j) has its centre at
r_i = (i + 1/2) dr, theta_j = (j + 1/2) dtheta; the outer faces of the last ring lie exactly
on the wafer edge, so the boundary is represented without a staircase. The innermost ring's
cells are wedges whose inner face has zero length. Unknowns are numbered k = i n_theta + j.
"""

from __future__ import annotations

from dataclasses import dataclass
from functools import cached_property

import numpy as np

__all__ = ["PolarGrid", "FaceOperators", "face_operators"]


@dataclass(frozen=True)
class PolarGrid:
    """Polar grid on a disk of ``radius`` (m) with ``n_r`` rings and ``n_theta`` sectors.

    ``n_theta`` must be even (the cell across the centre is a neighbour of the first ring)
    and >= 8; ``n_r`` >= 3.
    """

    radius: float
    n_r: int
    n_theta: int

    def __post_init__(self) -> None:
        if not (np.isfinite(self.radius) and self.radius > 0):
            raise ValueError(f"radius must be > 0 m; got {self.radius!r}")
        if int(self.n_r) != self.n_r or self.n_r < 3:
            raise ValueError(f"n_r must be an integer >= 3; got {self.n_r!r}")
        if int(self.n_theta) != self.n_theta or self.n_theta < 8 or self.n_theta % 2:
            raise ValueError(f"n_theta must be an even integer >= 8; got {self.n_theta!r}")

    @property
    def dr(self) -> float:
        """Ring width, m."""
        return self.radius / self.n_r

    @property
    def dtheta(self) -> float:
        """Sector angle, rad."""
        return 2.0 * np.pi / self.n_theta

    @property
    def size(self) -> int:
        """Number of cells (unknowns)."""
        return self.n_r * self.n_theta

    @cached_property
    def r(self) -> np.ndarray:
        """Cell-centre radii r_i, m, shape (n_r, 1)."""
        return ((np.arange(self.n_r) + 0.5) * self.dr)[:, None]

    @cached_property
    def theta(self) -> np.ndarray:
        """Cell-centre angles theta_j, rad, shape (1, n_theta)."""
        return ((np.arange(self.n_theta) + 0.5) * self.dtheta)[None, :]

    @cached_property
    def centres(self) -> tuple[np.ndarray, np.ndarray]:
        """Cartesian cell centres (x, y), m, each of shape (n_r, n_theta)."""
        return self.r * np.cos(self.theta), self.r * np.sin(self.theta)

    @cached_property
    def area(self) -> np.ndarray:
        """Exact cell areas r_i dr dtheta, m^2, shape (n_r, n_theta); they sum to pi R^2."""
        return np.broadcast_to(self.r * self.dr * self.dtheta, (self.n_r, self.n_theta)).copy()

    @cached_property
    def radial_faces(self) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """Outer radial faces of each cell: (x, y, length) at r_{i+1/2} = (i+1) dr, theta_j."""
        rf = ((np.arange(self.n_r) + 1.0) * self.dr)[:, None]
        x = rf * np.cos(self.theta)
        y = rf * np.sin(self.theta)
        return x, y, np.broadcast_to(rf * self.dtheta, x.shape).copy()

    @cached_property
    def angular_faces(self) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """Counter-clockwise angular faces of each cell: (x, y, length) at r_i, theta_{j+1/2}."""
        tf = (np.arange(self.n_theta) + 1.0)[None, :] * self.dtheta
        x = self.r * np.cos(tf)
        y = self.r * np.sin(tf)
        return x, y, np.full(x.shape, self.dr)

    def rim(self, per_sector: int = 4) -> tuple[np.ndarray, np.ndarray]:
        """Points (x, y) on the rim of the disk, ``per_sector`` per sector, m.

        The film of a tilted, domed wafer is extreme on its rim, outside every cell centre.
        """
        t = np.linspace(0.0, 2.0 * np.pi, per_sector * self.n_theta, endpoint=False)
        return self.radius * np.cos(t), self.radius * np.sin(t)

    def integrate(self, field) -> float:
        """Midpoint-rule integral of a cell field over the disk (second order), field unit x m^2."""
        return float(np.sum(np.asarray(field) * self.area))

    @cached_property
    def radial_derivative_stencil(self):
        """Two-term stencil of d(phi)/dr at every cell centre, for phi = 0 on the edge.

        Returns ``((cols_a, w_a), (cols_b, w_b))``, arrays of shape (n_r, n_theta): central
        differences inside; across the centre for the first ring (the neighbour is the cell
        at theta + pi); on the last ring the quadratic through r_{i-1}, r_i and the edge
        value 0 at r_i + dr/2.
        """
        n_r, n_t, dr = self.n_r, self.n_theta, self.dr
        i = np.arange(n_r)[:, None] * np.ones((1, n_t), dtype=int)
        j = np.arange(n_t)[None, :] * np.ones((n_r, 1), dtype=int)
        ca = self.index(np.minimum(i + 1, n_r - 1), j)
        wa = np.full(i.shape, 0.5 / dr)
        cb = np.where(i == 0, self.index(0, j + n_t // 2), self.index(np.maximum(i - 1, 0), j))
        wb = np.full(i.shape, -0.5 / dr)
        last = i == n_r - 1
        ca = np.where(last, self.index(i, j), ca)
        wa = np.where(last, -1.0 / dr, wa)
        wb = np.where(last, -1.0 / (3.0 * dr), wb)
        return (ca, wa), (cb, wb)

    def gradient(self, field, edge_value: float = 0.0):
        """Cartesian gradient (d/dx, d/dy) at the cell centres of a cell field, unit/m.

        ``edge_value`` is the field's value on the wafer edge (second order everywhere).
        """
        f = np.asarray(field, dtype=float) - edge_value
        flat = f.ravel()
        (ca, wa), (cb, wb) = self.radial_derivative_stencil
        d_r = flat[ca] * wa + flat[cb] * wb
        d_t = (np.roll(f, -1, axis=1) - np.roll(f, 1, axis=1)) / (2.0 * self.dtheta * self.r)
        c, s = np.cos(self.theta), np.sin(self.theta)
        return c * d_r - s * d_t, s * d_r + c * d_t

    def interpolate(self, field, x, y, edge_value: float | None = None) -> np.ndarray:
        """A cell field at points (x, y) (m) on the disk, bilinear in (r, theta).

        The centre takes the mean of the first ring and the rim ``edge_value``, or, when it is
        None, the linear extrapolation 1.5 f_last - 0.5 f_previous over the last half ring:
        second order for a smooth field. Points beyond the rim are extrapolated likewise.
        """
        x, y = np.broadcast_arrays(np.asarray(x, dtype=float), np.asarray(y, dtype=float))
        if edge_value is None:
            return (self.interpolation_matrix(x.ravel(), y.ravel()) @ np.asarray(field, dtype=float).ravel()).reshape(x.shape)
        m, rim = self.interpolation_matrix(x.ravel(), y.ravel(), rim_separate=True)
        return (m @ np.asarray(field, dtype=float).ravel() + rim * float(edge_value)).reshape(x.shape)

    def interpolation_matrix(self, x, y, rim_separate: bool = False):
        """Sparse matrix (points x cells) of :meth:`interpolate` at the points (x, y), m.

        With ``rim_separate`` the rim nodes are not extrapolated from the cells: returns the
        matrix and, per point, the weight of the rim value (for a given edge value).
        """
        import scipy.sparse as sp

        x = np.asarray(x, dtype=float).ravel()
        y = np.asarray(y, dtype=float).ravel()
        n_r, n_t, dr, dth = self.n_r, self.n_theta, self.dr, self.dtheta
        r_nodes = np.concatenate([[0.0], (np.arange(n_r) + 0.5) * dr, [self.radius]])
        r = np.hypot(x, y)
        s = np.mod(np.arctan2(y, x), 2.0 * np.pi) / dth - 0.5  # fractional sector index
        j0 = np.floor(s).astype(int)
        t = s - j0
        k = np.clip(np.searchsorted(r_nodes, r, side="right") - 1, 0, n_r)
        a = (r - r_nodes[k]) / (r_nodes[k + 1] - r_nodes[k])
        ja, jb = np.mod(j0, n_t), np.mod(j0 + 1, n_t)
        rows, cols, vals = [], [], []
        rim = np.zeros(x.size)
        point = np.arange(x.size)
        # node (ring index kk in 0..n_r+1 of the radial nodes, sector j) with weight wgt
        for kk, wk in ((k, 1.0 - a), (k + 1, a)):
            for jj, wj in ((ja, 1.0 - t), (jb, t)):
                wgt = wk * wj
                centre = kk == 0
                ring = (kk >= 1) & (kk <= n_r)
                edge = kk == n_r + 1
                if np.any(centre):  # mean of the first ring
                    p = np.repeat(point[centre], n_t)
                    rows.append(p)
                    cols.append(np.tile(np.arange(n_t), int(centre.sum())))
                    vals.append(np.repeat(wgt[centre] / n_t, n_t))
                rows.append(point[ring])
                cols.append((kk[ring] - 1) * n_t + jj[ring])
                vals.append(wgt[ring])
                if rim_separate:
                    rim[edge] += wgt[edge]
                else:  # 1.5 f_last - 0.5 f_previous
                    for ring_index, c in ((n_r - 1, 1.5), (n_r - 2, -0.5)):
                        rows.append(point[edge])
                        cols.append(ring_index * n_t + jj[edge])
                        vals.append(c * wgt[edge])
        m = sp.csr_matrix((np.concatenate(vals), (np.concatenate(rows), np.concatenate(cols))), shape=(x.size, self.size))
        return (m, rim) if rim_separate else m

    def index(self, i, j) -> np.ndarray:
        """Linear unknown index of cell (i, j), with j taken modulo n_theta."""
        return np.asarray(i) * self.n_theta + np.mod(j, self.n_theta)


@dataclass(frozen=True)
class FaceOperators:
    """Cell -> face interpolation and face -> cell divergence of the polar grid (sparse)."""

    interp_radial: sp.csr_matrix  # radial faces x cells
    interp_angular: sp.csr_matrix  # angular faces x cells
    div_radial: sp.csr_matrix  # cells x radial faces: +1 for the cell inside, -1 outside
    div_angular: sp.csr_matrix  # cells x angular faces: +1 clockwise cell, -1 counter-clockwise
    ring_parity: np.ndarray  # (n_r, n_theta) ring index % 2
    sector_parity: np.ndarray  # (n_r, n_theta) sector index % 2


_OPERATORS: dict = {}


def face_operators(grid: PolarGrid) -> FaceOperators:
    """The :class:`FaceOperators` of a grid (built once per grid and cached).

    Radial face (i, j) is the outer face of cell (i, j); the film on it is the mean of the two
    cells beside it, extrapolated over the last half ring at the rim. Angular face (i, j) is the
    counter-clockwise face of cell (i, j), shared with (i, j + 1).
    """
    import scipy.sparse as sp

    ops = _OPERATORS.get(grid)
    if ops is not None:
        return ops
    n_r, n_t, n = grid.n_r, grid.n_theta, grid.size
    i = np.repeat(np.arange(n_r), n_t)
    j = np.tile(np.arange(n_t), n_r)
    f = np.arange(n)
    inner = i < n_r - 1
    P = grid.index(i, j)
    # radial face (i, j) is the outer face of cell (i, j)
    out = grid.index(np.minimum(i + 1, n_r - 1), j)
    prev = grid.index(np.maximum(i - 1, 0), j)
    rows = np.concatenate([f, f])
    cols = np.concatenate([P, np.where(inner, out, prev)])
    vals = np.concatenate([np.where(inner, 0.5, 1.5), np.where(inner, 0.5, -0.5)])
    interp_r = sp.csr_matrix((vals, (rows, cols)), shape=(n, n))
    div_r = sp.csr_matrix(
        (np.concatenate([np.ones(n), -np.ones(inner.sum())]), (np.concatenate([P, out[inner]]), np.concatenate([f, f[inner]]))),
        shape=(n, n),
    )
    # angular face (i, j) is the counter-clockwise face of cell (i, j), shared with (i, j + 1)
    ccw = grid.index(i, j + 1)
    interp_a = sp.csr_matrix((np.full(2 * n, 0.5), (np.concatenate([f, f]), np.concatenate([P, ccw]))), shape=(n, n))
    div_a = sp.csr_matrix((np.concatenate([np.ones(n), -np.ones(n)]), (np.concatenate([P, ccw]), np.concatenate([f, f]))), shape=(n, n))
    ops = FaceOperators(
        interp_r, interp_a, div_r, div_a, (i % 2).reshape(n_r, n_t), (j % 2).reshape(n_r, n_t)
    )
    if len(_OPERATORS) > 16:
        _OPERATORS.clear()
    _OPERATORS[grid] = ops
    return ops
