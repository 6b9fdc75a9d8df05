"""Per-window area and boundary length of a cell's merged shapes, through its hierarchy.

Each cell is handled once, in one of two ways:

* **flat** (a leaf, or a cell whose flattened shapes number at most ``flat_limit``): its
  shapes on the chosen layers are flattened by gdstk and merged by :func:`gdstk.boolean`
  tile by tile (the boolean is quadratic in the number of shapes; tiles keep it linear).
  The merged outline is kept as boundary segments (:mod:`.raster`), from which any
  orientation and grid offset is rasterised exactly.
* **composed** (everything else): the cell's raster is the sum of its children's rasters,
  each computed once per distinct (orientation, offset of the cell against the window
  grid) and pasted at every placement, plus its own shapes.  The sum is exact wherever
  at most one contributor is present: shapes from two contributors can only overlap or
  touch inside the intersection of their closed bounding boxes.  Every window that meets
  such an intersection ("zone") is recomputed from the merged geometry gathered from all
  contributors there: every shape that meets the closed window is gathered whole and
  merged (so that an edge on the window's border is judged with both sides known, and
  Green's theorem sees closed outlines).

References rotated by a multiple of 90 degrees (mirrored or not) with magnification 1 are
used as references; any other reference is flattened into its parent's own shapes by
gdstk (its vertices then lie on the merge's 1e-6 dbu grid, not the file's 1 dbu grid).  All lengths are in
database units.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import gdstk
import numpy as np

from .raster import Segments, net_segments, rasterise

__all__ = ["CellRasters"]

IDENTITY = (1, 0, 0, 1)
_TARGET_PER_TILE = 400  # shapes per boolean call: gdstk.boolean is quadratic in their number
MERGE_PRECISION = 1e-6  # dbu: where gdstk creates a vertex (oblique edges), it lands on this grid


def _orientation(rotation: float, x_reflection: bool, magnification: float):
    """The integer matrix of a GDS placement (mirror about x first, then rotate), or None."""
    if magnification != 1.0:
        return None
    quarter = rotation / (math.pi / 2)
    k = round(quarter)
    if abs(quarter - k) > 1e-9:
        return None
    c, s = [(1, 0), (0, 1), (-1, 0), (0, -1)][k % 4]
    r = (c, -s, s, c)
    if x_reflection:
        r = (r[0], -r[1], r[2], -r[3])
    return r


def _compose(m, n):
    """Matrix product m @ n of two (a, b, c, d) integer matrices."""
    return (m[0] * n[0] + m[1] * n[2], m[0] * n[1] + m[1] * n[3],
            m[2] * n[0] + m[3] * n[2], m[2] * n[1] + m[3] * n[3])


def _apply(m, pts: np.ndarray) -> np.ndarray:
    return np.stack([m[0] * pts[:, 0] + m[1] * pts[:, 1], m[2] * pts[:, 0] + m[3] * pts[:, 1]], axis=1)


def _box_apply(m, box):
    """Bounding box of a box (x0, y0, x1, y1) under matrix m."""
    corners = np.array([[box[0], box[1]], [box[2], box[1]], [box[0], box[3]], [box[2], box[3]]], float)
    p = _apply(m, corners)
    return (*p.min(axis=0), *p.max(axis=0))


def _inverse(m):
    det = m[0] * m[3] - m[1] * m[2]  # +-1
    return (m[3] * det, -m[1] * det, -m[2] * det, m[0] * det)


def placements(cell) -> list:
    """(child name, 2x2 matrix, (n, 2) translations in database units) of each reference of ``cell``
    at a multiple of 90 degrees (mirrored or not, magnification 1), arrays expanded; references at
    other angles or magnifications are left to the caller (they are flattened)."""
    out = []
    for ref in cell.references:
        if not isinstance(ref.cell, gdstk.Cell):
            continue
        m = _orientation(ref.rotation, ref.x_reflection, ref.magnification)
        if m is None:
            continue
        origin = np.round(np.asarray(ref.origin, float))
        if ref.repetition.size > 0:
            offsets = np.round(np.asarray(ref.repetition.get_offsets(), float)).reshape(-1, 2)
        else:
            offsets = np.zeros((1, 2))
        out.append((ref.cell.name, m, origin + offsets))
    return out


@dataclass(frozen=True)
class _Instances:
    """All placements of one child by one reference: orientation and (n, 2) translations."""

    child: str
    m: tuple
    t: np.ndarray


def ring_boxes(rings: list[np.ndarray]) -> np.ndarray:
    """(n, 4) bounding boxes (xmin, ymin, xmax, ymax) of vertex arrays."""
    if not rings:
        return np.zeros((0, 4))
    lengths = np.fromiter((len(r) for r in rings), dtype=np.int64, count=len(rings))
    pts = np.concatenate(rings)
    starts = np.concatenate([[0], np.cumsum(lengths)[:-1]])
    lo = np.minimum.reduceat(pts, starts, axis=0)
    hi = np.maximum.reduceat(pts, starts, axis=0)
    return np.concatenate([lo, hi], axis=1)


def merge_tiled(rings: list, tile: float | None = None) -> list[np.ndarray]:
    """Merge polygons (gdstk Polygons or vertex arrays, dbu) with gdstk, tile by tile.

    Returns the merged rings (vertex arrays).  Pieces of one merged shape that fall in
    different tiles meet along the tile's edge; :func:`.raster.net_segments` cancels
    those cuts.
    """
    if not rings:
        return []
    if isinstance(rings[0], gdstk.Polygon):
        bb = np.array([p.bounding_box() for p in rings], dtype=float).reshape(-1, 4)
    else:
        bb = ring_boxes(rings)
    x0, y0 = bb[:, 0].min(), bb[:, 1].min()
    x1, y1 = bb[:, 2].max(), bb[:, 3].max()
    if tile is None:
        tile = max(math.sqrt(max((x1 - x0) * (y1 - y0), 1.0) * _TARGET_PER_TILE / len(rings)), 1.0)
    nx = max(int(math.ceil((x1 - x0) / tile)), 1)
    ny = max(int(math.ceil((y1 - y0) / tile)), 1)
    if nx * ny == 1:
        return [p.points for p in gdstk.boolean(rings, [], "or", precision=MERGE_PRECISION)]
    i0 = np.clip(np.floor((bb[:, 0] - x0) / tile).astype(np.int64), 0, nx - 1)
    i1 = np.clip(np.floor((bb[:, 2] - x0) / tile).astype(np.int64), 0, nx - 1)
    j0 = np.clip(np.floor((bb[:, 1] - y0) / tile).astype(np.int64), 0, ny - 1)
    j1 = np.clip(np.floor((bb[:, 3] - y0) / tile).astype(np.int64), 0, ny - 1)
    # every (shape, tile) pair the shape's bounding box touches
    cx, cy = i1 - i0 + 1, j1 - j0 + 1
    cnt = cx * cy
    sid = np.repeat(np.arange(len(rings)), cnt)
    k = np.arange(cnt.sum()) - np.repeat(np.cumsum(cnt) - cnt, cnt)
    ti = np.repeat(i0, cnt) + k % np.repeat(cx, cnt)
    tj = np.repeat(j0, cnt) + k // np.repeat(cx, cnt)
    tid = tj * nx + ti
    order = np.argsort(tid, kind="stable")
    sid, tid = sid[order], tid[order]
    bounds = np.nonzero(np.diff(tid))[0] + 1
    out: list[np.ndarray] = []
    for group in np.split(np.arange(len(tid)), bounds):
        t = int(tid[group[0]])
        ti_, tj_ = t % nx, t // nx
        # tile edges at whole dbu; the last tile reaches past the shapes
        lx, ly = math.floor(x0 + ti_ * tile), math.floor(y0 + tj_ * tile)
        hx = math.floor(x0 + (ti_ + 1) * tile) if ti_ < nx - 1 else x1 + 1
        hy = math.floor(y0 + (tj_ + 1) * tile) if tj_ < ny - 1 else y1 + 1
        if ti_ == 0:
            lx = x0 - 1
        if tj_ == 0:
            ly = y0 - 1
        clip = gdstk.rectangle((lx, ly), (hx, hy))
        res = gdstk.boolean([rings[i] for i in sid[group]], clip, "and", precision=MERGE_PRECISION)
        out.extend(p.points for p in res)
    return out


def _coarsen(area, length, fx0, fy0, step, phase, window):
    """Window sums of a raster on the grid step * k (phase a multiple of step)."""
    r = window // step
    out = []
    lo = []
    for axis, (f0, p) in enumerate(((fx0, phase[0] // step), (fy0, phase[1] // step))):
        n = area.shape[1 - axis]
        k_lo = (f0 - p) // r
        k_hi = (f0 + n - 1 - p) // r
        lo.append((k_lo, k_hi - k_lo + 1, f0 - (p + k_lo * r)))
    (kx, nkx, offx), (ky, nky, offy) = lo
    for arr in (area, length):
        pad = np.zeros((nky * r, nkx * r))
        pad[offy:offy + arr.shape[0], offx:offx + arr.shape[1]] = arr
        out.append(pad.reshape(nky, r, nkx, r).sum(axis=(1, 3)))
    return out[0], out[1], int(kx), int(ky)


class CellRasters:
    """Window rasters of the merged shapes of cells of a gdstk library (dbu).

    ``layers`` is a collection of (layer, datatype) pairs whose shapes are merged
    together; ``window`` the window side (dbu, integer); ``flat_limit`` the number of
    flattened shapes up to which a cell with references is flattened rather than composed.
    """

    def __init__(self, library: gdstk.Library, layers, window: int, flat_limit: int = 200_000):
        self.cells = {c.name: c for c in library.cells if isinstance(c, gdstk.Cell)}
        self.layers = tuple(sorted(set(layers)))
        self.w = int(window)
        self.flat_limit = flat_limit
        self._count: dict[str, int] = {}
        self._bbox: dict[str, tuple | None] = {}
        self._flat: dict[str, bool] = {}
        self._segments: dict[str, Segments] = {}  # flat cells: all; composed: own shapes
        self._rings: dict[str, tuple[list, np.ndarray]] = {}  # merged rings and their boxes
        self._inst: dict[str, list[_Instances]] = {}
        self._zones: dict[str, np.ndarray] = {}
        self._memo: dict[tuple, tuple] = {}
        self.stats = {"flat_cells": 0, "composed_cells": 0, "rasters": 0, "zone_windows": 0}

    # -- what a cell holds --------------------------------------------------------
    def _own_rings(self, cell: gdstk.Cell) -> list[gdstk.Polygon]:
        """The cell's own shapes on the layers, plus those of references that are not a
        90-degree placement (flattened by gdstk; the merge puts them on a 1e-6 dbu grid)."""
        out = []
        for layer, dtype in self.layers:
            out.extend(cell.get_polygons(depth=0, layer=layer, datatype=dtype))
            for ref in cell.references:
                if isinstance(ref.cell, gdstk.Cell) and _orientation(
                        ref.rotation, ref.x_reflection, ref.magnification) is None:
                    out.extend(ref.get_polygons(layer=layer, datatype=dtype))
        return out

    def _references(self, name: str) -> list[_Instances]:
        if name in self._inst:
            return self._inst[name]
        out = [_Instances(child, m, translations) for child, m, translations in placements(self.cells[name])]
        self._inst[name] = out
        return out

    def count(self, name: str) -> int:
        """Number of shapes on the layers in the flattened cell."""
        if name not in self._count:
            cell = self.cells[name]
            n = sum(len(cell.get_polygons(depth=0, layer=l, datatype=d)) for l, d in self.layers)
            for ref in cell.references:
                if isinstance(ref.cell, gdstk.Cell):
                    reps = max(ref.repetition.size, 1)
                    n += reps * self.count(ref.cell.name)
            self._count[name] = n
        return self._count[name]

    def bbox(self, name: str):
        """Bounding box (dbu) of the cell's shapes on the layers, or None if it has none.

        Exact for flat cells; a superset (the union of the children's boxes) otherwise.
        """
        if name in self._bbox:
            return self._bbox[name]
        if self.is_flat(name):
            box = self._flat_segments(name).bbox
        else:
            boxes = []
            own = self._own_segments(name).bbox
            if own is not None:
                boxes.append(own)
            for inst in self._references(name):
                cb = self.bbox(inst.child)
                if cb is None:
                    continue
                b = _box_apply(inst.m, cb)
                boxes.append((b[0] + inst.t[:, 0].min(), b[1] + inst.t[:, 1].min(),
                              b[2] + inst.t[:, 0].max(), b[3] + inst.t[:, 1].max()))
            if boxes:
                arr = np.array(boxes)
                box = (*arr[:, :2].min(axis=0), *arr[:, 2:].max(axis=0))
            else:
                box = None
        self._bbox[name] = box
        return box

    def is_flat(self, name: str) -> bool:
        if name not in self._flat:
            has_refs = bool(self._references(name))
            self._flat[name] = (not has_refs) or self.count(name) <= self.flat_limit
            self.stats["flat_cells" if self._flat[name] else "composed_cells"] += 1
        return self._flat[name]

    def _flat_segments(self, name: str) -> Segments:
        if name not in self._segments:
            rings = []
            cell = self.cells[name]
            for layer, dtype in self.layers:
                rings.extend(cell.get_polygons(layer=layer, datatype=dtype))
            merged = merge_tiled(rings)
            self._store(name, merged)
        return self._segments[name]

    def _own_segments(self, name: str) -> Segments:
        if name not in self._segments:
            self._store(name, merge_tiled(self._own_rings(self.cells[name])))
        return self._segments[name]

    def _store(self, name: str, merged: list[np.ndarray]) -> None:
        self._segments[name] = net_segments(merged)
        boxes = ring_boxes(merged)
        self._rings[name] = (merged, boxes)

    # -- geometry in a box (for the zones) -----------------------------------------
    def query(self, name: str, box) -> list[np.ndarray]:
        """Shapes of the cell (cell frame, dbu) that may meet the closed ``box``; not merged."""
        if self.is_flat(name):
            self._flat_segments(name)
        else:
            self._own_segments(name)
        rings, boxes = self._rings[name]
        out = []
        if len(boxes):
            hit = np.nonzero((boxes[:, 0] <= box[2]) & (boxes[:, 2] >= box[0])
                             & (boxes[:, 1] <= box[3]) & (boxes[:, 3] >= box[1]))[0]
            out.extend(rings[i] for i in hit)
        if self.is_flat(name):
            return out
        for inst in self._references(name):
            cb = self.bbox(inst.child)
            if cb is None:
                continue
            b = _box_apply(inst.m, cb)
            hit = np.nonzero((inst.t[:, 0] + b[0] <= box[2]) & (inst.t[:, 0] + b[2] >= box[0])
                             & (inst.t[:, 1] + b[1] <= box[3]) & (inst.t[:, 1] + b[3] >= box[1]))[0]
            inv = _inverse(inst.m)
            for k in hit:
                t = inst.t[k]
                local = _box_apply(inv, (box[0] - t[0], box[1] - t[1], box[2] - t[0], box[3] - t[1]))
                for r in self.query(inst.child, local):
                    out.append(_apply(inst.m, r) + t)
        return out

    def zones(self, name: str) -> np.ndarray:
        """(k, 4) closed boxes (cell frame) where shapes of two contributors may meet."""
        if name in self._zones:
            return self._zones[name]
        boxes, owner = [], []
        _, own_boxes = self._rings[name] if name in self._rings else (None, np.zeros((0, 4)))
        if len(own_boxes):
            boxes.append(own_boxes)
            owner.append(np.full(len(own_boxes), -1))
        first = 0
        for inst in self._references(name):
            cb = self.bbox(inst.child)
            if cb is None:
                continue
            b = _box_apply(inst.m, cb)
            n = len(inst.t)
            boxes.append(np.stack([inst.t[:, 0] + b[0], inst.t[:, 1] + b[1],
                                   inst.t[:, 0] + b[2], inst.t[:, 1] + b[3]], axis=1))
            owner.append(first + np.arange(n))
            first += n
        if not boxes:
            self._zones[name] = np.zeros((0, 4))
            return self._zones[name]
        bx = np.concatenate(boxes)
        ow = np.concatenate(owner)
        order = np.argsort(bx[:, 0], kind="stable")
        bx, ow = bx[order], ow[order]
        hi = np.searchsorted(bx[:, 0], bx[:, 2], side="right")  # candidates i < j < hi
        cnt = np.maximum(hi - np.arange(len(bx)) - 1, 0)
        total = int(cnt.sum())
        if total > 20_000_000:
            raise MemoryError("too many overlapping placements to compose")
        i = np.repeat(np.arange(len(bx)), cnt)
        j = i + 1 + (np.arange(total) - np.repeat(np.cumsum(cnt) - cnt, cnt))
        keep = ((bx[i, 1] <= bx[j, 3]) & (bx[j, 1] <= bx[i, 3])
                & ~((ow[i] == -1) & (ow[j] == -1)))
        i, j = i[keep], j[keep]
        z = np.stack([np.maximum(bx[i, 0], bx[j, 0]), np.maximum(bx[i, 1], bx[j, 1]),
                      np.minimum(bx[i, 2], bx[j, 2]), np.minimum(bx[i, 3], bx[j, 3])], axis=1)
        self._zones[name] = z
        return z

    # -- rasters -------------------------------------------------------------------
    def raster(self, name: str, m=IDENTITY, phase=(0, 0)):
        """(area, length, ix0, iy0) of the cell under orientation ``m`` on the grid whose
        lines are ``phase + k * window`` (see :func:`.raster.rasterise`)."""
        key = (name, m, int(phase[0]), int(phase[1]))
        if key not in self._memo:
            if self.is_flat(name):
                seg = self._flat_segments(name).oriented(m)
                self._memo[key] = rasterise(seg, phase, self.w)
            else:
                self._memo[key] = self._composed(name, m, phase)
            self.stats["rasters"] += 1
        return self._memo[key]

    def _fine(self, name: str, m, step: int):
        key = ("fine", name, m, step)
        if key not in self._memo:
            seg = self._flat_segments(name).oriented(m)
            self._memo[key] = (*rasterise(seg, (0, 0), step), step)
            self.stats["rasters"] += 1
        return self._memo[key]

    def _extent(self, box, phase):
        w = self.w
        ix0 = int(math.floor((box[0] - phase[0]) / w)) - 1
        iy0 = int(math.floor((box[1] - phase[1]) / w)) - 1
        ix1 = int(math.floor((box[2] - phase[0]) / w)) + 1
        iy1 = int(math.floor((box[3] - phase[1]) / w)) + 1
        return ix0, iy0, ix1 - ix0 + 1, iy1 - iy0 + 1

    def _composed(self, name: str, m, phase):
        w = self.w
        box = self.bbox(name)
        if box is None:
            return np.zeros((0, 0)), np.zeros((0, 0)), 0, 0
        ix0, iy0, nx, ny = self._extent(_box_apply(m, box), phase)
        own = self._own_segments(name).oriented(m)
        area, length, _, _ = rasterise(own, phase, w, extent=(ix0, iy0, nx, ny))
        ph = np.array(phase, dtype=np.int64)
        for inst in self._references(name):
            if self.bbox(inst.child) is None:
                continue
            mc = _compose(m, inst.m)
            t = _apply(m, inst.t).astype(np.int64)
            cphase = np.mod(ph - t, w)
            shift = (cphase + t - ph) // w  # child window k is this grid's window k + shift
            groups, inverse = np.unique(cphase, axis=0, return_inverse=True)
            fine = None
            if len(groups) > 2 and self.is_flat(inst.child):
                # several offsets: one raster on the finest grid holding all their lines,
                # summed into windows per offset (exact: lengths on a fine line are halved
                # on both sides, and both halves land in the same window)
                step = math.gcd(w, *(int(v) for v in groups.ravel()))
                if w // step <= 64:
                    fine = self._fine(inst.child, mc, step)
            for g, cp in enumerate(groups):
                if fine is not None:
                    ca, cl, cx0, cy0 = _coarsen(*fine, (int(cp[0]), int(cp[1])), w)
                else:
                    ca, cl, cx0, cy0 = self.raster(inst.child, mc, (int(cp[0]), int(cp[1])))
                if ca.size == 0:
                    continue
                sel = shift[inverse.reshape(-1) == g]
                h, wd = ca.shape
                rows = (sel[:, 1] + cy0 - iy0)[:, None, None] + np.arange(h)[None, :, None]
                cols = (sel[:, 0] + cx0 - ix0)[:, None, None] + np.arange(wd)[None, None, :]
                rows, cols = np.broadcast_arrays(rows, cols)
                np.add.at(area, (rows, cols), np.broadcast_to(ca, rows.shape))
                np.add.at(length, (rows, cols), np.broadcast_to(cl, rows.shape))
        self._fix_zones(name, m, phase, area, length, ix0, iy0)
        return area, length, ix0, iy0

    def _fix_zones(self, name, m, phase, area, length, ix0, iy0):
        """Recompute, from the merged shapes, every window that meets a zone."""
        z = self.zones(name)
        if len(z) == 0:
            return
        w = self.w
        ny, nx = area.shape
        zb = np.array([_box_apply(m, b) for b in z])
        # windows k whose closed box [p + k w, p + (k + 1) w] meets the closed zone [a, b]
        kx0 = np.ceil((zb[:, 0] - phase[0]) / w).astype(np.int64) - 1 - ix0
        kx1 = np.floor((zb[:, 2] - phase[0]) / w).astype(np.int64) - ix0
        ky0 = np.ceil((zb[:, 1] - phase[1]) / w).astype(np.int64) - 1 - iy0
        ky1 = np.floor((zb[:, 3] - phase[1]) / w).astype(np.int64) - iy0
        diff = np.zeros((ny + 1, nx + 1), dtype=np.int64)
        np.add.at(diff, (np.clip(ky0, 0, ny), np.clip(kx0, 0, nx)), 1)
        np.add.at(diff, (np.clip(ky1 + 1, 0, ny), np.clip(kx0, 0, nx)), -1)
        np.add.at(diff, (np.clip(ky0, 0, ny), np.clip(kx1 + 1, 0, nx)), -1)
        np.add.at(diff, (np.clip(ky1 + 1, 0, ny), np.clip(kx1 + 1, 0, nx)), 1)
        mask = np.cumsum(np.cumsum(diff, axis=0), axis=1)[:ny, :nx] > 0
        if not mask.any():
            return
        self.stats["zone_windows"] += int(mask.sum())
        inv = _inverse(m)
        block = 16  # windows per side of one recomputed block
        rows, cols = np.nonzero(mask)
        for bj, bi in sorted(set(zip((rows // block).tolist(), (cols // block).tolist()))):
            r0, c0 = bj * block, bi * block
            sub = mask[r0:r0 + block, c0:c0 + block]
            rr, cc = np.nonzero(sub)
            # every shape meeting the block's masked windows (closed, one dbu beyond):
            # merged whole, their outlines give the exact fields of those windows
            lo_x = phase[0] + (ix0 + c0 + cc.min()) * w - 1
            hi_x = phase[0] + (ix0 + c0 + cc.max() + 1) * w + 1
            lo_y = phase[1] + (iy0 + r0 + rr.min()) * w - 1
            hi_y = phase[1] + (iy0 + r0 + rr.max() + 1) * w + 1
            local = _box_apply(inv, (lo_x, lo_y, hi_x, hi_y))
            shapes = [_apply(m, r) for r in self.query(name, local)]
            seg = net_segments(merge_tiled(shapes))
            ext = (ix0 + c0, iy0 + r0, sub.shape[1], sub.shape[0])
            a2, l2, _, _ = rasterise(seg, phase, w, extent=ext)
            area[r0:r0 + sub.shape[0], c0:c0 + sub.shape[1]][sub] = a2[sub]
            length[r0:r0 + sub.shape[0], c0:c0 + sub.shape[1]][sub] = l2[sub]
