"""The independent reference of the layout tests: KLayout's own flat merge of a file (no hierarchy,
nothing of cmpsim's), rasterised on the windows of an extraction."""

from __future__ import annotations

import klayout.db as kdb
import numpy as np


def klayout_flat(path, pairs, res):
    """(density per window, the merged flat region) of the (layer, datatype) ``pairs`` under the
    extraction's top cell, on the windows of ``res`` (a :class:`cmpsim.layout.LayoutWindows`)."""
    ly = kdb.Layout()
    ly.read(str(path))
    top = ly.cell(res.top)
    region = kdb.Region()
    for l, d in pairs:
        li = ly.find_layer(l, d)
        if li is not None:
            region += kdb.Region(top.begin_shapes_rec(li))
    region.merge()
    w = round(res.window / res.dbu)
    ny, nx = res.density.shape
    o = kdb.Point(round(res.origin[0] / res.dbu), round(res.origin[1] / res.dbu))
    return np.asarray(region.rasterize(o, kdb.Vector(w, w), nx, ny)) / float(w * w), region
