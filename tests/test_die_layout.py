"""The die model on real layouts (issue 33): per-window fields, stacks, hotspots, outputs, the wafer, bad input.

Every layout is built here with gdstk (line arrays of known density, width and space; a
hierarchy of references, stepped); none is read from outside the repository.
"""

import json
import xml.etree.ElementTree as ET

import gdstk
import numpy as np
import pytest
from click.testing import CliRunner

from cmpsim import die
from cmpsim.cli import main
from cmpsim.die.chip import DieModel, StackLevel, layout_die, read_stack, simulate_stack
from cmpsim.die.layout import Layout
from cmpsim.die.process import DieProcess

K = 2e-9  # m/s: a blanket rate given, so that most tests solve no wafer
PL = 0.3e-3  # m: a planarization length of the order of these small dies


def _lines(name, layer, width, pitch, size, datatype=0):
    """A cell of vertical lines (um): width, pitch, over a size x size block."""
    cell = gdstk.Cell(name)
    n = int(round(size / pitch))
    for i in range(n):
        cell.add(gdstk.rectangle((i * pitch, 0), (i * pitch + width, size), layer=layer, datatype=datatype))
    return cell


def _chip(path, steps=2, origin=(1000.0, -500.0)):
    """A hierarchical, stepped chip (um, dbu 1 nm): per step a 200 um tile with two line arrays on layer 1/0
    (1 um lines at 4 um pitch; 2 um at 4 um) and one on layer 2/0 (0.5 um at 2 um pitch), the tile stepped
    steps x steps at a 400 um pitch, with 200 um of empty gap; also met1 (68/20 and fill 36/28) for the PDK names."""
    lib = gdstk.Library(unit=1e-6, precision=1e-9)
    a = _lines("A", 1, 1.0, 4.0, 100.0)
    b = _lines("B", 1, 2.0, 4.0, 100.0)
    c = _lines("C", 2, 0.5, 2.0, 100.0)
    m = _lines("M", 68, 1.0, 4.0, 60.0, 20)
    mf = gdstk.Cell("MF")
    mf.add(gdstk.rectangle((60, 0), (100, 40), layer=36, datatype=28))
    tile = gdstk.Cell("TILE")
    tile.add(gdstk.Reference(a, (0, 0)), gdstk.Reference(b, (100, 0)), gdstk.Reference(c, (0, 100)),
             gdstk.Reference(m, (100, 100)), gdstk.Reference(mf, (100, 100)))
    top = gdstk.Cell("CHIP")
    top.add(gdstk.Reference(tile, origin, columns=steps, rows=steps, spacing=(400.0, 400.0)))
    # a marker shape on another layer marks the die's outline (the gap after the last step)
    top.add(gdstk.rectangle(origin, (origin[0] + 400.0 * steps, origin[1] + 400.0 * steps), layer=100))
    lib.add(a, b, c, m, mf, tile, top)
    if str(path).endswith(".oas"):
        lib.write_oas(str(path))
    else:
        lib.write_gds(str(path))
    return path


@pytest.fixture(scope="module")
def chip(tmp_path_factory):
    return _chip(tmp_path_factory.mktemp("chip") / "chip.gds")


@pytest.fixture(scope="module")
def stack_file(tmp_path_factory):
    p = tmp_path_factory.mktemp("stack") / "stack.toml"
    p.write_text('window = "20 um"\n[spec]\nthickness = "2 nm"\n'
                 '[[level]]\nname = "m1"\nlayers = ["1/0"]\nprocess = "copper"\ntrench_depth = "0.4 um"\n'
                 '[[level]]\nname = "m2"\nlayers = ["2/0"]\nprocess = "oxide"\nstep_height = "0.6 um"\n')
    return p


