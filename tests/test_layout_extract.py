"""Layout extraction: window densities against an independent exact computation, width
and space exact on line arrays, the hierarchy (arrays, rotations, mirrors, overlaps) and
every bad input.  The layouts are built here with gdstk (no file outside the suite)."""

from __future__ import annotations

import gzip
import math
import shutil

import gdstk
import numpy as np
import pytest

from cmpsim.layout import extract_windows, read_layout
from klayout_reference import klayout_flat

UM = 1e-6


def write_all(lib: gdstk.Library, tmp_path, name="chip"):
    """The library as .gds, .gds.gz and .oas."""
    gds = tmp_path / f"{name}.gds"
    lib.write_gds(str(gds))
    gz = tmp_path / f"{name}.gds.gz"
    with open(gds, "rb") as src, gzip.open(gz, "wb") as dst:
        shutil.copyfileobj(src, dst)
    oas = tmp_path / f"{name}.oas"
    lib.write_oas(str(oas))
    return gds, gz, oas


def exact_density(path, layers, res):
    """Independent reference: read and flatten with gdstk (not the KLayout engine under test),
    intersect every window, sum the areas."""
    dbu = gdstk.gds_units(str(path))[1]
    lib = gdstk.read_gds(str(path), unit=dbu)
    cell = next(c for c in lib.cells if c.name == res.top)
    polys = []
    for layer, dtype in layers:
        polys.extend(cell.get_polygons(layer=layer, datatype=dtype))
    w = round(res.window / dbu)
    ox, oy = round(res.origin[0] / dbu), round(res.origin[1] / dbu)
    ny, nx = res.density.shape
    out = np.zeros((ny, nx))
    for j in range(ny):
        for i in range(nx):
            x0, y0 = ox + i * w, oy + j * w
            clip = gdstk.boolean(polys, gdstk.rectangle((x0, y0), (x0 + w, y0 + w)), "and", precision=1e-6)
            out[j, i] = sum(p.area() for p in clip) / (w * w)
    return out


def klayout_density(path, layers, res):
    """KLayout's own flat merge of the same file (no hierarchy, no engine of cmpsim's), rasterised on the windows."""
    return klayout_flat(path, layers, res)[0]


#: gdstk keeps real-valued vertices where oblique edges cross or a 36.87-degree placement turns a
#: path; KLayout, like every layout database, puts them on the 1 nm grid: the two differ by about
#: (length of such edges) x 0.5 nm / window^2, below 1e-5 for these test layouts.
GRID_SNAP = 1e-5


def line_array(cell, x0, y0, width, pitch, n, length, layer=(68, 20), vertical=True):
    for k in range(n):
        if vertical:
            cell.add(gdstk.rectangle((x0 + k * pitch, y0), (x0 + k * pitch + width, y0 + length),
                                     layer=layer[0], datatype=layer[1]))
        else:
            cell.add(gdstk.rectangle((x0, y0 + k * pitch), (x0 + length, y0 + k * pitch + width),
                                     layer=layer[0], datatype=layer[1]))


# -- line arrays: width and space exact ----------------------------------------------

@pytest.mark.parametrize("vertical", [True, False])
@pytest.mark.parametrize("offset", [0.0, 0.3, 1.7])
def test_line_array_width_space_exact(tmp_path, vertical, offset):
    """Lines of width 0.5 um at 2 um pitch: every window inside the array (10 um = 5 pitches)
    gives width 0.5 um, space 1.5 um and density 0.25, wherever the array starts."""
    lib = gdstk.Library(unit=1e-6, precision=1e-9)
    top = lib.new_cell("TOP")
    if vertical:
        line_array(top, offset, 0, 0.5, 2.0, 39, 80.0, vertical=True)
    else:
        line_array(top, 0, offset, 0.5, 2.0, 39, 80.0, vertical=False)
    top.add(gdstk.rectangle((0, 0), (80, 80), layer=235, datatype=4))  # die outline
    gds, _, _ = write_all(lib, tmp_path)
    res = extract_windows(gds, ["68/20"], 10 * UM)
    assert res.density.shape == (8, 8)
    inner = (slice(1, -1), slice(1, -1))
    np.testing.assert_allclose(res.width[inner], 0.5 * UM, rtol=1e-12)
    np.testing.assert_allclose(res.space[inner], 1.5 * UM, rtol=1e-12)
    np.testing.assert_allclose(res.density[inner], 0.25, rtol=1e-12)
    np.testing.assert_allclose(res.density, exact_density(gds, [(68, 20)], res), atol=1e-9)


