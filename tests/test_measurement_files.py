"""Measurement files as a process engineer transcribes published data: spreadsheet exports, the units of
papers and patents, values with their units, and the values that cannot be fitted. Reading only (no solve),
except where a command must refuse before it solves; each test well under a second or two."""

from __future__ import annotations

import math

import numpy as np
import pytest
from click.testing import CliRunner

from cmpsim.calibration.measurements import ThermalRecord
from cmpsim.calibration.mixed import read_all
from cmpsim.calibration.uncertainty import uncertainty
from cmpsim.cli import main
from cmpsim.inputs import units
from cmpsim.inputs.config import Config

H = "quantity,value,unit,applied_pressure,rotation_speed,film"


def _write(tmp_path, name, text, encoding="utf-8"):
    p = tmp_path / name
    p.write_bytes(text.encode(encoding))
    return p


def _points(path):
    return [pt for d in read_all([path]).datasets for pt in d.points]


def test_a_spreadsheet_export_reads_as_written(tmp_path):
    # Excel's "CSV UTF-8": a byte-order mark, CRLF, capitalised column names and a trailing comma on every line
    text = "\ufeff# dataset: excel\r\nQuantity,Value,Unit,Applied_Pressure,Rotation_Speed,Film,\r\nremoval_rate,150,nm/min,4 psi,60 rpm,oxide,\r\n\r\nremoval_rate,220,nm/min,6 psi,60 rpm,oxide,\r\n"
    m = read_all([_write(tmp_path, "excel.csv", text)])
    assert [d.name for d in m.datasets] == ["excel"]  # the comment line under the BOM is still the header block
    pts = m.datasets[0].points
    assert [p.value_si for p in pts] == pytest.approx([2.5e-9, 220e-9 / 60])
    assert [p.line for p in pts] == [3, 5]  # line numbers of the file
    assert pts[0].conditions == {"applied_pressure": "4 psi", "rotation_speed": "60 rpm", "film": "oxide"}


def test_a_filled_field_beyond_the_header_is_still_refused(tmp_path):
    p = _write(tmp_path, "extra.csv", "quantity,value,unit\nremoval_rate,150,nm/min,oops\n")
    with pytest.raises(ValueError, match=r"extra.csv:2: row 1: 4 fields but the header has 3"):
        read_all([p])


@pytest.mark.parametrize(
    "unit, si",
    [
        ("nm/min", 1e-9 / 60), ("Å/min", 1e-10 / 60), ("A/min", 1e-10 / 60), ("Angstrom/min", 1e-10 / 60), ("angstroms/min", 1e-10 / 60),
        ("NM/MIN", 1e-9 / 60), ("A/sec", 1e-10), ("A/s", 1e-10), ("nm/s", 1e-9), ("um/h", 1e-6 / 3600), ("um/hr", 1e-6 / 3600),
        ("kA/min", 1e-7 / 60), ("nm min-1", 1e-9 / 60), ("micron/min", 1e-6 / 60),
    ],
)
def test_removal_rate_units_of_published_tables(unit, si):
    assert units.convert(1.0, unit, "m/s") == pytest.approx(si, rel=1e-12)
    assert units.convert(si, "m/s", unit) == pytest.approx(1.0, rel=1e-12)  # and back, as the reports write them


@pytest.mark.parametrize(
    "text, target, si",
    [
        ("4 PSI", "Pa", 4 * 6894.757293168361), ("4 Psi", "Pa", 4 * 6894.757293168361), ("300 g/cm2", "Pa", 300 * 9.80665 * 10),
        ("0.3 kg/cm2", "Pa", 0.3 * 9.80665e4), ("4 lb/in2", "Pa", 4 * 6894.757293168361), ("27.6 kPa", "Pa", 27600.0), ("0.0276 MPa", "Pa", 27600.0),
        ("60 RPM", "rad/s", 2 * math.pi), ("60 r/min", "rad/s", 2 * math.pi), ("100 cm/s", "m/s", 1.0),
        ("200 MM", "m", 0.2), ("8 IN", "m", 0.2032), ("5000 A", "m", 5e-7), ("1.5 kA", "m", 1.5e-7), ("1E3 A", "m", 1e-7), ("60 SEC", "s", 60.0),
    ],
)
def test_condition_cells_in_the_spellings_of_papers(text, target, si):
    assert units.to_si(text, target) == pytest.approx(si, rel=1e-9)


