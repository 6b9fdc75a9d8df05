"""Calibration of the pad's friction and heat removal on a measured friction and temperature (docs/calibrate-die.md)."""

from __future__ import annotations

import math
from importlib import resources
from pathlib import Path

import numpy as np
import pytest

from cmpsim.calibration.measurements import MeasurementError, ThermalRecord, read_measurements
from cmpsim.calibration.thermal import calibrate_thermal, frictional_power, predict_thermal, step_rise
from cmpsim.inputs.config import Config

DATA = Path(__file__).parents[1] / "src" / "cmpsim" / "data" / "calibration"
WHITE = DATA / "pad_white2003.csv"
SHIN = DATA / "pad_shin2025.csv"
#: The measured rises of a pad in a copper step: White et al. 2003 (9.1 K) to Shin et al. 2025 (15 K in 90 s).
MEASURED_RANGE = (9.1, 15.0)


@pytest.fixture(scope="module")
def white():
    return calibrate_thermal(read_measurements(WHITE))


def test_bad_rows_are_refused_by_row_and_column(tmp_path):
    f = tmp_path / "pad.csv"
    head = "quantity,value,unit,uncertainty,time,applied_pressure\n"
    for row, col in (("pad_temperature_rise,9,K,1,,6 psi\n", "time"),
                     ("pad_temperature_rise,9,m,1,60 s,6 psi\n", "value"),
                     ("pad_temperature_rise,9,K,1,60 s,6 m\n", "applied_pressure"),
                     ("friction_coefficient,12,1,,,6 psi\n", "value")):
        f.write_text(head + "friction_coefficient,0.2,1,0.03,,6 psi\n" + row)
        with pytest.raises(MeasurementError) as exc:
            read_measurements(f)
        assert "pad.csv:3" in str(exc.value) and f"'{col}'" in str(exc.value), str(exc.value)


def test_frictional_power_is_linear_in_the_summit_friction():
    cfg = Config.preset("300mm").replace(grid="coarse")
    fp = frictional_power(cfg)
    assert fp.contact > 0 and fp.slurry >= 0
    # the model's effective friction with the default mu: 0.45 on the grooved preset at 3 psi (docs/polisher.md)
    assert fp.friction(cfg.friction_coefficient) == pytest.approx(0.45, abs=0.02)
    assert step_rise(fp, 0.2, None, 30.0) < step_rise(fp, 0.4, None, 30.0)


def test_white_calibration_lands_the_measured_rise_and_friction(white):
    recs = white.records
    assert white.free == ["friction_coefficient", "pad_heat_transfer_coefficient"]
    before = dict(zip([r.quantity for r in recs], white.model_before))
    after = dict(zip([r.quantity for r in recs], white.model_after))
    assert before["pad_temperature_rise"] > 15.0  # measured: 23.4 K uncalibrated
    assert after["pad_temperature_rise"] == pytest.approx(9.1, abs=1.0)
    assert after["friction_coefficient"] == pytest.approx(0.215, abs=0.035)
    for n in white.free:
        lo, hi = white.ci95[n]
        assert 0 < lo < white.values[n] < hi < math.inf
    assert np.isfinite(white.correlation).all()
    assert set(white.constants) == {"friction_coefficient", "pad_heat_transfer_coefficient"}


def test_without_degrees_of_freedom_the_intervals_need_the_uncertainties(white):
    """White's two rows fix both constants with no degree of freedom left: with their uncertainties the intervals are
    (J^T J)^-1's (tested above); without, they are undefined (printed [-, -], with a note), not [0, inf]."""
    from dataclasses import replace

    assert white.dof == 0 and white.absolute_sigma
    bare = calibrate_thermal([replace(r, uncertainty=None) for r in white.records], free=white.free)
    assert bare.dof == 0 and not bare.absolute_sigma
    assert all(math.isnan(v) for n in bare.free for v in bare.ci95[n])
    assert any("no degrees of freedom left" in s for s in bare.identifiability) and "[-, -]" in bare.summary()


def test_a_rise_alone_cannot_separate_friction_from_heat_removal():
    rise = [r for r in read_measurements(WHITE) if r.quantity == "pad_temperature_rise"]
    cal = calibrate_thermal(rise + rise, free=["friction_coefficient", "pad_heat_transfer_coefficient"])
    assert any("cannot be separated" in s or "not determined" in s or "singular" in s.split(":")[0] for s in cal.identifiability), cal.identifiability


