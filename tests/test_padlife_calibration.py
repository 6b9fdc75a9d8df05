"""The pad life's glazing and conditioning constants calibrated from a lot's wafers (issue 38, "What to build").

A lot simulated with known constants is recovered within the fit's 95 % intervals, through the
API and through `cmpsim calibrate LOT.csv --recipe`; the process file carries them to `cmpsim lot
--config` and `cmpsim validate --recipe`; what a lot cannot separate is said. No published
per-wafer lot is shipped (docs/calibrate.md, section 9): the data here are synthetic."""

import json
from dataclasses import replace
import math
from importlib import resources
from pathlib import Path

import numpy as np
import pytest
from click.testing import CliRunner

from cmpsim.calibration.lotdata import LotRecord
from cmpsim.calibration.padlife import (
    GLAZING_CONSTANTS,
    LotSetting,
    calibrate_padlife,
    default_constants,
    padlife_constants,
    predict_lot,
)
from cmpsim.cli import main

RECIPE = Path(str(resources.files("cmpsim") / "data" / "recipe_oxide.toml"))
COARSE = {"grid": "coarse"}
WAFERS = 10
NOISE = 1e-9  # m: one standard uncertainty of a wafer's measured removal


def _lot(true: dict, conditioning: str = "none", seed: int = 1):
    """Per-wafer removal of a lot polished with the constants ``true``, with 1 nm of measurement noise."""
    setting = LotSetting(RECIPE, conditioning=conditioning, seed=0, overrides=dict(COARSE))
    shape = [LotRecord(w, "removal", 0.0, NOISE) for w in range(1, WAFERS + 1)]
    clean = predict_lot(shape, true, setting)
    rng = np.random.default_rng(seed)
    return [LotRecord(w, "removal", float(v + rng.normal(0.0, NOISE)), NOISE, dataset="synthetic_lot", line=w + 1)
            for w, v in zip(range(1, WAFERS + 1), clean)], setting


@pytest.fixture(scope="module")
def doubled_wear():
    """A lot without conditioning whose pad wears twice as fast as the default (Jeong-calibrated) pad."""
    true = {"pad_wear_coefficient": 2 * default_constants()["pad_wear_coefficient"]}
    records, setting = _lot(true)
    return true, records, calibrate_padlife(records, setting)


def test_the_data_choose_the_wear_coefficient_and_recover_it_within_its_interval(doubled_wear):
    true, _, cal = doubled_wear
    assert cal.free == ["pad_wear_coefficient"]
    lo, hi = cal.ci95["pad_wear_coefficient"]
    assert lo < true["pad_wear_coefficient"] < hi
    assert hi / lo < 1.1  # ten wafers at 1 nm fix it to a few per cent
    assert np.sqrt(np.mean(cal.residuals_after**2)) < 1.5 * NOISE < np.sqrt(np.mean(cal.residuals_before**2))
    assert cal.chi2 < 3 * cal.dof


def test_a_lot_without_conditioning_says_what_it_cannot_separate(doubled_wear):
    _, _, cal = doubled_wear
    left = dict(cal.left)
    assert "cannot be separated" in left["critical_glazed_area"]  # only k_w^a / G_c is seen by a decay of this length
    assert "conditioner_rate_constant" not in left and "conditioner_rate_constant" not in cal.free  # no disk, nothing to say about it
    assert "singular values" in " ".join(cal.identifiability)


def test_both_glazing_constants_free_are_recovered_within_their_intervals_and_their_correlation_reported():
    d = default_constants()
    true = {"pad_wear_coefficient": 2.0 * d["pad_wear_coefficient"], "critical_glazed_area": 0.6 * d["critical_glazed_area"]}
    records, setting = _lot(true)
    cal = calibrate_padlife(records, setting, ["pad_wear_coefficient", "critical_glazed_area"])
    for n, v in true.items():
        lo, hi = cal.ci95[n]
        assert lo < v < hi, n
    assert cal.correlation[0, 1] > 0.95
    assert any("cannot be separated" in s and "correlation" in s for s in cal.identifiability)


