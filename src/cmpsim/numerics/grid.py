"""Cell-centred polar finite-volume grid on the wafer disk.

The disk of radius R_w is cut into ``n_r`` rings and ``n_theta`` sectors of width
dtheta = 2 pi / n_theta. The rings are either equally wide (dr = R_w / n_r) or graded towards
the wafer edge (:func:`graded_ring_faces`: a smooth map of equally spaced ring indices, rim
rings ``edge_ratio`` times narrower than the central ones; ``docs/model.md``, "Grid"). Cell
(i, j) has its centre at the middle r_i = (r_{i-1/2} + r_{i+1/2}) / 2 of its ring,
theta_j = (j + 1/2) dtheta; the outer faces of the last ring lie exactly on the wafer edge,
so the boundary is represented without a staircase. The innermost ring's cells are wedges
whose inner face has zero length. Unknowns are numbered k = i n_theta + j.
"""

from __future__ import annotations

from dataclasses import dataclass
from functools import cached_property

import numpy as np

__all__ = ["PolarGrid", "FaceOperators", "face_operators", "graded_ring_faces", "ring_count", "edge_graded_grid", "GRID_PRESETS", "GRID_EDGE"]

#: Named grids: central rings x sectors of the polar finite-volume grid (see docs/model.md,
#: "Grid"); with ``grid_grading = "uniform"`` (the paper preset) the rings x sectors of equal rings.
GRID_PRESETS = {"coarse": (8, 24), "default": (24, 64), "fine": (48, 128)}
#: Edge grading of the named grids (``grid_grading = "edge"``): (width of the rim ring, m;
#: growth of the ring width inwards per ring). Each preset halves the next finer one's rings
#: everywhere, so all share one ring map on a given wafer, and the rim ring has the same width
#: on every wafer: one preset, one accuracy at the edge (``docs/model.md``, "Grid").
GRID_EDGE = {"coarse": (0.9e-3, 0.45), "default": (0.3e-3, 0.15), "fine": (0.15e-3, 0.075)}

#: Points of the table from which the graded ring map is inverted (its error, ~1e-9 R_w, is
#: far below any ring width; the same table serves every refinement of a map).
_MAP_POINTS = 4001


def _spacing_map(radius: float, edge_ratio: float, edge_length: float):
    """(r, xi): the normalised ring index xi(r) in [0, 1] of a graded map on a table of radii r, m.

    The local ring width is proportional to Delta(d) = 1/s + (1 - 1/s) tanh(d / l) of the
    distance d = R_w - r from the rim (s = ``edge_ratio``, l = ``edge_length``): 1/s of the
    central width at the rim, growing smoothly (at the rate (1 - 1/s) / l) towards it inside.
    xi = int_0^r dr'/Delta / int_0^R dr'/Delta.
    """
    d = np.linspace(radius, 0.0, _MAP_POINTS)  # distance from the rim, centre first
    r = radius - d
    inv = 1.0 / (1.0 / edge_ratio + (1.0 - 1.0 / edge_ratio) * np.tanh(d / edge_length))
    xi = np.concatenate([[0.0], np.cumsum(0.5 * (inv[1:] + inv[:-1]) * np.diff(r))])
    return r, xi


def graded_ring_faces(radius: float, n_r: int, edge_ratio: float, edge_length: float) -> np.ndarray:
    """Radii of the ring faces 0 = r_{-1/2} < ... < r_{n_r - 1/2} = R_w of a graded grid, m.

    Ring k spans the equal steps k / n_r <= xi <= (k + 1) / n_r of the map of
    :func:`_spacing_map`: its width follows Delta(R_w - r) times a constant, so the rim rings
    are ``edge_ratio`` times narrower than the central ones and neighbouring widths differ by
    O(1 / n_r): a refinement (2 n_r) halves every ring of the same map, which keeps the
    finite volumes second order (``tests/test_grid.py``). ``edge_ratio = 1`` gives equal rings.
    """
    if edge_ratio == 1.0:
        return np.arange(n_r + 1) * (radius / n_r)
    r, xi = _spacing_map(radius, edge_ratio, edge_length)
    faces = np.interp(np.arange(n_r + 1) / n_r, xi / xi[-1], r)
    faces[0], faces[-1] = 0.0, radius
    return faces