# ---------------------------------------------------------------------------- fields
def test_every_window_has_the_density_width_and_space_of_its_line_array(chip):
    lay = layout_die(chip, ["1/0"], 20e-6)
    assert lay.windowed and lay.origin == pytest.approx((1e-3, -0.5e-3)) and lay.shape == (40, 40)
    x, y = lay.coordinates()
    assert x[0] == pytest.approx(1e-3 + 10e-6) and y[0] == pytest.approx(-0.5e-3 + 10e-6)
    # windows inside block A (1 um at 4 um) and block B (2 um at 4 um) of the first tile
    for (ix, iy), (rho, w, s) in {(2, 2): (0.25, 1e-6, 3e-6), (7, 2): (0.5, 2e-6, 2e-6)}.items():
        assert lay.density[iy, ix] == pytest.approx(rho, abs=1e-12)
        assert lay.widths()[iy, ix] == pytest.approx(w, rel=1e-12)
        assert lay.spaces()[iy, ix] == pytest.approx(s, rel=1e-12)
    assert np.all(lay.density[12:18, 12:18] == 0)  # the gap between steps
    # the same windows in every step of the reticle
    assert np.allclose(lay.density[:20, :20], lay.density[20:, 20:], rtol=0, atol=1e-12)


def test_named_layers_merge_drawn_and_fill(chip):
    lay = layout_die(chip, ["met1"], 20e-6, pdk="sky130")
    assert set(lay.layers) == {(68, 20), (36, 28)}
    assert lay.density[5, 5] == pytest.approx(0.25, abs=1e-12)  # met1 lines 1 um at 4 um
    assert lay.density[5, 8] == pytest.approx(1.0)  # the fill block covers windows [8, 5] and [9, 5] whole


def test_the_per_window_path_equals_the_region_path_on_block_layouts():
    grid = die.builtin_layout("lines", 500e-6)
    rho, w = grid.density, grid.line_width
    with np.errstate(divide="ignore", invalid="ignore"):
        space = np.where(rho > 0, w * (1 - rho) / rho, 0.0)
    windows = Layout(rho, grid.cell_size, w, "lines", space, (0.0, 0.0), (0.0, 0.0, *grid.size), True, ((1, 0),))
    for process in ("oxide", "copper"):
        ref = die.simulate(grid, blanket_rate=K, process=process, planarization_length=2e-3)
        model = DieModel(process=process, blanket_rate=K, planarization_length=2e-3)
        got = model.run(windows)
        assert got.time == pytest.approx(ref.time, rel=1e-12)
        for name in ("za", "zb", "t_planar", "t_clear"):
            a, b = getattr(got.evolution, name), getattr(ref.evolution, name)
            assert np.allclose(a, b, rtol=1e-12, atol=1e-21, equal_nan=True), (process, name)
        # every region's value at its site is the window's
        for r in ref.regions():
            iy, ix = next(reg.site for reg in grid.regions() if reg.index == r["index"])
            for key, field in (("step_height", got.evolution.step_height), ("dishing", got.evolution.dishing), ("erosion", got.evolution.erosion)):
                v = field[iy, ix]
                assert (r[key] is None and not np.isfinite(v)) or r[key] == pytest.approx(v, rel=1e-12, abs=1e-21)
        assert "regions" not in got.to_dict() and "windows" in got.to_dict()


# ---------------------------------------------------------------------------- stacks
def test_an_incoming_height_is_carried_exactly_and_an_incoming_step_adds_to_the_initial_step(chip):
    lay = layout_die(chip, ["1/0"], 20e-6)
    rng = np.random.default_rng(3)
    height = rng.normal(0, 20e-9, lay.shape)
    for process in ("oxide", "copper"):
        model = DieModel(process=process, blanket_rate=K, planarization_length=PL)
        alone = model.run(lay)
        moved = model.run(lay, alone.time, incoming=(height, np.zeros(lay.shape)))
        assert np.allclose(moved.evolution.mean_height - alone.evolution.mean_height, height, rtol=0, atol=1e-18)
        for name in ("step_height", "dishing", "erosion"):
            assert np.allclose(getattr(moved.evolution, name), getattr(alone.evolution, name), rtol=0, atol=1e-18, equal_nan=True)
        from cmpsim.die.evolution import DieEvolution

        ev = DieEvolution(lay, model.process, lay.density, K, 7e-6, None, (0.0, 30e-9))
        ev0 = DieEvolution(lay, model.process, lay.density, K, 7e-6, None, None)
        two = (lay.density > 0) & (lay.density < 1)
        assert np.allclose((ev.za0 - ev.zb0)[two], (ev0.za0 - ev0.zb0)[two] + 30e-9, rtol=0, atol=1e-18)
        assert np.allclose(ev.mean_height, ev0.mean_height, rtol=0, atol=1e-18)  # the step keeps the cell's mean


