"""One block of a layout merged by KLayout, and its per-window area and boundary length.

A *block* is a cell's shapes on the chosen layers, flattened and merged by KLayout's deep
(hierarchical) mode, with the subtrees of some children left out (those placed and composed
separately, :mod:`.hierarchy`).  Per window of a square grid it gives:

* the **area** of the merged shapes: :meth:`klayout.db.Region.rasterize` (exact: the area of
  the polygons clipped to each pixel);
* the **boundary length** (the outline of the merged shapes; a piece lying on a window's edge
  counts half in each window): every axis-parallel edge becomes a 2-dbu-wide rectangle centred
  on it (``Edges.extended(0, 0, 1, 1)``), whose rasterised area is twice its length inside
  each window, exactly, an edge on a window line being split half and half; the oblique edges
  (KLayout rounds the corners of their rectangles) are taken out and rasterised exactly from
  their end points (:func:`.segments.rasterise_lines`).

A block placed at several offsets against the window grid is rasterised once for all of
them: its outline comes out of KLayout as segments, and :func:`.segments.rasterise_lines`
integrates them on the union of every offset's window lines.

Coordinates are database units (integers).
"""

from __future__ import annotations

from dataclasses import dataclass

import klayout.db as kdb
import numpy as np

from .segments import Segments, rasterise_lines

__all__ = ["Block", "merged_region", "edges_to_segments", "grid_rasters", "border_segments", "fits_klayout", "COORD_LIMIT"]


def merged_region(cell: kdb.Cell, layer_indexes, store: kdb.DeepShapeStore | None = None, *,
                  excluded=(), box: kdb.Box | None = None) -> kdb.Region:
    """The merged shapes of ``cell`` on the layers (dbu, cell frame), a flat region.

    ``store`` merges them in KLayout's deep (hierarchical) mode first; ``excluded`` are cell
    indexes whose subtrees are left out; ``box`` restricts the shapes to those touching it
    (whole shapes).
    """
    region = None
    for li in layer_indexes:
        it = cell.begin_shapes_rec_touching(li, box) if box is not None else cell.begin_shapes_rec(li)
        if excluded:
            it.unselect_cells(list(excluded))
        part = kdb.Region(it, store) if store is not None else kdb.Region(it)
        region = part if region is None else region + part
    if region is None:
        return kdb.Region()
    region.merge()
    if store is None:
        return region
    # A deep merge is merged cell by cell: two identical placements of one cell at one spot (real
    # tape-outs have them) stay two copies of the same merged polygons when flattened, and would be
    # counted twice. The merged pieces are copied flat and merged once more (cheap: they are few and
    # already merged), so the region is the flat merge KLayout gives, whatever the hierarchy.
    flat = kdb.Region()
    flat.insert(region)
    flat.merge()
    return flat


def edges_to_segments(edges: kdb.Edges) -> Segments:
    """The edges of a merged region as :class:`Segments` with the material on their left.

    KLayout's outlines run with the material on their right (hulls clockwise), so every
    edge is reversed.
    """
    n = edges.count()
    if n == 0:
        return Segments.empty()
    arr = np.fromiter((v for e in edges.each() for v in (e.x2, e.y2, e.x1, e.y1)), dtype=np.float64, count=4 * n)
    arr = arr.reshape(n, 4)
    return Segments(arr[:, :2].copy(), arr[:, 2:].copy())


def _ortho_and_oblique(edges: kdb.Edges) -> tuple[kdb.Edges, kdb.Edges]:
    ortho, oblique = edges.split_with_angle(kdb.Edges.OrthoEdges)
    return ortho, oblique


#: KLayout's coordinates are 32-bit integers: [-COORD_LIMIT, COORD_LIMIT - 1] dbu.
COORD_LIMIT = 2**31


def fits_klayout(x0: int, y0: int, x1: int, y1: int, margin: int = 2) -> bool:
    """Whether the box (dbu) grown by ``margin`` lies inside KLayout's 32-bit coordinates."""
    return min(x0, y0) - margin >= -COORD_LIMIT and max(x1, y1) + margin <= COORD_LIMIT - 1