def test_a_constant_left_at_a_wrong_value_is_flagged_by_the_chi_square():
    """Both k_w and G_c off (x 2, x 0.6): the lot chooses k_w alone, which predicts the wafers to 1.9 nm RMS but
    absorbs G_c's error (k_w 1.10e-14 for a true 5.53e-15, with an interval that is conditional on G_c);
    with 1 nm uncertainties the chi-square (36 for 9) says so, and the report warns."""
    d = default_constants()
    true = {"pad_wear_coefficient": 2.0 * d["pad_wear_coefficient"], "critical_glazed_area": 0.6 * d["critical_glazed_area"]}
    records, setting = _lot(true)
    cal = calibrate_padlife(records, setting)
    assert cal.free == ["pad_wear_coefficient"]
    assert np.sqrt(np.mean(cal.residuals_after**2)) < 2.5 * NOISE
    assert cal.chi2 > 3 * cal.dof
    text = cal.summary()
    assert "conditional on critical_glazed_area" in text and "not described within its uncertainties" in text


def test_a_conditioned_lot_recovers_the_conditioner_constant_and_reports_its_tie_to_the_wear():
    """Ex situ at half the default disk constant: the first wafers approach the balance of wear and renewal,
    which separates k_c from k_w (correlation +0.98, reported); G_c is not separable (fixed, said)."""
    d = default_constants()
    true = {**d, "conditioner_rate_constant": 0.5 * d["conditioner_rate_constant"]}
    records, setting = _lot(true, "ex_situ")
    cal = calibrate_padlife(records, setting)
    assert cal.free == ["pad_wear_coefficient", "conditioner_rate_constant"]
    for n in cal.free:
        lo, hi = cal.ci95[n]
        assert lo < true[n] < hi, n
    assert "cannot be separated" in dict(cal.left)["critical_glazed_area"]
    assert any("pad_wear_coefficient and conditioner_rate_constant cannot be separated" in s for s in cal.identifiability)
    assert np.sqrt(np.mean(cal.residuals_after**2)) < 1.5 * NOISE


def test_a_constant_the_lot_does_not_see_is_refused_by_name(tmp_path):
    """A lot without conditioning does not change with the disk's constant: asked for, k_c would come back at its
    start with an interval [0, inf]; it is refused naming it, as the die's and the wafer-scale fits refuse one,
    and from the command line with exit status 2 and nothing written."""
    setting = LotSetting(RECIPE, conditioning="none", seed=0, overrides=dict(COARSE))
    shape = [LotRecord(w, "removal", 0.0, NOISE) for w in (1, 2, 3)]
    records = [replace(r, value=float(v)) for r, v in zip(shape, predict_lot(shape, None, setting))]
    with pytest.raises(ValueError, match=r"^free conditioner_rate_constant: this lot's rows do not change with it .*not identifiable"):
        calibrate_padlife(records, setting, ["pad_wear_coefficient", "conditioner_rate_constant"])
    lot_csv = tmp_path / "lot.csv"
    lot_csv.write_text("dataset,quantity,value,unit,uncertainty,wafer\n" + "".join(f"lot,removal,{r.value * 1e9!r},nm,1,{r.wafer}\n" for r in records))
    out = tmp_path / "cal.toml"
    res = CliRunner().invoke(main, ["calibrate", str(lot_csv), "--recipe", str(RECIPE), "--lot-conditioning", "none", "--grid", "coarse",
                                    "--free", "conditioner_rate_constant", "--quiet", "--out", str(out)])
    assert res.exit_code == 2 and "free conditioner_rate_constant: this lot's rows do not change with it" in " ".join(res.output.split())
    assert not out.exists()


def test_without_degrees_of_freedom_the_intervals_need_the_uncertainties():
    """One wafer, one constant: with its uncertainty the covariance is (J^T J)^-1; without, no scatter is left to
    scale it by, and the interval is undefined (printed [-, -], with a note), not [0, inf]."""
    setting = LotSetting(RECIPE, conditioning="none", seed=0, overrides=dict(COARSE))
    shape = [LotRecord(3, "removal", 0.0, NOISE)]
    one = [replace(shape[0], value=float(predict_lot(shape, {"pad_wear_coefficient": 2 * default_constants()["pad_wear_coefficient"]},
                                                     setting)[0]))]
    given = calibrate_padlife(one, setting, ["pad_wear_coefficient"])
    lo, hi = given.ci95["pad_wear_coefficient"]
    assert given.dof == 0 and given.absolute_sigma and 0 < lo < given.values["pad_wear_coefficient"] < hi < math.inf
    bare = calibrate_padlife([replace(one[0], uncertainty=None)], setting, ["pad_wear_coefficient"])
    assert bare.dof == 0 and not bare.absolute_sigma and all(math.isnan(v) for v in bare.ci95["pad_wear_coefficient"])
    assert any("no degrees of freedom left" in s for s in bare.identifiability) and "[-, -]" in bare.summary()