@pytest.mark.parametrize("text, target", [("3 kg", "Pa"), ("60m", "rad/s"), ("4", "Pa"), ("60", "s"), ("2 nm", "Pa")])
def test_a_unit_of_the_wrong_dimension_is_still_refused(text, target):
    with pytest.raises(ValueError, match="wrong dimension"):
        units.to_si(text, target, "x")


def test_a_unit_pint_reads_is_never_reinterpreted():
    assert units.to_si("20 mPa", "Pa") == pytest.approx(0.02)  # millipascal as written, not MPa
    assert units.to_si("3 s", "s") == 3.0


def test_a_value_written_with_its_unit(tmp_path):
    p = _write(tmp_path, "v.csv", "quantity,value,unit,uncertainty\nremoval_rate,150 nm/min,,10 nm/min\nremoval_rate,2200,A/min,10 nm/min\n"
               "removal_rate,1.6e3 A/min,A/min,50\n")
    pts = _points(p)
    assert [q.value_si for q in pts] == pytest.approx([150e-9 / 60, 220e-9 / 60, 160e-9 / 60])
    assert [q.uncertainty_si for q in pts] == pytest.approx([10e-9 / 60, 10e-9 / 60, 5e-9 / 60])


@pytest.mark.parametrize(
    "row, column, message",
    [
        ("removal_rate,150 nm/min,A/min,", "value", "carries the unit 'nm/min' but the unit column says 'A/min'"),
        ("removal_rate,150,nm/min,5%", "uncertainty", "a relative uncertainty in % is not read"),
        ("removal_rate,-150,nm/min,", "value", "a removal_rate is >= 0"),
    ],
)
def test_a_value_that_cannot_be_read_names_its_row_and_column(tmp_path, row, column, message):
    p = _write(tmp_path, "bad.csv", "quantity,value,unit,uncertainty\n" + row + "\n")
    with pytest.raises(ValueError, match=rf"bad.csv:2: row 1, column '{column}': .*{message}"):
        read_all([p])


def test_a_thickness_above_the_initial_thickness_is_refused(tmp_path):
    p = _write(tmp_path, "t.csv", "quantity,value,unit,time,initial_thickness\nthickness,800,nm,60 s,1 um\nthickness,12000,A,60 s,1 um\n")
    with pytest.raises(ValueError, match=r"t.csv:3: row 2, column 'value': the thickness left \(12000 A\) exceeds the initial_thickness"):
        read_all([p])


def test_one_series_in_several_units_is_compared_in_one(tmp_path):
    p = _write(tmp_path, "mix.csv", f"{H}\nremoval_rate,150,NM/MIN,4 PSI,60 RPM,oxide\nremoval_rate,2200,Angstrom/min,6 psi,60 rpm,oxide\n"
               "removal_rate,4.5,nm/s,8 psi,60 rpm,oxide\n")
    pts = _points(p)
    assert {q.unit for q in pts} == {"NM/MIN"}
    assert [q.value for q in pts] == pytest.approx([150, 220, 270])
    assert [q.value_si for q in pts] == pytest.approx([150e-9 / 60, 220e-9 / 60, 4.5e-9])


@pytest.mark.parametrize("unit, rise, unc", [("K", 10.0, 1.0), ("°C", 10.0, 1.0), ("degC", 10.0, 1.0), ("degF", 18.0, 1.8), ("°F", 18.0, 1.8)])
def test_a_temperature_rise_is_a_difference_of_temperatures(tmp_path, unit, rise, unc):
    p = _write(tmp_path, "pad.csv", f"quantity,value,unit,uncertainty,time\npad_temperature_rise,{rise},{unit},{unc},60 s\n")
    (r,) = read_all([p]).pad
    assert isinstance(r, ThermalRecord)
    assert (r.value, r.uncertainty) == pytest.approx((10.0, 1.0))  # 18 degF of rise is 10 K, not 265 K