def test_a_two_level_stack_differs_from_its_second_level_alone_by_what_the_first_left(chip, stack_file):
    levels, options = read_stack(stack_file)
    assert [lv.name for lv in levels] == ["m1", "m2"] and levels[0].process.trench_depth == pytest.approx(0.4e-6)
    st = simulate_stack(chip, stack_file, blanket_rate=K, planarization_length=PL)
    first, second = st.levels
    alone = DieModel(process=levels[1].process, blanket_rate=K, planarization_length=PL).run(layout_die(chip, ["2/0"], 20e-6))
    left_height, left_step = first.evolution.topography()
    assert np.ptp(left_height) > 1e-9  # the first level leaves topography
    # exactly the second level polished over what the first left
    again = DieModel(process=levels[1].process, blanket_rate=K, planarization_length=PL).run(
        layout_die(chip, ["2/0"], 20e-6), incoming=(left_height, left_step))
    assert np.array_equal(again.evolution.mean_height, second.evolution.mean_height)
    diff = second.evolution.mean_height - alone.evolution.mean_height
    # the surface is the second level's own plus the first level's height map, up to the share of the step left
    assert np.max(np.abs(diff - left_height)) <= np.max(left_step) + 1e-15
    assert second.thickness_range != pytest.approx(alone.thickness_range, rel=1e-3)
    d = st.to_dict()
    assert [lv["name"] for lv in d["levels"]] == ["m1", "m2"]
    assert {"thickness_range", "hotspots", "hotspot_count", "dishing_max", "time"} <= set(d["levels"][0])
    assert d["thickness_range"] == pytest.approx(second.thickness_range)
    assert d["hotspot_count"] == len(d["hotspots"]) == sum(lv["hotspot_count"] for lv in d["levels"])
    assert all(h["level"] in ("m1", "m2") for h in d["hotspots"])


# ---------------------------------------------------------------------------- the command and its files
def test_layout_run_writes_the_contract_and_hotspots_that_open_in_klayout(chip, tmp_path):
    out = tmp_path / "out"
    res = CliRunner().invoke(main, ["die", str(chip), "--layer", "1/0", "--window", "20um", "--process", "copper",
                                    "--blanket-rate", "120nm/min", "--planarization-length", "0.3mm",
                                    "--spec", "thickness=2nm", "--spec", "dishing=10nm", "--spec", "erosion=5nm",
                                    "--spec", "step_height=20nm", "--json", "--out", str(out)])
    assert res.exit_code == 0, res.output
    d = json.loads(res.stdout)
    assert {"hotspots", "hotspot_count", "thickness_range", "windows"} <= set(d) and "regions" not in d
    assert d["hotspot_count"] == len(d["hotspots"]) > 0 and d["thickness_range"] > 0
    assert all(set(h) == {"kind", "x", "y", "value", "limit"} for h in d["hotspots"])
    assert {h["kind"] for h in d["hotspots"]} <= {"thickness", "dishing", "erosion", "step_height"}
    assert d["spec"]["thickness"] == pytest.approx(2e-9) and d["units"]["thickness_range"] == "m"
    x0, y0, x1, y1 = d["windows"]["bbox"]
    assert all(x0 <= h["x"] <= x1 and y0 <= h["y"] <= y1 for h in d["hotspots"])
    for name in ("die.nc", "die.png", "die.json", "hotspots.lyrdb", "hotspots.csv"):
        assert (out / name).stat().st_size > 0, name
    import xarray as xr

    with xr.open_dataset(out / "die.nc") as ds:
        for name in ("density", "line_width", "space", "mean_height", "thickness", "step_height", "dishing", "erosion"):
            assert ds[name].dims == ("y", "x") and ds[name].attrs["units"] in ("m", "1"), name
        assert ds["x"].attrs["units"] == "m" and float(ds["x"][0]) == pytest.approx(1e-3 + 10e-6)
        assert float(ds["thickness_range"]) == pytest.approx(d["thickness_range"])
    # the report database: XML of KLayout's format, every marker inside the layout's bounding box (microns)
    root = ET.parse(out / "hotspots.lyrdb").getroot()
    assert root.tag == "report-database" and root.findtext("top-cell") == "CHIP"
    cats = {c.findtext("name") for c in root.iter("category") if c.find("name") is not None}
    items = root.find("items").findall("item")
    assert len(items) == d["hotspot_count"] and {i.findtext("category") for i in items} <= cats
    for it in items:
        box = next(v.text for v in it.find("values") if v.text.startswith("box:"))
        a, b = box[len("box: ("):-1].split(";")
        bx0, by0 = map(float, a.split(","))
        bx1, by1 = map(float, b.split(","))
        assert x0 * 1e6 - 1e-6 <= bx0 < bx1 <= x1 * 1e6 + 1e-6 and y0 * 1e6 - 1e-6 <= by0 < by1 <= y1 * 1e6 + 1e-6
    lines = (out / "hotspots.csv").read_text().splitlines()
    assert lines[0].startswith("level,kind,x_m") and len(lines) == d["hotspot_count"] + 1
    rdb = pytest.importorskip("klayout.rdb", reason="KLayout's Python module (the test extra) opens the report database")
    db = rdb.ReportDatabase("")
    db.load(str(out / "hotspots.lyrdb"))
    assert db.num_items() == d["hotspot_count"] and db.top_cell_name == "CHIP"


