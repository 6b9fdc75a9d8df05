"""The layout floor on KLayout (issue 37): every hierarchy feature a tape-out has, each checked
against an independent flat computation: KLayout's own flat merge of the same file (no hierarchy,
no code of cmpsim's) and, where the shapes are generated here, their exact areas.

Layouts are written here with gdstk (a writer independent of the engine under test) or with
KLayout where only KLayout writes the feature (PCell context cells, OASIS CBLOCKs, strict mode);
one real tape-out ships in tests/data (tests/data/NOTICE.md).
"""

from __future__ import annotations

import gzip
import math
import shutil
import subprocess
import sys
from pathlib import Path

import gdstk
import klayout.db as kdb
import numpy as np
import pytest
from click.testing import CliRunner
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from cmpsim.cli import main
from klayout_reference import klayout_flat
from cmpsim.layout import LayoutTooLarge, extract_levels, extract_windows, read_layout, top_cell

UM = 1e-6
DATA = Path(__file__).parent / "data"
REAL = DATA / "sg13g2_FMD_QNC_OTA_TIA.gds.gz"


# ------------------------------------------------------------------------ a randomised hierarchy
@st.composite
def hierarchies(draw):
    """A leaf of random rectangles, a block of arrays of the leaf in random orientations (placements
    overlapping and abutting), a die of arrays of the block and of the leaf, and own shapes."""
    lib = gdstk.Library(unit=1e-6, precision=1e-9)
    leaf = lib.new_cell("LEAF")
    for k in range(draw(st.integers(2, 7))):
        x0 = draw(st.integers(0, 60)) * 0.05
        y0 = draw(st.integers(0, 60)) * 0.05
        w = draw(st.integers(1, 40)) * 0.05
        h = draw(st.integers(1, 40)) * 0.05
        layer = [(68, 20), (36, 28)][k] if k < 2 else draw(st.sampled_from([(68, 20), (36, 28)]))
        leaf.add(gdstk.rectangle((x0, y0), (x0 + w, y0 + h), layer=layer[0], datatype=layer[1]))
    block = lib.new_cell("BLOCK")
    for _ in range(draw(st.integers(1, 4))):
        rot = draw(st.integers(0, 3)) * math.pi / 2
        mirror = draw(st.booleans())
        cols, rows = draw(st.integers(1, 6)), draw(st.integers(1, 6))
        sx = draw(st.integers(20, 70)) * 0.05  # at most 3.5 um: placements of a 3-5 um leaf overlap or abut
        sy = draw(st.integers(20, 70)) * 0.05
        ox, oy = draw(st.integers(0, 200)) * 0.05, draw(st.integers(0, 200)) * 0.05
        block.add(gdstk.Reference(leaf, (ox, oy), rotation=rot, x_reflection=mirror, columns=cols, rows=rows, spacing=(sx, sy)))
    top = lib.new_cell("TOP")
    bx, by = draw(st.integers(200, 500)) * 0.05, draw(st.integers(200, 500)) * 0.05  # overlapping or apart
    top.add(gdstk.Reference(block, (0, 0), columns=draw(st.integers(1, 4)), rows=draw(st.integers(1, 3)), spacing=(bx, by)))
    top.add(gdstk.Reference(block, (draw(st.integers(0, 400)) * 0.05, 3.0), rotation=draw(st.integers(0, 3)) * math.pi / 2,
                            x_reflection=draw(st.booleans())))
    if draw(st.booleans()):
        top.add(gdstk.rectangle((1.0, 1.0), (30.0, 2.0), layer=68, datatype=20))  # a rail over everything
    window = draw(st.integers(40, 160)) * 0.05 * UM
    return lib, window


@settings(max_examples=25, deadline=None, suppress_health_check=[HealthCheck.function_scoped_fixture, HealthCheck.too_slow])
@given(case=hierarchies())
def test_random_hierarchies_equal_klayouts_flat_merge(tmp_path, case):
    """Random arrays, orientations and overlapping placements: the densities equal KLayout's flat merge
    (to float rounding) whether every placement is composed (big=0) or the engine chooses; composed and
    flat give the same boundary, width and space."""
    lib, window = case
    path = tmp_path / "random.gds"
    lib.write_gds(str(path))
    lay = read_layout(path)
    try:
        comp = extract_windows(lay, ["68/20", "36/28"], window, big=0)
    except ValueError as exc:  # a die smaller than the window is refused, by name
        assert "--window" in str(exc)
        return
    flat = extract_windows(lay, ["68/20", "36/28"], window, big=10**9)
    auto = extract_windows(lay, ["68/20", "36/28"], window)
    ref, region = klayout_flat(path, [(68, 20), (36, 28)], comp)
    for r in (comp, flat, auto):
        np.testing.assert_allclose(r.density, ref, atol=1e-12)
    np.testing.assert_allclose(comp.boundary, flat.boundary, rtol=1e-9, atol=1e-15)
    np.testing.assert_allclose(comp.width, flat.width, rtol=1e-9, atol=1e-15)
    # the outline of the merged shapes: every window's boundary adds up to KLayout's edge length, less the
    # halves of the outline on the die's border that fall outside the grid
    total = comp.boundary.sum() / comp.dbu
    assert total <= region.edges().length() + 1e-6