def test_line_array_several_widths(tmp_path):
    """Blocks of different width and space, each spanning whole windows."""
    lib = gdstk.Library(unit=1e-6, precision=1e-9)
    top = lib.new_cell("TOP")
    specs = [(0.25, 1.0), (1.0, 4.0), (2.0, 2.5), (5.0, 10.0)]  # (width, pitch), window 20 um
    for k, (w, p) in enumerate(specs):
        n = int(round(60 / p))
        line_array(top, 0, 60 * k, w, p, n, 60.0, vertical=False)
    gds, _, _ = write_all(lib, tmp_path)
    res = extract_windows(gds, "68/20", 20 * UM)
    for k, (w, p) in enumerate(specs):
        rows = slice(3 * k + 1, 3 * k + 2)  # the middle window row of the block
        np.testing.assert_allclose(res.width[rows, 1], w * UM, rtol=1e-12)
        np.testing.assert_allclose(res.space[rows, 1], (p - w) * UM, rtol=1e-12)
    np.testing.assert_allclose(res.density, exact_density(gds, [(68, 20)], res), atol=1e-9)


def test_empty_and_full_windows(tmp_path):
    lib = gdstk.Library(unit=1e-6, precision=1e-9)
    top = lib.new_cell("TOP")
    top.add(gdstk.rectangle((0, 0), (30, 30)))
    top.add(gdstk.rectangle((0, 0), (30, 30), layer=68, datatype=20))
    top.add(gdstk.rectangle((0, 0), (50, 50), layer=235, datatype=4))
    gds, _, _ = write_all(lib, tmp_path)
    res = extract_windows(gds, "68/20", 10 * UM)
    assert res.density[1, 1] == 1.0 and res.width[1, 1] == pytest.approx(10 * UM) and res.space[1, 1] == 0
    # the corner window: the square's edges on the die's border count half (10 um of boundary)
    assert res.boundary[0, 0] == pytest.approx(10 * UM) and res.width[0, 0] == pytest.approx(20 * UM)
    assert res.density[4, 4] == 0.0 and res.width[4, 4] == 0 and res.space[4, 4] == pytest.approx(10 * UM)
    np.testing.assert_allclose(res.x, (np.arange(5) + 0.5) * 10 * UM)
    assert res.bbox == pytest.approx((0, 0, 50 * UM, 50 * UM))


# -- the hierarchy -------------------------------------------------------------------

def hierarchical_library():
    """Cells with own shapes, arrays of rotated and mirrored references, drawn and fill
    datatypes overlapping, abutting and overlapping placements, a 36.87-degree reference,
    a diagonal-edged shape and a path."""
    lib = gdstk.Library(unit=1e-6, precision=1e-9)
    leaf = lib.new_cell("LEAF")
    line_array(leaf, 0.5, 0.25, 0.4, 1.3, 5, 6.0)
    leaf.add(gdstk.rectangle((0, 0), (7, 0.6), layer=68, datatype=20))  # rail across the lines
    leaf.add(gdstk.rectangle((3, 1), (6.5, 4.5), layer=36, datatype=28))  # fill over drawn
    leaf.add(gdstk.Polygon([(0, 7), (2, 7), (3, 8), (1, 8)], layer=68, datatype=20))  # 45 degrees
    leaf.add(gdstk.FlexPath([(0, 9), (6, 9), (6, 12)], 0.5, layer=68, datatype=20))
    block = lib.new_cell("BLOCK")
    block.add(gdstk.Reference(leaf, (0, 0), columns=3, rows=2, spacing=(7.0, 12.5)))  # abutting rails
    block.add(gdstk.Reference(leaf, (30, 2), rotation=math.pi / 2))
    block.add(gdstk.Reference(leaf, (31, 20), rotation=math.pi, x_reflection=True))
    block.add(gdstk.Reference(leaf, (22, 26), rotation=-math.pi / 2, x_reflection=True))
    # not a multiple of 90 degrees: flattened into BLOCK; cos = 0.8 and sin = 0.6 keep the
    # leaf's vertices (multiples of 5 nm) on the 1 nm grid, so no snapping blurs the check
    block.add(gdstk.Reference(leaf, (5, 27), rotation=math.atan2(3, 4)))
    block.add(gdstk.rectangle((20, 0), (24, 30), layer=36, datatype=28))  # overlaps placements
    top = lib.new_cell("TOP")
    top.add(gdstk.Reference(block, (0, 0), columns=3, rows=2, spacing=(33.0, 40.0)))
    top.add(gdstk.Reference(block, (105, 83), rotation=math.pi, columns=2, rows=1, spacing=(-34.5, 0)))
    top.add(gdstk.Reference(block, (100, 5), x_reflection=True, rotation=math.pi / 2))  # overlaps
    top.add(gdstk.rectangle((10, 35), (90, 37.5), layer=68, datatype=20))  # own shapes over children
    return lib