def test_a_constant_the_pad_rows_do_not_see_is_refused_by_name(tmp_path):
    """A friction does not change with the heat removal: asked for on friction rows alone, h_s would come back at
    its start with an interval [0, inf]; it is refused naming it, as the die's and the wafer-scale fits refuse
    one, and from the command line with exit status 2 and nothing written."""
    from click.testing import CliRunner

    from cmpsim.cli import main

    fric = [r for r in read_measurements(WHITE) if r.quantity == "friction_coefficient"]
    with pytest.raises(ValueError, match=r"^free pad_heat_transfer_coefficient: these pad rows do not change with it .*not identifiable"):
        calibrate_thermal(fric, free=["friction_coefficient", "pad_heat_transfer_coefficient"])
    assert calibrate_thermal(fric).free == ["friction_coefficient"]  # the data's own choice leaves it
    f = tmp_path / "friction.csv"
    f.write_text("".join(ln + "\n" for ln in WHITE.read_text().splitlines() if "pad_temperature_rise" not in ln))
    out = tmp_path / "cal.toml"
    res = CliRunner().invoke(main, ["calibrate", str(f), "--free", "friction_coefficient,pad_heat_transfer_coefficient", "--quiet",
                                    "--out", str(out)])
    assert res.exit_code == 2 and "free pad_heat_transfer_coefficient: these pad rows do not change with it" in " ".join(res.output.split())
    assert not out.exists()


def test_synthetic_trace_recovers_both_constants():
    """A trace made by the model (mu 0.25, h_s 120 W/m^2K) at five times is fitted back within its intervals."""
    cond = {"applied_pressure": "4 psi"}
    base = Config.preset("300mm").replace(grid="coarse")
    times = (5.0, 10.0, 20.0, 40.0, 80.0)
    recs = [ThermalRecord("pad_temperature_rise", 1.0, 0.05, t, cond) for t in times]
    truth = {"friction_coefficient": 0.25, "pad_heat_transfer_coefficient": 120.0}
    vals = predict_thermal(recs, truth, base)
    recs = [ThermalRecord(r.quantity, float(v), r.uncertainty, r.time, cond) for r, v in zip(recs, vals)]
    cal = calibrate_thermal(recs, base)
    assert cal.free == ["friction_coefficient", "pad_heat_transfer_coefficient"]
    for n, v in truth.items():
        lo, hi = cal.ci95[n]
        assert lo <= v <= hi and cal.values[n] == pytest.approx(v, rel=1e-3)


@pytest.mark.slow
def test_copper_bulk_step_rise_lands_in_the_measured_range_after_calibration(white):
    """The copper recipe's 30 s bulk step (3 psi, 93 rpm, 300 mm): +35.0 K with the defaults, +12.0 K calibrated on White."""
    from cmpsim.polisher.engine import polish

    recipe = str(resources.files("cmpsim") / "data" / "recipe_copper.toml")
    run = polish(recipe, overrides=white.constants)
    v = run.steps[0].pad_temperature["value"]
    rise = v[-1] - v[0]
    assert MEASURED_RANGE[0] <= rise <= MEASURED_RANGE[1], rise


def test_bulk_step_column_rise_in_the_measured_range_after_calibration(white):
    """The same step through the column alone (the recipe's solve of the bulk step, coarse grid)."""
    cfg = Config.preset("300mm").replace(grid="coarse", film="copper")
    fp = frictional_power(cfg)
    before = step_rise(fp, cfg.friction_coefficient, None, 30.0)
    after = step_rise(fp, white.values["friction_coefficient"], white.values["pad_heat_transfer_coefficient"], 30.0)
    assert before > 2 * MEASURED_RANGE[1]
    assert MEASURED_RANGE[0] <= after <= MEASURED_RANGE[1], after


@pytest.mark.xfail(strict=True, reason="held out: Shin et al. 2025 (2 psi, 93 rpm, 300 mm, 15 K in 90 s, still rising) is predicted "
                   "8.8 K by the model calibrated on White 2003 (26.5 K uncalibrated): the sink platen saturates in 11-13 s where "
                   "Shin's pad still rose at 90 s (docs/polisher.md); docs/calibrate-die.md")
def test_shin_rise_predicted_within_its_uncertainty(white):
    s = read_measurements(SHIN)
    m = white.predict(s)
    assert abs(m[0] - s[0].value) < 2 * s[0].uncertainty