def test_calibrate_from_the_command_line_writes_the_pad_life_and_lot_and_validate_use_it(tmp_path):
    true = {"pad_wear_coefficient": 2 * default_constants()["pad_wear_coefficient"]}
    records, _ = _lot(true)
    lot_csv = tmp_path / "lot.csv"
    lot_csv.write_text("dataset,quantity,value,unit,uncertainty,wafer\n"
                       + "".join(f"synthetic_lot,removal,{r.value * 1e9:.3f},nm,1,{r.wafer}\n" for r in records))
    out = tmp_path / "calibrated.toml"
    res = CliRunner().invoke(main, ["calibrate", str(lot_csv), "--recipe", str(RECIPE), "--lot-conditioning", "none", "--grid", "coarse",
                                    "--quiet", "--out", str(out)])
    assert res.exit_code == 0, res.output
    assert "== pad life: 10 wafer row(s)" in res.output and "fixed critical_glazed_area" in res.output
    consts = padlife_constants(out)
    lo, hi = json.loads(json.dumps(__import__("tomllib").loads(out.read_text())["calibration"]["padlife"]["ci95"]))["pad_wear_coefficient"]
    assert lo < true["pad_wear_coefficient"] < hi and lo < consts["pad_wear_coefficient"] < hi
    lot = CliRunner().invoke(main, ["lot", str(RECIPE), "--config", str(out), "--conditioning", "none", "--wafers", "10", "--seed", "0",
                                    "--set", "grid=coarse", "--json"])
    assert lot.exit_code == 0, lot.output
    wafers = json.loads(lot.output)["wafers"]
    removed = np.array([w["incoming_mean"] - w["final_thickness_mean"] for w in wafers])
    assert np.sqrt(np.mean((removed - [r.value for r in records]) ** 2)) < 1.5 * NOISE
    # held out: validate compares the rows with the calibrated lot (points.csv, measured and model)
    val = CliRunner().invoke(main, ["validate", str(lot_csv), "--config", str(out), "--recipe", str(RECIPE), "--lot-conditioning", "none",
                                    "--grid", "coarse", "--out", str(tmp_path / "heldout")])
    assert val.exit_code == 0, val.output
    import csv

    rows = list(csv.DictReader((tmp_path / "heldout" / "points.csv").open()))
    assert len(rows) == WAFERS and all(r["status"] == "ok" for r in rows)
    assert max(abs(float(r["error"])) for r in rows) < 4.0  # nm
    # a recipe that runs its pad's life glazes with them in `cmpsim polish --config` too
    recipe = tmp_path / "oxide_glazing.toml"
    recipe.write_text(RECIPE.read_text().replace('[[film]]', 'conditioning = "none"\n[[film]]', 1))
    rates = []
    for extra in (["--config", str(out)], []):
        pol = CliRunner().invoke(main, ["polish", str(recipe), *extra, "--set", "grid=coarse", "--json"])
        assert pol.exit_code == 0, pol.output
        rates.append(json.loads(pol.output)["steps"][0]["glazing"]["rate_factor"][-1])
    assert rates[0] < rates[1] < 1  # the calibrated pad (k_w doubled) has glazed further by the end of the step
    # the uncalibrated lot misses the same wafers by tens of nm
    plain = CliRunner().invoke(main, ["lot", str(RECIPE), "--conditioning", "none", "--wafers", "10", "--seed", "0", "--set", "grid=coarse",
                                      "--json"])
    removed0 = np.array([w["incoming_mean"] - w["final_thickness_mean"] for w in json.loads(plain.output)["wafers"]])
    assert np.sqrt(np.mean((removed0 - [r.value for r in records]) ** 2)) > 20e-9