LAYERS = [(68, 20), (36, 28)]


@pytest.mark.parametrize("big", [0, 10**9])
def test_hierarchy_density_exact(tmp_path, big):
    """Composed (big=0: every plain placement merged once and pasted) or merged flat, the densities equal the independent
    flatten-and-clip computation (gdstk) to the grid snapping, and KLayout's own flat merge to
    1e-12, on windows of 10 and 7.3 um."""
    gds, _, _ = write_all(hierarchical_library(), tmp_path)
    for window in (10 * UM, 7.3 * UM):
        res = extract_windows(gds, ["68/20", "36/28"], window, big=big)
        np.testing.assert_allclose(res.density, klayout_density(gds, LAYERS, res), atol=1e-12)
        np.testing.assert_allclose(res.density, exact_density(gds, LAYERS, res), atol=GRID_SNAP)
        assert res.density.max() > 0.3


def test_hierarchy_composed_equals_flat(tmp_path):
    """Width, space and boundary of the composed path equal those of the flattened one (to
    the 1e-6 dbu where gdstk places the vertices it creates on oblique edges)."""
    gds, _, _ = write_all(hierarchical_library(), tmp_path)
    a = extract_windows(gds, ["68/20", "36/28"], 10 * UM, big=0)
    b = extract_windows(gds, ["68/20", "36/28"], 10 * UM, big=10**9)
    np.testing.assert_allclose(a.density, b.density, atol=1e-9)
    for f in ("width", "space", "boundary"):
        np.testing.assert_allclose(getattr(a, f), getattr(b, f), rtol=1e-9)


def test_formats_agree(tmp_path):
    gds, gz, oas = write_all(hierarchical_library(), tmp_path)
    results = [extract_windows(p, ["68/20", "36/28"], 10 * UM, big=0) for p in (gds, gz, oas)]
    ref = klayout_density(gds, LAYERS, results[0])
    for r in results:
        np.testing.assert_allclose(r.density, ref, atol=1e-12)
        np.testing.assert_allclose(r.width, results[0].width, rtol=1e-12)
        assert r.top == "TOP" and r.layers == ((36, 28), (68, 20))


def test_stepped_array_of_line_arrays(tmp_path):
    """A reticle stepping a line-array block 12 x 9 (window-aligned and not): exact width
    and space inside each block, densities exact everywhere; the block is rastered once
    per phase, not per placement."""
    lib = gdstk.Library(unit=1e-6, precision=1e-9)
    blk = lib.new_cell("BLK")
    line_array(blk, 0, 0, 0.75, 2.5, 20, 50.0)  # 50 x 50 um of lines, 0.75 / 1.75 um
    top = lib.new_cell("RETICLE")
    top.add(gdstk.Reference(blk, (0, 0), columns=12, rows=9, spacing=(50.0, 50.0)))
    gds, _, _ = write_all(lib, tmp_path)
    res = extract_windows(gds, "68/20", 10 * UM, big=0)
    assert res.density.shape == (45, 60)
    inner = res.density > 0.29
    np.testing.assert_allclose(res.density[inner], 0.3, rtol=1e-12)
    assert inner.sum() > 0.9 * inner.size
    np.testing.assert_allclose(res.width[5:-5, 5:-5], 0.75 * UM, rtol=1e-12)
    np.testing.assert_allclose(res.space[5:-5, 5:-5], 1.75 * UM, rtol=1e-12)
    small = extract_windows(gds, "68/20", 10 * UM, big=10**9)
    np.testing.assert_allclose(res.density, small.density, atol=1e-12)
    np.testing.assert_allclose(res.width, small.width, rtol=1e-12)


