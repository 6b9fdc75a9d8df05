"""Per-window area and boundary length of a die's merged shapes: blocks, placements, seams, zones.

The steps (docs/layouts.md, "The engine"):

1. :func:`.hierarchy.plan` splits the die into blocks placed in its frame.
2. Each block is merged once by KLayout's deep mode (:func:`.blocks.merged_region`).  A block
   whose placements all sit at one offset against the window grid is rasterised by KLayout
   (:func:`.blocks.grid_rasters`); one placed at several offsets has its outline read out
   once and integrated exactly on the union of every offset's window lines
   (:func:`.segments.rasterise_lines`), then summed into windows per offset.  Every
   placement adds its block's windows to the die's.
3. Seams: where two placed blocks' boxes only touch, the areas add exactly; outline pieces of
   both that coincide along the seam are not boundary of the union and are taken out
   (:func:`.segments.cancel_axis`).
4. Zones: where two placed blocks' boxes overlap with positive area their shapes may
   overlap; every window meeting such an overlap is recomputed from all the shapes there,
   merged flat by KLayout.  When zones would cover most of the die, the die is merged flat
   whole instead (KLayout's deep mode; the result is the same).

All lengths are database units (integers); the caller converts.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Callable

import klayout.db as kdb
import numpy as np

from .blocks import COORD_LIMIT, Block, grid_rasters, merged_region
from .hierarchy import BIG, BlockKey, Plan, block_box, overlap_zones, placed_boxes, plan
from .segments import Segments, cancel_axis, rasterise_lines, window_lines

__all__ = ["WindowGrid", "window_rasters", "Progress"]

#: A callable told (stage, done, total) as the extraction goes on.
Progress = Callable[[str, int, int], None]

#: Sub-cells of one non-uniform rasterisation (area and length, float64: 16 bytes each).
MAX_SUBCELLS = 20_000_000
#: Zone windows recomputed per flat merge (a tile of TILE x TILE windows).
TILE = 8
#: Above this fraction of the die's windows in zones, the die is merged flat whole.
FLAT_FRACTION = 0.5


@dataclass(frozen=True)
class WindowGrid:
    """A square grid of windows in the die's frame (dbu): window [j, i] is
    [ox + i w, ox + (i+1) w] x [oy + j w, oy + (j+1) w]."""

    ox: int
    oy: int
    w: int
    nx: int
    ny: int

    def xs(self) -> np.ndarray:
        return self.ox + np.arange(self.nx + 1, dtype=float) * self.w

    def ys(self) -> np.ndarray:
        return self.oy + np.arange(self.ny + 1, dtype=float) * self.w


def _inverse(m) -> tuple[int, int, int, int]:
    det = m[0] * m[3] - m[1] * m[2]  # +-1
    return (m[3] * det, -m[1] * det, -m[2] * det, m[0] * det)


def _apply(m, x, y):
    return m[0] * x + m[1] * y, m[2] * x + m[3] * y


class _Canvas:
    """The die's area and length arrays and the pasting of block windows into them."""

    def __init__(self, grid: WindowGrid):
        self.grid = grid
        self.area = np.zeros((grid.ny, grid.nx))
        self.length = np.zeros((grid.ny, grid.nx))

    def paste(self, area: np.ndarray, length: np.ndarray, col0: np.ndarray, row0: np.ndarray) -> None:
        """Add the (h, w) windows at every offset (col0[k], row0[k]) (the die's window indexes
        of their window [0, 0]); what falls outside the die's grid is dropped."""
        h, w = area.shape
        if h == 0 or w == 0 or len(col0) == 0:
            return
        g = self.grid
        nz = np.nonzero((area != 0) | (length != 0))
        if len(nz[0]) == 0:
            return
        rr, cc = nz
        va, vl = area[nz], length[nz]
        flat_a, flat_l = self.area.reshape(-1), self.length.reshape(-1)
        if len(col0) == 1:  # one placement: every window once, plain fancy indexing adds
            rows, cols = row0[0] + rr, col0[0] + cc
            ok = (rows >= 0) & (rows < g.ny) & (cols >= 0) & (cols < g.nx)
            idx = rows[ok] * g.nx + cols[ok]
            flat_a[idx] += va[ok]
            flat_l[idx] += vl[ok]
            return
        chunk = max(1, 4_000_000 // max(len(rr), 1))
        for s in range(0, len(col0), chunk):
            rows = (row0[s:s + chunk, None] + rr[None, :]).ravel()
            cols = (col0[s:s + chunk, None] + cc[None, :]).ravel()
            n = len(col0[s:s + chunk])
            ok = (rows >= 0) & (rows < g.ny) & (cols >= 0) & (cols < g.nx)
            idx = rows[ok] * g.nx + cols[ok]
            np.add.at(flat_a, idx, np.tile(va, n)[ok])
            np.add.at(flat_l, idx, np.tile(vl, n)[ok])


def _single_offset(block: Block, m, t, grid: WindowGrid, canvas: _Canvas) -> None:
    """A block whose placements share one orientation and offset: KLayout rasterises it in its own frame."""
    w = grid.w
    inv = _inverse(m)
    # the die's window lattice seen from the block's frame: origin inv (o - t) + w Z^2
    bx, by = _apply(inv, grid.ox - int(t[0, 0]), grid.oy - int(t[0, 1]))
    box = block.box
    # one window to spare on each side: an edge on the block's first grid line sends half its length there
    ox = bx - (math.ceil((bx - box.left) / w) + 1) * w
    oy = by - (math.ceil((by - box.bottom) / w) + 1) * w
    nx = max(math.ceil((box.right - ox) / w), 1) + 1
    ny = max(math.ceil((box.top - oy) / w), 1) + 1
    area, length = grid_rasters(block.region, (ox, oy), w, nx, ny)
    # block window (i, j) -> its centre in the die's frame -> the die's window there (first placement)
    ci = ox + (np.arange(nx) + 0.5) * w
    cj = oy + (np.arange(ny) + 0.5) * w
    cx, cy = np.meshgrid(ci, cj)
    px, py = _apply(m, cx, cy)
    cols = np.floor((px + int(t[0, 0]) - grid.ox) / w).astype(np.int64)
    rows = np.floor((py + int(t[0, 1]) - grid.oy) / w).astype(np.int64)
    c0, r0 = int(cols.min()), int(rows.min())
    die_area = np.zeros((int(rows.max()) - r0 + 1, int(cols.max()) - c0 + 1))
    die_length = np.zeros_like(die_area)
    die_area[rows - r0, cols - c0] = area
    die_length[rows - r0, cols - c0] = length
    # the other placements sit at the same offset: whole windows away from the first
    col0 = c0 + (t[:, 0] - t[0, 0]) // w
    row0 = r0 + (t[:, 1] - t[0, 1]) // w
    canvas.paste(die_area, die_length, col0.astype(np.int64), row0.astype(np.int64))


def _phase_chunks(values: np.ndarray, per: int) -> list[np.ndarray]:
    u = np.unique(values)
    return [u[i:i + per] for i in range(0, len(u), per)]


def _many_offsets(block: Block, m, t: np.ndarray, grid: WindowGrid, canvas: _Canvas) -> None:
    """A block at several offsets: one exact integration on the union of their window lines."""
    w = grid.w
    seg = block.segments().transformed(m)
    bb = seg.bbox
    if bb is None:
        return
    phx = np.mod(grid.ox - t[:, 0], w)
    phy = np.mod(grid.oy - t[:, 1], w)
    span_x = (bb[2] - bb[0]) / w + 3
    span_y = (bb[3] - bb[1]) / w + 3
    per = max(1, int(math.sqrt(MAX_SUBCELLS / max(span_x * span_y, 1.0))))
    for cx in _phase_chunks(phx, per):
        for cy in _phase_chunks(phy, per):
            sel = np.isin(phx, cx) & np.isin(phy, cy)
            if not sel.any():
                continue
            xs = window_lines(cx, w, bb[0], bb[2])
            ys = window_lines(cy, w, bb[1], bb[3])
            area, length = rasterise_lines(seg, xs, ys)
            ca = np.zeros((area.shape[0] + 1, area.shape[1] + 1))
            cl = np.zeros_like(ca)
            ca[1:, 1:] = area.cumsum(0).cumsum(1)
            cl[1:, 1:] = length.cumsum(0).cumsum(1)
            tsel = t[sel]
            pairs, inverse = np.unique(np.stack([phx[sel], phy[sel]], axis=1), axis=0, return_inverse=True)
            inverse = np.asarray(inverse).ravel()
            for g, (fx, fy) in enumerate(pairs):
                ix = np.nonzero(np.mod(xs - fx, w) == 0)[0]
                iy = np.nonzero(np.mod(ys - fy, w) == 0)[0]
                wa = ca[np.ix_(iy[1:], ix[1:])] - ca[np.ix_(iy[:-1], ix[1:])] - ca[np.ix_(iy[1:], ix[:-1])] + ca[np.ix_(iy[:-1], ix[:-1])]
                wl = cl[np.ix_(iy[1:], ix[1:])] - cl[np.ix_(iy[:-1], ix[1:])] - cl[np.ix_(iy[1:], ix[:-1])] + cl[np.ix_(iy[:-1], ix[:-1])]
                here = tsel[inverse == g]
                # the oriented block's window [0, 0] starts at xs[ix[0]]: the die's window of that corner
                col0 = ((xs[ix[0]] + here[:, 0] - grid.ox) // w).astype(np.int64)
                row0 = ((ys[iy[0]] + here[:, 1] - grid.oy) // w).astype(np.int64)
                canvas.paste(wa, wl, col0, row0)


def _seams(blocks: dict[BlockKey, Block], placements, grid: WindowGrid, canvas: _Canvas) -> None:
    """Take out the outline pieces that two touching blocks share along their seam."""
    parts = []
    for key, (m_all, t_all) in placements.items():
        block = blocks.get(key)
        if block is None:
            continue
        border = block.border()
        if len(border) == 0:
            continue
        for m in {tuple(r) for r in m_all.tolist()}:
            sel = np.all(m_all == np.array(m), axis=1)
            oriented = border.transformed(m)
            for tx, ty in t_all[sel]:
                parts.append(Segments(oriented.a + (tx, ty), oriented.b + (tx, ty)))
    if len(parts) < 2:
        return
    every = Segments.concat(parts)
    net = cancel_axis(every)
    # nothing cancelled: the same total length (integer dbu: exact). Not the count: a piece that cancels
    # part of a longer one leaves as many pieces as there were (a random hierarchy found it: two
    # placements abutting on a stretch where another layer's edge meets the border)
    if np.sum(np.hypot(*(net.b - net.a).T)) == np.sum(np.hypot(*(every.b - every.a).T)):
        return
    xs, ys = grid.xs(), grid.ys()
    _, before = rasterise_lines(every, xs, ys, area=False)
    _, after = rasterise_lines(net, xs, ys, area=False)
    canvas.length += after - before


def _zone_mask(zones: np.ndarray, grid: WindowGrid) -> np.ndarray:
    """Windows (closed) that meet a zone (closed box)."""
    w = grid.w
    mask = np.zeros((grid.ny, grid.nx), dtype=bool)
    if len(zones) == 0:
        return mask
    kx0 = np.clip(np.ceil((zones[:, 0] - grid.ox) / w).astype(np.int64) - 1, 0, grid.nx)
    kx1 = np.clip(np.floor((zones[:, 2] - grid.ox) / w).astype(np.int64), -1, grid.nx - 1)
    ky0 = np.clip(np.ceil((zones[:, 1] - grid.oy) / w).astype(np.int64) - 1, 0, grid.ny)
    ky1 = np.clip(np.floor((zones[:, 3] - grid.oy) / w).astype(np.int64), -1, grid.ny - 1)
    ok = (kx1 >= kx0) & (ky1 >= ky0)
    diff = np.zeros((grid.ny + 1, grid.nx + 1), dtype=np.int64)
    np.add.at(diff, (ky0[ok], kx0[ok]), 1)
    np.add.at(diff, (ky1[ok] + 1, kx0[ok]), -1)
    np.add.at(diff, (ky0[ok], kx1[ok] + 1), -1)
    np.add.at(diff, (ky1[ok] + 1, kx1[ok] + 1), 1)
    return np.cumsum(np.cumsum(diff, axis=0), axis=1)[:grid.ny, :grid.nx] > 0


def _recompute(top: kdb.Cell, layer_indexes, mask: np.ndarray, grid: WindowGrid, canvas: _Canvas, progress) -> None:
    """Every masked window again, from all the shapes touching it, merged flat."""
    w = grid.w
    tiles = sorted({(r // TILE, c // TILE) for r, c in zip(*np.nonzero(mask))})
    for n, (tj, ti) in enumerate(tiles):
        r0, c0 = tj * TILE, ti * TILE
        sub = mask[r0:r0 + TILE, c0:c0 + TILE]
        rr, cc = np.nonzero(sub)
        j0, j1 = int(r0 + rr.min()), int(r0 + rr.max() + 1)
        i0, i1 = int(c0 + cc.min()), int(c0 + cc.max() + 1)
        # the shapes touching the tile (a query box: no shape lies beyond KLayout's 32-bit coordinates)
        box = kdb.Box(*(min(max(v, -COORD_LIMIT), COORD_LIMIT - 1) for v in (grid.ox + i0 * w - 1, grid.oy + j0 * w - 1,
                                                                              grid.ox + i1 * w + 1, grid.oy + j1 * w + 1)))
        region = merged_region(top, layer_indexes, None, box=box)
        area, length = grid_rasters(region, (grid.ox + i0 * w, grid.oy + j0 * w), w, i1 - i0, j1 - j0)
        keep = mask[j0:j1, i0:i1]
        canvas.area[j0:j1, i0:i1][keep] = area[keep]
        canvas.length[j0:j1, i0:i1][keep] = length[keep]
        if progress:
            progress("overlaps", n + 1, len(tiles))


def _flat(top: kdb.Cell, layer_indexes, grid: WindowGrid, store, progress) -> _Canvas:
    canvas = _Canvas(grid)
    if progress:
        progress("merge", 0, 1)
    region = merged_region(top, layer_indexes, store)
    area, length = grid_rasters(region, (grid.ox, grid.oy), grid.w, grid.nx, grid.ny)
    canvas.area += area
    canvas.length += length
    if progress:
        progress("merge", 1, 1)
    return canvas


def _new_store(threads: int) -> kdb.DeepShapeStore:
    store = kdb.DeepShapeStore()
    store.threads = threads
    return store


def _check_reach(top: kdb.Cell, layer_indexes) -> None:
    """A ValueError if shapes on the layers reach KLayout's largest coordinate, 2**31 - 1 dbu, in x or y:
    KLayout's merge does not finish there (klayout 0.30: it loops, or fails an internal check)."""
    box = kdb.Box()
    for li in layer_indexes:
        box += top.bbox(li)
    if not box.empty() and max(box.right, box.top) >= COORD_LIMIT - 1:
        raise ValueError(f"top cell {top.name!r}: shapes reach {max(box.right, box.top)} dbu in {'x' if box.right >= COORD_LIMIT - 1 else 'y'}, "
                         f"KLayout's largest coordinate (2**31 - 1), where its merge does not finish; move the die "
                         "(e.g. in KLayout, Edit > Layout > Move) at least one database unit back from it")


def window_rasters(layout: kdb.Layout, top: kdb.Cell, layer_indexes, grid: WindowGrid, *,
                   threads: int = 2, big: int | None = None, progress: Progress | None = None, stats: dict | None = None):
    """(area, length) per window of the merged shapes of ``layer_indexes`` under ``top`` (dbu^2, dbu).

    ``big``: a child is composed when its shapes span at least this many windows in x and y
    (default :data:`.hierarchy.BIG`; a huge number merges the die flat). ``threads``: KLayout's
    threads in the deep merge. ``stats`` (a dict) receives what was done: blocks, placements,
    zone windows, whether the die was merged flat.
    """
    stats = {} if stats is None else stats
    big = BIG if big is None else big
    _check_reach(top, layer_indexes)
    the_plan: Plan = plan(layout, top, layer_indexes, grid.w, big)
    try:
        return _rasters(layout, top, layer_indexes, grid, the_plan, threads, progress, stats)
    finally:
        if the_plan.tiles:  # cells the plan added (a large array cut into tiles): the layout is given back as it came
            layout.delete_cells(list(the_plan.tiles))


def _rasters(layout: kdb.Layout, top: kdb.Cell, layer_indexes, grid: WindowGrid, the_plan: Plan, threads: int, progress, stats: dict):
    """:func:`window_rasters` on a plan."""
    stats.update(blocks=len(the_plan.placements), placements=the_plan.count, flat=False, zone_windows=0)
    boxes = {}
    if the_plan.composed:
        for key in the_plan.placements:
            b = block_box(layout, key, layer_indexes)
            if b is not None:
                boxes[key] = b
        placed = np.concatenate([placed_boxes(b, *the_plan.placements[k]) for k, b in boxes.items()]) if boxes else np.zeros((0, 4), dtype=np.int64)
        zones = overlap_zones(placed)
        mask = _zone_mask(zones, grid) if zones is not None else None
        seams = overlap_zones(placed, touching=True)
        need_seams = seams is None or len(seams) > 0  # None: too many pairs to tell; look at every border
    if not the_plan.composed or mask is None or mask.mean() > FLAT_FRACTION:
        stats["flat"] = True
        canvas = _flat(top, layer_indexes, grid, _new_store(threads), progress)
        return canvas.area, canvas.length
    canvas = _Canvas(grid)
    blocks: dict[BlockKey, Block] = {}
    for n, key in enumerate(boxes):
        # a store of its own per block: what KLayout's deep merge holds is let go with it (the region returned is flat)
        region = merged_region(layout.cell(key.cell), layer_indexes, _new_store(threads), excluded=key.excluded)
        if region.is_empty():
            continue
        block = blocks[key] = Block(region, region.bbox())
        m_all, t_all = the_plan.placements[key]
        for m in sorted({tuple(r) for r in m_all.tolist()}):
            t = t_all[np.all(m_all == np.array(m), axis=1)]
            phases = np.unique(np.stack([np.mod(grid.ox - t[:, 0], grid.w), np.mod(grid.oy - t[:, 1], grid.w)], axis=1), axis=0)
            if len(phases) == 1:
                _single_offset(block, m, t, grid, canvas)
            else:
                _many_offsets(block, m, t, grid, canvas)
        if need_seams:
            block.border()  # read before the region is let go (cheap from the outline when it was read)
        block.release()
        if progress:
            progress("merge", n + 1, len(boxes))
    if need_seams:
        _seams(blocks, the_plan.placements, grid, canvas)
    blocks.clear()
    stats["zone_windows"] = int(mask.sum())
    if mask.any():
        _recompute(top, layer_indexes, mask, grid, canvas, progress)
    return canvas.area, canvas.length