def test_a_lot_under_the_fabs_own_control_is_replayed_at_its_logged_times(tmp_path):
    """A fab's lot is run by its own controller, whose model is not cmpsim's. Here: a pad that glazes twice
    as fast, controlled by a double EWMA whose pad model is the default one; each wafer's removal and polish
    time logged. With the times (column ``time``) the calibration replays them and recovers k_w within its
    interval; the replay of the true pad gives the logged removals exactly."""
    from cmpsim.calibration.lotdata import read_lot_rows
    from cmpsim.polisher.lot import run_lot

    d = default_constants()
    true = {"pad_wear_coefficient": 2 * d["pad_wear_coefficient"]}
    fab = run_lot(RECIPE, WAFERS, control="ewma", conditioning="none", seed=0, overrides=dict(COARSE), pad_constants=true,
                  model_pad_constants=d, zone_feedback=False)
    rng = np.random.default_rng(3)
    lot_csv = tmp_path / "fab_lot.csv"
    lot_csv.write_text("dataset,quantity,value,unit,uncertainty,wafer,time\n" + "".join(
        f"fab_lot,removal,{(w.incoming_mean - w.final_thickness_mean + rng.normal(0, NOISE)) * 1e9:.4f},nm,1,{w.index},{w.polish_time!r} s\n"
        for w in fab.wafers))
    records = read_lot_rows(lot_csv, lot_csv.read_text())
    assert [r.time for r in records] == [w.polish_time for w in fab.wafers]
    setting = LotSetting(RECIPE, conditioning="none", control="ewma", seed=0, overrides=dict(COARSE))
    replay = predict_lot(records, true, setting)
    assert np.allclose(replay, [w.incoming_mean - w.final_thickness_mean for w in fab.wafers], rtol=0, atol=1e-15)
    cal = calibrate_padlife(records, setting)
    lo, hi = cal.ci95["pad_wear_coefficient"]
    assert cal.free == ["pad_wear_coefficient"] and lo < true["pad_wear_coefficient"] < hi


def test_a_lot_whose_controller_moved_the_zones_is_replayed_with_its_logged_zone_pressures(tmp_path):
    """A controller with zone feedback sets each wafer's zone pressures too: logged in ``zone_pressures`` (one
    quoted cell, psi), they are replayed with the times, and the removals come back exactly; the times
    alone (the recipe's pressures) do not give them."""
    from cmpsim.calibration.lotdata import read_lot_rows
    from cmpsim.polisher.lot import run_lot

    d = default_constants()
    fab = run_lot(RECIPE, 3, control="ewma", conditioning="none", seed=0, overrides=dict(COARSE), model_pad_constants=d)
    assert len({w.zone_pressures for w in fab.wafers}) > 1  # the feedback moved them
    psi = 6894.757293168361
    lines = "".join(f'fab,removal,{(w.incoming_mean - w.final_thickness_mean) * 1e9!r},nm,{w.index},{w.polish_time!r} s,'
                    f'"{", ".join(repr(p / psi) for p in w.zone_pressures)} psi"\n' for w in fab.wafers)
    lot_csv = tmp_path / "fab_zones.csv"
    lot_csv.write_text("dataset,quantity,value,unit,wafer,time,zone_pressures\n" + lines)
    records = read_lot_rows(lot_csv, lot_csv.read_text())
    assert records[1].zone_pressures == pytest.approx(fab.wafers[1].zone_pressures, rel=1e-12)
    setting = LotSetting(RECIPE, conditioning="none", seed=0, overrides=dict(COARSE))
    removed = [w.incoming_mean - w.final_thickness_mean for w in fab.wafers]
    assert np.allclose(predict_lot(records, d, setting), removed, rtol=0, atol=1e-13)
    times_only = [replace(r, zone_pressures=None) for r in records]
    assert np.max(np.abs(predict_lot(times_only, d, setting) - removed)) > 1e-10


def test_validate_replays_a_logged_lot_from_the_command_line(tmp_path):
    from cmpsim.polisher.lot import run_lot

    fab = run_lot(RECIPE, 3, control="ewma", conditioning="none", seed=0, overrides=dict(COARSE), zone_feedback=False)
    lot_csv = tmp_path / "lot.csv"
    lot_csv.write_text("dataset,quantity,value,unit,wafer,time\n" + "".join(
        f"fab,removal,{(w.incoming_mean - w.final_thickness_mean) * 1e9!r},nm,{w.index},{w.polish_time!r} s\n" for w in fab.wafers))
    res = CliRunner().invoke(main, ["validate", str(lot_csv), "--recipe", str(RECIPE), "--lot-conditioning", "none", "--grid", "coarse",
                                    "--out", str(tmp_path / "v")])
    assert res.exit_code == 0, res.output
    import csv

    rows = list(csv.DictReader((tmp_path / "v" / "points.csv").open()))
    assert len(rows) == 3 and max(abs(float(r["error"])) for r in rows) < 1e-6  # nm: the lot given back
    assert "replayed at the logged" in " ".join(res.output.split())  # the comparison's note (a table cell, wrapped)