def test_off_grid_rotation(tmp_path):
    """A 30-degree reference puts vertices off the 1 nm grid: KLayout, like every layout tool,
    puts the transformed vertices back on the database grid (1 nm), so the densities differ
    from gdstk's real-valued flattening by at most perimeter x 0.5 nm / window^2 (< 1e-6 here)."""
    lib = hierarchical_library()
    block = next(c for c in lib.cells if c.name == "BLOCK")
    leaf = next(c for c in lib.cells if c.name == "LEAF")
    block.add(gdstk.Reference(leaf, (12, 15), rotation=math.radians(30)))
    gds, _, _ = write_all(lib, tmp_path)
    res = extract_windows(gds, ["68/20", "36/28"], 10 * UM, big=0)
    # the block holding the rotated leaf is merged once in its own frame, KLayout's flat merge in the
    # die's: each puts the off-grid vertices on the 1 nm grid where it stands, so the two differ by up to
    # (rotated outline in a window, ~100 um) x 1 nm / (10 um)^2 = 1e-3 at worst; +-0.5 nm roundings of
    # hundreds of vertices mostly cancel, and 1e-4 holds with margin (1.7e-5 measured)
    np.testing.assert_allclose(res.density, klayout_density(gds, LAYERS, res), atol=1e-4)
    np.testing.assert_allclose(res.density, exact_density(gds, LAYERS, res), atol=1e-4)
    flat = extract_windows(gds, ["68/20", "36/28"], 10 * UM, big=10**9)  # KLayout's deep merge snaps in BLOCK's frame too
    np.testing.assert_allclose(flat.density, klayout_density(gds, LAYERS, res), atol=1e-4)
    np.testing.assert_allclose(flat.density, res.density, atol=1e-4)


def test_origin_and_partial_windows(tmp_path):
    gds, _, _ = write_all(hierarchical_library(), tmp_path)
    res = extract_windows(gds, ["68/20", "36/28"], 10 * UM, origin=(-3 * UM, -4 * UM))
    assert res.origin == pytest.approx((-3 * UM, -4 * UM))
    np.testing.assert_allclose(res.density, klayout_density(gds, LAYERS, res), atol=1e-12)
    np.testing.assert_allclose(res.density, exact_density(gds, LAYERS, res), atol=GRID_SNAP)


# -- names and layer maps --------------------------------------------------------------

def test_pdk_name_merges_drawn_and_fill(tmp_path):
    gds, _, _ = write_all(hierarchical_library(), tmp_path)
    by_name = extract_windows(gds, "met1", 10 * UM, pdk="sky130")
    by_pairs = extract_windows(gds, ["68/20", "36/28"], 10 * UM)
    np.testing.assert_allclose(by_name.density, by_pairs.density, atol=1e-15)


def test_pdk_name_without_fill_in_the_file(simple_gds):
    """An unfilled layout has no fill datatype: the name uses the pairs the file has."""
    res = extract_windows(simple_gds, "met1", 10 * UM, top="TOP", pdk="sky130")
    assert res.layers == ((68, 20),) and res.density[0, 0] == 1.0


def test_layer_map_file(tmp_path):
    gds, _, _ = write_all(hierarchical_library(), tmp_path)
    lm = tmp_path / "map.toml"
    lm.write_text('m1 = ["68/20", "36/28"]\nrail = ["68/20"]\n')
    a = extract_windows(gds, "M1", 10 * UM, layer_map=lm)
    b = extract_windows(gds, ["68/20", "36/28"], 10 * UM)
    np.testing.assert_allclose(a.density, b.density, atol=1e-15)


# -- bad input ---------------------------------------------------------------------------

@pytest.fixture
def simple_gds(tmp_path):
    lib = gdstk.Library(unit=1e-6, precision=1e-9)
    top = lib.new_cell("TOP")
    top.add(gdstk.rectangle((0, 0), (40, 30), layer=68, datatype=20))
    other = lib.new_cell("SPARE")  # a second top cell, holding the only 69/20 shape
    other.add(gdstk.rectangle((0, 0), (1, 1), layer=69, datatype=20))
    path = tmp_path / "simple.gds"
    lib.write_gds(str(path))
    return path


def test_not_a_layout(tmp_path):
    bad = tmp_path / "notes.gds"
    bad.write_text("this is not a layout\n")
    with pytest.raises(ValueError, match=r"layout path .* is not a layout file.*GDSII.*OASIS"):
        read_layout(bad)
    gzbad = tmp_path / "notes.gds.gz"
    with gzip.open(gzbad, "wb") as fh:
        fh.write(b"plain text, gzipped")
    with pytest.raises(ValueError, match="neither gzipped GDSII nor gzipped OASIS"):
        extract_windows(gzbad, "68/20", 10 * UM)
    trunc = tmp_path / "trunc.gds"
    trunc.write_bytes(b"\x00\x06\x00\x02\x02\x58" + b"\x00" * 5)
    with pytest.raises(ValueError, match="could not be read as a layout"):
        read_layout(trunc)