def test_a_stack_run_from_the_command_line(chip, stack_file, tmp_path):
    out = tmp_path / "st"
    res = CliRunner().invoke(main, ["die", str(chip), "--stack", str(stack_file), "--blanket-rate", "120nm/min",
                                    "--planarization-length", "0.3mm", "--json", "--out", str(out)])
    assert res.exit_code == 0, res.output
    d = json.loads(res.stdout)
    assert [lv["name"] for lv in d["levels"]] == ["m1", "m2"] and d["spec"] == {"thickness": pytest.approx(2e-9)}
    import xarray as xr

    with xr.open_dataset(out / "die.nc") as ds:
        assert ds["mean_height"].dims == ("level", "y", "x") and list(ds["level"].values) == ["m1", "m2"]
    assert (out / "die_m1.png").exists() and (out / "die_m2.png").exists() and (out / "hotspots.lyrdb").exists()


def test_a_wafer_of_layout_dies_reports_hotspots_per_die(tmp_path):
    p = tmp_path / "big.oas"
    lib = gdstk.Library(unit=1e-6, precision=1e-9)
    top = gdstk.Cell("BIG")  # a 10 x 10 mm die: a dense and a sparse array of 10 um lines
    dense = _lines("D", 1, 10.0, 12.5, 2000.0)
    top.add(gdstk.Reference(dense, (0, 0)), gdstk.Reference(_lines("S", 1, 10.0, 50.0, 2000.0), (6000, 6000)))
    top.add(gdstk.rectangle((0, 0), (10000, 10000), layer=100))
    lib.add(top, *top.dependencies(True))
    lib.write_oas(str(p))
    res = CliRunner().invoke(main, ["die", str(p), "--layer", "1/0", "--window", "250um", "--wafer", "--process", "copper",
                                    "--spec", "thickness=20nm", "--set", "grid=coarse", "--set", "wafer_diameter=150mm",
                                    "--json", "--out", str(tmp_path / "w")])
    assert res.exit_code == 0, res.output
    d = json.loads(res.stdout)
    assert d["die_reading"] == "exact" and len(d["dies"]) > 50
    counts = [x["hotspot_count"] for x in d["dies"]]
    assert all(isinstance(c, int) for c in counts) and max(counts) > 0
    assert all(x["thickness_range"] > 0 for x in d["dies"])
    assert d["wafer_hotspot_count"] == sum(counts)
    assert (tmp_path / "w" / "wafer.png").stat().st_size > 0


# ---------------------------------------------------------------------------- bad input
@pytest.mark.parametrize("case", ["not_a_layout", "missing_layer", "empty_layer", "window_too_large", "unknown_process", "no_layer",
                                  "stack_layer_map_missing", "stack_level_layer_missing", "placement_past_2_31", "missing_file", "directory",
                                  "stack_window_too_large"])
