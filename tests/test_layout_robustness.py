"""Odd but legal layouts found by the robustness sweep (docs/layouts.md, "Robustness"): each built
here with KLayout, each checked against KLayout's flat merge of the same file or against an exact
area, and the messages of what cannot be extracted."""

from __future__ import annotations

import klayout.db as kdb
import numpy as np
import pytest
from klayout_reference import klayout_flat

from cmpsim.layout import extract_levels, extract_windows, read_layout

UM = 1e-6
MAX = 2**31 - 1  # KLayout's largest coordinate (dbu)


def _polygon(points) -> kdb.Polygon:
    poly = kdb.Polygon()
    poly.assign_hull([kdb.Point(x, y) for x, y in points], False)  # as drawn: no normalisation
    return poly


def _write(ly: kdb.Layout, path) -> str:
    ly.write(str(path))
    return str(path)


def test_bow_ties_count_as_klayouts_flat_merge(tmp_path):
    """A self-intersecting polygon of zero signed area (a bow-tie: two triangles of 100 um^2, wound in
    opposite senses) in a cell arrayed 3 x 2 and once in the top cell: KLayout's deep store drops it
    whole; the extraction keeps both triangles, as KLayout's flat merge does."""
    ly = kdb.Layout()
    ly.dbu = 0.001
    l1 = ly.layer(1, 0)
    top, leaf = ly.create_cell("TOP"), ly.create_cell("LEAF")
    bow = _polygon([(0, 0), (0, 20000), (20000, 0), (20000, 20000)])
    leaf.shapes(l1).insert(bow)
    leaf.shapes(l1).insert(kdb.Box(0, 25000, 20000, 27000))
    top.insert(kdb.CellInstArray(leaf.cell_index(), kdb.Trans(kdb.Vector(0, 0)), kdb.Vector(30000, 0), kdb.Vector(0, 30000), 3, 2))
    top.shapes(l1).insert(bow.moved(100000, 0))
    path = _write(ly, tmp_path / "bowtie.gds")
    assert read_layout(path).db.cell("LEAF").shapes(read_layout(path).db.layer(1, 0)).size() == 2
    for big in (0, None):
        res = extract_windows(path, "1/0", 5 * UM, big=big)
        ref, _ = klayout_flat(path, [(1, 0)], res)
        np.testing.assert_allclose(res.density, ref, atol=1e-12)
        exact = 7 * 2 * 100e6 + 6 * 40e6  # dbu^2: seven bow-ties of two triangles, six bars
        assert res.density.sum() * 5000**2 == pytest.approx(exact, rel=1e-12)


@pytest.mark.parametrize("corner", ["max", "min"])
def test_a_die_at_the_ends_of_klayouts_coordinates(tmp_path, corner):
    """A die drawn against +-2**31 dbu (a grid reaching past KLayout's 32-bit coordinates: its rasteriser
    read zero there): the same windows as the same die moved to the origin, flat and composed."""
    def die(at: int) -> kdb.Layout:
        ly = kdb.Layout()
        ly.dbu = 0.001
        l1 = ly.layer(1, 0)
        top, leaf = ly.create_cell("TOP"), ly.create_cell("LEAF")
        leaf.shapes(l1).insert(kdb.Box(0, 0, 21000, 20000))
        leaf.shapes(l1).insert(_polygon([(0, 22000), (20000, 22000), (0, 31000)]))
        top.insert(kdb.CellInstArray(leaf.cell_index(), kdb.Trans(kdb.Vector(at + 3, at + 7)), kdb.Vector(33001, 0), kdb.Vector(0, 32003), 3, 2))
        top.shapes(l1).insert(kdb.Box(at, at, at + 99003 + 7, at + 1000))  # the die's corner, 7 dbu past the last leaf
        return ly

    at = MAX - 99011 if corner == "max" else -MAX - 1
    far = _write(die(at), tmp_path / "far.gds")
    near = _write(die(0), tmp_path / "near.gds")
    assert read_layout(far).db.top_cell().bbox().right == (MAX - 1 if corner == "max" else -MAX + 99009)
    for big in (0, None):
        a = extract_windows(far, "1/0", 5 * UM, big=big)
        b = extract_windows(near, "1/0", 5 * UM, big=big)
        np.testing.assert_allclose(a.density, b.density, atol=1e-12)
        np.testing.assert_allclose(a.boundary, b.boundary, rtol=1e-12, atol=1e-15)
        assert a.density.max() > 0.5
    if corner == "max":  # one dbu further: KLayout's merge does not finish with a shape on 2**31 - 1
        with pytest.raises(ValueError, match=r"shapes reach 2147483647 dbu in x, KLayout's largest coordinate .* move the die"):
            extract_windows(_write(die(at + 1), tmp_path / "limit.gds"), "1/0", 5 * UM)


