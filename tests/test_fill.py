"""Dummy fill: the rules, the free sites (never within the keep-out of a drawn shape, and only
those), spacing, the window fields after fill against re-extraction, the GDS/OASIS files, and
the model-based choice on a synthetic 10 x 10 mm floorplan of dense and sparse blocks. The
layouts are built here with gdstk (a test-only generator; nothing outside the suite); the keep-out
is checked with gdstk's booleans and, independently of the fill's own code, with KLayout's
separation check on the written fill file."""

from __future__ import annotations

import json
import math

import gdstk
import klayout.db as kdb
import numpy as np
import pytest

from cmpsim.die.fill import DEFAULT_LIMITS, die_layout, hotspot_count, plan_fill, thickness, thickness_range
from cmpsim.die.polish import simulate
from cmpsim.layout import extract_windows, read_layout, top_cell
from cmpsim.layout.fill import (FILL_RULES, FillRules, fill_polygons, fill_rules, fill_sites, filled_windows,
                                resolve_fill, select_fill, write_fill)

UM = 1e-6
NM = 1000  # dbu per um (1 nm database unit)
RATE = 2e-9  # blanket rate (m/s): no wafer solve in the suite's die runs


# ------------------------------------------------------------------------------ layouts
def small_chip(path):
    """A 200 x 160 um chip: rectangles, an L, a polygon with a notch, a 45-degree shape, a path,
    a child cell placed rotated, mirrored and as an array."""
    lib = gdstk.Library(unit=1e-9, precision=1e-9)
    child = lib.new_cell("CHILD")
    child.add(gdstk.rectangle((0, 0), (6 * NM, 1 * NM), layer=68, datatype=20))
    child.add(gdstk.rectangle((0, 0), (1 * NM, 9 * NM), layer=68, datatype=20))
    top = lib.new_cell("TOP")
    top.add(gdstk.rectangle((0, 0), (200 * NM, 160 * NM), layer=235, datatype=4))  # the die, no metal
    top.add(gdstk.rectangle((10 * NM, 10 * NM), (40 * NM, 14 * NM), layer=68, datatype=20))
    top.add(gdstk.Polygon([(60 * NM, 20 * NM), (90 * NM, 20 * NM), (90 * NM, 25 * NM), (66 * NM, 25 * NM),
                           (66 * NM, 50 * NM), (60 * NM, 50 * NM)], layer=68, datatype=20))  # an L
    top.add(gdstk.Polygon([(120 * NM, 10 * NM), (150 * NM, 10 * NM), (150 * NM, 40 * NM), (140 * NM, 40 * NM),
                           (140 * NM, 20 * NM), (130 * NM, 20 * NM), (130 * NM, 40 * NM), (120 * NM, 40 * NM)],
                          layer=68, datatype=20))  # a U (a notch to fill into)
    top.add(gdstk.Polygon([(20 * NM, 100 * NM), (30 * NM, 100 * NM), (50 * NM, 120 * NM), (40 * NM, 120 * NM)],
                          layer=68, datatype=20))  # 45 degrees
    top.add(gdstk.FlexPath([(100 * NM, 80 * NM), (180 * NM, 80 * NM)], 2 * NM, layer=68, datatype=20))
    top.add(gdstk.Reference(child, (170 * NM, 120 * NM), rotation=math.pi / 2))
    top.add(gdstk.Reference(child, (100 * NM, 130 * NM), x_reflection=True))
    top.add(gdstk.Reference(child, (60 * NM, 130 * NM), columns=3, rows=2, spacing=(12 * NM, 14 * NM)))
    top.add(gdstk.rectangle((0, 150 * NM), (3 * NM, 160 * NM), layer=69, datatype=20))  # another layer: no keep-out
    lib.write_gds(str(path))
    return path


def floorplan(path):
    """A 10 x 10 mm die: two dense blocks (3 x 3 mm, 2 um lines at 4 um pitch: density 0.5) and one
    sparse block (2 um lines at 20 um pitch: 0.1), empty space between."""
    lib = gdstk.Library(unit=1e-9, precision=1e-9)
    line = lib.new_cell("LINE")
    line.add(gdstk.rectangle((0, 0), (2 * NM, 3000 * NM), layer=68, datatype=20))
    dense = lib.new_cell("DENSE")
    dense.add(gdstk.Reference(line, (0, 0), columns=750, rows=1, spacing=(4 * NM, 0)))
    sparse = lib.new_cell("SPARSE")
    sparse.add(gdstk.Reference(line, (0, 0), columns=150, rows=1, spacing=(20 * NM, 0)))
    top = lib.new_cell("TOP")
    top.add(gdstk.rectangle((0, 0), (10000 * NM, 10000 * NM), layer=235, datatype=4))
    top.add(gdstk.Reference(dense, (1000 * NM, 1000 * NM)))
    top.add(gdstk.Reference(dense, (6000 * NM, 5500 * NM)))
    top.add(gdstk.Reference(sparse, (5500 * NM, 1000 * NM)))
    lib.write_gds(str(path))
    return path