def test_bad_input_is_refused_naming_the_parameter_and_nothing_is_written(chip, tmp_path, case):
    args = ["die", str(chip), "--layer", "1/0", "--blanket-rate", "100nm/min"]
    expect = {"not_a_layout": "not a layout", "missing_layer": "'7/0'", "empty_layer": "empty layer",
              "window_too_large": "larger than the die", "unknown_process": "unknown process 'tungsten'",
              "no_layer": "--layer", "stack_layer_map_missing": "layer_map", "stack_level_layer_missing": "level 'm2' of 2: --layer '7/0'",

              "placement_past_2_31": "past KLayout's 32-bit coordinates",
              # a missing file whose name is not a layout's was called "a CSV grid or a built-in die"; a directory "does not exist"
              "missing_file": "chip.gds.zip' does not exist", "directory": "is a directory",
              # the window was the stack file's, the message spoke of --window alone
              "stack_window_too_large": "choose a smaller window (from --stack s.toml: window = '5 mm')"}[case]
    if case == "not_a_layout":
        bad = tmp_path / "text.gds"
        bad.write_text("hello, not GDSII\n")
        args[1] = str(bad)
    elif case == "missing_layer":
        args[3] = "7/0"
    elif case == "empty_layer":
        lib = gdstk.Library(unit=1e-6, precision=1e-9)
        c = gdstk.Cell("E")
        c.add(gdstk.rectangle((0, 0), (100, 100), layer=5))
        other = gdstk.Cell("UNUSED")  # layer 1/0 exists in the file, but not under the top cell E
        other.add(gdstk.rectangle((0, 0), (1, 1), layer=1))
        lib.add(c, other)
        args[1] = str(tmp_path / "e.gds")
        lib.write_gds(args[1])
        args += ["--top", "E"]
    elif case == "window_too_large":
        args += ["--window", "2mm"]
    elif case == "unknown_process":
        st = tmp_path / "s.toml"
        st.write_text('[[level]]\nname = "m1"\nlayers = ["1/0"]\nprocess = "tungsten"\n')
        args = ["die", str(chip), "--stack", str(st), "--blanket-rate", "100nm/min"]
    elif case == "placement_past_2_31":  # a magnified placement there was a traceback of KLayout's merge (status 1)
        lib = gdstk.Library(unit=1e-6, precision=1e-9)
        leaf, top = gdstk.Cell("LEAF"), gdstk.Cell("TOP")
        leaf.add(gdstk.rectangle((0, 0), (1000, 1000), layer=1))
        top.add(gdstk.rectangle((0, 0), (100, 100), layer=1), gdstk.Reference(leaf, (0, 0), magnification=5000))
        lib.add(leaf, top)
        args[1] = str(tmp_path / "far.gds")
        lib.write_gds(args[1])
        args += ["--window", "1mm"]
    elif case == "missing_file":
        args[1] = str(tmp_path / "chip.gds.zip")
    elif case == "directory":
        args[1] = str(tmp_path)
    elif case == "no_layer":
        args = args[:2] + args[4:]
    elif case == "stack_window_too_large":
        st = tmp_path / "s.toml"
        st.write_text('window = "5 mm"\n[[level]]\nname = "m1"\nlayers = ["1/0"]\nprocess = "oxide"\n')
        args = ["die", str(chip), "--stack", str(st), "--blanket-rate", "100nm/min"]
    elif case.startswith("stack_"):  # a stack's layer map that is not there (was a traceback), a level's layer the chip lacks
        st = tmp_path / "s.toml"
        second = "m2" if case == "stack_layer_map_missing" else "7/0"
        st.write_text(f'[[level]]\nname = "m1"\nlayers = ["1/0"]\nprocess = "oxide"\n[[level]]\nname = "m2"\nlayers = ["{second}"]\nprocess = "oxide"\n')
        args = ["die", str(chip), "--stack", str(st), "--blanket-rate", "100nm/min"]
        if case == "stack_layer_map_missing":
            args += ["--layer-map", str(tmp_path / "no_such_map.toml")]
    out = tmp_path / "never"
    res = CliRunner().invoke(main, args + ["--out", str(out)])
    assert res.exit_code == 2, res.output
    assert expect in res.output and "Traceback" not in res.output
    assert not out.exists()


def test_the_built_in_dies_and_csv_grids_still_run_as_before():
    res = CliRunner().invoke(main, ["die", "uniform", "--json", "--time", "1 min", "--blanket-rate", "100 nm/min"])
    assert res.exit_code == 0, res.output
    d = json.loads(res.stdout)
    assert d["regions"] and d["hotspot_count"] == 0 and d["hotspots"] == []
    bad = CliRunner().invoke(main, ["die", "uniform", "--layer", "1/0"])
    assert bad.exit_code == 2 and "--layer" in bad.output