def test_a_file_without_shapes_says_so(tmp_path):
    """An empty top cell, or one with texts only: the message says the file holds no shapes (not an empty list)."""
    ly = kdb.Layout()
    top = ly.create_cell("TOP")
    top.shapes(ly.layer(1, 0)).insert(kdb.Text("VDD", 0, 0))
    path = _write(ly, tmp_path / "texts.gds")
    with pytest.raises(ValueError, match=r"--layer '1/0' .* its layers are: none \(the file holds no shapes"):
        extract_windows(path, "1/0", 5 * UM)


def test_a_library_of_unused_cells_lists_ten_names(tmp_path):
    """Three hundred uninstantiated cells are three hundred top cells: the message lists ten and names --top."""
    ly = kdb.Layout()
    for k in range(300):
        ly.create_cell(f"LIB_{k:03d}").shapes(ly.layer(1, 0)).insert(kdb.Box(0, 0, 30000, 30000))
    path = _write(ly, tmp_path / "library.gds")
    with pytest.raises(ValueError, match=r"300 top-level cells \['LIB_000', .*'LIB_009', \.\.\. and 290 more\]: choose the die with --top") as err:
        extract_windows(path, "1/0", 5 * UM)
    assert len(str(err.value)) < 400
    res = extract_windows(path, "1/0", 5 * UM, top="LIB_123")
    assert res.density.min() == 1.0


def test_a_window_off_the_database_unit_names_window(tmp_path):
    ly = kdb.Layout()
    ly.dbu = 0.005
    ly.create_cell("TOP").shapes(ly.layer(1, 0)).insert(kdb.Box(0, 0, 10000, 10000))
    path = _write(ly, tmp_path / "dbu5nm.gds")
    with pytest.raises(ValueError, match=r"--window = 5.002e-06 m is not a whole number of database units: it must be a multiple .* 5e-09 m"):
        extract_levels(path, ["1/0"], 5.002 * UM)
    assert extract_windows(path, "1/0", 5 * UM).density.shape == (10, 10)


def test_a_stack_level_without_its_layers_is_named(tmp_path):
    """A stack whose second level names a layer the file lacks: the message names the level (the stack
    file's name for it, else its number), not only the layer."""
    ly = kdb.Layout()
    ly.create_cell("TOP").shapes(ly.layer(1, 0)).insert(kdb.Box(0, 0, 10000, 10000))
    path = _write(ly, tmp_path / "one_layer.gds")
    with pytest.raises(ValueError, match=r"^level 'm2' of 2: --layer '99/0' \(99/0\) is not in one_layer.gds; its layers are: 1/0"):
        extract_levels(path, ["1/0", "99/0"], 5 * UM, names=["m1", "m2"])
    with pytest.raises(ValueError, match=r"^level 2 of 2: --layer '99/0'"):
        extract_levels(path, ["1/0", "99/0"], 5 * UM)


def test_a_recursive_hierarchy_is_named(tmp_path):
    """A corrupt file whose cell A places B and B places A: refused naming the recursion (KLayout's own words were an internal
    error about a topological sort)."""
    gdstk = pytest.importorskip("gdstk")  # KLayout will not write such a file
    lib = gdstk.Library(unit=1e-6, precision=1e-9)
    a, b, top = lib.new_cell("A"), lib.new_cell("B"), lib.new_cell("TOP")
    a.add(gdstk.rectangle((0, 0), (10, 10), layer=1), gdstk.Reference("B", (20, 0)))
    b.add(gdstk.rectangle((0, 0), (5, 5), layer=1), gdstk.Reference("A", (0, 20)))
    top.add(gdstk.Reference("A", (0, 0)))
    path = tmp_path / "recursive.gds"
    lib.write_gds(str(path))
    with pytest.raises(ValueError, match=r"recursive.gds' has a recursive cell hierarchy \(a cell placed inside itself"):
        read_layout(path)