@pytest.mark.parametrize("rise", ["0", "-3"])
def test_a_pad_that_does_not_warm_is_refused(tmp_path, rise):
    p = _write(tmp_path, "pad.csv", f"quantity,value,unit,time\npad_temperature_rise,{rise},K,60 s\n")
    with pytest.raises(ValueError, match=r"pad.csv:2: row 1, column 'value': a pad temperature rise must be > 0 K"):
        read_all([p])


def test_a_structure_in_microns_and_angstroms(tmp_path):
    p = _write(tmp_path, "d.csv", "quantity,value,unit,process,line_width,line_space,structure_size\ndishing,500 A,,copper,10 micron,10 µm,100 UM\n")
    (r,) = read_all([p]).structures
    assert (r.value, r.line_width, r.line_space, r.structure_size) == pytest.approx((5e-8, 1e-5, 1e-5, 1e-4))


def test_a_lot_row_with_a_spreadsheet_wafer_number(tmp_path):
    p = _write(tmp_path, "lot.csv", "quantity,value,unit,wafer\nthickness,5000,A,1.0\nthickness,512 nm,,2\n")
    lots = read_all([p]).lots
    assert [r.wafer for r in lots] == [1, 2]
    assert [r.value for r in lots] == pytest.approx([5e-7, 5.12e-7])
    bad = _write(tmp_path, "lot2.csv", "quantity,value,unit,wafer\nthickness,500,nm,2.5\n")
    with pytest.raises(ValueError, match=r"lot2.csv:2: row 1, column 'wafer': '2.5' is not a wafer number"):
        read_all([bad])


def test_one_data_set_name_in_two_files_names_both(tmp_path):
    a = _write(tmp_path, "a.csv", "# dataset: same\nquantity,value,unit\nremoval_rate,150,nm/min\n")
    b = _write(tmp_path, "b.csv", "# dataset: same\nquantity,value,unit\nremoval_rate,160,nm/min\n")
    with pytest.raises(ValueError, match=r"repeated: 'same' in .*a.csv and .*b.csv"):
        read_all([a, b])


def test_a_foreign_config_file_is_named(tmp_path):
    p = _write(tmp_path, "pyproject.toml", "[tool.poetry]\nname = 'x'\n")
    with pytest.raises(ValueError, match=r"config file '.*pyproject.toml': unknown parameter 'tool'"):
        Config.from_toml(p)


def test_an_exact_fit_without_uncertainties_has_no_interval():
    # two points, one input, residuals zero: the reduced chi-square cannot scale the covariance
    J = np.array([[1.0], [2.0]])
    u = uncertainty(J, 1e-30, 1, False, {"x": 1.0}, {"x": False}, {"x": 1.0}, {"x": (0.0, 10.0)})
    assert all(math.isnan(v) for v in u.ci95["x"]) and math.isnan(u.stderr["x"])
    assert any("fitted exactly" in n for n in u.notes)
    u = uncertainty(J, 0.5, 1, False, {"x": 1.0}, {"x": False}, {"x": 1.0}, {"x": (0.0, 10.0)})  # a real scatter: scaled as before
    assert u.stderr["x"] == pytest.approx(math.sqrt(0.5 / 5.0))


def test_calibrate_refuses_a_zero_without_uncertainty_and_writes_nothing(tmp_path):
    p = _write(tmp_path, "zero.csv", f"{H}\nremoval_rate,0,nm/min,4 psi,60 rpm,oxide\nremoval_rate,220,nm/min,6 psi,60 rpm,oxide\n")
    out = tmp_path / "cal.toml"
    r = CliRunner().invoke(main, ["calibrate", str(p), "--grid", "coarse", "--out", str(out), "--quiet"])
    assert r.exit_code == 2, r.output
    assert "zero.csv:2: row 1, column 'uncertainty': a measured removal_rate of 0 needs its uncertainty" in r.output
    assert not out.exists()