# ---------------------------------------------------------------------------- a stack with a calibration's die constants
def _die_calibration(tmp_path, process="copper", extra=""):
    """A process file whose [calibration.die] fits contact_height and summit_radius of ``process`` with a covariance (SI, logs)."""
    p = tmp_path / f"cal_{process}.toml"
    p.write_text(f'[calibration.die]\nprocess = "{process}"\n{extra}'
                 '[calibration.die.constants]\ncontact_height = 2e-8\nsummit_radius = 5e-6\n'
                 '[calibration.die.uncertainty]\nnames = ["contact_height", "summit_radius"]\nvalues = [2e-8, 5e-6]\n'
                 'covariance_log = [[0.04, 0.01], [0.01, 0.09]]\n')
    return p


def test_a_stack_applies_a_calibrations_die_constants_to_the_levels_of_its_process(chip, stack_file, tmp_path):
    from cmpsim.calibration.processfile import die_constants

    dc = die_constants(_die_calibration(tmp_path))
    st = simulate_stack(chip, stack_file, blanket_rate=K, planarization_length=PL, calibration=dc)
    plain = simulate_stack(chip, stack_file, blanket_rate=K, planarization_length=PL)
    m1, m2 = st.levels
    # the copper level runs with the fitted constants and carries their covariance; the oxide level is as before
    assert m1.process.contact_height == 2e-8 and m1.process.summit_radius == 5e-6 and m1.uncertainty is dc.uncertainty
    assert m1.process.trench_depth == pytest.approx(0.4e-6)  # the stack file's own input is kept
    assert m2.uncertainty is None and m2.process == plain.levels[1].process
    alone = DieModel(process=m1.process, blanket_rate=K, planarization_length=PL).run(layout_die(chip, ["1/0"], 20e-6))
    assert np.array_equal(m1.evolution.thickness, alone.evolution.thickness, equal_nan=True)
    hot = st.to_dict()["hotspots"]
    assert hot and all(("interval" in h) == (h["level"] == "m1") for h in hot)
    for h in hot:
        if h["level"] == "m1":
            lo, hi = h["interval"]
            assert lo <= h["value"] <= hi and 0.0 <= h["probability"] <= 1.0


def test_a_stack_refuses_a_calibration_it_cannot_apply(chip, stack_file, tmp_path):
    from cmpsim.calibration.processfile import die_constants

    copper = die_constants(_die_calibration(tmp_path))
    st = tmp_path / "clash.toml"
    st.write_text(stack_file.read_text().replace('trench_depth = "0.4 um"', 'trench_depth = "0.4 um"\ncontact_height = "30 nm"'))
    with pytest.raises(ValueError, match=r"level 'm1' sets contact_height, calibrated in"):
        simulate_stack(chip, st, blanket_rate=K, planarization_length=PL, calibration=copper)
    oxide_only = tmp_path / "oxide.toml"
    oxide_only.write_text('[[level]]\nname = "m2"\nlayers = ["2/0"]\nprocess = "oxide"\n')
    with pytest.raises(ValueError, match="calibrated on copper structures; no level of the stack is copper"):
        simulate_stack(chip, oxide_only, blanket_rate=K, planarization_length=PL, calibration=copper)


def test_a_stack_run_takes_the_process_file_from_the_command_line(chip, stack_file, tmp_path):
    cal = _die_calibration(tmp_path)
    res = CliRunner().invoke(main, ["die", str(chip), "--stack", str(stack_file), "--blanket-rate", "120nm/min",
                                    "--planarization-length", "0.3mm", "--config", str(cal), "--json"])
    assert res.exit_code == 0, res.output
    d = json.loads(res.stdout)
    assert "uncertainty" in d["levels"][0] and "uncertainty" not in d["levels"][1]
    assert any("probability" in h for h in d["hotspots"])
    assert d["at_risk_count"] == len(d["at_risk"]) == d["levels"][0]["at_risk_count"] and "at_risk" not in d["levels"][1]
    text = CliRunner().invoke(main, ["die", str(chip), "--stack", str(stack_file), "--blanket-rate", "120nm/min",
                                     "--planarization-length", "0.3mm", "--config", str(cal)])
    assert text.exit_code == 0, text.output
    assert ("may exceed it" in text.output) == bool(d["at_risk"]) and "interval" in text.output and "probability" in text.output