def test_cmpsim_die_without_a_layer_lists_the_files_layers(tmp_path):
    """A newcomer's first try on a layout, `cmpsim die CHIP.gds`, is told which layers carry shapes (exit 2)."""
    from click.testing import CliRunner

    from cmpsim.cli import main

    ly = kdb.Layout()
    top = ly.create_cell("TOP")
    top.shapes(ly.layer(8, 0)).insert(kdb.Box(0, 0, 10000, 10000))
    top.shapes(ly.layer(10, 22)).insert(kdb.Box(0, 0, 5000, 5000))
    top.shapes(ly.layer(63, 0)).insert(kdb.Text("label", 0, 0))
    path = _write(ly, tmp_path / "chip.gds")
    res = CliRunner().invoke(main, ["die", path, "--out", str(tmp_path / "out")])
    assert res.exit_code == 2
    said = " ".join(res.output.split())
    assert "needs --layer" in said and said.rstrip().endswith("chip.gds's layers with shapes: 8/0, 10/22")  # the text layer is not one
    assert not (tmp_path / "out").exists()


def _leaf_in_top(at=(0, 0), trans=None, leaf_box=(0, 0, 1000, 1000)):
    """TOP (a 100 um square) placing LEAF (a box) once, by ``trans`` (a KLayout transformation) or at ``at``."""
    ly = kdb.Layout()
    ly.dbu = 0.001
    l1 = ly.layer(1, 0)
    top, leaf = ly.create_cell("TOP"), ly.create_cell("LEAF")
    leaf.shapes(l1).insert(kdb.Box(*leaf_box))
    top.shapes(l1).insert(kdb.Box(0, 0, 100000, 100000))
    return ly, top, leaf


@pytest.mark.parametrize("case", ["magnified", "translated", "wrapped", "array"])
def test_a_placement_past_klayouts_coordinates_is_named(tmp_path, case):
    """Placements whose shapes land past 2**31 dbu, legal in GDSII/OASIS: KLayout's boxes overflow there. A magnified one
    came out at -2**31 (a traceback from KLayout's merge, or a 2 m die of 11 billion windows); a translated one wrapped round
    and was dropped from the die's box, its shapes silently left out (density 1.0 over the 100 um square alone). Refused,
    naming the placement; --top the cell it places is still extracted."""
    ly, top, leaf = _leaf_in_top(leaf_box=(0, 0, 1_500_000_000, 2_000_000) if case == "translated" else (0, 0, 1000, 1000))
    place = {"magnified": kdb.CellInstArray(leaf.cell_index(), kdb.ICplxTrans(5e6, 0, False, 0, 0)),
             "translated": kdb.CellInstArray(leaf.cell_index(), kdb.Trans(1_500_000_000, 0)),
             "wrapped": kdb.CellInstArray(leaf.cell_index(), kdb.Trans(MAX - 999, 0)),  # its right edge on 2**31
             "array": kdb.CellInstArray(leaf.cell_index(), kdb.Trans(), kdb.Vector(1_100_000_000, 0), kdb.Vector(0, 2000), 3, 2)}[case]
    top.insert(place)
    options = kdb.SaveLayoutOptions()
    options.format = "OASIS"  # GDSII cannot hold the array's corners
    path = str(tmp_path / "far.oas")
    ly.write(path, options)
    reach = {"magnified": "5,000,000,000", "translated": "3,000,000,000", "wrapped": "2,147,483,648", "array": "2,200,001,000"}[case]
    with pytest.raises(ValueError, match=rf"far.oas: the placement of cell 'LEAF' in 'TOP' at .* puts shapes {reach} dbu from the origin "
                                         r".* past KLayout's 32-bit coordinates .* choose a cell below it with --top, or fix the placement"):
        extract_windows(path, "1/0", 20 * UM)
    assert extract_windows(path, "1/0", 1 * UM if case != "translated" else 1000 * UM, top="LEAF").density.max() == 1.0
    ly2, top2, leaf2 = _leaf_in_top()
    top2.insert(kdb.CellInstArray(leaf2.cell_index(), kdb.Trans(MAX - 1000, 0)))  # one dbu short of the wrap: not this check's
    ly2.write(str(tmp_path / "near.oas"), options)
    with pytest.raises(ValueError, match=r"shapes reach 2147483647 dbu in x, KLayout's largest coordinate"):
        extract_windows(str(tmp_path / "near.oas"), "1/0", 20 * UM)