# ------------------------------------------------------------------------ each feature
def _lib_with(features):
    lib = gdstk.Library(unit=1e-6, precision=1e-9)
    leaf = lib.new_cell("LEAF")
    leaf.add(gdstk.rectangle((0, 0), (4, 0.5), layer=68, datatype=20))   # rail, shared with the row above
    leaf.add(gdstk.rectangle((0, 3.5), (4, 4.0), layer=68, datatype=20))
    leaf.add(gdstk.rectangle((1, 1), (1.5, 3), layer=68, datatype=20))
    top = lib.new_cell("TOP")
    if "rows" in features:  # standard-cell rows: abutting cells, every other row mirrored, rails overlapping
        for r in range(6):
            top.add(gdstk.Reference(leaf, (0, r * 3.75 + (4.0 if r % 2 else 0)), x_reflection=bool(r % 2), columns=12, rows=1,
                                    spacing=(4.0, 0)))
    if "magnified" in features:
        top.add(gdstk.Reference(leaf, (60, 5), magnification=2.5))
    if "oblique" in features:
        top.add(gdstk.Reference(leaf, (60, 30), rotation=math.radians(45)))
        top.add(gdstk.Polygon([(70, 40), (80, 40), (85, 45), (75, 45)], layer=68, datatype=20))
    if "path" in features:
        top.add(gdstk.FlexPath([(50, 50), (90, 50), (90, 70)], 1.0, layer=68, datatype=20))
        top.add(gdstk.Label("VDD", (51, 50), layer=68, texttype=20))  # a text on the layer: never a shape
    if "properties" in features:
        poly = gdstk.rectangle((40, 60), (45, 70), layer=68, datatype=20)
        poly.set_gds_property(1, "net VSS")
        top.add(poly)
    return lib


@pytest.mark.parametrize("features", [("rows",), ("rows", "magnified"), ("oblique",), ("rows", "path", "properties"),
                                      ("rows", "magnified", "oblique", "path", "properties")])
def test_each_hierarchy_feature_equals_klayouts_flat_merge(tmp_path, features):
    lib = _lib_with(features)
    path = tmp_path / "chip.gds"
    lib.write_gds(str(path))
    for big in (0, None):
        res = extract_windows(path, "68/20", 5 * UM, big=big)
        ref, _ = klayout_flat(path, [(68, 20)], res)
        np.testing.assert_allclose(res.density, ref, atol=1e-12)
        assert res.density.max() > 0.05


def test_standard_cell_rows_exact_area(tmp_path):
    """Exact areas of generated shapes: six rows of twelve abutting cells at a row pitch of 3.75 um,
    so that each row's top rail (3.5-4 um) overlaps the next row's bottom rail by 0.25 um over 48 um."""
    lib = gdstk.Library(unit=1e-6, precision=1e-9)
    leaf = lib.new_cell("LEAF")
    leaf.add(gdstk.rectangle((0, 0), (4, 0.5), layer=68, datatype=20))
    leaf.add(gdstk.rectangle((0, 3.5), (4, 4.0), layer=68, datatype=20))
    leaf.add(gdstk.rectangle((1, 1), (1.5, 3), layer=68, datatype=20))
    top = lib.new_cell("TOP")
    top.add(gdstk.Reference(leaf, (0, 0), columns=12, rows=6, spacing=(4.0, 3.75)))
    path = tmp_path / "rows.gds"
    lib.write_gds(str(path))
    per_row = 2 * 48 * 0.5 + 12 * 0.5 * 2
    exact = 6 * per_row - 5 * 0.25 * 48  # um^2
    for big in (0, None, 10**9):
        res = extract_windows(path, "68/20", 4 * UM, big=big)
        assert res.density.sum() * (res.window / UM) ** 2 == pytest.approx(exact, rel=1e-12)
        ref, _ = klayout_flat(path, [(68, 20)], res)
        np.testing.assert_allclose(res.density, ref, atol=1e-12)