def test_validate_refuses_a_position_beyond_the_wafer_before_solving(tmp_path):
    p = _write(tmp_path, "prof.csv", "quantity,value,unit,radius\nremoval_rate,150,nm/min,10 mm\nremoval_rate,150,nm/min,2 in\n")
    out = tmp_path / "v"
    r = CliRunner().invoke(main, ["validate", str(p), "--grid", "coarse", "--out", str(out), "--markdown"])
    assert r.exit_code == 2, r.output
    assert "prof.csv:3: row 2, column 'radius': radius 50.8 mm lies beyond the wafer (radius 38.1 mm" in r.output
    assert not out.exists()


@pytest.mark.parametrize("name, kind", [("recipe_copper.toml", "is a recipe"), ("example_sweep.toml", "is a sweep specification")])
def test_a_recipe_or_a_sweep_given_as_config_says_what_it_is(name, kind):
    from importlib import resources

    with pytest.raises(ValueError, match=rf"config file '.*{name}' {kind}"):
        Config.from_toml(str(resources.files("cmpsim") / "data" / name))


def test_a_template_with_empty_rows_and_the_columns_of_other_families(tmp_path):
    # a fab's template: every family's columns, ",,,," rows between the points; only the filled ones count
    p = _write(tmp_path, "t.csv", "quantity,value,unit,process,line_width,wafer,applied_pressure\nremoval_rate,150,nm/min,,,,4 psi\n,,,,,,\n"
               "removal_rate,220,nm/min,,,,6 psi\n")
    pts = _points(p)
    assert [(q.line, q.value_si, q.conditions) for q in pts] == [(2, pytest.approx(2.5e-9), {"applied_pressure": "4 psi"}),
                                                               (4, pytest.approx(220e-9 / 60), {"applied_pressure": "6 psi"})]
    typo = _write(tmp_path, "typo.csv", "quantity,value,unit,aplied_pressure\nremoval_rate,150,nm/min,\n")
    with pytest.raises(ValueError, match="unknown column 'aplied_pressure'.*did you mean applied_pressure"):  # a name no family knows is refused, filled or not
        read_all([typo])


@pytest.mark.parametrize(
    "text, message",
    [
        ("quantity;value;unit\nremoval_rate;150,5;nm/min\n", "separated by semicolons"),
        ("quantity,value,unit\nremoval_rate,\"1,500\",A/min\n", r"'1,500' is not a number \(a thousands separator or a decimal comma"),
    ],
)
def test_a_european_export_is_explained(tmp_path, text, message):
    with pytest.raises(ValueError, match=message):
        read_all([_write(tmp_path, "eu.csv", text)])


def test_a_file_not_in_utf8_says_how_to_save_it(tmp_path):
    p = _write(tmp_path, "l1.csv", "quantity,value,unit,time\nremoval,1.5,\u00b5m,60 s\n", encoding="latin-1")
    with pytest.raises(ValueError, match=r"l1.csv' is not UTF-8 text.*CSV UTF-8"):
        read_all([p])


def test_a_free_input_the_data_do_not_depend_on_is_refused_and_nothing_written(tmp_path):
    # wafer-mean rates do not depend on the metrology edge exclusion: its "fitted" value was wherever the optimiser left it
    p = _write(tmp_path, "two.csv", f"{H}\nremoval_rate,150,nm/min,4 psi,60 rpm,oxide\nremoval_rate,220,nm/min,6 psi,60 rpm,oxide\n")
    out = tmp_path / "cal.toml"
    r = CliRunner().invoke(main, ["calibrate", str(p), "--free", "edge_exclusion", "--grid", "coarse", "--out", str(out), "--quiet"])
    assert r.exit_code == 2, r.output
    assert "--free edge_exclusion: the model's values at these data do not change with it" in r.output
    assert not out.exists()