def test_top_a_ghost_cell_says_it_is_not_defined(tmp_path):
    """--top a cell the file places but does not define: the message says so (it said the layer was drawn under other top cells)."""
    ly, top, _ = _leaf_in_top()
    ghost = ly.create_cell("GHOST")
    top.insert(kdb.CellInstArray(ghost.cell_index(), kdb.Trans(50000, 50000)))
    ghost.ghost_cell = True
    path = _write(ly, tmp_path / "ghost.gds")
    with pytest.raises(ValueError, match=r"^--top 'GHOST': ghost.gds places this cell but does not define it \(a ghost cell, without shapes\); "
                                         r"its top-level cells are \['LEAF', 'TOP'\]"):
        extract_windows(path, "1/0", 5 * UM, top="GHOST")
    assert extract_windows(path, "1/0", 5 * UM, top="TOP").density.min() == 1.0
    one = kdb.Layout()
    one.create_cell("TOP").shapes(one.layer(1, 0)).insert(kdb.Box(0, 0, 10000, 10000))
    with pytest.raises(ValueError, match=r"--top 'NOPE': no such cell in one.gds; its top-level cells are \['TOP'\] \(1 cell in all\)$"):
        extract_windows(_write(one, tmp_path / "one.gds"), "1/0", 5 * UM, top="NOPE")  # said "(1 cells in all)"


def test_a_gzipped_oasis_is_read_and_a_directory_named(tmp_path):
    """KLayout reads gzipped OASIS (.oas.gz): so does the extraction (it was refused as "not gzipped GDSII"), the same windows
    as the plain file; a directory given as the layout is called one (it was said not to exist)."""
    import gzip

    ly, top, leaf = _leaf_in_top()
    top.insert(kdb.CellInstArray(leaf.cell_index(), kdb.ICplxTrans(1.5, 30, True, 150000, 0), kdb.Vector(3000, 0), kdb.Vector(0, 3000), 9, 7))
    options = kdb.SaveLayoutOptions()
    options.format = "OASIS"
    plain = str(tmp_path / "chip.oas")
    ly.write(plain, options)
    zipped = tmp_path / "chip.oas.gz"
    zipped.write_bytes(gzip.compress((tmp_path / "chip.oas").read_bytes()))
    assert read_layout(zipped).format == "oas.gz"
    a, b = extract_windows(plain, "1/0", 5 * UM), extract_windows(zipped, "1/0", 5 * UM)
    np.testing.assert_array_equal(a.density, b.density)
    ref, _ = klayout_flat(zipped, [(1, 0)], b)
    np.testing.assert_allclose(b.density, ref, atol=1e-12)
    (tmp_path / "dir.gds").mkdir()
    with pytest.raises(ValueError, match=r"layout path .*dir.gds' is a directory: give the layout file in it"):
        read_layout(tmp_path / "dir.gds")


def test_a_layout_that_cannot_be_opened_is_named(tmp_path, monkeypatch):
    """A file without read permission (the suite may run as root, where chmod does not stop a read: the open is made to fail as it
    would): exit-2 material naming the path, not a PermissionError's traceback."""
    from cmpsim.layout import reader

    path = tmp_path / "locked.gds"
    path.write_bytes(b"\x00\x06\x00\x02\x02\x58")

    def denied(*args, **kwargs):
        raise PermissionError(13, "Permission denied")

    monkeypatch.setattr(reader, "open", denied, raising=False)
    with pytest.raises(ValueError, match=r"layout path .*locked.gds' cannot be opened \(Permission denied\): check that it is a readable file"):
        read_layout(path)


def test_a_large_array_of_a_small_cell_is_cut_into_tiles(tmp_path):
    """A fill array of small squares was merged flat, every square held by KLayout: 1000 x 1000 took 22 s and 0.9 GB,
    a 20 mm chip's 10,000 x 10,000 would have needed about 80 GB. Such arrays are now cut into tiles (cells of k x k
    elements, placed many times like any big cell): KLayout's flat merge gives the same windows, the layout is given
    back unchanged, and the 10^8 squares take well under a second."""
    ly = kdb.Layout()
    ly.dbu = 0.001
    l1 = ly.layer(1, 0)
    top, sq, tri = ly.create_cell("TOP"), ly.create_cell("SQUARE"), ly.create_cell("TRIANGLE")
    sq.shapes(l1).insert(kdb.Box(0, 0, 1000, 1000))
    tri.shapes(l1).insert(_polygon([(0, 0), (1500, 0), (0, 1500)]))
    # rotated and mirrored, tiles left over at the far edges, negative pitch, squares that abut (pitch = size), a top-level shape across
    top.insert(kdb.CellInstArray(sq.cell_index(), kdb.Trans(1, True, 3000, 7000), kdb.Vector(2000, 0), kdb.Vector(0, -1900), 133, 71))
    top.insert(kdb.CellInstArray(sq.cell_index(), kdb.Trans(300000, 0), kdb.Vector(1000, 0), kdb.Vector(0, 2500), 90, 61))
    top.insert(kdb.CellInstArray(tri.cell_index(), kdb.Trans(3, False, 0, 10000), kdb.Vector(-2000, 0), kdb.Vector(0, 2000), 64, 80))
    top.shapes(l1).insert(kdb.Box(-150000, 0, 400000, 3000))
    path = _write(ly, tmp_path / "fill.gds")
    layout = read_layout(path)
    cells = sorted(c.name for c in layout.db.each_cell())
    for window in (5 * UM, 20 * UM):
        stats = {}
        res = extract_windows(layout, "1/0", window, stats=stats)
        ref, _ = klayout_flat(path, [(1, 0)], res)
        np.testing.assert_allclose(res.density, ref, atol=1e-12)
        assert not stats["flat"] and stats["placements"] < 2000  # tiles, not 20,000 squares
        flat = extract_windows(layout, "1/0", window, big=10**9)
        np.testing.assert_allclose(res.boundary, flat.boundary, rtol=1e-9, atol=1e-15)
    assert sorted(c.name for c in layout.db.each_cell()) == cells

    chip = kdb.Layout()
    chip.dbu = 0.001
    top, sq = chip.create_cell("CHIP"), chip.create_cell("FILL")
    sq.shapes(chip.layer(1, 0)).insert(kdb.Box(0, 0, 1000, 1000))
    top.insert(kdb.CellInstArray(sq.cell_index(), kdb.Trans(), kdb.Vector(2000, 0), kdb.Vector(0, 2000), 10_000, 10_000))
    res = extract_windows(_write(chip, tmp_path / "chip.gds"), "1/0", 100 * UM)
    assert res.density.shape == (200, 200) and np.all(res.density == 0.25)  # 50 x 50 squares of 1 um^2 in (100 um)^2