def test_pcell_context_cell_is_not_a_top_cell(tmp_path):
    """A file written by KLayout with a PCell instance carries $$$CONTEXT_INFO$$$; read in another
    process (where the PCell's library is unknown) the die is still the one top cell."""
    script = r"""
import sys
import klayout.db as kdb
class Bar(kdb.PCellDeclarationHelper):
    def __init__(self):
        super().__init__()
        self.param("w", self.TypeDouble, "width", default=2.0)
        self.param("l", self.TypeLayer, "layer", default=kdb.LayerInfo(68, 20))
    def produce_impl(self):
        self.cell.shapes(self.l_layer).insert(kdb.DBox(0, 0, self.w, 10.0))
lib = kdb.Library(); lib.description = "test"; lib.layout().register_pcell("Bar", Bar()); lib.register("CMPSIM_TEST")
ly = kdb.Layout(); ly.dbu = 0.001
top = ly.create_cell("DIE")
top.shapes(ly.layer(68, 20)).insert(kdb.Box(0, 0, 40000, 1000))
pc = ly.create_cell("Bar", "CMPSIM_TEST", {"w": 3.0})
top.insert(kdb.CellInstArray(pc.cell_index(), kdb.Trans(5000, 5000)))
ly.write(sys.argv[1])
"""
    path = tmp_path / "pcell.gds"
    subprocess.run([sys.executable, "-c", script, str(path)], check=True)
    assert b"$$$CONTEXT_INFO$$$" in path.read_bytes()
    lay = read_layout(path)
    assert top_cell(lay).name == "DIE"
    res = extract_windows(lay, "68/20", 10 * UM)
    assert res.density.sum() * res.window**2 == pytest.approx((40 * 1 + 3 * 10) * UM**2, rel=1e-12)


def test_oasis_cblocks_strict_and_gzip_read_alike(tmp_path):
    lib = _lib_with(("rows", "oblique"))
    gds = tmp_path / "chip.gds"
    lib.write_gds(str(gds))
    ly = kdb.Layout()
    ly.read(str(gds))
    opts = kdb.SaveLayoutOptions()
    opts.format = "OASIS"
    opts.oasis_write_cblocks = True
    opts.oasis_strict_mode = True
    opts.oasis_compression_level = 10
    oas = tmp_path / "chip.oas"
    ly.write(str(oas), opts)
    gz = tmp_path / "chip.gds.gz"
    with open(gds, "rb") as src, gzip.open(gz, "wb") as dst:
        shutil.copyfileobj(src, dst)
    ref = extract_windows(gds, "68/20", 5 * UM)
    for p, fmt in ((oas, "oas"), (gz, "gds.gz")):
        assert read_layout(p).format == fmt
        res = extract_windows(p, "68/20", 5 * UM)
        np.testing.assert_allclose(res.density, ref.density, atol=1e-12)
        np.testing.assert_allclose(res.width, ref.width, rtol=1e-12)


# ------------------------------------------------------------------------ a real tape-out
def test_real_tapeout_with_a_context_cell():
    """IHP SG13G2, written by KLayout with $$$CONTEXT_INFO$$$: one die, Metal1 drawn + fill (8/0, 8/22)
    equal to KLayout's flat merge; the stack of every metal on one read."""
    lay = read_layout(REAL)
    assert top_cell(lay).name == "DiffAmp_NOFILL"
    res = extract_windows(lay, "metal1", 20 * UM, pdk="sg13g2")
    ref, _ = klayout_flat(REAL, [(8, 0), (8, 22)], res)
    np.testing.assert_allclose(res.density, ref, atol=1e-12)
    levels = extract_levels(lay, ["metal1", "metal2", "metal3", "topmetal1"], 20 * UM, pdk="sg13g2")
    np.testing.assert_allclose(levels[0].density, res.density, atol=0)
    assert all(lv.density.shape == res.density.shape for lv in levels)


def test_real_tapeout_cli_with_progress_and_no_traceback(tmp_path):
    out = tmp_path / "die"
    r = CliRunner().invoke(main, ["die", str(REAL), "--layer", "metal1", "--pdk", "sg13g2", "--blanket-rate", "200nm/min",
                                  "--spec", "thickness=5nm", "--out", str(out), "--json"])
    assert r.exit_code == 0, r.output
    assert (out / "hotspots.lyrdb").is_file() and (out / "die.nc").is_file()


# ------------------------------------------------------------------------ limits and bad input
def test_progress_is_told(tmp_path):
    lib = _lib_with(("rows",))
    path = tmp_path / "chip.gds"
    lib.write_gds(str(path))
    seen = []
    extract_windows(path, "68/20", 5 * UM, progress=lambda stage, done, total: seen.append((stage, done, total)))
    assert seen and seen[-1][1] == seen[-1][2]


