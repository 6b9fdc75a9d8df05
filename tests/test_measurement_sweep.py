"""Data files as users type them in (a robustness sweep of the readers): each case is refused naming its line,
row and column, or read as meant; never a traceback, never a value read other than as written."""

from __future__ import annotations

import pytest

from cmpsim.calibration.mixed import read_all
from cmpsim.inputs import units

H = "quantity,value,unit,applied_pressure,rotation_speed,film"


def _write(tmp_path, name, text, encoding="utf-8"):
    p = tmp_path / name
    p.write_bytes(text.encode(encoding))
    return p


def _refused(tmp_path, name, text, match):
    """Write the file and assert the readers refuse it with a message matching ``match``."""
    p = _write(tmp_path, name, text)
    with pytest.raises(ValueError, match=match):
        read_all([p])


@pytest.mark.parametrize(
    "header, row, column",
    [
        (H, "removal_rate,150,nm/min,\"3,5 psi\",60 rpm,copper", "applied_pressure"),  # pint dropped the comma: 35 psi
        (H, "removal_rate,150,nm/min,\"34,500 Pa\",60 rpm,copper", "applied_pressure"),
        ("quantity,value,unit,process,line_width", "dishing,25,nm,copper,\"1,5 um\"", "line_width"),  # was read as 15 um
        ("quantity,value,unit,time,applied_pressure,rotation_speed", "removal,300,nm,\"1,5 min\",4 psi,60 rpm", "time"),
        ("wafer,quantity,value,unit,time", "1,thickness,500,nm,\"1,5 min\"", "time"),
    ],
)
def test_a_quantity_with_a_comma_is_refused_not_read_without_it(tmp_path, header, row, column):
    _refused(tmp_path, "comma.csv", f"{header}\n{row}\n", rf"comma.csv:2: row 1, column '{column}': .*has a comma.*decimal point")


def test_a_quantity_with_a_comma_is_refused_by_the_units_too():
    with pytest.raises(ValueError, match="has a comma"):
        units.to_si("3,5 psi", "Pa", "applied_pressure")
    assert units.to_si("3.5 psi", "Pa") == pytest.approx(3.5 * 6894.757, rel=1e-6)


@pytest.mark.parametrize(
    "header, row",
    [
        ("quantity,value,unit,uncertainty", "removal_rate,150,nm/min,\"1,5\""),  # the film reader's message had no place
        ("quantity,value", "removal_rate,\"1,5 um/min\""),
    ],
)
def test_a_decimal_comma_in_a_value_or_uncertainty_names_its_place(tmp_path, header, row):
    column = header.split(",")[-1]
    _refused(tmp_path, "eu.csv", f"{header}\n{row}\n", rf"eu.csv:2: row 1, column '{column}': '1,5.*' is not a number \(a thousands separator")


def test_a_lot_file_with_a_repeated_column_is_refused(tmp_path):
    # the second 'value' was read and the first dropped without a word
    _refused(tmp_path, "lot.csv", "wafer,quantity,value,unit,value\n1,thickness,500,nm,600\n", r"lot.csv:1: column 'value': a column name is repeated in the header")


@pytest.mark.parametrize(
    "header, row",
    [
        ("quantity,value,unit,applied_pressure,Applied_Pressure", "removal_rate,150,nm/min,5 psi,4 psi"),
        ("quantity,value,unit,process,line_width,line_width", "dishing,25,nm,copper,1 um,2 um"),
        ("quantity,value,unit,applied_pressure (psi),applied_pressure [kPa]", "removal_rate,150,nm/min,5,30"),
    ],
)
def test_a_repeated_column_is_named(tmp_path, header, row):
    _refused(tmp_path, "twice.csv", f"{header}\n{row}\n", r"twice.csv:1: (header, )?column '(applied_pressure|line_width)': (a column name is repeated|duplicate column names)")