RULES = FillRules(size=2 * UM, spacing=1.5 * UM, keepout=2.5 * UM, edge=1 * UM)


@pytest.fixture(scope="module")
def chip(tmp_path_factory):
    path = small_chip(tmp_path_factory.mktemp("fill") / "chip.gds")
    w = extract_windows(path, ["68/20"], 20 * UM)
    s = fill_sites(path, ["68/20"], w, RULES)
    return path, w, s


def drawn_polygons(path, layer=(68, 20), top="TOP"):
    """The drawn shapes, flattened by gdstk (an engine independent of the fill's)."""
    lib = gdstk.read_oas(str(path), unit=1e-9) if str(path).endswith(".oas") else gdstk.read_gds(str(path), unit=1e-9)
    cell = next(c for c in lib.cells if c.name == top)
    return cell.get_polygons(layer=layer[0], datatype=layer[1])


def rectangles(boxes, layer=36, datatype=28):
    """gdstk rectangles of (n, 4) boxes."""
    return [gdstk.rectangle((x0, y0), (x1, y1), layer=layer, datatype=datatype) for x0, y0, x1, y1 in np.asarray(boxes).tolist()]


def klayout_boxes(path):
    """Every shape of the file's top cell, flattened by KLayout: ((layer, datatype), bbox, is_box) per shape."""
    ly = kdb.Layout()
    ly.read(str(path))
    (top,) = ly.top_cells()
    out = []
    for li in ly.layer_indexes():
        info = ly.get_info(li)
        it = top.begin_shapes_rec(li)
        while not it.at_end():
            shape = it.shape().polygon.transformed(it.trans())
            b = shape.bbox()
            out.append(((info.layer, info.datatype), (b.left, b.bottom, b.right, b.top), shape.is_box()))
            it.next()
    return out


def square_boxes(sites, chosen):
    iy, ix = np.nonzero(chosen)
    x, y = sites.cx[ix], sites.cy[iy]
    return np.stack([x, y, x + sites.size, y + sites.size], axis=1).astype(float)


# ------------------------------------------------------------------------------ rules
def test_rules_per_pdk_and_overrides():
    for pdk, table in FILL_RULES.items():
        for name, r in table.items():
            assert r.size > 0 and r.spacing > 0 and r.keepout > 0, (pdk, name)
            assert pdk in r.source
    assert fill_rules("gf180mcu", "metal2") == FILL_RULES["gf180mcu"]["metal2"]
    r = fill_rules("sg13g2", "metal3", keepout=4 * UM)
    assert r.keepout == 4 * UM and r.size == FILL_RULES["sg13g2"]["metal3"].size and "overrides" in r.source
    assert fill_rules("sg13g2", "topmetal1").size == 3 * UM
    assert fill_rules(None, size=1 * UM, spacing=1 * UM, keepout=1 * UM).pitch == pytest.approx(2 * UM)
    with pytest.raises(ValueError, match="pdk"):
        fill_rules("tsmc7")
    with pytest.raises(ValueError, match="metal9"):
        fill_rules("gf180mcu", "metal9")
    with pytest.raises(ValueError, match="keepout"):
        fill_rules(None, size=1 * UM, spacing=1 * UM)
    with pytest.raises(ValueError, match="spacing"):
        FillRules(1 * UM, 0.0, 1 * UM)
    with pytest.raises(ValueError, match="size"):
        FillRules(-1.0, 1 * UM, 1 * UM)
    with pytest.raises(Exception):
        RULES.size = 1.0  # frozen


# ------------------------------------------------------------------------------ geometry
def test_fill_never_violates_the_keepout(chip):
    """Every free site filled: fill AND (drawn grown by keep-out - 1 nm) is empty, also around
    the oblique shape, the path and the rotated, mirrored and arrayed child."""
    path, w, s = chip
    chosen = select_fill(s, s.capacity)
    assert chosen.sum() == s.free.sum() > 500
    fill = rectangles(fill_polygons(s, chosen))
    drawn = drawn_polygons(path)
    for join in ("miter", "round"):
        grown = gdstk.offset(drawn, RULES.keepout / 1e-9 - 1.0, join=join, use_union=True)
        assert gdstk.boolean(fill, grown, "and") == []
    # ... and stays inside the die by `edge`
    box = square_boxes(s, chosen)
    e = RULES.edge / 1e-9
    assert box[:, 0].min() >= e and box[:, 1].min() >= e
    assert box[:, 2].max() <= 200 * NM - e and box[:, 3].max() <= 160 * NM - e