def grid_rasters(region: kdb.Region, origin: tuple[int, int], window: int, nx: int, ny: int):
    """Area (dbu^2) and boundary length (dbu) of a merged region per window of a square grid.

    Window [j, i] is [ox + i w, ox + (i+1) w] x [oy + j w, oy + (j+1) w]. Exact (see the module).
    A grid, or shapes, reaching past KLayout's 32-bit coordinates (a die drawn near +-2**31 dbu:
    KLayout's rasteriser would overflow and read zero) are integrated from the outline instead
    (:func:`.segments.rasterise_lines`, exact as well).
    """
    if region.is_empty() or nx <= 0 or ny <= 0:
        return np.zeros((max(ny, 0), max(nx, 0))), np.zeros((max(ny, 0), max(nx, 0)))
    bb = region.bbox()
    if not (fits_klayout(int(origin[0]), int(origin[1]), int(origin[0]) + nx * int(window), int(origin[1]) + ny * int(window))
            and fits_klayout(bb.left, bb.bottom, bb.right, bb.top)):
        xs = int(origin[0]) + np.arange(nx + 1, dtype=float) * int(window)
        ys = int(origin[1]) + np.arange(ny + 1, dtype=float) * int(window)
        return rasterise_lines(edges_to_segments(region.edges()), xs, ys)
    o = kdb.Point(int(origin[0]), int(origin[1]))
    step = kdb.Vector(int(window), int(window))
    area = np.asarray(region.rasterize(o, step, nx, ny), dtype=float)
    # the rectilinear polygons' edges are all axis-parallel; only the others need their edges sorted (cheap filter first)
    rect, other = region.rectilinear(), region.non_rectilinear()
    if other.is_empty():
        ortho, oblique = rect.edges(), kdb.Edges()
    else:
        ortho, oblique = _ortho_and_oblique(other.edges())
        ortho += rect.edges()
    strips = ortho.extended(0, 0, 1, 1, False)
    length = 0.5 * np.asarray(strips.rasterize(o, step, nx, ny), dtype=float)
    if not oblique.is_empty():
        xs = origin[0] + np.arange(nx + 1, dtype=float) * window
        ys = origin[1] + np.arange(ny + 1, dtype=float) * window
        _, extra = rasterise_lines(edges_to_segments(oblique), xs, ys, area=False)
        length += extra
    return area, length


def border_segments(region: kdb.Region, box: kdb.Box) -> Segments:
    """The outline pieces of ``region`` that lie on the edges of ``box`` (its bounding box):
    the only ones that can meet another block's outline where the two boxes just touch."""
    if region.is_empty() or box.empty():
        return Segments.empty()
    frame = kdb.Region(box) - kdb.Region(box.enlarged(-1, -1)) if box.width() > 2 and box.height() > 2 else kdb.Region(box)
    return on_box(edges_to_segments(region.edges().interacting(frame)), box)


def on_box(seg: Segments, box: kdb.Box) -> Segments:
    """The segments that lie on an edge of ``box``."""
    if len(seg) == 0:
        return seg
    a, b = seg.a, seg.b
    on = (((a[:, 0] == b[:, 0]) & ((a[:, 0] == box.left) | (a[:, 0] == box.right)))
          | ((a[:, 1] == b[:, 1]) & ((a[:, 1] == box.bottom) | (a[:, 1] == box.top))))
    return Segments(a[on], b[on])


@dataclass
class Block:
    """A merged block and what its placements need: the region, its box, its outline."""

    region: kdb.Region
    box: kdb.Box
    _segments: Segments | None = None
    _border: Segments | None = None

    def release(self) -> None:
        """Let go of the region and the outline (the border stays)."""
        self.region = kdb.Region()
        self._segments = None

    def segments(self) -> Segments:
        """The whole outline (material on the left), read out of KLayout once."""
        if self._segments is None:
            self._segments = edges_to_segments(self.region.edges())
        return self._segments

    def border(self) -> Segments:
        """The outline pieces on the block's bounding box (from the outline when it was read out, else from KLayout)."""
        if self._border is None:
            if self._segments is not None:
                self._border = on_box(self._segments, self.box)
            else:
                self._border = border_segments(self.region, self.box)
        return self._border
