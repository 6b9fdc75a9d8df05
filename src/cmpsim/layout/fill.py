"""Dummy fill geometry: the free fill sites of every window, the choice of squares, the file.

**The lattice.** The fill is a set of squares of side ``s`` (``size``) on a lattice laid out
window by window: in a window of side W the squares' lower-left corners sit at
``x0 + spacing // 2 + i * pitch`` (``pitch = size + spacing``, ``i < W // pitch``), the same in
y, so that every square lies inside one window (the density a square adds belongs to one
window only) and two squares, in one window or in two neighbouring windows, are at least
``spacing`` apart.

**Blocked sites.** A site is blocked when its square would come closer than ``keepout`` (k)
to a drawn shape, or closer than ``edge`` to the die's edge (the top cell's bounding box; a
test on the lattice coordinates).  For the drawn shapes D (all layers, KLayout's deep,
hierarchical region), with distances measured as boxes (Chebyshev: a square at Chebyshev
distance >= k is at Euclidean distance >= k too):

* the square [x, x + s]^2 is blocked iff its open interior meets the open set D grown by the
  box [-k, k]^2, i.e. iff its corner (x, y) lies in the interior of D (+) [-k - s, k]^2 (the
  Minkowski sum).  A square at exactly ``keepout`` is allowed; so is one at exactly
  ``keepout`` from two shapes on opposite sides;
* the corners are integers (dbu).  In doubled coordinates (every shape magnified by 2, the
  lattice at even numbers X = 2x) the open condition becomes a closed one with no rounding:
  X is blocked iff it lies in the **closed** region H = 2D (+) [-(2s + E), E]^2, with E the
  largest even integer below 2k (E = 2 ceil(k) - 2).  H is D magnified by 2, sized by
  s + E with square corners and moved by (-s, -s): KLayout's deep ``sized`` (mode 2 keeps
  the 90-degree corners square, so on Manhattan shapes it is exactly the box growth);
* a closed region is a union of closed pieces, so H can be taken apart freely: every
  polygon of H is cut into trapezoids (KLayout's decomposition; rectangles where H is
  Manhattan) and a site is blocked iff it lies in the closed bounding box of one of them.
  Exact on Manhattan shapes;
* a drawn polygon with an oblique edge (e.g. SKY130's chamfered cell corners) is added
  as its Minkowski sum with the box [-(2s + E + 2), E + 2]^2 (KLayout's ``minkowski_sum``,
  exact: its distance is the box's, Chebyshev, where ``sized`` moves an oblique edge by the
  Euclidean distance only; the 2 more cover the half-dbu of the closed test), and its
  trapezoids (whose corners on an oblique side are rounded to the grid) block as their
  bounding boxes grown by 1: conservative (never a square closer than ``keepout``, a few
  legal sites lost near oblique edges).

**Cost.** H stays hierarchical: KLayout's deep region is inserted into a scratch layout
(a cell per cell of the die where the grown shapes live), each cell's own trapezoids are
computed once in its own frame, and the cells are placed by their instances (arrays,
any rotation, mirror or magnification; a bounding box under a non-90-degree placement is
taken conservatively); a cell with at most :data:`_FLAT_RECTS` rectangles below it is
flattened once and pasted at each placement.  The boxes mark the lattice with a 2-D
difference array (four additions per box, one cumulative sum), vectorised.  Growing and
merging by KLayout is what keeps a whole chip fast: the grown shapes of a standard-cell
macro merge into a few polygons, whatever its cell count.  (Subtracting H from the die's box
and reading the free region instead would flatten it: 68 s on a 20 mm stepped chip where
this takes 5-8 s.)

Only numpy and KLayout (``klayout.db``) are imported, and cmpsim.layout; see docs/fill.md.
"""

from __future__ import annotations

import math
import os
import time
from dataclasses import dataclass, field, replace
from pathlib import Path

import klayout.db as kdb
import numpy as np

from .extract import LayoutWindows, dbu_count, window_fields
from .fillrules import FILL_RULES, FillRules, fill_rules, resolve_fill
from .layermaps import parse_layer, resolve_layers
from .reader import Layout, LayoutTooLarge, layer_indexes, layers_in, read_layout, top_cell

__all__ = ["FillRules", "FILL_RULES", "fill_rules", "resolve_fill", "FillSites", "fill_sites", "select_fill",
           "filled_windows", "write_fill", "fill_polygons", "MAX_SITES"]

