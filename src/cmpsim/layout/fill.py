"""Dummy fill geometry: the rules, the fill sites of every window, the squares, the file.

The fill is a set of squares of side ``size`` on a lattice laid out window by window: in
a window of side W the squares sit at ``x0 + spacing // 2 + i * pitch`` (``pitch = size +
spacing``, ``i < W // pitch``), the same in y, so that every square lies inside one window
(the density a square adds belongs to one window only) and two squares, in one window or
in two neighbouring windows, are at least ``spacing`` apart.  A lattice site is **blocked**
when its square would come closer than ``keepout`` to a drawn shape, or closer than
``edge`` to the die's edge (the top cell's bounding box).  Blocking is decided on the
shapes, not on the merged region:

* a rectangle (x0, y0, x1, y1) blocks the sites whose centre lies in the open box
  (x0 - keepout - size/2, x1 + keepout + size/2) x (the same in y): the square then
  overlaps the rectangle grown by ``keepout`` (Chebyshev growth: a square at a Euclidean
  distance >= keepout is a fortiori allowed).  A square at exactly ``keepout`` is allowed.
* any other Manhattan polygon is cut into horizontal slabs (exact rectangles whose union
  is the polygon), so the rule above stays exact;
* a polygon with an oblique edge blocks as its bounding box (conservative: it never lets a
  square violate the keep-out, it may forbid a few legal ones).

The blocked sites are marked with a 2-D difference array (four additions per rectangle,
one cumulative sum), vectorised over all rectangles.  The hierarchy is used: every cell is
flattened once into rectangles (in its own frame, cached) and each placement only
transforms and translates that array (90-degree orientations; any other reference is
flattened into its parent by gdstk).  Memory is one cell's rectangles at a time, not the
chip's.

Only numpy and gdstk are imported (and cmpsim.layout); see docs/fill.md.
"""

from __future__ import annotations

import math
import os
from dataclasses import dataclass, field, replace
from pathlib import Path

import gdstk
import numpy as np

from .extract import LayoutWindows, dbu_count, window_fields
from .hierarchy import _orientation, placements
from .layermaps import parse_layer, resolve_layers
from .reader import Layout, layers_in, read_layout, top_cell

__all__ = ["FillRules", "FILL_RULES", "fill_rules", "FillSites", "fill_sites", "select_fill", "filled_windows",
           "write_fill", "fill_polygons"]


@dataclass(frozen=True)
class FillRules:
    """The geometry rules of square dummy fill (all lengths in m).

    ``size`` the side of a fill square; ``spacing`` the least distance between two fill
    squares; ``keepout`` the least distance from a fill square to a drawn shape of the
    layer; ``edge`` the least distance from a fill square to the die's edge (the top
    cell's bounding box); ``source`` where the numbers come from.
    """

    size: float
    spacing: float
    keepout: float
    edge: float = 0.0
    source: str = "user"

    def __post_init__(self) -> None:
        for name in ("size", "spacing", "keepout", "edge"):
            v = getattr(self, name)
            if not (isinstance(v, (int, float)) and math.isfinite(v) and v >= 0):
                raise ValueError(f"fill rule {name} = {v!r} must be a length >= 0 m")
        if self.size <= 0:
            raise ValueError(f"fill rule size = {self.size!r} must be > 0 m")
        if self.spacing <= 0:
            raise ValueError(f"fill rule spacing = {self.spacing!r} must be > 0 m (squares must not touch)")

    @property
    def pitch(self) -> float:
        """size + spacing (m): the lattice step."""
        return self.size + self.spacing

    def replace(self, **values) -> "FillRules":
        """A copy with some rules changed (m); the source becomes "... with overrides"."""
        values = {k: v for k, v in values.items() if v is not None}
        if not values:
            return self
        src = self.source if "overrides" in self.source else f"{self.source}, with overrides"
        return replace(self, **values, source=src)


