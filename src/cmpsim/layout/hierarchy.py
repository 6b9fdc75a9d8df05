"""Which parts of a layout are merged once and placed many times: the plan of the extraction.

A chip is mostly a few large cells placed many times (macros, stepped blocks, tiles).  Merging
each of them once and pasting its window raster at every placement is what makes a whole chip
cheap; merging everything flat is what KLayout's deep mode already does well for the rest.
The plan walks the hierarchy from the die's top cell:

* a child placed by a plain 90-degree transformation (mirrored or not, magnification 1) whose
  shapes on the layers span at least :data:`BIG` windows in x and in y is **composed**: its own
  plan is placed at each of its placements (arrays expanded);
* everything else under a cell (its own shapes, small children such as standard cells and
  fill cells, rotated or magnified placements) is that cell's **rest**: one block merged by
  KLayout with the composed children's subtrees left out;
* a child is composed only if every placement of it in the cell is composable and no small
  child of the cell calls it (its shapes would be lost from the rest otherwise);
* a small child placed in the cell only by large plain regular arrays (fill) is **tiled**: each
  array is cut into tiles of k x k elements spanning at least :data:`BIG` windows
  (:func:`array_tiles`, cells added to the layout and deleted by the caller), placed like
  composed children, so that 10^8 fill squares are a few blocks and not 10^8 flat shapes.

The result is a list of blocks, each with its placements in the die's frame: an integer
orientation matrix and a translation (dbu).  Where two placed blocks' bounding boxes overlap
with positive area, their shapes may overlap: those **zones** are recomputed flat
(:mod:`.extract`); where they only touch, areas add exactly and only coincident outline
pieces along the seam must cancel (:func:`.segments.cancel_axis`).
"""

from __future__ import annotations

from dataclasses import dataclass

import klayout.db as kdb
import numpy as np

__all__ = ["BlockKey", "Plan", "plan", "overlap_zones", "placed_boxes", "block_box", "array_tiles", "BIG"]

#: A child is composed when its shapes span at least this many windows in x and in y.
BIG = 4
#: Placements of blocks above which composition is given up for the cell (merged flat instead).
MAX_PLACEMENTS = 2_000_000
#: Candidate pairs of overlapping placements above which composition is given up.
MAX_PAIRS = 5_000_000
#: A cell is composed only if the overlaps of its parts' boxes cover less than this fraction of it.
FLAT_FRACTION = 0.3
#: Elements of a regular array of a small cell from which it is cut into tiles (:func:`array_tiles`).
TILE_MIN = 4096


def block_box(layout: kdb.Layout, key: "BlockKey", layer_indexes) -> tuple[int, int, int, int] | None:
    """The bounding box (dbu) of a block's shapes, without merging: the cell's own shapes and
    the placements of every child the block keeps."""
    cell = layout.cell(key.cell)
    box = kdb.Box()
    if not key.excluded:
        for li in layer_indexes:
            box += cell.bbox(li)
    else:
        excluded = set(key.excluded)
        for li in layer_indexes:
            box += kdb.Region(cell.shapes(li)).bbox()
        for inst in cell.each_inst():
            if inst.cell_index in excluded:
                continue
            for li in layer_indexes:
                box += inst.bbox_per_layer(li)
    if box.empty():
        return None
    return (box.left, box.bottom, box.right, box.top)


@dataclass(frozen=True)
class BlockKey:
    """A block: the cell (KLayout index) and the children's subtrees left out of it."""

    cell: int
    excluded: tuple[int, ...] = ()


@dataclass
class Plan:
    """Blocks and their placements in the die's frame.

    ``placements[key]`` = (m, t): ``m`` an (n, 4) int array of orientation matrices
    (a, b, c, d: x' = a x + b y, y' = c x + d y) and ``t`` an (n, 2) int64 array of translations.
    """

    placements: dict[BlockKey, tuple[np.ndarray, np.ndarray]]
    #: Tile cells the plan added to the layout (:func:`array_tiles`); the caller deletes them when done.
    tiles: tuple[int, ...] = ()

    @property
    def count(self) -> int:
        return sum(len(t) for _, t in self.placements.values())

    @property
    def composed(self) -> bool:
        return self.count > 1 or any(k.excluded for k in self.placements)


def _matrix(trans: kdb.Trans) -> tuple[int, int, int, int]:
    o = trans * kdb.Point(0, 0)
    ex = trans * kdb.Point(1, 0)
    ey = trans * kdb.Point(0, 1)
    return (ex.x - o.x, ey.x - o.x, ex.y - o.y, ey.y - o.y)


def _layer_box(cell: kdb.Cell, layer_indexes) -> kdb.Box:
    box = kdb.Box()
    for li in layer_indexes:
        box += cell.bbox(li)
    return box