#: A cell whose blocking rectangles (its own and its children's) number at most this is flattened
#: once and pasted at every placement; a larger one is walked through its instances.
_FLAT_RECTS = 1_000_000
#: Rectangles marked on the lattice per batch (bounds the memory of a walk).
_BATCH = 2_000_000
#: Lattice sites of one die above which fill_sites refuses (about 13 bytes each while marking).
MAX_SITES = 300_000_000


# ---------------------------------------------------------------------------------- the grown shapes
def _grown(cell: kdb.Cell, lis, s: int, e: int, threads: int) -> tuple[kdb.Region, kdb.DeepShapeStore]:
    """H of the module docstring (doubled dbu): the drawn shapes magnified by 2, sized by s + e and moved by
    (-s, -s), with every polygon that has an oblique edge added as its Minkowski sum with the box
    [-(2 s + e + 2), e + 2]^2; merged. A deep region (its store returned: the region lives as long as it)."""
    store = kdb.DeepShapeStore()
    store.threads = threads
    twice = kdb.ICplxTrans(2.0)
    drawn = None
    for li in lis:
        part = kdb.Region(cell.begin_shapes_rec(li), store, twice)
        drawn = part if drawn is None else drawn + part
    grown = drawn.sized(s + e)
    grown.move(kdb.Vector(-s, -s))
    oblique = drawn.non_rectilinear()
    if not oblique.is_empty():
        grown = grown + oblique.minkowski_sum(kdb.Box(-(2 * s + e + 2), -(2 * s + e + 2), e + 2, e + 2))
        grown.merge()
    return grown, store


def _matrix(t: kdb.ICplxTrans) -> tuple[np.ndarray, bool]:
    """The 2x2 matrix of a placement (rotation, mirror about x first, magnification) and whether it
    maps integer boxes to integer boxes exactly (a multiple of 90 degrees, magnification 1)."""
    a = math.radians(t.angle)
    c, s = math.cos(a), math.sin(a)
    quarter = abs(t.angle / 90.0 - round(t.angle / 90.0)) < 1e-9
    if quarter:
        c, s = float(round(c)), float(round(s))
    m = t.mag * np.array([[c, -s], [s, c]])
    if t.is_mirror():
        m = m @ np.array([[1.0, 0.0], [0.0, -1.0]])
    return m, quarter and abs(t.mag - 1.0) < 1e-12


def _place(r: np.ndarray, m: np.ndarray, exact: bool, t: np.ndarray) -> np.ndarray:
    """Boxes (n, 4) under x' = m x + t for every translation t (k, 2): (k n, 4) bounding boxes
    (exact under 90-degree placements, rounded outwards otherwise)."""
    xs = (r[:, 0], r[:, 2])
    ys = (r[:, 1], r[:, 3])
    cx = np.stack([m[0, 0] * x + m[0, 1] * y for x in xs for y in ys], axis=1)
    cy = np.stack([m[1, 0] * x + m[1, 1] * y for x in xs for y in ys], axis=1)
    b = np.stack([cx.min(axis=1), cy.min(axis=1), cx.max(axis=1), cy.max(axis=1)], axis=1)
    if not exact:
        b = np.concatenate([np.floor(b[:, :2]), np.ceil(b[:, 2:])], axis=1)
    return (b[None, :, :] + t[:, None, [0, 1, 0, 1]]).reshape(-1, 4)