# The default rules per open PDK (m). Sources:
# * gf180mcu: OpenROAD-flow-scripts, flow/platforms/gf180/fill.json (the density_fill rules
#   of the GF180MCU platform): Metal1-5 non-OPC fill 2 um minimum side (widths 12/6/3/2 um by
#   2 um), "space_to_fill" 1.0 um, "space_to_non_fill" 2.0 um, "space_to_outline" 5 um.
# * sg13g2: OpenROAD-flow-scripts, flow/platforms/ihp-sg13g2/fill.json: Metal1-4 fill squares
#   2.00/1.00/0.58/0.3(0.4) um, space_to_fill 0.3 um, space_to_non_fill 3 um; Metal5,
#   TopMetal1-2 3 um squares, space_to_fill 1.6 um, space_to_non_fill 3 um; space_to_outline 70 um.
#   The largest square is used (fewest shapes).
# * sky130: ASSUMED, not read from the PDK here: the open_pdks fill generator (magic "cif
#   ostyle wafflefill" in sky130A.tech, sky130/custom/scripts/generate_fill.py) makes square
#   met1-met5 fill; its sizes were not read. 2 um squares, 1 um apart, 3 um from drawn metal
#   are chosen to be legal under SKY130's metal width/space rules (met1 min width 0.14 um,
#   space 0.14 um, periphery rules m1.1/m1.2) with margin. Override them for a tape-out.
_UM = 1e-6
_GF = FillRules(2.0 * _UM, 1.0 * _UM, 2.0 * _UM, 5.0 * _UM, "gf180mcu: OpenROAD-flow-scripts platforms/gf180/fill.json")
_SG = FillRules(2.0 * _UM, 0.3 * _UM, 3.0 * _UM, 70.0 * _UM, "sg13g2: OpenROAD-flow-scripts platforms/ihp-sg13g2/fill.json")
_SG_TOP = FillRules(3.0 * _UM, 1.6 * _UM, 3.0 * _UM, 70.0 * _UM, "sg13g2: OpenROAD-flow-scripts platforms/ihp-sg13g2/fill.json")
_SKY = FillRules(2.0 * _UM, 1.0 * _UM, 3.0 * _UM, 0.0, "sky130: assumed (PDK fill sizes not read; see layout/fill.py)")

#: pdk -> layer name -> FillRules (layer names as in :data:`cmpsim.layout.PDK_LAYER_MAPS`).
FILL_RULES: dict[str, dict[str, FillRules]] = {
    "sky130": {name: _SKY for name in ("li1", "met1", "met2", "met3", "met4", "met5")},
    "gf180mcu": {name: _GF for name in ("metal1", "metal2", "metal3", "metal4", "metal5", "metaltop")},
    "sg13g2": {**{f"metal{i}": _SG for i in range(1, 5)}, "metal5": _SG_TOP, "topmetal1": _SG_TOP, "topmetal2": _SG_TOP},
}


def fill_rules(pdk: str | None = None, layer: str | None = None, **overrides) -> FillRules:
    """The fill rules of ``pdk`` for ``layer`` (a name; default its first metal), overrides applied.

    Without a PDK every rule must be given (``size``, ``spacing``, ``keepout``; ``edge``
    defaults to 0). Raises ValueError naming the parameter and the valid values.
    """
    if pdk is None:
        missing = [k for k in ("size", "spacing", "keepout") if overrides.get(k) is None]
        if missing:
            raise ValueError(f"fill rules without a pdk need {', '.join(missing)} (or pdk = one of {sorted(FILL_RULES)})")
        return FillRules(**{k: v for k, v in overrides.items() if v is not None})
    if pdk not in FILL_RULES:
        raise ValueError(f"pdk {pdk!r} has no fill rules; valid: {sorted(FILL_RULES)}")
    table = FILL_RULES[pdk]
    name = next(iter(table)) if layer is None else str(layer).lower()
    if name not in table:
        raise ValueError(f"layer {layer!r} has no fill rules in {pdk}; valid: {sorted(table)}")
    return table[name].replace(**overrides)