def test_a_row_whose_first_cell_begins_with_a_hash_is_not_dropped_as_a_comment(tmp_path):
    head = "label,quantity,value,unit,applied_pressure,rotation_speed,film\n"
    _refused(tmp_path, "hash.csv", head + "2,removal_rate,120,nm/min,2 psi,43 rpm,copper\n#1,removal_rate,150,nm/min,5 psi,63 rpm,copper\n", r"hash.csv:3: row 2, column 'label': the line starts with '#' but has the header's 7 fields")
    # quoted, the cell is a label; a comment line, even with commas, is still a comment
    ok = _write(tmp_path, "ok.csv", head + '"#1",removal_rate,150,nm/min,5 psi,63 rpm,copper\n# note: 5 psi, 63 rpm, copper\n')
    [pt] = read_all([ok]).datasets[0].points
    assert (pt.label, pt.value) == ("#1", 150.0)


@pytest.mark.parametrize("encoding", ["utf-16", "utf-16-le"])
def test_a_utf16_file_is_named_as_such(tmp_path, encoding):
    # without its byte-order mark, UTF-16 decoded as UTF-8 and the header read 'q\x00u\x00a...': "required column 'quantity' is missing"
    p = _write(tmp_path, "u16.csv", "quantity,value,unit\nremoval_rate,150,nm/min\n", encoding=encoding)
    with pytest.raises(ValueError, match=r"u16.csv' is UTF-16 text, not UTF-8 \(save it as UTF-8"):
        read_all([p])


def test_a_latin1_file_names_the_line_of_its_first_foreign_byte(tmp_path):
    p = _write(tmp_path, "l1.csv", "quantity,value,unit\nremoval_rate,150,nm/min\nremoval_rate,0.2,\u00b5m/min\n", encoding="latin-1")
    with pytest.raises(ValueError, match=r"l1.csv' is not UTF-8 text: line 3 has the byte"):
        read_all([p])


@pytest.mark.parametrize("header", [H, "quantity,value,unit,process,line_width,line_space", "wafer,quantity,value,unit"])
def test_a_header_without_rows_says_so(tmp_path, header):
    # a structure or lot template was refused for its columns ("unknown column 'process'") by the film reader
    _refused(tmp_path, "empty.csv", f"# dataset: t\n{header}\n,,,\n", r"empty.csv:2: the file has a header but no data rows")


def test_a_unit_after_a_comma_in_the_header(tmp_path):
    # '"value, nm/min"' was one column name: "required column 'value' is missing (header: quantity, value, nm/min, ...)"
    p = _write(tmp_path, "hdr.csv", 'quantity,"value, nm/min","applied_pressure, psi",rotation_speed\nremoval_rate,150,5,60 rpm\n')
    [pt] = read_all([p]).datasets[0].points
    assert (pt.value, pt.unit, pt.conditions["applied_pressure"]) == (150.0, "nm/min", "5 psi")



@pytest.mark.parametrize(
    "header, row, column, message",
    [
        ("quantity,value,unit,process,line_width,time", "dishing,25,nm,copper,1 um,1:30", "time", r"'1:30' is written as a clock"),
        ("wafer,quantity,value,unit,time", "1,thickness,500,nm,1:30", "time", r"'1:30' is written as a clock"),
        ("quantity,value,unit,process,line_width", "dishing,25,nm,copper,1", "line_width", r"'1' has no unit .*; write it with its unit \(e.g. '1 um'\)"),
        (H, "removal_rate,150,nm/min,5,60 rpm,copper", "applied_pressure", r"'5' has no unit .*; write it with its unit \(e.g. '5 psi'\)"),
        ("quantity,value,unit,process,line_width,line_space", "dishing,25,nm,copper,1 um,0 um", "line_space",
         r"must be a length > 0 \(a space of 0 .* leave the cell empty for an isolated line"),
    ],
)
def test_a_time_as_a_clock_a_bare_number_and_a_space_of_0_say_how_to_write_them(tmp_path, header, row, column, message):
    # they said "has the wrong dimension; expected units convertible to 's'" (pint reads 1:30 as a ratio)
    _refused(tmp_path, "say.csv", f"{header}\n{row}\n", rf"say.csv:2: row 1, column '{column}'.*{message}")