class _Boxes:
    """The blocking boxes of a hierarchical region, cell by cell (doubled dbu, each cell's frame)."""

    def __init__(self, layout: kdb.Layout, layer: int):
        self.layout, self.layer = layout, layer
        self._own: dict[int, np.ndarray] = {}
        self._flat: dict[int, np.ndarray] = {}
        self._count: dict[int, int] = {}
        self._insts: dict[int, list] = {}
        self.stats = {"cells": 0, "visits": 0, "rectangles": 0}

    def own(self, ci: int) -> np.ndarray:
        """The closed boxes of the trapezoids of the cell's own shapes."""
        if ci not in self._own:
            shapes = self.layout.cell(ci).shapes(self.layer)
            out = np.zeros((0, 4))
            if not shapes.is_empty():
                traps = kdb.Region(shapes).decompose_trapezoids_to_region(kdb.Polygon.TD_htrapezoids)
                n = traps.count()
                # a trapezoid with an oblique side has corners rounded to the grid: its box is taken 1 unit larger
                out = np.fromiter((v for p in traps.each() for b in (p.bbox() if p.is_box() else p.bbox().enlarged(1, 1),)
                                   for v in (b.left, b.bottom, b.right, b.top)), dtype=np.float64, count=4 * n).reshape(n, 4)
            self._own[ci] = out
            self.stats["cells"] += 1
        return self._own[ci]

    def instances(self, ci: int) -> list:
        """(child, matrix, exact, (k, 2) translations) of the cell's instances, arrays expanded."""
        if ci not in self._insts:
            out = []
            for inst in self.layout.cell(ci).each_inst():
                t = inst.cplx_trans
                m, exact = _matrix(t)
                d = np.array([[float(t.disp.x), float(t.disp.y)]])
                if inst.is_regular_array():
                    a, b = inst.a, inst.b
                    i, j = np.meshgrid(np.arange(inst.na), np.arange(inst.nb), indexing="ij")
                    d = d + np.stack([i.ravel() * a.x + j.ravel() * b.x, i.ravel() * a.y + j.ravel() * b.y], axis=1)
                out.append((inst.cell_index, m, exact, d))
            self._insts[ci] = out
        return self._insts[ci]

    def count(self, ci: int) -> int:
        if ci not in self._count:
            self._count[ci] = len(self.own(ci)) + sum(len(d) * self.count(c) for c, _, _, d in self.instances(ci))
        return self._count[ci]

    def flat(self, ci: int) -> np.ndarray:
        """Every box below the cell, in its frame (cached)."""
        if ci not in self._flat:
            parts = [self.own(ci)] + [_place(self.flat(c), m, ex, d) for c, m, ex, d in self.instances(ci) if self.count(c)]
            self._flat[ci] = np.concatenate(parts)
        return self._flat[ci]

    def walk(self, ci: int, m: np.ndarray, exact: bool, t: np.ndarray, visit) -> None:
        """Call ``visit(boxes)`` with the boxes of the cell placed at x' = m x + t (every t), in batches."""
        if self.count(ci) <= _FLAT_RECTS:
            r = self.flat(ci)
            if len(r):
                step = max(1, _BATCH // len(r))
                for k in range(0, len(t), step):
                    self._visit(_place(r, m, exact, t[k:k + step]), visit)
            return
        if len(self.own(ci)):
            step = max(1, _BATCH // len(self.own(ci)))
            for k in range(0, len(t), step):
                self._visit(_place(self.own(ci), m, exact, t[k:k + step]), visit)
        for c, mc, exc, d in self.instances(ci):
            if not self.count(c):
                continue
            moved = d @ m.T  # the child's translations in the frame above
            step = max(1, _BATCH // len(d))
            for k in range(0, len(t), step):
                tt = (t[k:k + step, None, :] + moved[None, :, :]).reshape(-1, 2)
                self.walk(c, m @ mc, exact and exc, tt, visit)

    def _visit(self, boxes: np.ndarray, visit) -> None:
        self.stats["visits"] += 1
        self.stats["rectangles"] += len(boxes)
        visit(boxes)


# ---------------------------------------------------------------------------------- sites
@dataclass
class FillSites:
    """The fill lattice of a die and which of its sites are free (dbu unless said).

    ``free`` (ny*m, nx*m) booleans, row along y; window (iy, ix) holds the sites
    [iy*m:(iy+1)*m, ix*m:(ix+1)*m]; ``cx`` (nx*m,), ``cy`` (ny*m,) the lower-left corners
    of the squares (dbu); ``per_window`` m; ``window``, ``size`` in dbu; ``origin`` the
    lower-left corner of window [0, 0] (dbu); ``dbu`` (m); ``rules``; ``stats`` the cost.
    """

    free: np.ndarray
    cx: np.ndarray
    cy: np.ndarray
    per_window: int
    window: int
    size: int
    origin: tuple[int, int]
    dbu: float
    rules: FillRules
    shape: tuple[int, int]
    stats: dict = field(default_factory=dict)

    @property
    def capacity(self) -> np.ndarray:
        """(ny, nx) number of free sites per window."""
        ny, nx = self.shape
        m = self.per_window
        return self.free.reshape(ny, m, nx, m).sum(axis=(1, 3))

    @property
    def square_area(self) -> float:
        """Area of one fill square (m^2)."""
        return (self.size * self.dbu) ** 2

    @property
    def fillable_density(self) -> np.ndarray:
        """(ny, nx) the density all free sites of a window would add."""
        return self.capacity * float(self.size) ** 2 / float(self.window) ** 2

    @property
    def density_step(self) -> float:
        """The density one square adds to its window."""
        return float(self.size) ** 2 / float(self.window) ** 2


def _too_large(what: str, exc: BaseException | None = None) -> LayoutTooLarge:
    detail = f" ({str(exc).strip()})" if exc is not None and str(exc).strip() else ""
    return LayoutTooLarge(f"{what} does not fit in this machine's memory{detail}: choose a larger window (--window), "
                          "a smaller region (--top a sub-cell) or more memory")


def fill_sites(layout: Layout | str | os.PathLike, layers, windows: LayoutWindows, rules: FillRules, *,
               top: str | None = None, pdk: str | None = None, layer_map=None) -> FillSites:
    """The free fill sites of every window of ``windows`` (the grid of :func:`extract_windows`).

    ``layers`` are the drawn layers the fill must keep ``rules.keepout`` away from (the same
    specs as :func:`extract_windows`; pairs the file lacks are skipped, none of them present is
    an error). The window side must hold at least one pitch. Raises ValueError naming the rule
    or option, :class:`LayoutTooLarge` when the lattice or the shapes do not fit the machine.
    """
    t0 = time.perf_counter()
    if not isinstance(layout, Layout):
        layout = read_layout(layout)
    cell = top_cell(layout, top if top is not None else windows.top)
    dbu = layout.dbu
    groups = resolve_layers(layers, pdk=pdk, layer_map=layer_map)
    present = layers_in(layout)
    pairs = {p for g in groups for p in g if p in present}
    if not pairs:
        want = ", ".join(f"{l}/{d}" for g in groups for l, d in g)
        listing = ", ".join(f"{l}/{d}" for l, d in sorted(present))
        raise ValueError(f"layers {want} are not in {layout.path.name}: fill would ignore every drawn shape; "
                         f"its layers are: {listing}")
    W = dbu_count(windows.window, dbu, "window")
    s = dbu_count(rules.size, dbu, "fill size")
    g = dbu_count(rules.spacing, dbu, "fill spacing")
    k = round(rules.keepout / dbu, 6)  # keepout in dbu, need not be whole
    e = rules.edge / dbu
    p = s + g
    m = W // p
    if m < 1:
        raise ValueError(f"window = {windows.window:g} m is smaller than one fill pitch ({rules.pitch:g} m): choose a larger window")
    ny, nx = windows.density.shape
    if ny * m * nx * m > MAX_SITES:
        raise LayoutTooLarge(f"the fill lattice of {ny * m:,} x {nx * m:,} sites (pitch {rules.pitch:g} m) is more than the "
                             f"{MAX_SITES:,} this machine's memory is sized for: choose a larger fill pitch (--fill-size, "
                             "--fill-spacing) or a smaller region (--top a sub-cell)")
    ox, oy = dbu_count(windows.origin[0], dbu, "origin x"), dbu_count(windows.origin[1], dbu, "origin y")
    i = np.arange(m)
    lx = (ox + (np.arange(nx)[:, None] * W + g // 2 + i[None, :] * p)).ravel().astype(np.int64)
    ly = (oy + (np.arange(ny)[:, None] * W + g // 2 + i[None, :] * p)).ravel().astype(np.int64)
    X2, Y2 = 2 * lx, 2 * ly  # the lattice in doubled dbu
    E = 2 * math.ceil(k) - 2  # the largest even integer below 2k
    diff = np.zeros((len(ly) + 1, len(lx) + 1), dtype=np.int32)

    def visit(r: np.ndarray) -> None:
        i0 = np.searchsorted(X2, r[:, 0], side="left")
        i1 = np.searchsorted(X2, r[:, 2], side="right")
        j0 = np.searchsorted(Y2, r[:, 1], side="left")
        j1 = np.searchsorted(Y2, r[:, 3], side="right")
        ok = (i1 > i0) & (j1 > j0)
        i0, i1, j0, j1 = i0[ok], i1[ok], j0[ok], j1[ok]
        np.add.at(diff, (j0, i0), 1)
        np.add.at(diff, (j0, i1), -1)
        np.add.at(diff, (j1, i0), -1)
        np.add.at(diff, (j1, i1), 1)

    try:
        grown, store = _grown(cell, layer_indexes(layout, pairs), s, E, max(1, min(2, os.cpu_count() or 1)))
        scratch = kdb.Layout()
        scratch.dbu = layout.db.dbu / 2.0
        root = scratch.create_cell("BLOCKED")
        li = scratch.layer(1, 0)
        scratch.insert(root.cell_index(), li, grown)
        del grown, store
        # cells with no grown shape below them are dropped with their instances (most standard cells)
        empty = [c.cell_index() for c in scratch.each_cell() if c.cell_index() != root.cell_index() and c.bbox(li).empty()]
        if empty:
            scratch.delete_cells(empty)
        boxes = _Boxes(scratch, li)
        boxes.walk(root.cell_index(), np.eye(2), True, np.zeros((1, 2)), visit)
    except MemoryError as exc:
        raise _too_large(f"the fill keep-out of layers {sorted(pairs)} under {cell.name!r}", exc) from None
    except RuntimeError as exc:
        if "bad_alloc" in str(exc) or "memory" in str(exc).lower():
            raise _too_large(f"the fill keep-out of layers {sorted(pairs)} under {cell.name!r}", exc) from None
        raise
    blocked = np.cumsum(np.cumsum(diff, axis=0, dtype=np.int32), axis=1, dtype=np.int32)[:-1, :-1] > 0
    del diff
    box = cell.bbox()
    inside_x = (lx >= box.left + e) & (lx + s <= box.right - e)
    inside_y = (ly >= box.bottom + e) & (ly + s <= box.top - e)
    free = ~blocked & inside_y[:, None] & inside_x[None, :]
    stats = dict(boxes.stats, seconds=time.perf_counter() - t0, sites=int(free.size), free=int(free.sum()))
    return FillSites(free, lx, ly, int(m), int(W), int(s), (ox, oy), dbu, rules, (ny, nx), stats)


# ---------------------------------------------------------------------------------- choice
def select_fill(sites: FillSites, counts) -> np.ndarray:
    """Boolean (ny*m, nx*m): ``counts[iy, ix]`` free sites of each window, spread evenly.

    In each window the free sites are taken in row order and site r (0-based) of c is
    chosen when floor((r + 1) n / c) > floor(r n / c): exactly n of them, evenly spaced
    along the order (so a free window gets a regular pattern). ``counts`` are clipped to
    [0, capacity].
    """
    ny, nx = sites.shape
    m = sites.per_window
    cap = sites.capacity
    n = np.clip(np.rint(np.asarray(counts, dtype=float)), 0, cap).astype(np.int64)
    # window-major order of the sites: (iy, ix, a, b)
    free = sites.free.reshape(ny, m, nx, m).transpose(0, 2, 1, 3).reshape(ny * nx, m * m)
    rank = np.cumsum(free, axis=1) - 1  # rank among the free sites of the window
    c = cap.reshape(-1, 1)
    nn = n.reshape(-1, 1)
    with np.errstate(divide="ignore", invalid="ignore"):
        pick = free & (((rank + 1) * nn) // np.maximum(c, 1) > (rank * nn) // np.maximum(c, 1))
    return pick.reshape(ny, nx, m, m).transpose(0, 2, 1, 3).reshape(ny * m, nx * m)


def filled_windows(windows: LayoutWindows, sites: FillSites, chosen: np.ndarray) -> LayoutWindows:
    """The window fields with the chosen squares added (exact: the squares keep ``keepout`` > 0 from
    every drawn shape and ``spacing`` > 0 from each other, and each lies in one window, so the
    area and the boundary of a window add: A + n s^2, L + 4 n s)."""
    ny, nx = sites.shape
    m = sites.per_window
    n = chosen.reshape(ny, m, nx, m).sum(axis=(1, 3)).astype(float)
    side = sites.size * sites.dbu
    if sites.rules.keepout <= 0:
        raise ValueError("filled_windows needs keepout > 0: fill touching a drawn shape would merge with it")
    area = windows.density * windows.window**2 + n * side**2
    boundary = windows.boundary + 4.0 * n * side
    density, width, space = window_fields(area, boundary, windows.window)
    return replace(windows, density=density, width=width, space=space, boundary=boundary)


# ---------------------------------------------------------------------------------- output
def fill_polygons(sites: FillSites, chosen: np.ndarray) -> np.ndarray:
    """The chosen squares as an (n, 4) int64 array of boxes (x0, y0, x1, y1; dbu, the die's frame)."""
    iy, ix = np.nonzero(chosen)
    x, y = sites.cx[ix], sites.cy[iy]
    return np.stack([x, y, x + sites.size, y + sites.size], axis=1).astype(np.int64)


def _runs(ix: np.ndarray, iy: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Windows (row-major, sorted) grouped into runs along x: (first ix, iy, length) of each."""
    brk = np.ones(len(ix), dtype=bool)
    brk[1:] = (iy[1:] != iy[:-1]) | (ix[1:] != ix[:-1] + 1)
    start = np.nonzero(brk)[0]
    length = np.diff(np.append(start, len(ix)))
    return ix[start], iy[start], length


def write_fill(path: str | os.PathLike, sites: FillSites, chosen: np.ndarray, layer, *, cell_name: str = "CMPSIM_FILL") -> Path:
    """Write the chosen squares as a GDSII (``.gds``) or OASIS (``.oas``) file with KLayout, atomically.

    ``layer`` is ``"L/D"`` or (layer, datatype). The top cell ``cell_name`` places, per
    window, a cell holding that window's pattern of squares; windows with the same pattern
    (every fully free window with the same count) share one cell, placed as one array per run
    of neighbouring windows along x, so the file grows with the number of distinct patterns
    and runs, not squares. Units: the layout's dbu. Nothing is written on error.
    """
    pair = parse_layer(layer) if isinstance(layer, str) else (tuple(layer) if layer is not None else None)
    if pair is None:
        raise ValueError(f"fill layer {layer!r} must be \"L/D\" such as \"36/28\"")
    path = Path(path)
    suffix = path.suffix.lower()
    if suffix not in (".gds", ".oas"):
        raise ValueError(f"fill file {str(path)!r} must end in .gds or .oas")
    ny, nx = sites.shape
    m = sites.per_window
    W, s = sites.window, sites.size
    ly = kdb.Layout()
    ly.dbu = sites.dbu * 1e6  # um
    li = ly.layer(int(pair[0]), int(pair[1]))
    top = ly.create_cell(cell_name)
    pats = chosen.reshape(ny, m, nx, m).transpose(0, 2, 1, 3).reshape(ny * nx, m * m)
    used = np.nonzero(pats.any(axis=1))[0]
    if used.size:
        packed = np.packbits(pats[used], axis=1)
        uniq, inverse = np.unique(packed, axis=0, return_inverse=True)
        inverse = np.asarray(inverse).ravel()
        # the corners inside a window (relative to its lower-left corner): the lattice is the same in every window
        rel_x = sites.cx[:m] - sites.origin[0]
        rel_y = sites.cy[:m] - sites.origin[1]
        step = kdb.Vector(int(W), 0)
        for u in range(len(uniq)):
            a, b = np.nonzero(np.unpackbits(uniq[u])[: m * m].reshape(m, m))  # a along y, b along x
            pc = ly.create_cell(f"{cell_name}_P{u}")
            shapes = pc.shapes(li)
            for x, y in zip(rel_x[b].tolist(), rel_y[a].tolist()):
                shapes.insert(kdb.Box(x, y, x + s, y + s))
            wins = used[inverse == u]
            for jx, jy, n in zip(*(v.tolist() for v in _runs(wins % nx, wins // nx))):
                at = kdb.Trans(kdb.Vector(int(sites.origin[0] + jx * W), int(sites.origin[1] + jy * W)))
                if n == 1:
                    top.insert(kdb.CellInstArray(pc.cell_index(), at))
                else:
                    top.insert(kdb.CellInstArray(pc.cell_index(), at, step, kdb.Vector(0, int(W)), n, 1))
    options = kdb.SaveLayoutOptions()
    options.format = "GDS2" if suffix == ".gds" else "OASIS"
    tmp = path.with_name(path.name + ".tmp" + suffix)
    try:
        ly.write(str(tmp), options)
        os.replace(tmp, path)
    except BaseException:
        tmp.unlink(missing_ok=True)
        raise
    return path