def test_squares_respect_spacing_and_lie_in_one_window(chip):
    _, w, s = chip
    chosen = select_fill(s, s.capacity)
    b = square_boxes(s, chosen)
    gap_x = np.maximum(b[:, None, 0] - b[None, :, 2], b[None, :, 0] - b[:, None, 2])
    gap_y = np.maximum(b[:, None, 1] - b[None, :, 3], b[None, :, 1] - b[:, None, 3])
    gap = np.maximum(gap_x, gap_y)  # Chebyshev gap between two squares (<= Euclidean)
    np.fill_diagonal(gap, np.inf)
    assert gap.min() >= RULES.spacing / 1e-9
    W = s.window
    assert np.all(b[:, 0] // W == (b[:, 2] - 1) // W) and np.all(b[:, 1] // W == (b[:, 3] - 1) // W)


def test_free_sites_are_exactly_those_outside_the_keepout(chip):
    """On the Manhattan shapes the blocking is exact: a site is blocked iff its square grown by
    the keep-out (a box) overlaps a drawn shape with positive area. The 45-degree shape blocks
    its bounding box (conservative), so sites near it are left out of the comparison."""
    path, w, s = chip
    drawn = drawn_polygons(path)
    k = RULES.keepout / 1e-9
    e = RULES.edge / 1e-9
    iy, ix = np.indices(s.free.shape)
    x, y = s.cx[ix.ravel()], s.cy[iy.ravel()]
    free = s.free.ravel()
    inside = (x >= e) & (y >= e) & (x + s.size <= 200 * NM - e) & (y + s.size <= 160 * NM - e)
    oblique = (x < 50 * NM + k) & (x + s.size > 20 * NM - k) & (y < 120 * NM + k) & (y + s.size > 100 * NM - k)
    db = np.array([p.bounding_box() for p in drawn]).reshape(-1, 4)
    checked = 0
    for i in np.nonzero(inside & ~oblique)[0]:
        bx = (x[i] - k, y[i] - k, x[i] + s.size + k, y[i] + s.size + k)
        near = [drawn[j] for j in np.nonzero((db[:, 0] < bx[2]) & (db[:, 2] > bx[0]) & (db[:, 1] < bx[3]) & (db[:, 3] > bx[1]))[0]]
        area = sum(p.area() for p in gdstk.boolean(near, gdstk.rectangle(bx[:2], bx[2:]), "and")) if near else 0.0
        assert (area > 1e-6) == (not free[i]), (x[i], y[i], area)
        checked += 1
    assert checked > 1500
    assert not free[~inside].any()


def test_filled_windows_equal_reextraction(chip, tmp_path):
    """The fields after fill (A + n s^2, L + 4 n s per window) equal extract_windows on layout + fill."""
    path, w, s = chip
    rng = np.random.default_rng(3)
    counts = rng.integers(0, s.capacity + 1)
    chosen = select_fill(s, counts)
    np.testing.assert_array_equal(chosen.reshape(s.shape[0], s.per_window, s.shape[1], s.per_window).sum(axis=(1, 3)), counts)
    after = filled_windows(w, s, chosen)
    lib = gdstk.read_gds(str(path), unit=1e-9)
    top = next(c for c in lib.cells if c.name == "TOP")
    top.add(*rectangles(fill_polygons(s, chosen), 68, 20))
    merged = tmp_path / "merged.gds"
    lib.write_gds(str(merged))
    ref = extract_windows(merged, ["68/20"], 20 * UM, origin=w.origin)
    np.testing.assert_allclose(after.density, ref.density, atol=1e-12)
    np.testing.assert_allclose(after.boundary, ref.boundary, rtol=1e-12, atol=1e-15)
    np.testing.assert_allclose(after.width, ref.width, rtol=1e-9, atol=1e-15)
    np.testing.assert_allclose(after.space, ref.space, rtol=1e-9, atol=1e-15)


@pytest.mark.parametrize("suffix", [".gds", ".oas"])
def test_write_fill_round_trip(chip, tmp_path, suffix):
    _, w, s = chip
    counts = np.minimum(s.capacity, 5)
    chosen = select_fill(s, counts)
    out = write_fill(tmp_path / f"fill{suffix}", s, chosen, "36/28")
    lay = read_layout(out)
    shapes = klayout_boxes(out)
    assert len(shapes) == chosen.sum() == counts.sum()
    assert {pair for pair, _, _ in shapes} == {(36, 28)} and all(is_box for _, _, is_box in shapes)
    got = np.array(sorted(b for _, b, _ in shapes))
    want = np.array(sorted(map(tuple, square_boxes(s, chosen).astype(int).tolist())))
    np.testing.assert_array_equal(got, want)
    assert lay.dbu == pytest.approx(1e-9)
    assert not list(tmp_path.glob("*.tmp*"))


def test_bad_inputs(chip, tmp_path):
    path, w, s = chip
    with pytest.raises(ValueError, match="fill pitch"):
        fill_sites(path, ["68/20"], w, FillRules(15 * UM, 6 * UM, 1 * UM))
    with pytest.raises(ValueError, match="database units"):
        fill_sites(path, ["68/20"], w, FillRules(2.0005 * UM, 1 * UM, 1 * UM))
    with pytest.raises(ValueError, match="not in chip.gds"):
        fill_sites(path, ["70/20"], w, RULES)
    chosen = select_fill(s, s.capacity)
    with pytest.raises(ValueError, match="L/D"):
        write_fill(tmp_path / "f.gds", s, chosen, "met1")
    with pytest.raises(ValueError, match=r"\.gds or \.oas"):
        write_fill(tmp_path / "f.txt", s, chosen, "36/28")
    w2 = extract_windows(path, ["68/20"], 40 * UM)
    with pytest.raises(ValueError, match="same grid"):
        plan_fill(w2, s, blanket_rate=RATE)


def test_sites_use_the_hierarchy(tmp_path):
    """A stepped block (an array and a rotated placement): the sites equal those of the same chip
    written flat, and the block's keep-out is computed once in its own cell (not per placement)."""
    lib = gdstk.Library(unit=1e-9, precision=1e-9)
    blk = lib.new_cell("BLK")
    blk.add(gdstk.Reference(lib.new_cell("L").add(gdstk.rectangle((0, 0), (1 * NM, 50 * NM), layer=68, datatype=20)),
                            (0, 0), columns=10, rows=1, spacing=(5 * NM, 0)))
    top = lib.new_cell("TOP")
    top.add(gdstk.rectangle((0, 0), (400 * NM, 300 * NM), layer=235, datatype=4))
    top.add(gdstk.Reference(blk, (10 * NM, 10 * NM), columns=4, rows=3, spacing=(95 * NM, 97 * NM)))
    top.add(gdstk.Reference(blk, (380 * NM, 10 * NM), rotation=math.pi / 2))
    hier = tmp_path / "hier.gds"
    lib.write_gds(str(hier))
    flat_lib = gdstk.Library(unit=1e-9, precision=1e-9)
    ft = flat_lib.new_cell("TOP")
    ft.add(*top.get_polygons())
    flat = tmp_path / "flat.gds"
    flat_lib.write_gds(str(flat))
    w = extract_windows(hier, ["68/20"], 25 * UM)
    a = fill_sites(hier, ["68/20"], w, RULES)
    b = fill_sites(flat, ["68/20"], w, RULES)
    np.testing.assert_array_equal(a.free, b.free)
    assert 0 < a.free.sum() < a.free.size
    assert a.stats["cells"] <= 3 and b.stats["cells"] == 1


# ------------------------------------------------------------------------------ the model
@pytest.fixture(scope="module")
def planned(tmp_path_factory):
    path = floorplan(tmp_path_factory.mktemp("fill") / "floorplan.gds")
    w = extract_windows(path, ["68/20"], 100 * UM)
    rules = FillRules(2 * UM, 2 * UM, 2 * UM)
    s = fill_sites(path, ["68/20"], w, rules)
    plan = plan_fill(w, s, blanket_rate=RATE, iterations=2)
    return path, w, s, plan


def test_model_based_fill_cuts_the_thickness_range(planned):
    path, w, s, plan = planned
    d = plan.to_dict()
    b, a = d["before"], d["after"]
    assert set(b) == set(a) == {"hotspot_count", "thickness_range"}
    assert a["thickness_range"] <= 0.7 * b["thickness_range"]  # done-when: at least 30 % less
    assert a["hotspot_count"] < b["hotspot_count"]
    assert d["added_area"] == pytest.approx(plan.counts.sum() * (2 * UM) ** 2)
    assert np.all(plan.counts <= s.capacity)
    assert plan.history == sorted(plan.history, reverse=True)
    # the after-die is the die model run on the exact window fields after fill
    again = simulate(die_layout(plan.windows), blanket_rate=RATE)
    assert thickness_range(again) == pytest.approx(a["thickness_range"], rel=1e-9)
    # the dense blocks cannot take fill (2 um spaces < keep-out)
    dense = w.density > 0.45
    assert plan.counts[dense].sum() == 0


def test_model_based_beats_a_flat_density_target(planned):
    """The same added area spread as a flat density target (each window raised towards one
    density, as far as its sites allow) leaves a larger thickness range than the model's choice."""
    path, w, s, plan = planned
    total = plan.counts.sum()
    step = s.density_step
    cap = s.capacity

    def flat(target):
        return np.minimum(cap, np.floor(np.maximum(target - w.density, 0.0) / step))

    lo, hi = 0.0, 1.0
    for _ in range(50):
        mid = 0.5 * (lo + hi)
        lo, hi = (mid, hi) if flat(mid).sum() < total else (lo, mid)
    counts = flat(hi)
    res = simulate(die_layout(filled_windows(w, s, select_fill(s, counts))), blanket_rate=RATE)
    assert thickness_range(res) > plan.to_dict()["after"]["thickness_range"]


def test_hotspots_and_thickness(planned):
    _, w, s, plan = planned
    t = thickness(plan.before)
    assert abs(t.mean()) < 1e-15
    assert hotspot_count(plan.before) == int(np.sum(np.abs(t) > DEFAULT_LIMITS["thickness"]))
    assert hotspot_count(plan.before, {"thickness": 1.0}) == 0
    assert hotspot_count(plan.before, {"thickness": 0.0, "step_height": 0.0}) >= w.density.size
    with pytest.raises(ValueError, match="unknown hotspot"):
        hotspot_count(plan.before, {"warp": 1e-9})
    # a caller's own counter is used for the summaries
    p2 = plan_fill(w, s, blanket_rate=RATE, iterations=0, hotspot_counter=lambda r: 7)
    assert p2.to_dict()["before"]["hotspot_count"] == 7 and p2.added_area == 0.0


# ------------------------------------------------------------------------------ cmpsim die --fill
def dense_and_sparse(path):
    """A 1 x 1 mm chip: a dense block (2 um lines at 4 um pitch, 0.5) and a sparse one (2 um lines at
    20 um pitch, 0.1), 400 x 400 um each, empty space between. GDSII or OASIS by the suffix."""
    lib = gdstk.Library(unit=1e-9, precision=1e-9)
    line = lib.new_cell("LINE")
    line.add(gdstk.rectangle((0, 0), (2 * NM, 400 * NM), layer=68, datatype=20))
    top = lib.new_cell("TOP")
    top.add(gdstk.rectangle((0, 0), (1000 * NM, 1000 * NM), layer=235, datatype=4))
    top.add(gdstk.Reference(line, (50 * NM, 50 * NM), columns=100, rows=1, spacing=(4 * NM, 0)))
    top.add(gdstk.Reference(line, (550 * NM, 550 * NM), columns=20, rows=1, spacing=(20 * NM, 0)))
    (lib.write_oas if str(path).endswith(".oas") else lib.write_gds)(str(path))
    return path


FILL_ARGS = ["--layer", "68/20", "--window", "50um", "--planarization-length", "0.3mm", "--blanket-rate", "120nm/min",
             "--spec", "thickness=20nm"]
FILL_RULE_ARGS = ["--fill-layer", "36/28", "--fill-size", "2um", "--fill-spacing", "2um", "--fill-keepout", "2um"]


def _die(*args):
    from click.testing import CliRunner

    from cmpsim.cli import main

    return CliRunner().invoke(main, ["die", *map(str, args)])


@pytest.fixture(scope="module")
def fill_run(tmp_path_factory):
    tmp = tmp_path_factory.mktemp("diefill")
    path = dense_and_sparse(tmp / "chip.gds")
    out = tmp / "out"
    res = _die(path, *FILL_ARGS, "--fill", *FILL_RULE_ARGS, "--json", "--out", out)
    assert res.exit_code == 0, res.output
    return path, out, json.loads(res.stdout)


def test_cli_fill_reports_before_and_after_with_the_die_commands_definitions(fill_run):
    path, out, d = fill_run
    f = d["fill"]
    assert {"before", "after", "added_area"} <= set(f)
    assert set(f["before"]) == set(f["after"]) == {"hotspot_count", "thickness_range"}
    assert f["units"]["added_area"] == d["units"]["added_area"] == "m^2" and f["units"]["thickness_range"] == "m"
    assert f["after"]["thickness_range"] < 0.7 * f["before"]["thickness_range"]
    assert f["after"]["hotspot_count"] < f["before"]["hotspot_count"]
    assert f["added_area"] == pytest.approx(f["squares"] * (2 * UM) ** 2) and 0 < f["added_area"] < (1000 * UM) ** 2
    assert f["layer"] == "36/28" and f["file"] == "fill.gds" and f["rules"]["keepout"] == pytest.approx(2 * UM)
    # the die of the JSON and of --out is the filled one ...
    assert d["thickness_range"] == f["after"]["thickness_range"] and d["hotspot_count"] == f["after"]["hotspot_count"]
    assert d["hotspot_count"] == len(d["hotspots"])
    on_disk = json.loads((out / "die.json").read_text())
    assert on_disk["fill"]["after"] == f["after"]
    # ... and `before` is exactly what `cmpsim die` says of the drawn layout (one die model, one hotspot count)
    res = _die(path, *FILL_ARGS, "--json")
    assert res.exit_code == 0, res.output
    drawn = json.loads(res.stdout)
    assert "fill" not in drawn
    assert f["before"] == {"hotspot_count": drawn["hotspot_count"], "thickness_range": drawn["thickness_range"]}


def test_cli_fill_file_reads_back_and_keeps_out_of_the_drawn_shapes(fill_run):
    path, out, d = fill_run
    assert {p.name for p in out.iterdir()} == {"die.json", "die.nc", "die.png", "hotspots.lyrdb", "hotspots.csv", "fill.gds"}
    lib = gdstk.read_gds(str(out / "fill.gds"), unit=1e-9)  # KLayout writes um user units: read in nm
    top = next(c for c in lib.top_level())
    fill = top.get_polygons()
    assert len(fill) == d["fill"]["squares"] > 0
    assert {(p.layer, p.datatype) for p in fill} == {(36, 28)}
    assert sum(p.area() for p in fill) * 1e-18 == pytest.approx(d["fill"]["added_area"], rel=1e-9)
    drawn = drawn_polygons(path)
    grown = gdstk.offset(drawn, 2 * NM - 1.0, join="miter", use_union=True)
    assert gdstk.boolean(fill, grown, "and") == []
    assert gdstk.boolean(fill, drawn, "and") == []


def test_cli_fill_oasis_in_oasis_out(tmp_path):
    path = dense_and_sparse(tmp_path / "chip.oas")
    res = _die(path, *FILL_ARGS, "--fill", *FILL_RULE_ARGS, "--json", "--out", tmp_path / "out")
    assert res.exit_code == 0, res.output
    assert json.loads(res.stdout)["fill"]["file"] == "fill.oas"
    assert (tmp_path / "out" / "fill.oas").is_file() and not (tmp_path / "out" / "fill.gds").exists()
    shapes = klayout_boxes(tmp_path / "out" / "fill.oas")
    assert len(shapes) == json.loads(res.stdout)["fill"]["squares"] and {pair for pair, _, _ in shapes} == {(36, 28)}


def test_cli_fill_defaults_from_the_pdk():
    rules, pair = resolve_fill(["met1"], "sky130")
    assert pair == (36, 28) and rules == FILL_RULES["sky130"]["met1"]
    rules, pair = resolve_fill(["68/20"], "sky130", keepout=4 * UM)  # the drawn pair names met1
    assert pair == (36, 28) and rules.keepout == pytest.approx(4 * UM) and "overrides" in rules.source
    rules, pair = resolve_fill(["metal2"], "gf180mcu", None, "36/9")
    assert pair == (36, 9) and rules == FILL_RULES["gf180mcu"]["metal2"]


def test_cli_fill_bad_input_exits_2_naming_the_option_and_writes_nothing(tmp_path):
    path = dense_and_sparse(tmp_path / "chip.gds")
    stack = tmp_path / "stack.toml"
    stack.write_text('[[level]]\nname = "m1"\nlayers = ["68/20"]\nprocess = "oxide"\n')
    out = tmp_path / "out"
    cases = [
        ([path, "--layer", "68/20", "--fill"], "--fill-layer"),
        ([path, "--layer", "68/20", "--fill", "--fill-layer", "36/28", "--fill-size", "2um"], "--fill-spacing, --fill-keepout"),
        ([path, "--layer", "68/20", "--fill", "--fill-layer", "met1", "--fill-size", "2um", "--fill-spacing", "1um",
          "--fill-keepout", "1um"], "--fill-layer 'met1'"),
        ([path, "--layer", "68/20", "--fill", *FILL_RULE_ARGS[:-1], "0um"], "--fill-keepout"),
        ([path, "--layer", "68/20", "--fill-size", "2um"], "needs --fill"),
        ([path, "--stack", stack, "--fill", *FILL_RULE_ARGS], "--fill with --stack"),
        ([path, "--layer", "68/20", "--wafer", "--fill", *FILL_RULE_ARGS], "--fill with --wafer"),
        (["uniform", "--fill", *FILL_RULE_ARGS], "--fill applies to a layout file"),
        ([path, "--layer", "68/20", "--pdk", "sky130", "--layer", "69/20", "--fill"], "--fill-layer"),
    ]
    for args, text in cases:
        res = _die(*args, "--out", out)
        assert res.exit_code == 2, (args, res.output)
        assert text in res.output, (args, res.output)
        assert not out.exists(), args


# ------------------------------------------------------------------------------ independent checks (KLayout)
def hierarchical_chip(path):
    """A 300 x 300 um chip of one small block placed many ways: arrays, 90-degree rotations, a mirror,
    a 30-degree rotation, a magnification, placements overlapping each other; the leaf has a
    Manhattan bar and a 45-degree triangle, and its placements in a row overlap."""
    lib = gdstk.Library(unit=1e-9, precision=1e-9)
    leaf = lib.new_cell("LEAF")
    leaf.add(gdstk.rectangle((0, 0), (4 * NM, 1 * NM), layer=68, datatype=20))
    leaf.add(gdstk.Polygon([(0, 2 * NM), (2 * NM, 2 * NM), (0, 4 * NM)], layer=68, datatype=20))
    row = lib.new_cell("ROW")
    row.add(gdstk.Reference(leaf, (0, 0), columns=6, rows=1, spacing=(3 * NM, 0)))  # overlapping leaves
    top = lib.new_cell("TOP")
    top.add(gdstk.rectangle((0, 0), (300 * NM, 300 * NM), layer=235, datatype=4))
    top.add(gdstk.Reference(row, (10 * NM, 10 * NM), columns=3, rows=4, spacing=(37 * NM, 23 * NM)))
    top.add(gdstk.Reference(row, (11 * NM, 10.5 * NM)))  # on top of an array element
    top.add(gdstk.Reference(row, (250 * NM, 20 * NM), rotation=math.pi / 2))
    top.add(gdstk.Reference(row, (250 * NM, 120 * NM), rotation=math.pi, x_reflection=True))
    top.add(gdstk.Reference(row, (150 * NM, 150 * NM), rotation=math.pi / 6))
    top.add(gdstk.Reference(row, (60 * NM, 220 * NM), magnification=1.5, rotation=-math.pi / 2))
    top.add(gdstk.rectangle((200 * NM, 200 * NM), (230 * NM, 260 * NM), layer=68, datatype=20))
    lib.write_gds(str(path))
    return path


def test_fill_keeps_out_by_klayouts_own_checks(tmp_path):
    """Every free site filled on a hierarchical chip, the fill file written and read back into the
    layout by KLayout: KLayout's separation check (Euclidean) finds no square closer than the
    keep-out to a drawn shape, none closer than the spacing to another, and the drawn shapes grown
    by the box [-(keep-out - 1 nm), keep-out - 1 nm]^2 (their Minkowski sum) meet no square."""
    path = hierarchical_chip(tmp_path / "hier.gds")
    w = extract_windows(path, ["68/20"], 25 * UM)
    s = fill_sites(path, ["68/20"], w, RULES)
    chosen = select_fill(s, s.capacity)
    out = write_fill(tmp_path / "fill.gds", s, chosen, "36/28")
    ly = kdb.Layout()
    ly.read(str(path))
    ly.read(str(out))  # the fill merged into the layout: its cell becomes a second top cell
    drawn = kdb.Region(ly.cell("TOP").begin_shapes_rec(ly.find_layer(68, 20)))
    fill = kdb.Region(ly.cell("CMPSIM_FILL").begin_shapes_rec(ly.find_layer(36, 28)))
    assert fill.count() == chosen.sum() > 5000
    k = round(RULES.keepout / 1e-9)
    assert drawn.separation_check(fill, k).is_empty()
    assert fill.space_check(round(RULES.spacing / 1e-9)).is_empty()
    assert (fill & drawn.minkowski_sum(kdb.Box(1 - k, 1 - k, k - 1, k - 1))).is_empty()  # Chebyshev distance too
    # the keep-out is not padded on Manhattan shapes: some square sits within 1 um more of the drawn rectangle
    assert not drawn.separation_check(fill, k + 1000).is_empty()
    # and the same chip flattened gives the same sites
    flat_lib = gdstk.Library(unit=1e-9, precision=1e-9)
    flat_lib.new_cell("TOP").add(*next(c for c in gdstk.read_gds(str(path), unit=1e-9).cells if c.name == "TOP").get_polygons())
    flat_lib.write_gds(str(tmp_path / "flat.gds"))
    np.testing.assert_array_equal(fill_sites(tmp_path / "flat.gds", ["68/20"], w, RULES).free, s.free)


def test_a_square_exactly_at_the_keepout_from_two_shapes_is_free(tmp_path):
    """Two bars exactly 2 keepout + size apart: the site between them, at exactly the keep-out from
    both, is free, its neighbours are not (an odd square side in dbu, where half a square is not
    a whole dbu)."""
    rules = FillRules(2.001 * UM, 1.499 * UM, 2.5 * UM)
    x = 749 + 2 * 3500  # the third lattice column of window 0
    for left, right, free in ((0, 0, True), (1, 0, False), (0, -1, False)):  # then 1 nm closer on either side
        lib = gdstk.Library(unit=1e-9, precision=1e-9)
        top = lib.new_cell("TOP")
        top.add(gdstk.rectangle((0, 0), (40 * NM, 40 * NM), layer=235, datatype=4))
        top.add(gdstk.rectangle((0, 0), (x - 2500 + left, 40 * NM), layer=68, datatype=20))
        top.add(gdstk.rectangle((x + 2001 + 2500 + right, 0), (40 * NM, 40 * NM), layer=68, datatype=20))
        path = tmp_path / f"gap{left}{right}.gds"
        lib.write_gds(str(path))
        w = extract_windows(path, ["68/20"], 20 * UM)
        s = fill_sites(path, ["68/20"], w, rules)
        col = int(np.nonzero(s.cx == x)[0][0])
        assert s.free.sum() == (s.free.shape[0] if free else 0)
        assert s.free[:, col].all() == free


def test_fill_file_places_patterns_as_arrays(chip, tmp_path):
    """Windows with the same pattern share one cell, placed as arrays along x: fewer instances than windows."""
    _, w, s = chip
    chosen = select_fill(s, np.minimum(s.capacity, 3))
    out = write_fill(tmp_path / "fill.oas", s, chosen, (36, 28))
    ly = kdb.Layout()
    ly.read(str(out))
    topc = ly.cell("CMPSIM_FILL")
    filled = int((chosen.reshape(s.shape[0], s.per_window, s.shape[1], s.per_window).sum(axis=(1, 3)) > 0).sum())
    assert topc.child_instances() < filled
    assert sum(1 for _ in topc.each_inst() if _.is_regular_array()) > 0
    assert ly.dbu == pytest.approx(1e-3)
    assert len(klayout_boxes(out)) == chosen.sum()


def test_a_lattice_too_large_for_the_machine_is_refused_naming_the_options(chip, monkeypatch):
    import cmpsim.layout.fill as layout_fill
    from cmpsim.layout import LayoutTooLarge

    path, w, s = chip
    monkeypatch.setattr(layout_fill, "MAX_SITES", s.free.size - 1)
    with pytest.raises(LayoutTooLarge, match="--fill-size"):
        fill_sites(path, ["68/20"], w, RULES)


@pytest.mark.parametrize("seed", range(4))
def test_random_oblique_shapes_and_placements_keep_out(tmp_path, seed):
    """Random triangles and quadrilaterals at any angle, placed at any rotation, mirrored, magnified,
    overlapping: every free site filled keeps the keep-out by KLayout's separation check (Euclidean)
    and its box distance (Minkowski sum), and odd rules in dbu change nothing."""
    rng = np.random.default_rng(seed)
    rules = FillRules(1.001 * UM, 0.999 * UM, 1.237 * UM)
    lib = gdstk.Library(unit=1e-9, precision=1e-9)
    cell = lib.new_cell("C")
    for _ in range(6):
        pts = rng.uniform(0, 12 * NM, size=(int(rng.integers(3, 5)), 2)).round()
        cell.add(gdstk.Polygon(pts, layer=68, datatype=20))
    top = lib.new_cell("TOP")
    top.add(gdstk.rectangle((0, 0), (150 * NM, 150 * NM), layer=235, datatype=4))
    for _ in range(8):
        top.add(gdstk.Reference(cell, tuple(rng.uniform(10 * NM, 130 * NM, 2).round()), rotation=float(rng.uniform(0, 2 * math.pi)),
                                magnification=float(rng.choice([1.0, 1.0, 1.7])), x_reflection=bool(rng.integers(2))))
    path = tmp_path / "random.gds"
    lib.write_gds(str(path))
    w = extract_windows(path, ["68/20"], 15 * UM)
    s = fill_sites(path, ["68/20"], w, rules)
    out = write_fill(tmp_path / "fill.gds", s, select_fill(s, s.capacity), "36/28")
    ly = kdb.Layout()
    ly.read(str(path))
    ly.read(str(out))
    drawn = kdb.Region(ly.cell("TOP").begin_shapes_rec(ly.find_layer(68, 20)))
    fill = kdb.Region(ly.cell("CMPSIM_FILL").begin_shapes_rec(ly.find_layer(36, 28)))
    k = 1237
    assert fill.count() > 500
    assert drawn.separation_check(fill, k).is_empty()
    assert (fill & drawn.minkowski_sum(kdb.Box(1 - k, 1 - k, k - 1, k - 1))).is_empty()
