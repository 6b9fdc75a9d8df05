"""The edge rasteriser and the hierarchy engine of cmpsim.layout, and (when KLayout is
installed) a cross-check of the densities against KLayout's TilingProcessor."""

from __future__ import annotations

import math

import gdstk
import numpy as np
import pytest

from cmpsim.layout import extract_windows, read_layout
from cmpsim.layout.hierarchy import CellRasters
from cmpsim.layout.raster import net_segments, rasterise


def rings(*polys):
    return [np.asarray(p, float) for p in polys]


def test_hole_slits_cancel():
    """A square with two holes (gdstk joins them with slits): area and boundary exact."""
    merged = gdstk.boolean(gdstk.rectangle((0, 0), (100, 100)),
                           [gdstk.rectangle((20, 20), (40, 40)), gdstk.rectangle((60, 55), (70, 90))], "not")
    area, length, _, _ = rasterise(net_segments([p.points for p in merged]), (0, 0), 50)
    assert area.sum() == 10000 - 400 - 350
    assert length.sum() == 400 + 80 + 90


def test_touching_pieces_and_window_edges():
    """Two squares meeting along x = 50 (a grid line): the shared edge is not boundary; an
    edge on a grid line counts half on each side."""
    seg = net_segments(rings([(0, 0), (50, 0), (50, 10), (0, 10)], [(50, 0), (100, 0), (100, 10), (50, 10)]))
    area, length, ix0, iy0 = rasterise(seg, (0, 0), 50)
    assert (ix0, iy0) == (-1, -1)
    assert area[1, 1] == 500 and area[1, 2] == 500
    assert length.sum() == 220
    assert length[0, 1] == 25 and length[1, 0] == 5 and length[1, 1] == 80


def test_oblique_edges_exact():
    """A 45-degree parallelogram over a grid line: area split exactly."""
    seg = net_segments(rings([(0, 0), (40, 0), (80, 40), (40, 40)]))
    area, length, _, _ = rasterise(seg, (0, 0), 50)
    assert area.sum() == pytest.approx(1600)
    assert area[1, 1] == pytest.approx(400 + 750)  # x < 50: 40 x 10 below y = 10, then 50 - y up to 40
    assert length.sum() == pytest.approx(80 + 2 * 40 * math.sqrt(2))


@pytest.mark.parametrize("m", [(0, -1, 1, 0), (-1, 0, 0, -1), (1, 0, 0, -1), (0, 1, 1, 0)])
def test_orientation_is_an_array_permutation(m):
    rng = np.random.default_rng(1)
    rects = [gdstk.rectangle((x, y), (x + w, y + h)) for x, y, w, h in rng.integers(0, 300, (40, 4))]
    merged = gdstk.boolean(rects, [], "or")
    seg = net_segments([p.points for p in merged])
    a0, l0, _, _ = rasterise(seg, (0, 0), 37)
    a1, l1, _, _ = rasterise(seg.oriented(m), (0, 0), 37)
    assert a1.sum() == pytest.approx(a0.sum()) and l1.sum() == pytest.approx(l0.sum())
    assert np.all(a1 >= -1e-9)


def test_stepped_block_rastered_once_per_phase():
    """A block stepped 50 x 40 at a pitch that is not a multiple of the window: the block is
    rastered once (on the 5 um grid common to its offsets, then summed into windows per
    offset), not once per placement; the result equals the flattened computation."""
    lib = gdstk.Library(unit=1e-9, precision=1e-9)
    blk = lib.new_cell("BLK")
    for k in range(100):
        blk.add(gdstk.rectangle((k * 200, 0), (k * 200 + 80, 20000), layer=1, datatype=0))
    top = lib.new_cell("TOP")
    top.add(gdstk.Reference(blk, (0, 0), columns=50, rows=40, spacing=(25000, 25000)))
    top.add(gdstk.Reference(blk, (3000, 1001000), columns=4, rows=1, spacing=(25000, 0)))
    eng = CellRasters(lib, [(1, 0)], 10000, flat_limit=0)
    area, length, ix0, iy0 = eng.raster("TOP")
    assert eng.stats["composed_cells"] == 1 and eng.stats["flat_cells"] == 1
    # the top; the block once on the 5 um grid (4 offsets); the second row at its 2 offsets
    assert eng.stats["rasters"] == 1 + 1 + 2
    assert eng.stats["zone_windows"] == 0  # 20 um blocks at 25 um pitch never meet
    assert area.sum() == pytest.approx(2004 * 100 * 80 * 20000)
    flat = CellRasters(lib, [(1, 0)], 10000, flat_limit=10**9)
    fa, fl, fx0, fy0 = flat.raster("TOP")
    assert (fx0, fy0) == (ix0, iy0)
    sl = (slice(0, fa.shape[0]), slice(0, fa.shape[1]))
    np.testing.assert_allclose(area[sl], fa, atol=1e-6)
    np.testing.assert_allclose(length[sl], fl, atol=1e-9)
    assert np.abs(area).sum() == pytest.approx(np.abs(fa).sum())


def test_klayout_cross_check(tmp_path):
    """Densities equal KLayout's TilingProcessor on a hierarchical layout (skipped without klayout)."""
    kdb = pytest.importorskip("klayout.db")
    lib = gdstk.Library(unit=1e-6, precision=1e-9)
    leaf = lib.new_cell("LEAF")
    for k in range(6):
        leaf.add(gdstk.rectangle((k * 1.5, 0), (k * 1.5 + 0.6, 9), layer=68, datatype=20))
    leaf.add(gdstk.rectangle((0, 4), (9, 5.2), layer=36, datatype=28))
    top = lib.new_cell("TOP")
    top.add(gdstk.Reference(leaf, (0, 0), columns=7, rows=5, spacing=(9.5, 9.0)))
    top.add(gdstk.Reference(leaf, (80, 3), rotation=math.pi / 2, columns=2, rows=3, spacing=(-10, 10)))
    path = tmp_path / "x.gds"
    lib.write_gds(str(path))
    res = extract_windows(path, ["68/20", "36/28"], 5e-6, flat_limit=0)
    ly = kdb.Layout()
    ly.read(str(path))
    li = ly.layer()
    for l, d in ((68, 20), (36, 28)):
        ly.copy_layer(ly.find_layer(l, d), li)
    ny, nx = res.density.shape
    out = np.zeros((ny, nx))

    class Rec(kdb.TileOutputReceiver):
        def put(self, ix, iy, tile, obj, dbu, clip):
            out[iy, ix] = obj

    tp = kdb.TilingProcessor()
    tp.input("m", ly, ly.top_cell().cell_index(), li)
    tp.dbu = ly.dbu
    tp.tile_size(5, 5)
    tp.tile_origin(res.origin[0] * 1e6, res.origin[1] * 1e6)
    tp.tiles(nx, ny)
    tp.output("o", Rec())
    tp.queue("_output(o, to_f(m.area(_tile.bbox)) / to_f(_tile.bbox.area))")
    tp.execute("density")
    np.testing.assert_allclose(res.density, out, atol=1e-12)