def _array_translations(inst: kdb.Instance, i: np.ndarray, j: np.ndarray) -> np.ndarray:
    """(len(i) * len(j), 2) translations (dbu) of the elements of a regular array at every pair of
    indices ``i`` along its vector a and ``j`` along b, ``i`` outer."""
    d, a, b = inst.trans.disp, inst.a, inst.b
    ii, jj = np.meshgrid(np.asarray(i, dtype=np.int64), np.asarray(j, dtype=np.int64), indexing="ij")
    ii, jj = ii.ravel(), jj.ravel()
    return np.stack([d.x + ii * a.x + jj * b.x, d.y + ii * a.y + jj * b.y], axis=1)


def _instance_translations(inst: kdb.Instance) -> np.ndarray:
    """(n, 2) translations of every placement of an instance (arrays expanded)."""
    if not inst.is_regular_array():
        d = inst.trans.disp
        return np.array([[d.x, d.y]], dtype=np.int64)
    return _array_translations(inst, np.arange(max(inst.na, 1)), np.arange(max(inst.nb, 1)))


def _tile_counts(inst: kdb.Instance, span: int) -> tuple[int, int] | None:
    """Elements per tile along the array's vectors (a, b) so that a tile spans at least ``span`` dbu
    along each vector the array repeats on; None when the array is not worth tiling: complex, fewer
    than :data:`TILE_MIN` elements, or fewer than two tiles (see :func:`array_tiles`)."""
    if inst.is_complex() or not inst.is_regular_array() or inst.na * inst.nb < TILE_MIN:
        return None
    a, b = inst.a, inst.b
    if inst.na > 1 and inst.nb > 1 and a.x * b.y - a.y * b.x == 0:  # parallel or zero vectors: the elements pile up
        return None
    counts = []
    for n, v in ((inst.na, a), (inst.nb, b)):
        step = max(abs(v.x), abs(v.y))
        counts.append(n if n == 1 or step == 0 else min(n, max(1, -(-span // step))))
    if (inst.na + counts[0] - 1) // counts[0] * ((inst.nb + counts[1] - 1) // counts[1]) < 2:
        return None
    return counts[0], counts[1]


def array_tiles(layout: kdb.Layout, inst: kdb.Instance, counts: tuple[int, int], made: dict) -> list[tuple[int, np.ndarray]]:
    """A large regular array of a small cell as tiles: cells of k1 x k2 elements (and the partial
    ones at its far edges) added to the layout, each with its translations in the parent's frame.

    A fill array of 10^8 squares merged flat holds every square; its tiles are a handful of blocks
    merged once and placed many times, like any big cell (the windows are the same: the tiles
    hold exactly the array's elements). ``made`` caches the tile cells by (cell, orientation,
    vectors, counts) across arrays; the caller deletes them (:attr:`Plan.tiles`).
    """
    k1, k2 = counts
    a, b = inst.a, inst.b
    rot = kdb.Trans(inst.trans.rot, inst.trans.is_mirror(), 0, 0)
    out = []
    for n1, s1 in ((k1, np.arange(0, inst.na - k1 + 1, k1)), (inst.na % k1, np.array([inst.na - inst.na % k1]))):
        for n2, s2 in ((k2, np.arange(0, inst.nb - k2 + 1, k2)), (inst.nb % k2, np.array([inst.nb - inst.nb % k2]))):
            if n1 == 0 or n2 == 0 or len(s1) == 0 or len(s2) == 0:
                continue
            key = (inst.cell_index, str(rot), a.x, a.y, b.x, b.y, n1, n2)
            if key not in made:
                tile = layout.create_cell(f"$cmpsim$tile${len(made)}")
                tile.insert(kdb.CellInstArray(inst.cell_index, rot, a, b, n1, n2))
                made[key] = tile.cell_index()
            out.append((made[key], _array_translations(inst, s1, s2)))
    return out


def plan(layout: kdb.Layout, top: kdb.Cell, layer_indexes, window: int, big: int = BIG) -> Plan:
    """The blocks of ``top`` on the layers and their placements (see the module).

    ``big``: a child is composed when its shapes span at least ``big`` windows of side
    ``window`` (dbu) in x and in y; 0 composes every plain placement.
    """
    memo: dict[int, dict[BlockKey, tuple[np.ndarray, np.ndarray]]] = {}
    made: dict = {}  # tile cells added to the layout (array_tiles)
    big = int(big) * int(window)
    one = np.array([[1, 0, 0, 1]], dtype=np.int64)

    def is_big(ci: int) -> bool:
        box = _layer_box(layout.cell(ci), layer_indexes)
        return (not box.empty()) and box.width() >= big and box.height() >= big

    def pays(cell: kdb.Cell, rest: BlockKey, tiles=(), tiled=frozenset()) -> bool:
        """Whether composing the cell leaves most of it outside the overlaps of its parts (its
        composed children's placements, and its ``tiles`` (tile cell, translations) standing for the
        arrays of the children ``tiled``): the zones (recomputed
        flat) must cover less than :data:`FLAT_FRACTION` of its box."""
        boxes = []
        for tc, t in tiles:
            b = block_box(layout, BlockKey(tc), layer_indexes)
            if b is not None:
                boxes.append(placed_boxes(b, np.broadcast_to(one, (len(t), 4)), t))
        b = block_box(layout, rest, layer_indexes)
        if b is not None:
            boxes.append(np.array([b], dtype=np.int64))
        excluded = set(rest.excluded) - set(tiled)
        for inst in cell.each_inst():
            if inst.cell_index in excluded:
                cb = _layer_box(layout.cell(inst.cell_index), layer_indexes)
                m = np.array([_matrix(inst.trans)], dtype=np.int64)
                boxes.append(placed_boxes((cb.left, cb.bottom, cb.right, cb.top), m, _instance_translations(inst)))
        if len(boxes) == 0:
            return False
        zones = overlap_zones(np.concatenate(boxes))
        if zones is None:
            return False
        whole = _layer_box(cell, layer_indexes)
        covered = float(np.sum((zones[:, 2] - zones[:, 0]).astype(float) * (zones[:, 3] - zones[:, 1])))
        return covered < FLAT_FRACTION * float(whole.width()) * float(whole.height())

    def visit(ci: int) -> dict[BlockKey, tuple[np.ndarray, np.ndarray]]:
        if ci in memo:
            return memo[ci]
        cell = layout.cell(ci)
        flat = {BlockKey(ci): (np.array([[1, 0, 0, 1]], dtype=np.int64), np.zeros((1, 2), dtype=np.int64))}
        ok: dict[int, bool] = {}
        for inst in cell.each_inst():
            c = inst.cell_index
            fine = (not inst.is_complex()) and ok.get(c, True)
            ok[c] = fine and (c in ok or is_big(c))
        small = [c for c, v in ok.items() if not v]
        arrays: dict[int, list | None] = {c: [] for c in small}  # a small child placed here only by large plain arrays is tiled
        for inst in cell.each_inst():
            c = inst.cell_index
            if arrays.get(c) is not None:
                counts = _tile_counts(inst, big)
                arrays[c] = None if counts is None else arrays[c] + [(inst, counts)]
        tiled = {c for c, v in arrays.items() if v}
        while True:  # what stays in the rest must not call what is left out of it
            called: set[int] = set()
            for c in small:
                if c not in tiled:
                    called.update(layout.cell(c).called_cells())
            if not tiled & called:
                break
            tiled -= called
        composed = [c for c, v in ok.items() if v and c not in called]
        out: dict[BlockKey, list] = {}
        if not composed and not tiled:
            memo[ci] = flat
            return flat
        rest = BlockKey(ci, tuple(sorted(composed + list(tiled))))
        tiles = [part for c in sorted(tiled) for inst, counts in arrays[c] for part in array_tiles(layout, inst, counts, made)]
        if not pays(cell, rest, tiles, tiled):
            memo[ci] = flat
            return flat
        out[rest] = [(one, np.zeros((1, 2), dtype=np.int64))]
        total = 1 + sum(len(t) for _, t in tiles)
        if total > MAX_PLACEMENTS:
            memo[ci] = flat
            return flat
        for tc, t in tiles:
            out.setdefault(BlockKey(tc), []).append((np.broadcast_to(one, (len(t), 4)), t))
        for inst in cell.each_inst():
            c = inst.cell_index
            if c not in composed:
                continue
            mi = _matrix(inst.trans)
            ti = _instance_translations(inst)
            for key, (mc, tc) in visit(c).items():
                # (mi, ti) o (mc, tc): m = mi mc, t = mi tc + ti, for every pair
                m = np.stack([mi[0] * mc[:, 0] + mi[1] * mc[:, 2], mi[0] * mc[:, 1] + mi[1] * mc[:, 3],
                              mi[2] * mc[:, 0] + mi[3] * mc[:, 2], mi[2] * mc[:, 1] + mi[3] * mc[:, 3]], axis=1)
                rt = np.stack([mi[0] * tc[:, 0] + mi[1] * tc[:, 1], mi[2] * tc[:, 0] + mi[3] * tc[:, 1]], axis=1)
                n = len(ti) * len(tc)
                total += n
                if total > MAX_PLACEMENTS:
                    memo[ci] = flat
                    return flat
                tt = (rt[None, :, :] + ti[:, None, :]).reshape(-1, 2)
                mm = np.broadcast_to(m[None, :, :], (len(ti), len(m), 4)).reshape(-1, 4)
                out.setdefault(key, []).append((mm, tt))
        memo[ci] = {k: (np.concatenate([p[0] for p in v]), np.concatenate([p[1] for p in v])) for k, v in out.items()}
        return memo[ci]

    try:
        return Plan(visit(top.cell_index()), tuple(made.values()))
    except BaseException:
        layout.delete_cells(list(made.values()))
        raise


def placed_boxes(box: tuple[int, int, int, int], m: np.ndarray, t: np.ndarray) -> np.ndarray:
    """(n, 4) boxes (x0, y0, x1, y1) of a block's box under each placement (m, t)."""
    corners = np.array([[box[0], box[1]], [box[2], box[1]], [box[0], box[3]], [box[2], box[3]]], dtype=np.int64)
    xs = m[:, None, 0] * corners[None, :, 0] + m[:, None, 1] * corners[None, :, 1] + t[:, None, 0]
    ys = m[:, None, 2] * corners[None, :, 0] + m[:, None, 3] * corners[None, :, 1] + t[:, None, 1]
    return np.stack([xs.min(axis=1), ys.min(axis=1), xs.max(axis=1), ys.max(axis=1)], axis=1)


def overlap_zones(boxes: np.ndarray, touching: bool = False) -> np.ndarray | None:
    """(k, 4) intersections with positive area of every pair of boxes (closed boxes, dbu).

    Boxes are paired through buckets of the median box size (larger boxes with every box); None
    when the candidate pairs exceed :data:`MAX_PAIRS` (the caller then merges the cell flat
    instead of composing it). ``touching``: the intersections that are a segment instead (boxes
    that only touch along a line: the seams).
    """
    n = len(boxes)
    if n < 2:
        return np.zeros((0, 4), dtype=np.int64)
    boxes = np.asarray(boxes, dtype=np.int64)
    size = np.maximum(boxes[:, 2] - boxes[:, 0], boxes[:, 3] - boxes[:, 1])
    g = max(int(np.median(size)), 1)
    large = size > g  # paired with every box directly; the rest through buckets of side g
    pairs_i, pairs_j = [], []
    li = np.nonzero(large)[0]
    if len(li) * n > MAX_PAIRS:
        return None
    for k in li:
        j = np.arange(n)
        j = j[(j != k) & (~large | (j > k))]
        pairs_i.append(np.full(len(j), k))
        pairs_j.append(j)
    si = np.nonzero(~large)[0]
    if len(si) > 1:
        # a small box (side <= g) starting in bucket (u, v) ends in (u + 1, v + 1) at most: two small
        # boxes can overlap only if their start buckets differ by at most one in each direction
        u = np.floor_divide(boxes[si, 0], g)
        v = np.floor_divide(boxes[si, 1], g)
        key = u * (1 << 32) + v
        order = np.argsort(key, kind="stable")
        skey = key[order]
        for du in (-1, 0, 1):
            for dv in (-1, 0, 1):
                want = (u + du) * (1 << 32) + (v + dv)
                lo = np.searchsorted(skey, want, side="left")
                hi = np.searchsorted(skey, want, side="right")
                cnt = hi - lo
                if int(cnt.sum()) > MAX_PAIRS:
                    return None
                a = np.repeat(np.arange(len(si)), cnt)
                b = order[np.repeat(lo, cnt) + (np.arange(int(cnt.sum())) - np.repeat(np.cumsum(cnt) - cnt, cnt))]
                keep = a < b
                pairs_i.append(si[a[keep]])
                pairs_j.append(si[b[keep]])
    if not pairs_i:
        return np.zeros((0, 4), dtype=np.int64)
    i = np.concatenate(pairs_i)
    j = np.concatenate(pairs_j)
    if len(i) > MAX_PAIRS:
        return None
    z = np.stack([np.maximum(boxes[i, 0], boxes[j, 0]), np.maximum(boxes[i, 1], boxes[j, 1]),
                  np.minimum(boxes[i, 2], boxes[j, 2]), np.minimum(boxes[i, 3], boxes[j, 3])], axis=1)
    keep = (z[:, 2] > z[:, 0]) & (z[:, 3] > z[:, 1])
    if touching:  # boxes that only touch along a line: the seams
        keep = ((z[:, 2] == z[:, 0]) & (z[:, 3] > z[:, 1])) | ((z[:, 3] == z[:, 1]) & (z[:, 2] > z[:, 0]))
    return z[keep]