def test_too_many_windows_is_refused_naming_the_window(tmp_path, monkeypatch):
    import cmpsim.layout.extract as ex

    lib = _lib_with(("rows",))
    path = tmp_path / "chip.gds"
    lib.write_gds(str(path))
    monkeypatch.setattr(ex, "MAX_WINDOWS", 50)
    with pytest.raises(LayoutTooLarge, match=r"--window.*larger --window"):
        extract_windows(path, "68/20", 1 * UM)
    out = tmp_path / "never"
    r = CliRunner().invoke(main, ["die", str(path), "--layer", "68/20", "--window", "1um", "--blanket-rate", "100nm/min",
                                  "--out", str(out)])
    assert r.exit_code == 2 and "--window" in r.output and "Traceback" not in r.output
    assert not out.exists()


def test_several_top_cells_cli_names_top(tmp_path):
    lib = _lib_with(("rows",))
    lib.new_cell("SPARE").add(gdstk.rectangle((0, 0), (1, 1), layer=68, datatype=20))
    path = tmp_path / "two.gds"
    lib.write_gds(str(path))
    out = tmp_path / "never"
    r = CliRunner().invoke(main, ["die", str(path), "--layer", "68/20", "--blanket-rate", "100nm/min", "--out", str(out)])
    assert r.exit_code == 2 and "--top" in r.output and "['SPARE', 'TOP']" in r.output
    assert not out.exists()


def test_a_cell_placed_twice_on_the_same_spot_counts_once(tmp_path):
    """Real tape-outs place a cell twice at one spot (an SG13G2 test chip does, on Metal3): KLayout's deep
    merge keeps both copies of the merged polygons, one per placement; the engine merges them once more."""
    lib = gdstk.Library(unit=1e-6, precision=1e-9)
    sub = lib.new_cell("SUB")
    sub.add(gdstk.rectangle((0, 0), (6, 2), layer=30, datatype=0))
    mid = lib.new_cell("MID")
    mid.add(gdstk.Reference(sub, (5, 5)))
    top = lib.new_cell("TOP")
    top.add(gdstk.Reference(mid, (0, 0)))
    top.add(gdstk.Reference(mid, (0, 0)))  # the duplicate
    top.add(gdstk.Reference(sub, (5, 5)))  # and the same shapes once more, through another path
    top.add(gdstk.rectangle((0, 0), (40, 40), layer=1, datatype=0))
    path = tmp_path / "dup.gds"
    lib.write_gds(str(path))
    for big in (0, None, 10**9):
        res = extract_windows(path, "30/0", 20 * UM, big=big)
        assert res.density.sum() * (res.window / UM) ** 2 == pytest.approx(12.0, rel=1e-12)
        assert res.boundary.sum() / UM == pytest.approx(16.0, rel=1e-12)


def test_a_seam_that_cancels_part_of_a_longer_edge_is_taken_out(tmp_path):
    """Found by the random hierarchies: two placements abut, and along their seam one layer's edge
    (36/28, 50 dbu) meets part of another's (68/20, 150 dbu). The seam's cancellation leaves as many
    pieces as there were (two stubs of the longer edge), which an early exit read as "nothing
    cancelled": the composed boundary was 100 dbu too long. Composed, flat and KLayout agree now."""
    ly = kdb.Layout()
    ly.dbu = 0.001
    l1, l2 = ly.layer(68, 20), ly.layer(36, 28)
    leaf, block, top = ly.create_cell("LEAF"), ly.create_cell("BLOCK"), ly.create_cell("TOP")
    leaf.shapes(l1).insert(kdb.Box(0, 0, 150, 50))
    leaf.shapes(l2).insert(kdb.Box(50, 1500, 100, 3500))
    block.insert(kdb.CellInstArray(leaf.cell_index(), kdb.Trans(kdb.Trans.R90, 0, 0), kdb.Vector(-3500, 0), kdb.Vector(0, 1000), 2, 1))
    top.insert(kdb.CellInstArray(block.cell_index(), kdb.Trans(0, 0)))
    top.insert(kdb.CellInstArray(block.cell_index(), kdb.Trans(0, 3000)))
    path = tmp_path / "seam.gds"
    ly.write(str(path))
    comp = extract_windows(path, ["68/20", "36/28"], 2 * UM, big=0)
    flat = extract_windows(path, ["68/20", "36/28"], 2 * UM, big=10**9)
    np.testing.assert_allclose(comp.boundary, flat.boundary, rtol=1e-12, atol=1e-18)
    _, region = klayout_flat(path, [(68, 20), (36, 28)], comp)
    # KLayout's outline, less the halves of the outline on the die's border that fall outside the grid (100 dbu here)
    assert comp.boundary.sum() / comp.dbu == pytest.approx(region.edges().length() - 100, abs=1e-6)