# ---------------------------------------------------------------------------------- rectangles
def _slabs(pts: np.ndarray) -> np.ndarray | None:
    """Rectangles (k, 4) whose union is the Manhattan polygon ``pts`` (even-odd), or None if oblique."""
    nxt = np.roll(pts, -1, axis=0)
    vertical = pts[:, 0] == nxt[:, 0]
    horizontal = pts[:, 1] == nxt[:, 1]
    if not np.all(vertical | horizontal):
        return None
    ex = pts[vertical, 0]
    ey0 = np.minimum(pts[vertical, 1], nxt[vertical, 1])
    ey1 = np.maximum(pts[vertical, 1], nxt[vertical, 1])
    ys = np.unique(pts[:, 1])
    out = []
    for ya, yb in zip(ys[:-1], ys[1:]):
        ym = 0.5 * (ya + yb)
        xs = np.sort(ex[(ey0 < ym) & (ey1 > ym)])
        for xa, xb in zip(xs[0::2], xs[1::2]):
            if xb > xa:
                out.append((xa, ya, xb, yb))
    return np.array(out, dtype=float).reshape(-1, 4)


def _polygon_rects(polys) -> np.ndarray:
    """(n, 4) rectangles covering the polygons: exact for Manhattan ones, the bounding box otherwise."""
    rects = []
    others = []
    for p in polys:
        pts = p.points if isinstance(p, gdstk.Polygon) else np.asarray(p, float)
        if len(pts) == 4:
            x0, y0 = pts.min(axis=0)
            x1, y1 = pts.max(axis=0)
            # an axis-parallel rectangle has only two distinct x and two distinct y
            if np.count_nonzero(pts[:, 0] == x0) == 2 and np.count_nonzero(pts[:, 1] == y0) == 2:
                rects.append((x0, y0, x1, y1))
                continue
        others.append(pts)
    blocks = [np.array(rects, dtype=float).reshape(-1, 4)]
    for pts in others:
        r = _slabs(pts)
        if r is None:  # oblique: its bounding box (conservative)
            r = np.array([[*pts.min(axis=0), *pts.max(axis=0)]])
        blocks.append(r)
    return np.concatenate(blocks)


class _CellRects:
    """Each cell flattened once into rectangles (dbu, cell frame) on the layers, by reference placement."""

    def __init__(self, library: gdstk.Library, layers, flat_limit: int = 2_000_000):
        self.cells = {c.name: c for c in library.cells if isinstance(c, gdstk.Cell)}
        self.layers = tuple(sorted(set(layers)))
        self.flat_limit = flat_limit
        self._rects: dict[str, np.ndarray] = {}
        self.stats = {"cells_flattened": 0, "placements": 0, "rectangles": 0}

    def own(self, name: str) -> np.ndarray:
        """The cell's own shapes plus those of references that are not 90-degree placements."""
        key = ("own", name)
        if key not in self._rects:
            cell = self.cells[name]
            polys = []
            for layer, dtype in self.layers:
                polys.extend(cell.get_polygons(depth=0, layer=layer, datatype=dtype))
                for ref in cell.references:
                    if isinstance(ref.cell, gdstk.Cell) and _orientation(ref.rotation, ref.x_reflection, ref.magnification) is None:
                        polys.extend(ref.get_polygons(layer=layer, datatype=dtype))
            self._rects[key] = _polygon_rects(polys)
        return self._rects[key]

    def placements(self, name: str):
        """(child, matrix, (n, 2) translations) of the 90-degree references of a cell."""
        return placements(self.cells[name])

    def flat(self, name: str) -> np.ndarray:
        """All rectangles of the cell (its frame), flattened once and cached."""
        if name not in self._rects:
            parts = [self.own(name)]
            for child, m, t in self.placements(name):
                r = _orient(self.flat(child), m)
                parts.append((r[None, :, :] + np.concatenate([t, t], axis=1)[:, None, :]).reshape(-1, 4))
            self._rects[name] = np.concatenate(parts)
            self.stats["cells_flattened"] += 1
        return self._rects[name]

    def walk(self, name: str, visit, m=(1, 0, 0, 1), t=(0.0, 0.0), budget: int | None = None):
        """Call ``visit(rects)`` with the chip-frame rectangles, placement by placement.

        A cell whose flattened rectangles number at most ``flat_limit`` is flattened once and
        visited at each placement; a larger one is walked through its own references.
        """
        count = self.count(name)
        if count <= self.flat_limit or not self.placements(name):
            r = _orient(self.flat(name), m)
            r[:, [0, 2]] += t[0]
            r[:, [1, 3]] += t[1]
            self.stats["placements"] += 1
            self.stats["rectangles"] += len(r)
            visit(r)
            return
        r = _orient(self.own(name), m)
        r[:, [0, 2]] += t[0]
        r[:, [1, 3]] += t[1]
        visit(r)
        for child, mc, ts in self.placements(name):
            mm = _compose(m, mc)
            for tc in ts:
                tx = m[0] * tc[0] + m[1] * tc[1] + t[0]
                ty = m[2] * tc[0] + m[3] * tc[1] + t[1]
                self.walk(child, visit, mm, (tx, ty))

    def count(self, name: str) -> int:
        key = ("count", name)
        if key not in self._rects:
            cell = self.cells[name]
            n = sum(len(cell.get_polygons(depth=0, layer=l, datatype=d)) for l, d in self.layers)
            for child, _, t in self.placements(name):
                n += len(t) * self.count(child)
            self._rects[key] = n
        return self._rects[key]