def test_logged_times_are_all_or_none_and_one_per_wafer(tmp_path):
    from cmpsim.calibration.lotdata import LotDataError, logged_times, read_lot_rows

    def rows(text):
        f = tmp_path / "lot.csv"
        f.write_text("dataset,quantity,value,unit,wafer,time\n" + text)
        return read_lot_rows(f, f.read_text())

    assert logged_times(rows("lot,removal,250,nm,1,1 min\nlot,thickness,240,nm,1,60 s\nlot,removal,240,nm,2,61.5 s\n")) == [60.0, 61.5]
    assert logged_times(rows("lot,removal,250,nm,1,\nlot,removal,240,nm,2,\n")) is None
    with pytest.raises(LotDataError, match=r"wafers 2 have none"):
        logged_times(rows("lot,removal,250,nm,1,60 s\nlot,removal,240,nm,3,60 s\n"))
    with pytest.raises(LotDataError, match=r"wafer 1 has 60 s in another row, 62 s here"):
        logged_times(rows("lot,removal,250,nm,1,60 s\nlot,thickness,240,nm,1,62 s\n"))
    for bad in ("-5 s", "60 nm", "abc"):
        with pytest.raises(LotDataError, match=r"lot.csv:2: .*time"):
            rows(f"lot,removal,250,nm,1,{bad}\n")


def test_a_wafer_id_in_the_wafer_column_is_refused_before_any_solve(tmp_path):
    """A fab's wafer ID or slot (2301) read as a place in the lot would run 2301 recipe solves: refused naming
    the file, the row, the column, the valid range and what the column means."""
    from cmpsim.calibration.lotdata import MAX_LOT_WAFERS, LotDataError, read_lot_rows

    f = tmp_path / "ids.csv"
    head = "dataset,quantity,value,unit,wafer\n"
    f.write_text(head + "lot,removal,250,nm,2300\nlot,removal,240,nm,2301\n")
    with pytest.raises(LotDataError) as exc:
        read_lot_rows(f, f.read_text())
    msg = str(exc.value)
    assert msg.startswith(f"{f}:2: column 'wafer': '2300' is outside 1 to {MAX_LOT_WAFERS}") and "not a wafer ID or a slot" in msg, msg
    assert "counted from the first wafer on the pad" in msg
    f.write_text(head + f"lot,removal,250,nm,{MAX_LOT_WAFERS}\n")  # the bound itself is a place in the lot
    assert read_lot_rows(f, f.read_text())[0].wafer == MAX_LOT_WAFERS
    (tmp_path / "ids2.csv").write_text(head + f"lot,removal,250,nm,{MAX_LOT_WAFERS + 1}\n")
    res = CliRunner().invoke(main, ["validate", str(tmp_path / "ids2.csv"), "--recipe", str(RECIPE), "--out", str(tmp_path / "v")])
    assert res.exit_code == 2 and "ids2.csv:2: row 1, column 'wafer'" in " ".join(res.output.split()), res.output


def test_a_wafers_quantity_given_twice_is_refused_naming_both_rows(tmp_path):
    """Two rows of one wafer's removal (two lots pasted into one file, or a repeat) would be fitted as one lot's
    wafer measured twice: refused, equal or not, in one file and across the files given together."""
    from cmpsim.calibration.lotdata import LotDataError, read_lot_rows
    from cmpsim.calibration.mixed import read_all

    def rows(text, name="lot.csv"):
        f = tmp_path / name
        f.write_text("dataset,quantity,value,unit,wafer,film\n" + text)
        return f

    f = rows("lot,removal,250,nm,1,\nlot,removal,240,nm,2,\nlot,removal,251,nm,1,\n")
    with pytest.raises(LotDataError, match=r"lot.csv:4: column 'wafer': wafer 1's removal is 251 nm here and 250 nm in line 2: "):
        read_lot_rows(f, f.read_text())
    f = rows("lot,removal,250,nm,1,\nlot,removal,250,nm,1,\n")
    with pytest.raises(LotDataError, match=r"lot.csv:3: .*wafer 1's removal is given twice \(also in line 2, the same value\)"):
        read_lot_rows(f, f.read_text())
    f = rows("lot,removal,250,nm,1,\nlot,removal,250,nm,1,oxide\n")  # a lot measures the top film: named or not, the same quantity
    with pytest.raises(LotDataError, match=r"given twice .*films not given and oxide"):
        read_lot_rows(f, f.read_text())
    # a thickness and a removal of one wafer are two quantities
    f = rows("lot,removal,250,nm,1,\nlot,thickness,240,nm,1,\n")
    assert len(read_lot_rows(f, f.read_text())) == 2
    a = rows("lot,removal,250,nm,1,\nlot,removal,240,nm,2,\n", "a.csv")
    b = rows("lot,removal,260,nm,3,\nlot,removal,230,nm,2,\n", "b.csv")
    with pytest.raises(ValueError, match=r"b.csv:3: row 2, column 'wafer': wafer 2's removal is 230 nm here and 240 nm in .*a.csv:3"):
        read_all([a, b])