@pytest.mark.parametrize(
    "header, row, film",
    [
        (H, "removal_rate,150,nm/min,5 psi,60 rpm,Cu", "copper"),
        (H, "removal_rate,150,nm/min,5 psi,60 rpm,TEOS", "oxide"),
        ("wafer,quantity,value,unit,film", "1,thickness,500,nm,Cu", "copper"),  # the lot row kept 'cu' without a word
    ],
)
def test_a_film_named_as_papers_name_it_is_refused_with_cmpsims_name(tmp_path, header, row, film):
    _refused(tmp_path, "film.csv", f"{header}\n{row}\n", rf"film.csv:2: row 1, column 'film': .*oxide'?, '?copper.*write '{film}'")


def test_excels_separator_line(tmp_path):
    # "sep=," (Excel's hint) was taken for the header: "required column 'quantity' is missing (header: sep=)"
    ok = _write(tmp_path, "sep.csv", f"sep=,\n{H}\nremoval_rate,150,nm/min,5 psi,60 rpm,copper\n")
    [pt] = read_all([ok]).datasets[0].points
    assert (pt.value, pt.line) == (150.0, 3)
    eu = _write(tmp_path, "eu.csv", "sep=;\nquantity;value;unit\nremoval_rate;150,5;nm/min\n")
    with pytest.raises(ValueError, match=r"eu.csv:1: the line 'sep=;' says the file is separated by ';'"):
        read_all([eu])
    mixed = _write(tmp_path, "mixed.csv", "quantity;value;unit;note, free text\nremoval_rate;150,5;nm/min;x\n")
    with pytest.raises(ValueError, match=r"mixed.csv:1: required column 'quantity' is missing .*separated by semicolons"):
        read_all([mixed])


def test_a_lot_row_that_lost_its_wafer_number_says_so(tmp_path):
    # it became a film row and was refused as "quantity 'thickness' needs the time column"
    _refused(tmp_path, "lot.csv", "wafer,quantity,value,unit,time\n1,thickness,500,nm,60 s\n,thickness,480,nm,61 s\n", r"lot.csv:3: row 2, column 'wafer': empty, but the file's other rows are a lot's wafers")


def test_thousands_of_rows_parse_each_distinct_setting_once(tmp_path, monkeypatch):
    # each row's conditions were parsed by pint four times: 11 s for 10,000 rows of 12 settings (counted, not timed)
    parsed, parse = [], units._quantity_to_si
    monkeypatch.setattr(units, "_quantity_to_si", lambda *a: parsed.append(a[0]) or parse(*a))
    units._text_to_si.cache_clear()
    rows = "".join(f"removal_rate,{150 + k % 7},nm/min,{2 + k % 4} psi,{40 + 10 * (k % 3)} rpm,copper\n" for k in range(2000))
    p = _write(tmp_path, "big.csv", f"{H}\n{rows}")
    pts = read_all([p]).datasets[0].points
    assert len(pts) == 2000 and pts[-1].conditions["rotation_speed"] == "50 rpm"
    assert 7 <= len(parsed) and len(parsed) == len(set(parsed))  # the 4 pressures and 3 speeds, each once