def test_a_grid_larger_than_the_machines_memory_is_refused(tmp_path, monkeypatch):
    """`cmpsim die` holds about 700 bytes a window (11.1 GB for 15.8 million): the 25 million windows allowed needed about
    17.5 GB, so a smaller machine was killed or swapped instead of refusing. The limit now follows the machine's memory
    (here made 1 GiB: 1.34 million windows), naming --window and the least window that fits."""
    import cmpsim.layout.extract as ex

    ly = kdb.Layout()
    ly.dbu = 0.001
    ly.create_cell("TOP").shapes(ly.layer(1, 0)).insert(kdb.Box(0, 0, 12_000_000, 12_000_000))
    path = _write(ly, tmp_path / "chip.gds")
    monkeypatch.setattr(ex, "_physical_memory", lambda: 2**30)
    with pytest.raises(ex.LayoutTooLarge, match=r"into 1200 x 1200 = 1,440,000 windows, more than the 1,342,177 this machine's memory "
                                                r"\(its 1.0 GiB at about 800 bytes a window\) is sized for: choose a larger --window \(at least 10.4 um\)"):
        extract_windows(path, "1/0", 10 * UM)
    assert extract_windows(path, "1/0", 10.4 * UM).density.shape == (1154, 1154)  # 1,331,716 windows: fits
    monkeypatch.setattr(ex, "_physical_memory", lambda: None)  # a system that does not tell: the fixed limit
    assert ex.MAX_WINDOWS == 25_000_000 and extract_windows(path, "1/0", 10 * UM).density.shape == (1200, 1200)


@pytest.mark.parametrize("unit_um, unit_m", [(1e-5, 1e-11), (5e-5, 5e-11), (1e-6, 1e-12)])
def test_a_database_unit_below_a_tenth_of_a_nanometre(tmp_path, unit_um, unit_m):
    """A database unit of 0.01 nm, 0.05 nm or 1 pm (KLayout's 1e-05 um prints in exponent form): the unit in metres was read
    by pasting "e-6" to it, "1e-05e-6", and every such file was refused as "could not convert string to float"."""
    ly = kdb.Layout()
    ly.dbu = unit_um
    um = round(1 / unit_um)  # dbu per micrometre
    top, leaf = ly.create_cell("TOP"), ly.create_cell("LEAF")
    leaf.shapes(ly.layer(1, 0)).insert(kdb.Box(0, 0, 3 * um, 2 * um))
    top.insert(kdb.CellInstArray(leaf.cell_index(), kdb.Trans(), kdb.Vector(5 * um, 0), kdb.Vector(0, 5 * um), 40, 30))
    path = _write(ly, tmp_path / "fine.gds")
    assert read_layout(path).dbu == unit_m  # exactly the decimal unit
    res = extract_windows(path, "1/0", 20 * UM)
    ref, _ = klayout_flat(path, [(1, 0)], res)
    np.testing.assert_allclose(res.density, ref, atol=1e-12)
    assert res.density[0, 0] == pytest.approx(16 * 6 / 400, rel=1e-12)