def test_an_uncertainty_printed_with_its_plus_minus_sign(tmp_path):
    p = _write(tmp_path, "pm.csv", "quantity,value,unit,uncertainty,process,line_width,wafer,time\nremoval_rate,150,nm/min,±10,,,,\n"
               "dishing,50,nm,+/- 4,copper,1 um,,\nthickness,500,nm,+-5 nm,,,1,\npad_temperature_rise,9,K,± 1 K,,,,60 s\n")
    m = read_all([p])
    assert m.datasets[0].points[0].uncertainty_si == pytest.approx(10e-9 / 60)
    assert (m.structures[0].uncertainty, m.lots[0].uncertainty, m.pad[0].uncertainty) == pytest.approx((4e-9, 5e-9, 1.0))


@pytest.mark.parametrize(
    "text",
    [
        "quantity,value,unit,uncertainty\nfriction_coefficient,0.3,,5%\n",  # 5 % of 0.3, or 0.05? not guessed
        "quantity,value,unit,uncertainty\nfluid_load_fraction,0.5,1,5%\n",
        "quantity,value,unit,uncertainty,wafer\nthickness,500,nm,5 A,1\n",
    ],
)
def test_an_uncertainty_in_another_unit_than_its_value_is_not_guessed(tmp_path, text):
    with pytest.raises(ValueError, match=r"u.csv:2: row 1, column 'uncertainty'"):
        read_all([_write(tmp_path, "u.csv", text)])


def test_names_in_capitals_read(tmp_path):
    p = _write(tmp_path, "caps.csv", "Quantity,Value,Unit,Comparison,Film,Process,Line_Width,Applied_Pressure\n"
               "Removal_Rate,150,nm/min,Shape,Oxide,,,4 psi\nREMOVAL_RATE,220,nm/min,shape,OXIDE,,,6 psi\nDishing,50,nm,,,Copper,10 um,\n")
    m = read_all([p])
    assert [(q.quantity, q.comparison, q.film) for q in m.datasets[0].points] == [("removal_rate", "shape", "oxide")] * 2
    assert (m.structures[0].quantity, m.structures[0].process) == ("dishing", "copper")


def test_a_line_break_inside_a_cell_is_refused_naming_its_line(tmp_path):
    # the readers number rows by lines: a cell over two lines shifted every later row's line (and a mixed file's rows)
    p = _write(tmp_path, "nl.csv", 'quantity,value,unit,note\nremoval_rate,150,nm/min,"two\nlines"\nremoval_rate,160,nm/min,x\n')
    with pytest.raises(ValueError, match=r"nl.csv:2: a quoted field runs past the end of the line"):
        read_all([p])
    ok = _write(tmp_path, "q.csv", 'quantity,value,unit,note\nremoval_rate,150,nm/min,"a 5"" wafer, polished"\n')
    assert _points(ok)[0].value_si == pytest.approx(2.5e-9)


def test_calibrate_never_writes_over_its_own_data(tmp_path):
    p = _write(tmp_path, "d.csv", f"{H}\nremoval_rate,150,nm/min,4 psi,60 rpm,oxide\n")
    before = p.read_bytes()
    r = CliRunner().invoke(main, ["calibrate", str(p), "--out", str(p), "--quiet"])
    assert r.exit_code == 2 and "is one of the input files" in r.output, r.output
    assert p.read_bytes() == before


@pytest.mark.parametrize("text", ["93 1/min", "93 min^-1", "93 min-1", "1.55 Hz"])
def test_a_rotation_speed_without_an_angle_is_refused(tmp_path, text):
    # pint's radian is dimensionless: 93 1/min was read as 93 rad/min, 2 pi times slower than the 93 rpm it means
    with pytest.raises(ValueError, match="is a frequency without an angle"):
        units.to_si(text, "rad/s", "rotation_speed")
    p = _write(tmp_path, "r.csv", f"quantity,value,unit,rotation_speed\nremoval_rate,150,nm/min,{text}\n")
    with pytest.raises(ValueError, match=r"r.csv:2: row 1, column 'rotation_speed': .*without an angle"):
        read_all([p])
    assert units.to_si("93 rev/min", "rad/s") == pytest.approx(93 * 2 * math.pi / 60)