def test_rows_out_of_wafer_order_are_each_compared_with_their_own_wafer(tmp_path):
    """The rows may come in any order: each is compared with the wafer it names, and the logged times are
    put in wafer order."""
    from cmpsim.calibration.lotdata import logged_times, read_lot_rows

    f = tmp_path / "lot.csv"
    f.write_text("dataset,quantity,value,unit,uncertainty,wafer,time\nlot,removal,240,nm,1,3,62 s\nlot,removal,250,nm,1,1,60 s\n"
                 "lot,removal,245,nm,1,2,61 s\n")
    shuffled = read_lot_rows(f, f.read_text())
    assert [r.wafer for r in shuffled] == [3, 1, 2] and logged_times(shuffled) == [60.0, 61.0, 62.0]
    setting = LotSetting(RECIPE, conditioning="none", seed=0, overrides=dict(COARSE))
    ordered = sorted(shuffled, key=lambda r: r.wafer)
    model = predict_lot(ordered, None, setting)
    assert len(set(model)) == 3  # three wafers, three removals: a mix-up would show
    assert np.array_equal(predict_lot(shuffled, None, setting), model[[2, 0, 1]])


def test_lot_rows_without_a_recipe_are_noted_and_a_recipe_without_lot_rows_is_refused(tmp_path):
    lot_csv = tmp_path / "lot.csv"
    lot_csv.write_text("dataset,quantity,value,unit,uncertainty,wafer\nlot,removal,250,nm,1,1\nlot,removal,240,nm,1,2\n")
    res = CliRunner().invoke(main, ["calibrate", str(lot_csv), "--quiet", "--out", str(tmp_path / "x.toml")])
    assert res.exit_code == 2 and "--recipe" in res.output and not (tmp_path / "x.toml").exists()
    blanket = Path(str(resources.files("cmpsim") / "data" / "calibration" / "tugbawa2002_cu_blanket.csv"))
    res = CliRunner().invoke(main, ["calibrate", str(blanket), "--recipe", str(RECIPE), "--quiet", "--out", str(tmp_path / "y.toml")])
    assert res.exit_code == 2 and "wafer column" in res.output and not (tmp_path / "y.toml").exists()
    res = CliRunner().invoke(main, ["calibrate", str(blanket), "--free", "pad_wear_coefficient", "--quiet", "--out", str(tmp_path / "z.toml")])
    assert res.exit_code == 2 and "pad life constant" in res.output


def test_a_process_file_with_a_pad_life_constant_out_of_range_is_refused_naming_it(tmp_path):
    bad = tmp_path / "bad.toml"
    bad.write_text("[calibration]\nconstants = []\n[calibration.padlife.constants]\ncritical_glazed_area = 3.0\n")
    res = CliRunner().invoke(main, ["lot", str(RECIPE), "--config", str(bad), "--wafers", "1", "--set", "grid=coarse"])
    assert res.exit_code == 2 and "critical_glazed_area" in res.output
    with pytest.raises(ValueError, match="pad_wear_coefficient"):
        from cmpsim.polisher.pad import PadLife

        PadLife("none", constants={"pad_wear_coefficient": -1.0})


def test_the_default_constants_are_the_ones_calibrated_to_jeong():
    from cmpsim.physics.padlife import CALIBRATION

    d = default_constants()
    assert d["pad_wear_coefficient"] == CALIBRATION["wear_coefficient"]
    assert d["critical_glazed_area"] == CALIBRATION["critical_glazed_area"]
    assert d["conditioner_rate_constant"] == CALIBRATION["conditioner_rate_constant"]
    assert all(GLAZING_CONSTANTS[n][1][0] < v < GLAZING_CONSTANTS[n][1][1] for n, v in d.items())
    assert math.isfinite(d["pad_wear_coefficient"])