def ring_count(radius: float, centre_rings: float, edge_width: float, growth: float) -> tuple[int, float, float]:
    """Rings of an edge-graded grid: ``(n_r, edge_ratio, edge_length)`` (edge_length in m).

    The central rings are R_w / ``centre_rings`` wide, the rim ring about ``edge_width`` (m),
    neighbouring widths grow inwards by about the factor 1 + ``growth``; so edge_ratio =
    max(1, R_w / (centre_rings edge_width)), edge_length = (R_w / centre_rings - edge_width) / growth,
    and n_r = the number of rings these widths take, rounded up.
    """
    centre = radius / centre_rings
    ratio = max(1.0, centre / edge_width)
    if ratio == 1.0:
        return int(centre_rings), 1.0, 0.0
    length = (centre - edge_width) / growth
    _, xi = _spacing_map(radius, ratio, length)
    return int(np.ceil(xi[-1] / centre - 1e-9)), ratio, length


def edge_graded_grid(radius: float, centre_rings: float, n_theta: int, edge_width: float, growth: float) -> "PolarGrid":
    """The :class:`PolarGrid` of :func:`ring_count` (radius, edge_width in m)."""
    n_r, ratio, length = ring_count(radius, centre_rings, edge_width, growth)
    return PolarGrid(radius, n_r, n_theta, ratio, length)