@pytest.mark.parametrize(
    "header, row, column",
    [
        ("quantity,value,unit,process,line_width,line_space", "dishing,25,nm,copper,1 um,-", "line_space"),  # said "cannot read '-' (); ..."
        (H, "removal_rate,150,nm/min,n/a,60 rpm,copper", "applied_pressure"),
        ("quantity,value,unit,uncertainty", "removal_rate,150,nm/min,n/a", "uncertainty"),
        ("quantity,value,unit,uncertainty,process,line_width", "dishing,25,nm,-,copper,1 um", "uncertainty"),
        ("wafer,quantity,value,unit,uncertainty", "1,thickness,500,nm,n/a", "uncertainty"),
    ],
)
def test_a_cell_that_stands_for_no_value_says_to_leave_it_empty(tmp_path, header, row, column):
    _refused(tmp_path, "na.csv", f"{header}\n{row}\n", rf"na.csv:2: row 1, column '{column}': .*stands for no value: leave the cell empty")


@pytest.mark.parametrize(
    "header, row",
    [("quantity,value,unit", "removal_rate,150 ± 10,nm/min"), ("quantity,value", "removal_rate,150 +/- 10 nm/min"),
     ("wafer,quantity,value,unit", "1,thickness,500 ± 5,nm")],
)
def test_a_value_printed_with_its_uncertainty_says_where_the_uncertainty_goes(tmp_path, header, row):
    # said "value '150 ± 10' is not a number", or asked for a unit column the row had
    _refused(tmp_path, "pm.csv", f"{header}\n{row}\n", r"pm.csv:2: row 1, column 'value': .* holds an uncertainty: .* in the uncertainty column")


@pytest.mark.parametrize(
    "text, target",
    [("93/87 rpm", "rad/s"), ("34 500 Pa", "Pa"), ("2 3 psi", "Pa"), ("60 s 30", "s"), ("2^3 psi", "Pa"), ("200 mm (8 in)", "m")],
)
def test_a_quantity_with_two_numbers_is_refused(text, target):
    # pint multiplied or divided them: '93/87 rpm' (platen/head) was 1.07 rpm, '34 500 Pa' 17000 Pa
    with pytest.raises(ValueError, match="holds more than one number"):
        units.to_si(text, target, "x")


@pytest.mark.parametrize(
    "text, target, si",
    [("175 mL/min", "m^3/s", 175e-6 / 60), ("300 g/cm2", "Pa", 300 * 9.80665 * 10), ("249.5 nm min-1", "m/s", 249.5e-9 / 60),
     ("249.5 nm·min⁻¹", "m/s", 249.5e-9 / 60), ("1.2E+03 Pa", "Pa", 1200.0), ("2 m^3/s", "m^3/s", 2.0), ("5 1/s", "1/s", 5.0)],
)
def test_units_with_powers_still_read(text, target, si):
    assert units.to_si(text, target) == pytest.approx(si, rel=1e-9)


def test_a_platen_and_head_speed_in_one_cell_names_its_row(tmp_path):
    _refused(tmp_path, "rpm.csv", f"{H}\nremoval_rate,150,nm/min,5 psi,93/87 rpm,copper\n", r"rpm.csv:2: row 1, column 'rotation_speed': .*'93/87 rpm' holds more than one number")


@pytest.mark.parametrize(
    "header, row, column",
    [("quantity,value,unit", "removal_rate,1_497,A/min", "value"), ("quantity,value,unit,process,line_width", "dishing,25,nm,copper,1_0 um", "line_width"),
     ("wafer,quantity,value,unit", "1,thickness,5_000,A", "value")],
)
def test_an_underscore_between_digits_is_refused_as_a_separator(tmp_path, header, row, column):
    # Python's float() and pint read '1_497' as 1497: a thousands separator, which a comma is refused as
    _refused(tmp_path, "u.csv", f"{header}\n{row}\n", rf"u.csv:2: row 1, column '{column}': .*separator")


@pytest.mark.parametrize("header, row, where", [("quantity,value,,unit", "removal_rate,150,,nm/min", "3 \\(after 'value'\\)"),
                                                (",quantity,value,unit", ",removal_rate,150,nm/min", "1 \\(the first\\)")])
