"""Exact area and boundary length of merged shapes in the cells of a grid, from their outline.

KLayout merges the shapes (:mod:`.blocks`); what it cannot do is rasterise one cell's outline
on a *non-uniform* grid, which is what lets a block placed at many offsets against the
window grid be rasterised once for all of them (:func:`rasterise_lines`: the grid's lines
are the union of every offset's window lines).  Nothing here clips a polygon: the area of
the shapes inside a grid cell is the Green's-theorem integral of their outline (``-sum of
(clamp(y) - y0) dx`` over the edges, material on the left), the boundary length the length
of the outline inside the cell.  A boundary piece lying exactly on a grid line counts half
in each of the two cells it separates, so the per-cell lengths add up to the total, and a
window made of several grid cells gets its half-and-half share only on its own edges.

Coordinates are database units (dbu), float64 holding integers (exact below 2**53).
Two outline pieces that run along the same axis-parallel line in opposite directions cancel
(:func:`cancel_axis`): two blocks whose outlines touch along a seam.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

__all__ = ["Segments", "cancel_axis", "rasterise_lines", "window_lines"]


@dataclass(frozen=True)
class Segments:
    """Boundary segments of a merged shape set, material on their left (dbu).

    ``a`` and ``b`` are (n, 2) float arrays of start and end points.
    """

    a: np.ndarray
    b: np.ndarray

    def __len__(self) -> int:
        return len(self.a)

    @property
    def bbox(self):
        if len(self.a) == 0:
            return None
        pts = np.concatenate([self.a, self.b])
        return (*pts.min(axis=0), *pts.max(axis=0))

    def transformed(self, m: tuple[int, int, int, int], t=(0, 0)) -> "Segments":
        """The segments under x' = m x + t, ``m`` = (a, b, c, d) an integer matrix of
        determinant +-1.  A mirror turns the outline's sense, so the segments are reversed to
        keep the material on their left."""
        def apply(p):
            return np.stack([m[0] * p[:, 0] + m[1] * p[:, 1] + t[0], m[2] * p[:, 0] + m[3] * p[:, 1] + t[1]], axis=1)

        if tuple(m) == (1, 0, 0, 1) and t[0] == 0 and t[1] == 0:
            return self
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


def cancel_axis(seg: Segments) -> Segments:
    """The axis-parallel segments with coincident opposite pieces cancelled.

    Along every exact horizontal or vertical line the signed multiplicity of the segments is
    accumulated; the stretches where it is not zero are kept (with their multiplicity).
    Oblique segments are returned unchanged.
    """
    a, b = seg.a, seg.b
    if len(a) == 0:
        return seg
    axis = (a[:, 0] == b[:, 0]) | (a[:, 1] == b[:, 1])
    oa, ob = a[~axis], b[~axis]
    a, b = a[axis], b[axis]
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
    net = np.cumsum(d2)  # every line's events sum to zero, so the running sum restarts on each line
    live = (fam2[:-1] == fam2[1:]) & (c2[:-1] == c2[1:]) & (net[:-1] != 0) & (t2[1:] > t2[:-1])
    k = np.nonzero(live)[0]
    mult, f, c, t0, t1 = net[k], fam2[k], c2[k], t2[k], t2[k + 1]
    back = mult < 0
    s0, s1 = np.where(back, t1, t0), np.where(back, t0, t1)
    start = np.where((f == 0)[:, None], np.stack([s0, c], 1), np.stack([c, s0], 1))
    end = np.where((f == 0)[:, None], np.stack([s1, c], 1), np.stack([c, s1], 1))
    reps = np.abs(mult)
    return Segments(np.concatenate([np.repeat(start, reps, axis=0), oa]), np.concatenate([np.repeat(end, reps, axis=0), ob]))


def window_lines(phases, window: int, lo: float, hi: float) -> np.ndarray:
    """Sorted distinct grid lines ``phase + k * window`` for every phase, covering [lo, hi]
    with one window to spare on each side (dbu)."""
    phases = np.unique(np.mod(np.asarray(phases, dtype=np.int64), window))
    k0 = int(np.floor((lo - window) / window)) - 1
    k1 = int(np.ceil((hi + window) / window)) + 1
    ks = np.arange(k0, k1 + 1, dtype=np.int64)
    return np.unique((phases[:, None] + ks[None, :] * window).ravel()).astype(float)


def _crossings(lo: np.ndarray, hi: np.ndarray, lines: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """For intervals (lo, hi), the grid lines strictly inside: (interval index, line)."""
    k0 = np.searchsorted(lines, lo, side="right")
    k1 = np.searchsorted(lines, hi, side="left")
    cnt = np.maximum(k1 - k0, 0)
    idx = np.repeat(np.arange(len(lo)), cnt)
    first = np.repeat(np.cumsum(cnt) - cnt, cnt)
    k = np.repeat(k0, cnt) + (np.arange(int(cnt.sum())) - first)
    return idx, lines[k]


def rasterise_lines(seg: Segments, xs: np.ndarray, ys: np.ndarray, *, area: bool = True):
    """Area and boundary length of the shapes in every cell of the grid of lines ``xs``, ``ys``.

    ``xs`` and ``ys`` are sorted, distinct line coordinates (dbu); cell [j, i] is
    [xs[i], xs[i+1]] x [ys[j], ys[j+1]].  Returns ``(area, length)``, arrays of shape
    (len(ys) - 1, len(xs) - 1) (dbu^2, dbu); ``area=False`` skips the area (it is then None).
    The shapes must lie inside the grid's x range (area of shapes below the grid's lowest
    line is dropped; above its highest line it is counted in full, as the integral says).
    """
    xs = np.asarray(xs, dtype=float)
    ys = np.asarray(ys, dtype=float)
    nx, ny = len(xs) - 1, len(ys) - 1
    length = np.zeros((ny, nx))
    out_area = np.zeros((ny, nx)) if area else None
    a, b = seg.a, seg.b
    if len(a) == 0:
        return out_area, length
    i1, xl = _crossings(np.minimum(a[:, 0], b[:, 0]), np.maximum(a[:, 0], b[:, 0]), xs)
    i2, yl = _crossings(np.minimum(a[:, 1], b[:, 1]), np.maximum(a[:, 1], b[:, 1]), ys)
    dx, dy = b[:, 0] - a[:, 0], b[:, 1] - a[:, 1]
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
    pa = a[e] + sa[:, None] * (b[e] - a[e])
    pb = a[e] + sb[:, None] * (b[e] - a[e])
    pa = np.where((sa == 0)[:, None], a[e], pa)
    pb = np.where((sb == 1)[:, None], b[e], pb)
    # exact coordinates where a piece ends on a grid line (the division may round)
    mx = 0.5 * (pa[:, 0] + pb[:, 0])
    my = 0.5 * (pa[:, 1] + pb[:, 1])
    col = np.searchsorted(xs, mx, side="right") - 1
    row = np.searchsorted(ys, my, side="right") - 1
    seglen = np.hypot(pb[:, 0] - pa[:, 0], pb[:, 1] - pa[:, 1])
    # a piece on a grid line is shared half and half with the cell on its other side
    on_v = (pa[:, 0] == pb[:, 0]) & (col >= 0) & (col < len(xs)) & (xs[np.clip(col, 0, nx)] == mx)
    on_h = (pa[:, 1] == pb[:, 1]) & (row >= 0) & (row < len(ys)) & (ys[np.clip(row, 0, ny)] == my)
    shared = on_v | on_h
    _deposit(length, row, col, seglen * np.where(shared, 0.5, 1.0))
    _deposit(length, row - on_h, col - on_v, seglen * 0.5 * shared)
    if not area:
        return None, length
    # area: -dx * (y - y_row) in the piece's row, -dx * (row height) in every row below
    dxp = pb[:, 0] - pa[:, 0]
    live = (dxp != 0) & (col >= 0) & (col < nx)
    row_l, col_l, dxl, myl = row[live], col[live], dxp[live], my[live]
    inrow = (row_l >= 0) & (row_l < ny)
    _deposit(out_area, row_l[inrow], col_l[inrow], -dxl[inrow] * (myl[inrow] - ys[row_l[inrow]]))
    below = np.zeros((ny + 1, nx))  # below[r + 1]: what every row <= r receives in full (times its height)
    r_below = np.clip(row_l, 0, ny)
    np.add.at(below, (r_below, col_l), -dxl)
    heights = np.diff(ys)
    out_area += np.cumsum(below[::-1], axis=0)[::-1][1:] * heights[:, None]
    return out_area, length


def _deposit(arr: np.ndarray, row: np.ndarray, col: np.ndarray, val: np.ndarray) -> None:
    ny, nx = arr.shape
    ok = (row >= 0) & (row < ny) & (col >= 0) & (col < nx) & (val != 0)
    if np.any(ok):
        flat = np.bincount(row[ok] * nx + col[ok], weights=val[ok], minlength=nx * ny)
        arr += flat.reshape(ny, nx)