@dataclass(frozen=True)
class PolarGrid:
    """Polar grid on a disk of ``radius`` (m) with ``n_r`` rings and ``n_theta`` sectors.

    ``n_theta`` must be even (the cell across the centre is a neighbour of the first ring)
    and >= 8; ``n_r`` >= 3. ``edge_ratio`` (>= 1) is how many times narrower the rim rings
    are than the central ones, ``edge_length`` (m) the distance from the rim over which
    they widen (:func:`graded_ring_faces`); ``edge_ratio = 1``: equal rings.
    """

    radius: float
    n_r: int
    n_theta: int
    edge_ratio: float = 1.0
    edge_length: float = 0.0

    def __post_init__(self) -> None:
        if not (np.isfinite(self.radius) and self.radius > 0):
            raise ValueError(f"radius must be > 0 m; got {self.radius!r}")
        if int(self.n_r) != self.n_r or self.n_r < 3:
            raise ValueError(f"n_r must be an integer >= 3; got {self.n_r!r}")
        if int(self.n_theta) != self.n_theta or self.n_theta < 8 or self.n_theta % 2:
            raise ValueError(f"n_theta must be an even integer >= 8; got {self.n_theta!r}")
        if not (np.isfinite(self.edge_ratio) and self.edge_ratio >= 1.0):
            raise ValueError(f"edge_ratio must be >= 1; got {self.edge_ratio!r}")
        if self.edge_ratio > 1.0 and not (np.isfinite(self.edge_length) and self.edge_length > 0):
            raise ValueError(f"edge_length must be > 0 m for a graded grid (edge_ratio > 1); got {self.edge_length!r}")

    @property
    def graded(self) -> bool:
        """Whether the rings are graded towards the edge (else equally wide)."""
        return self.edge_ratio > 1.0

    @cached_property
    def ring_faces(self) -> np.ndarray:
        """Radii of the ring faces, 0, ..., R_w (n_r + 1 values), m."""
        return graded_ring_faces(self.radius, self.n_r, self.edge_ratio, self.edge_length)

    @cached_property
    def widths(self) -> np.ndarray:
        """Ring widths r_{i+1/2} - r_{i-1/2}, m, shape (n_r, 1)."""
        if not self.graded:
            return np.full((self.n_r, 1), self.dr)
        return np.diff(self.ring_faces)[:, None]

    @cached_property
    def spacings(self) -> np.ndarray:
        """Distance from each centre to the next one outwards (the last: to the rim), m, shape (n_r, 1)."""
        r = self.r[:, 0]
        return np.diff(np.concatenate([r, [self.radius]]))[:, None]

    @property
    def dr(self) -> float:
        """Mean ring width R_w / n_r, m (the ring width of a uniform grid; see :attr:`widths`)."""
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
        """Cell-centre radii r_i (ring middles), m, shape (n_r, 1)."""
        if not self.graded:
            return ((np.arange(self.n_r) + 0.5) * self.dr)[:, None]
        f = self.ring_faces
        return (0.5 * (f[1:] + f[:-1]))[:, None]

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
        """Exact cell areas r_i (r_{i+1/2} - r_{i-1/2}) dtheta, m^2, shape (n_r, n_theta); they sum to pi R^2."""
        return np.broadcast_to(self.r * self.widths * self.dtheta, (self.n_r, self.n_theta)).copy()

    @cached_property
    def radial_faces(self) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """Outer radial faces of each cell: (x, y, length) at r_{i+1/2}, theta_j."""
        rf = self.ring_faces[1:, None]
        x = rf * np.cos(self.theta)
        y = rf * np.sin(self.theta)
        return x, y, np.broadcast_to(rf * self.dtheta, x.shape).copy()

    @cached_property
    def angular_faces(self) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """Counter-clockwise angular faces of each cell: (x, y, length) at r_i, theta_{j+1/2}."""
        tf = (np.arange(self.n_theta) + 1.0)[None, :] * self.dtheta
        x = self.r * np.cos(tf)
        y = self.r * np.sin(tf)
        return x, y, np.broadcast_to(self.widths, x.shape).copy()

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
        """Three-term stencil of d(phi)/dr at every cell centre, for phi = 0 on the edge.

        Returns ``((cols_out, w_out), (cols_self, w_self), (cols_in, w_in))``, arrays of shape
        (n_r, n_theta): the derivative at r_i of the quadratic through the centres r_{i-1},
        r_i, r_{i+1} (second order on any ring widths; the central difference on equal rings);
        across the centre for the first ring (the neighbour is the cell at theta + pi, at
        -r_0); on the last ring through r_{i-1}, r_i and the edge value 0 at R_w.
        """
        n_r, n_t = self.n_r, self.n_theta
        r = self.r[:, 0]
        x_in = np.concatenate([[-r[0]], r[:-1]])
        x_out = np.concatenate([r[1:], [self.radius]])
        hb, ha = (r - x_in)[:, None], (x_out - r)[:, None]
        w_out = np.broadcast_to(hb / (ha * (ha + hb)), (n_r, n_t)).copy()
        w_self = np.broadcast_to((ha - hb) / (ha * hb), (n_r, n_t)).copy()
        w_in = np.broadcast_to(-ha / (hb * (ha + hb)), (n_r, n_t)).copy()
        if not self.graded:  # equal rings: exactly the central difference inside
            w_self[:-1] = 0.0
        i = np.arange(n_r)[:, None] * np.ones((1, n_t), dtype=int)
        j = np.arange(n_t)[None, :] * np.ones((n_r, 1), dtype=int)
        c_self = self.index(i, j)
        c_out = self.index(np.minimum(i + 1, n_r - 1), j)
        c_in = np.where(i == 0, self.index(0, j + n_t // 2), self.index(np.maximum(i - 1, 0), j))
        w_out[-1] = 0.0  # the edge value 0 carries no unknown
        return (c_out, w_out), (c_self, w_self), (c_in, w_in)

    @cached_property
    def radial_face_weights(self) -> tuple[np.ndarray, np.ndarray]:
        """Weights (w_own, w_other), shape (n_r, 1), of the linear interpolation of a cell field to
        the outer radial face of each ring: f(r_{i+1/2}) = w_own f_i + w_other f_{i+1} inside,
        and, for the last ring, the linear extrapolation to the rim from f_{n_r-1} and f_{n_r-2}
        (``w_other`` then weighs f_{n_r-2}). Equal rings: 1/2, 1/2 and 3/2, -1/2."""
        r, f = self.r[:, 0], self.ring_faces[1:]
        t = np.empty(self.n_r)
        t[:-1] = (f[:-1] - r[:-1]) / (r[1:] - r[:-1])  # share of the step to the next centre
        t[-1] = -(self.radius - r[-1]) / (r[-1] - r[-2])  # extrapolation beyond r_{n_r-1}
        if not self.graded:
            t[:-1], t[-1] = 0.5, -0.5
        return (1.0 - t)[:, None], t[:, None]

    def gradient(self, field, edge_value: float = 0.0):
        """Cartesian gradient (d/dx, d/dy) at the cell centres of a cell field, unit/m.

        ``edge_value`` is the field's value on the wafer edge (second order everywhere).
        """
        f = np.asarray(field, dtype=float) - edge_value
        flat = f.ravel()
        d_r = sum(flat[c] * w for c, w in self.radial_derivative_stencil)
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
        n_r, n_t, dth = self.n_r, self.n_theta, self.dtheta
        r_nodes = np.concatenate([[0.0], self.r[:, 0], [self.radius]])
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

    Radial face (i, j) is the outer face of cell (i, j); the film on it is interpolated linearly
    in r between the two cells beside it (their mean on equal rings), extrapolated over the last
    half ring at the rim (:attr:`PolarGrid.radial_face_weights`). Angular face (i, j) is the
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
    own, other = grid.radial_face_weights  # linear in r between the centres (1/2, 1/2 on equal rings)
    vals = np.concatenate([own[i, 0], other[i, 0]])
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