def test_missing_file(tmp_path):
    with pytest.raises(FileNotFoundError, match="layout path .* does not exist"):
        extract_windows(tmp_path / "nope.gds", "68/20", 10 * UM)


def test_several_top_cells(simple_gds):
    with pytest.raises(ValueError, match=r"2 top-level cells \['SPARE', 'TOP'\]: choose the die with --top NAME"):
        extract_windows(simple_gds, "68/20", 10 * UM)
    with pytest.raises(ValueError, match=r"--top 'NOPE': no such cell in simple.gds.*\['SPARE', 'TOP'\]"):
        extract_windows(simple_gds, "68/20", 10 * UM, top="NOPE")
    res = extract_windows(simple_gds, "68/20", 10 * UM, top="TOP")
    assert res.top == "TOP" and res.density.shape == (3, 4)


def test_missing_layer_named_and_listed(simple_gds):
    with pytest.raises(ValueError, match=r"layer '70/20' \(70/20\) is not in simple.gds; its layers are: 68/20, 69/20"):
        extract_windows(simple_gds, "70/20", 10 * UM, top="TOP")
    with pytest.raises(ValueError, match=r"layer 'met3' \(70/20, 34/28\) is not in"):
        extract_windows(simple_gds, "met3", 10 * UM, top="TOP", pdk="sky130")


def test_empty_layer(simple_gds):
    """69/20 is drawn in the file, but only under SPARE: under the die TOP it is empty."""
    with pytest.raises(ValueError, match=r"layers 69/20 have no shapes under top cell 'TOP' \(an empty layer"):
        extract_windows(simple_gds, "69/20", 10 * UM, top="TOP")
    assert extract_windows(simple_gds, "69/20", 1 * UM, top="SPARE").density.max() == 1.0


def test_window_larger_than_die(simple_gds):
    with pytest.raises(ValueError, match=r"window = 3.5e-05 m \(--window\) is larger than the die 'TOP' \(4e-05 x 3e-05 m\)"):
        extract_windows(simple_gds, "68/20", 35 * UM, top="TOP")
    with pytest.raises(ValueError, match="window = .* not a whole number of database units"):
        extract_windows(simple_gds, "68/20", 10.0005 * UM, top="TOP")
    with pytest.raises(ValueError, match="window = -1 must be a positive length"):
        extract_windows(simple_gds, "68/20", -1, top="TOP")


def test_bad_layer_specs(simple_gds, tmp_path):
    with pytest.raises(ValueError, match=r"layer 'metal9' is neither \"L/D\".*give a pdk"):
        extract_windows(simple_gds, "metal9", 10 * UM, top="TOP")
    with pytest.raises(ValueError, match=r"layer 'metal9' .*names known here: \['li1', 'met1'"):
        extract_windows(simple_gds, "metal9", 10 * UM, top="TOP", pdk="sky130")
    with pytest.raises(ValueError, match=r"pdk 'tsmc7' is unknown; valid: \['gf180mcu', 'sg13g2', 'sky130'\]"):
        extract_windows(simple_gds, "met1", 10 * UM, top="TOP", pdk="tsmc7")
    with pytest.raises(ValueError, match="layers is empty"):
        extract_windows(simple_gds, [], 10 * UM, top="TOP")
    bad = tmp_path / "bad.toml"
    bad.write_text('m1 = ["68-20"]\n')
    with pytest.raises(ValueError, match=r"layer_map bad.toml: 'm1' has '68-20', expected \"L/D\""):
        extract_windows(simple_gds, "m1", 10 * UM, top="TOP", layer_map=bad)
    broken = tmp_path / "broken.toml"
    broken.write_text("m1 = [\n")
    with pytest.raises(ValueError, match="layer_map .* is not valid TOML"):
        extract_windows(simple_gds, "m1", 10 * UM, top="TOP", layer_map=broken)
    with pytest.raises(FileNotFoundError, match="layer_map .* does not exist"):
        extract_windows(simple_gds, "m1", 10 * UM, top="TOP", layer_map=tmp_path / "none.toml")


def test_result_is_frozen(simple_gds):
    res = extract_windows(simple_gds, "68/20", 10 * UM, top="TOP")
    with pytest.raises(Exception):
        res.window = 1.0
    assert res.layers == ((68, 20),) and res.dbu == pytest.approx(1e-9)