def _compose(m, n):
    return (m[0] * n[0] + m[1] * n[2], m[0] * n[1] + m[1] * n[3], m[2] * n[0] + m[3] * n[2], m[2] * n[1] + m[3] * n[3])


def _orient(r: np.ndarray, m) -> np.ndarray:
    """Rectangles (n, 4) under a 90-degree orientation matrix m (a copy)."""
    if m == (1, 0, 0, 1):
        return r.copy()
    xa = m[0] * r[:, 0] + m[1] * r[:, 1]
    ya = m[2] * r[:, 0] + m[3] * r[:, 1]
    xb = m[0] * r[:, 2] + m[1] * r[:, 3]
    yb = m[2] * r[:, 2] + m[3] * r[:, 3]
    return np.stack([np.minimum(xa, xb), np.minimum(ya, yb), np.maximum(xa, xb), np.maximum(ya, yb)], axis=1)


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


def fill_sites(layout: Layout | str | os.PathLike, layers, windows: LayoutWindows, rules: FillRules, *,
               top: str | None = None, pdk: str | None = None, layer_map=None, flat_limit: int = 2_000_000) -> FillSites:
    """The free fill sites of every window of ``windows`` (the grid of :func:`extract_windows`).

    ``layers`` are the drawn layers the fill must keep ``rules.keepout`` away from (the same
    specs as :func:`extract_windows`; pairs the file lacks are skipped, none of them present is an
    error). The window side
    must hold at least one pitch. Cost: one pass over the rectangles of every placement.
    """
    import time

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
    k = rules.keepout / dbu
    e = rules.edge / dbu
    p = s + g
    m = W // p
    if m < 1:
        raise ValueError(f"window = {windows.window:g} m is smaller than one fill pitch ({rules.pitch:g} m): choose a larger window")
    ny, nx = windows.density.shape
    ox, oy = dbu_count(windows.origin[0], dbu, "origin x"), dbu_count(windows.origin[1], dbu, "origin y")
    i = np.arange(m)
    lx = (ox + (np.arange(nx)[:, None] * W + g // 2 + i[None, :] * p)).ravel().astype(float)
    ly = (oy + (np.arange(ny)[:, None] * W + g // 2 + i[None, :] * p)).ravel().astype(float)
    cxs, cys = lx + 0.5 * s, ly + 0.5 * s
    diff = np.zeros((len(cys) + 1, len(cxs) + 1), dtype=np.int32)
    grow = k + 0.5 * s

    def visit(r: np.ndarray) -> None:
        if not len(r):
            return
        x0 = np.searchsorted(cxs, r[:, 0] - grow, side="right")
        x1 = np.searchsorted(cxs, r[:, 2] + grow, side="left")
        y0 = np.searchsorted(cys, r[:, 1] - grow, side="right")
        y1 = np.searchsorted(cys, r[:, 3] + grow, side="left")
        ok = (x1 > x0) & (y1 > y0)
        x0, x1, y0, y1 = x0[ok], x1[ok], y0[ok], y1[ok]
        np.add.at(diff, (y0, x0), 1)
        np.add.at(diff, (y0, x1), -1)
        np.add.at(diff, (y1, x0), -1)
        np.add.at(diff, (y1, x1), 1)

    engine = _CellRects(layout.library, pairs, flat_limit=flat_limit)
    engine.walk(cell.name, visit)
    blocked = np.cumsum(np.cumsum(diff, axis=0), axis=1)[:-1, :-1] > 0
    (bx0, by0), (bx1, by1) = np.round(cell.bounding_box())
    inside_x = (lx >= bx0 + e) & (lx + s <= bx1 - e)
    inside_y = (ly >= by0 + e) & (ly + s <= by1 - e)
    free = ~blocked & inside_y[:, None] & inside_x[None, :]
    stats = dict(engine.stats, seconds=time.perf_counter() - t0, sites=int(free.size), free=int(free.sum()))
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
def fill_polygons(sites: FillSites, chosen: np.ndarray, layer: int = 0, datatype: int = 0) -> list[gdstk.Polygon]:
    """The chosen squares as flat gdstk rectangles (dbu) - for tests and small dies."""
    iy, ix = np.nonzero(chosen)
    s = sites.size
    return [gdstk.rectangle((x, y), (x + s, y + s), layer=layer, datatype=datatype)
            for x, y in zip(sites.cx[ix], sites.cy[iy])]


def write_fill(path: str | os.PathLike, sites: FillSites, chosen: np.ndarray, layer, *, cell_name: str = "CMPSIM_FILL") -> Path:
    """Write the chosen squares as a GDSII (``.gds``) or OASIS (``.oas``) library, atomically.

    ``layer`` is ``"L/D"`` or (layer, datatype). The top cell ``cell_name`` places, per
    window, a cell holding that window's pattern of squares; windows with the same pattern
    (every fully free window with the same count) share one cell, so the file grows with
    the number of distinct patterns and windows, not squares. Units: the layout's dbu.
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
    lib = gdstk.Library(unit=sites.dbu, precision=sites.dbu)
    top = lib.new_cell(cell_name)
    pats = chosen.reshape(ny, m, nx, m).transpose(0, 2, 1, 3).reshape(ny * nx, m * m)
    used = np.nonzero(pats.any(axis=1))[0]
    if used.size:
        packed = np.packbits(pats[used], axis=1)
        uniq, inverse = np.unique(packed, axis=0, return_inverse=True)
        inverse = np.asarray(inverse).ravel()
        g2 = sites.cx[1] - sites.cx[0] if m > 1 else 0  # the pitch (unused with m == 1)
        base = sites.cx[0] - sites.origin[0]  # the margin of the first site in a window
        for u in range(len(uniq)):
            bits = np.unpackbits(uniq[u])[: m * m].reshape(m, m).astype(bool)
            a, b = np.nonzero(bits)  # a along y, b along x
            pc = lib.new_cell(f"{cell_name}_P{u}")
            for yy, xx in zip(a, b):
                x = base + xx * g2
                y = base + yy * g2
                pc.add(gdstk.rectangle((x, y), (x + s, y + s), layer=pair[0], datatype=pair[1]))
            wins = used[inverse == u]
            offs = np.stack([sites.origin[0] + (wins % nx) * W, sites.origin[1] + (wins // nx) * W], axis=1).astype(float)
            if len(offs) == 1:
                top.add(gdstk.Reference(pc, tuple(offs[0])))
            else:
                # an explicit repetition holds the origin implicitly: the offsets are of the other copies
                ref = gdstk.Reference(pc, tuple(offs[0]))
                ref.repetition = gdstk.Repetition(offsets=[tuple(o) for o in offs[1:] - offs[0]])
                top.add(ref)
    tmp = path.with_name(path.name + ".tmp" + suffix)
    if suffix == ".gds":
        lib.write_gds(str(tmp))
    else:
        lib.write_oas(str(tmp))
    os.replace(tmp, path)
    return path
