"""Exact per-window area and boundary length of merged polygons, from their edges.

The polygons come from :func:`gdstk.boolean` (merged, possibly cut into tiles and with
holes joined to their outline by zero-width slits).  Nothing here clips a polygon: the
area of the shapes inside a window is the Green's-theorem integral of their outline
(``-sum of (clamp(y) - y0) dx`` over the edges, counter-clockwise), and the boundary
length is the length of the outline's segments inside the window.

Coordinates are in database units (dbu), float64: integers for the layout's own vertices
(exact below 2**53), multiples of the merge precision (1e-6 dbu) where gdstk had to
create a vertex (an oblique edge cut by a tile or crossing another).  Two outline pieces
that run along the same line in opposite directions cancel: the slits of a polygon with
holes, and the cut between two tiles of one merged shape, are not boundary.  A boundary segment that lies exactly on a window edge counts half in each of
the two windows it separates (so that the per-window lengths add up to the total).

All functions here work in dbu; the caller converts to metres.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

__all__ = ["Segments", "net_segments", "rasterise"]


@dataclass(frozen=True)
class Segments:
    """Boundary segments of a merged polygon set, material on their left (dbu).

    ``a`` and ``b`` are (n, 2) float arrays of integer-valued start and end points; the
    outline runs from ``a`` to ``b`` with the shapes on its left (counter-clockwise).
    ``bbox`` is (xmin, ymin, xmax, ymax) or None when there is no segment.
    """

    a: np.ndarray
    b: np.ndarray

    @property
    def bbox(self):
        if len(self.a) == 0:
            return None
        pts = np.concatenate([self.a, self.b])
        return (*pts.min(axis=0), *pts.max(axis=0))

    def oriented(self, m: tuple[int, int, int, int]) -> "Segments":
        """The segments under the integer matrix ``m`` = (a, b, c, d): x' = a x + b y, y' = c x + d y.

        A mirroring matrix (negative determinant) turns counter-clockwise outlines
        clockwise, so the segments are reversed to keep the material on their left.
        """
        if tuple(m) == (1, 0, 0, 1):
            return self

        def apply(p):
            return np.stack([m[0] * p[:, 0] + m[1] * p[:, 1], m[2] * p[:, 0] + m[3] * p[:, 1]], axis=1)

        a, b = apply(self.a), apply(self.b)
        if m[0] * m[3] - m[1] * m[2] < 0:
            a, b = b, a
        return Segments(a, b)

    @staticmethod
    def empty() -> "Segments":
        return Segments(np.zeros((0, 2)), np.zeros((0, 2)))

    @staticmethod
    def concat(parts: list["Segments"]) -> "Segments":
        parts = [p for p in parts if len(p.a)]
        if not parts:
            return Segments.empty()
        return Segments(np.concatenate([p.a for p in parts]), np.concatenate([p.b for p in parts]))


def _rings_to_edges(rings: list[np.ndarray]) -> tuple[np.ndarray, np.ndarray]:
    """Edges (start, end) of closed rings, each ring made counter-clockwise."""
    rings = [r for r in rings if len(r) >= 3]
    if not rings:
        return np.zeros((0, 2)), np.zeros((0, 2))
    lengths = np.array([len(r) for r in rings])
    p = np.concatenate(rings).astype(float)
    starts = np.concatenate([[0], np.cumsum(lengths)[:-1]])
    nxt = np.arange(len(p)) + 1
    nxt[starts + lengths - 1] = starts  # close every ring
    q = p[nxt]
    # twice the signed area of each ring (shoelace); clockwise rings are reversed
    cross = p[:, 0] * q[:, 1] - q[:, 0] * p[:, 1]
    twice_area = np.add.reduceat(cross, starts)
    flip = np.repeat(twice_area < 0, lengths)
    a = np.where(flip[:, None], q, p)
    b = np.where(flip[:, None], p, q)
    keep = np.any(a != b, axis=1)
    return a[keep], b[keep]


def _cancel_axis(a: np.ndarray, b: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Axis-parallel edges: signed multiplicity accumulated along each exact line."""
    horiz = a[:, 1] == b[:, 1]
    fam = np.where(horiz, 0, 1)
    coord = np.where(horiz, a[:, 1], a[:, 0])
    ta = np.where(horiz, a[:, 0], a[:, 1])
    tb = np.where(horiz, b[:, 0], b[:, 1])
    sign = np.where(tb > ta, 1, -1)
    lo, hi = np.minimum(ta, tb), np.maximum(ta, tb)
    fam2 = np.concatenate([fam, fam])
    c2 = np.concatenate([coord, coord])
    t2 = np.concatenate([lo, hi])
    d2 = np.concatenate([sign, -sign])
    order = np.lexsort((t2, c2, fam2))
    fam2, c2, t2, d2 = fam2[order], c2[order], t2[order], d2[order]
    net = np.cumsum(d2)  # every line's events sum to zero, so the running sum restarts
    live = (fam2[:-1] == fam2[1:]) & (c2[:-1] == c2[1:]) & (net[:-1] != 0) & (t2[1:] > t2[:-1])
    k = np.nonzero(live)[0]
    mult, f, c, t0, t1 = net[k], fam2[k], c2[k], t2[k], t2[k + 1]
    back = mult < 0
    s0, s1 = np.where(back, t1, t0), np.where(back, t0, t1)
    start = np.where((f == 0)[:, None], np.stack([s0, c], 1), np.stack([c, s0], 1))
    end = np.where((f == 0)[:, None], np.stack([s1, c], 1), np.stack([c, s1], 1))
    reps = np.abs(mult)
    return np.repeat(start, reps, axis=0), np.repeat(end, reps, axis=0)


