"""Twisted polygons: self-intersecting polygons whose signed area is zero, which KLayout's deep mode drops.

A polygon such as a bow-tie, (0,0) (0,2) (2,0) (2,2), winds once clockwise and once
anticlockwise: its signed area is zero although it covers two triangles. KLayout's flat merge
keeps both triangles (every point of non-zero winding is inside); its deep (hierarchical) store,
which the engine merges with, drops such a polygon whole when it takes it in (klayout 0.30:
``Region(iterator, DeepShapeStore)`` no longer holds it), so a window full of bow-ties would read
empty. GDSII and OASIS do not forbid these polygons and KLayout reads them as drawn.

:func:`untwist` finds them cell by cell (KLayout's raw-area filter, about 0.1 s for 300,000
shapes) and replaces each by its merged pieces, the area KLayout's flat merge gives it; a
polygon of zero merged area (a degenerate sliver) is left alone, it covers nothing either way.
Coordinates are database units.
"""

from __future__ import annotations

import klayout.db as kdb

__all__ = ["untwist"]


def _zero_area_cells(db: kdb.Layout):
    """(cell, layer index) pairs whose own shapes hold a polygon of zero signed area."""
    for cell in db.each_cell():
        for li in db.layer_indexes():
            shapes = cell.shapes(li)
            if shapes.is_empty():
                continue
            own = cell.begin_shapes_rec(li)
            own.max_depth = 0  # the cell's own shapes
            own.shape_flags = kdb.Shapes.SPolygons  # boxes and paths never twist
            raw = kdb.Region(own)
            raw.merged_semantics = False  # areas of the polygons as drawn, not of their merge
            if not raw.with_area(0, 1, False).is_empty():
                yield cell, li


def untwist(db: kdb.Layout) -> int:
    """Replace every polygon of zero signed area but positive merged area by its merged pieces,
    in place (every cell, every layer); returns how many were replaced."""
    replaced = 0
    for cell, li in list(_zero_area_cells(db)):
        shapes = cell.shapes(li)
        twisted = []
        for shape in shapes.each(kdb.Shapes.SPolygons):
            poly = shape.polygon
            if poly.area() != 0:
                continue
            merged = kdb.Region(poly).merged()
            if merged.area() > 0:
                twisted.append((shape, merged))
        for shape, merged in twisted:
            shapes.erase(shape)
            shapes.insert(merged)
            replaced += 1
    return replaced