def test_a_fit_that_mixes_points_with_and_without_uncertainty_says_how_it_weighted_them(tmp_path):
    from cmpsim.calibration import calibrate

    p = _write(tmp_path, "m.csv", "quantity,value,unit,uncertainty,applied_pressure,rotation_speed,film\n"
               "removal_rate,150,nm/min,10,4 psi,60 rpm,oxide\nremoval_rate,220,nm/min,,6 psi,60 rpm,oxide\n")
    cal = calibrate(read_all([p]).datasets, ["mechanical_factor_oxide"], grid="coarse")
    assert any("1 of 2 points have no uncertainty" in n for n in cal.notes)


def test_a_misspelt_free_name_is_named_as_unknown(tmp_path):
    # with only test structures, a typo of a die constant was reported as needing "removal or other wafer-scale rows"
    p = _write(tmp_path, "d.csv", "quantity,value,unit,process,line_width\ndishing,50,nm,copper,10 um\n")
    r = CliRunner().invoke(main, ["calibrate", str(p), "--free", "contact_hieght", "--out", str(tmp_path / "c.toml"), "--quiet"])
    assert r.exit_code == 2 and "--free contact_hieght: unknown parameter 'contact_hieght'; did you mean contact_height" in r.output, r.output


def test_units_after_every_value_need_no_unit_column(tmp_path):
    p = _write(tmp_path, "nu.csv", "quantity,value,applied_pressure,process,line_width,time\nremoval_rate,150 nm/min,4 psi,,,\n"
               "removal_rate,2.2e3 A/min,6 psi,,,\ndishing,50 nm,,copper,10 um,\npad_temperature_rise,9 K,,,,60 s\n")
    m = read_all([p])
    assert [q.value_si for q in m.datasets[0].points] == pytest.approx([2.5e-9, 220e-9 / 60])
    assert (m.structures[0].value, m.pad[0].value) == pytest.approx((5e-8, 9.0))
    bad = _write(tmp_path, "nu2.csv", "quantity,value\nremoval_rate,150 nm/min\nremoval_rate,160\n")
    with pytest.raises(ValueError, match=r"nu2.csv:1: required column 'unit' is missing .*line 3, row 2 has none"):
        read_all([bad])


def test_units_in_the_header(tmp_path):
    # a spreadsheet's "value (nm/min)" and "applied_pressure [psi]": the unit of every plain number below it
    p = _write(tmp_path, "hu.csv", "Quantity,Value (nm/min),Uncertainty (nm/min),Applied_Pressure [psi],rotation_speed (rpm),wafer (#)\n"
               "removal_rate,150,10,4,60,\nremoval_rate,2200 A/min,,6 psi,60,\nthickness,500 nm,,,,1\n")
    m = read_all([p])
    a, b = m.datasets[0].points
    assert (a.value_si, a.uncertainty_si, b.value_si) == pytest.approx((2.5e-9, 10e-9 / 60, 220e-9 / 60))
    assert a.conditions == {"applied_pressure": "4 psi", "rotation_speed": "60 rpm"} and b.conditions["applied_pressure"] == "6 psi"
    assert (m.lots[0].wafer, m.lots[0].value) == (1, pytest.approx(5e-7))


def test_text_handed_over_with_a_byte_order_mark(tmp_path):
    from cmpsim.validation.data import load_datasets

    (ds,) = load_datasets(tmp_path / "up.csv", text="\ufeffquantity,value,unit\nremoval_rate,150,nm/min\n")
    assert ds.points[0].value_si == pytest.approx(2.5e-9)


def test_a_quantity_in_words_suggests_its_name(tmp_path):
    p = _write(tmp_path, "q.csv", "quantity,value,unit\nremoval rate,150,nm/min\n")
    with pytest.raises(ValueError, match=r"q.csv:2: row 1, column 'quantity': unknown quantity 'removal rate' \(did you mean removal_rate"):
        read_all([p])