def test_a_column_without_a_name_is_named_by_its_place(tmp_path, header, row, where):
    # said "unknown column ''"
    _refused(tmp_path, "blank.csv", f"{header}\n{row}\n", rf"blank.csv:1: header, column {where} has no name: delete the sheet's empty column")


def test_zone_pressures_separated_by_spaces_are_refused(tmp_path):
    # one zone of 3.1 x 3.0 x 2.9 = 27 psi was read
    _refused(tmp_path, "zp.csv", "wafer,quantity,value,unit,time,zone_pressures\n1,thickness,500,nm,60 s,3.1 3.0 2.9 psi\n", r"zp.csv:2: row 1, column 'zone_pressures': .*holds more than one number")


@pytest.mark.parametrize("header, row, column", [(H, "removal_rate,249,5,nm/min,5 psi,63 rpm,copper", "value"),
                                                 ("quantity,value,unit,process,line_width", "dishing,1,497,A,copper,1 um", "value")])
def test_an_unquoted_decimal_comma_is_named_in_the_field_count(tmp_path, header, row, column):
    # said only "7 fields but the header has 6"
    _refused(tmp_path, "eu.csv", f"{header}\n{row}\n", rf"eu.csv:2: row 1: .* fields but the header has .*column '{column}': '[0-9]+,[0-9]+', a decimal comma")


@pytest.mark.parametrize(
    "rows, where",
    [("removal_rate,150,nm/min,shape\n", r"shape.csv:2: row 1, column 'comparison': shape data set 'shape' needs at least 2 points"),
     ("removal_rate,150,nm/min,shape\nremoval_rate,160,nm/min,absolute\n", r"shape.csv:3: row 2, column 'comparison': .* mixes comparison modes"),
     ("removal_rate,150,nm/min,shape\nfluid_load_fraction,0.5,1,shape\n", r"shape.csv:3: row 2, column 'quantity': shape data set 'shape' must hold one")],
)
def test_a_data_set_that_cannot_be_compared_names_the_row(tmp_path, rows, where):
    # named the file only
    _refused(tmp_path, "shape.csv", "quantity,value,unit,comparison\n" + rows, where)


@pytest.mark.parametrize("text, why", [("\u22123 psi", "a minus sign is written '-'"), ("\u20133 psi", "a minus sign is written '-'"),
                                       ("<5 psi", "a bound or an approximate value is not a value"),
                                       ("~5 psi", "a bound or an approximate value is not a value"),
                                       ("\u22485 psi", "a bound or an approximate value is not a value"), ("5 psi;", "write one number")])
def test_a_character_the_unit_parser_drops_is_refused(text, why):
    # pint's tokenizer dropped them without a word: a typographic minus read '-3 psi' as +3 psi, '<5 psi' as 5 psi
    with pytest.raises(ValueError, match=rf"applied_pressure: .* holds the character .*would drop without a word.*{why}"):
        units.to_si(text, "Pa", "applied_pressure")


def test_the_marks_of_units_still_read():
    assert units.to_si("1 nm\u00b7min\u207b\u00b9", "m/s") == pytest.approx(1e-9 / 60)
    assert units.to_si("2 m\u00b2", "m^2") == 2.0 and units.to_si("5 \u00b5m", "m") == pytest.approx(5e-6)
    assert units.to_si("(5) psi", "Pa") == pytest.approx(5 * 6894.757, rel=1e-6) and units.to_si("5\u00a0psi", "Pa") > 0


def test_a_value_with_a_typographic_minus_says_so(tmp_path):
    _refused(tmp_path, "minus.csv", "quantity,value,unit,x,y\nremoval_rate,150,nm/min,\u221250 mm,0 mm\n", r"minus.csv:2: row 1, column 'x': .*a minus sign is written '-'")
    _refused(tmp_path, "v.csv", "quantity,value,unit\nremoval_rate,\u2212150,nm/min\n", r"v.csv:2: row 1, column 'value': .*typographic: write '-'")