def _cancel_reverse(a: np.ndarray, b: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Oblique edges: an edge and its exact reverse cancel (the only way two outline
    pieces of merged, axis-tiled shapes can coincide off the axes)."""
    swap = (a[:, 0] > b[:, 0]) | ((a[:, 0] == b[:, 0]) & (a[:, 1] > b[:, 1]))
    lo = np.where(swap[:, None], b, a)
    hi = np.where(swap[:, None], a, b)
    key = np.concatenate([lo, hi], axis=1)
    uniq, inv = np.unique(key, axis=0, return_inverse=True)
    net = np.rint(np.bincount(inv.reshape(-1), weights=np.where(swap, -1.0, 1.0), minlength=len(uniq))).astype(np.int64)
    reps = np.abs(net)
    start = np.where((net < 0)[:, None], uniq[:, 2:], uniq[:, :2])
    end = np.where((net < 0)[:, None], uniq[:, :2], uniq[:, 2:])
    return np.repeat(start, reps, axis=0), np.repeat(end, reps, axis=0)


def net_segments(rings: list[np.ndarray]) -> Segments:
    """The boundary of a set of merged polygons, with coincident opposite edges cancelled.

    ``rings`` are (k, 2) vertex arrays in dbu, the output of :func:`gdstk.boolean`
    (merged; tiled along axis-parallel cuts; holes joined by axis-parallel slits).  Along
    every axis-parallel line the signed multiplicity of the edges is accumulated and the
    stretches where it is not zero are the boundary (slits and tile cuts cancel); an
    oblique edge cancels against its exact reverse.  The result runs counter-clockwise
    (material on the left).
    """
    a, b = _rings_to_edges(rings)
    if len(a) == 0:
        return Segments.empty()
    axis = (a[:, 0] == b[:, 0]) | (a[:, 1] == b[:, 1])
    sa, sb = _cancel_axis(a[axis], b[axis])
    if np.any(~axis):
        oa, ob = _cancel_reverse(a[~axis], b[~axis])
        sa, sb = np.concatenate([sa, oa]), np.concatenate([sb, ob])
    return Segments(sa, sb)


def _crossings(lo: np.ndarray, hi: np.ndarray, origin: float, w: float) -> tuple[np.ndarray, np.ndarray]:
    """For intervals (lo, hi), the grid lines origin + k w strictly inside: (interval index, line)."""
    k0 = np.floor((lo - origin) / w) + 1
    k1 = np.ceil((hi - origin) / w) - 1
    cnt = np.maximum(k1 - k0 + 1, 0).astype(np.int64)
    idx = np.repeat(np.arange(len(lo)), cnt)
    first = np.repeat(np.cumsum(cnt) - cnt, cnt)
    k = np.repeat(k0, cnt) + (np.arange(cnt.sum()) - first)
    return idx, origin + k * w


def rasterise(seg: Segments, origin: tuple[float, float], window: float, extent=None):
    """Area and boundary length of the shapes per window of a square grid (dbu).

    The grid's lines are ``origin + k * window``.  Returns ``(area, length, ix0, iy0)``:
    (ny, nx) arrays whose element [j, i] belongs to the window with lower-left corner
    ``origin + ((ix0 + i) * window, (iy0 + j) * window)``.  ``extent`` = (ix0, iy0, nx, ny)
    fixes the arrays' range (windows outside it are dropped); by default it covers the
    segments plus one window on every side.
    """
    ox, oy = origin
    w = float(window)
    a, b = seg.a, seg.b
    if extent is None:
        if len(a) == 0:
            return np.zeros((0, 0)), np.zeros((0, 0)), 0, 0
        pts = np.concatenate([a, b])
        lo = np.floor((pts.min(axis=0) - (ox, oy)) / w).astype(np.int64) - 1
        hi = np.floor((pts.max(axis=0) - (ox, oy)) / w).astype(np.int64) + 1
        ix0, iy0 = int(lo[0]), int(lo[1])
        nx, ny = int(hi[0] - lo[0] + 1), int(hi[1] - lo[1] + 1)
    else:
        ix0, iy0, nx, ny = extent
    area = np.zeros((ny, nx))
    below = np.zeros((ny + 1, nx))  # below[r + 1] holds what every row <= r receives in full
    length = np.zeros((ny, nx))
    if len(a) == 0:
        return area, length, ix0, iy0
    # split every segment where it crosses a grid line (parameter s in (0, 1))
    dx, dy = b[:, 0] - a[:, 0], b[:, 1] - a[:, 1]
    i1, xl = _crossings(np.minimum(a[:, 0], b[:, 0]), np.maximum(a[:, 0], b[:, 0]), ox, w)
    i2, yl = _crossings(np.minimum(a[:, 1], b[:, 1]), np.maximum(a[:, 1], b[:, 1]), oy, w)
    s1 = (xl - a[i1, 0]) / dx[i1]
    s2 = (yl - a[i2, 1]) / dy[i2]
    n = len(a)
    idx = np.concatenate([np.arange(n), np.arange(n), i1, i2])
    s = np.concatenate([np.zeros(n), np.ones(n), s1, s2])
    order = np.lexsort((s, idx))
    idx, s = idx[order], s[order]
    ok = (idx[:-1] == idx[1:]) & (s[1:] > s[:-1])
    j = np.nonzero(ok)[0]
    e = idx[j]
    sa, sb = s[j], s[j + 1]
    # exact ends where the piece starts or stops at the segment's own vertices
    pa = a[e] + sa[:, None] * (b[e] - a[e])
    pb = a[e] + sb[:, None] * (b[e] - a[e])
    pa = np.where((sa == 0)[:, None], a[e], pa)
    pb = np.where((sb == 1)[:, None], b[e], pb)
    mx = 0.5 * (pa[:, 0] + pb[:, 0])
    my = 0.5 * (pa[:, 1] + pb[:, 1])
    fx = (mx - ox) / w
    fy = (my - oy) / w
    col = np.floor(fx).astype(np.int64) - ix0
    row = np.floor(fy).astype(np.int64) - iy0
    seglen = np.hypot(pb[:, 0] - pa[:, 0], pb[:, 1] - pa[:, 1])
    # boundary length; a piece on a grid line is shared half and half
    on_v = (pa[:, 0] == pb[:, 0]) & (fx == np.floor(fx))
    on_h = (pa[:, 1] == pb[:, 1]) & (fy == np.floor(fy))
    half = np.where(on_v | on_h, 0.5, 1.0)
    _deposit(length, row, col, seglen * half)
    _deposit(length, row - on_h, col - on_v, seglen * 0.5 * (on_v | on_h))
    # area: -dx * (y - y_row) in the piece's row, -dx * window in every row below
    dxp = pb[:, 0] - pa[:, 0]
    live = dxp != 0
    row_l, col_l, dxl, myl = row[live], col[live], dxp[live], my[live]
    y_row = oy + (row_l + iy0) * w
    _deposit(area, row_l, col_l, -dxl * (myl - y_row))
    r_below = np.clip(row_l, 0, ny)  # rows under the grid are dropped, above it all count
    inside = (col_l >= 0) & (col_l < nx)
    np.add.at(below, (r_below[inside], col_l[inside]), -dxl[inside] * w)
    area += np.cumsum(below[::-1], axis=0)[::-1][1:]
    return area, length, ix0, iy0


def _deposit(arr: np.ndarray, row: np.ndarray, col: np.ndarray, val: np.ndarray) -> None:
    ny, nx = arr.shape
    ok = (row >= 0) & (row < ny) & (col >= 0) & (col < nx) & (val != 0)
    if np.any(ok):
        flat = np.bincount(row[ok] * nx + col[ok], weights=val[ok], minlength=nx * ny)
        arr += flat.reshape(ny, nx)
