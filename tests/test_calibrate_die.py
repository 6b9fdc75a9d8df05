"""Calibration of the die model on test structures, and hotspots with their uncertainty (docs/calibrate-die.md)."""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np
import pytest

from cmpsim.calibration.die import TestStructure, calibrate_die, heldout_comparison, predict_die
from cmpsim.calibration.measurements import MeasurementError, StructureRecord, read_measurements, shipped_measurement_paths
from cmpsim.die import simulate
from cmpsim.die.density import GaussianWeighting, effective_density
from cmpsim.die.uncertainty import DieUncertainty, exceedance_probability

DATA = Path(__file__).parents[1] / "src" / "cmpsim" / "data" / "calibration"
WIDTHS = DATA / "die_tugbawa2002_dishing_width.csv"
EROSION = DATA / "die_tugbawa2002_erosion_time.csv"


# ----------------------------------------------------------------------------- the reader

HEADER = "quantity,value,unit,uncertainty,process,line_width,line_space,structure_size,time,blanket_rate\n"
GOOD = "dishing,25,nm,4,copper,0.25 um,,,,\n"


@pytest.mark.parametrize(
    "row, column",
    [
        ("dishing,25,nm,4,copper,,,,,\n", "line_width"),
        ("dishing,25,nm/s,4,copper,1 um,,,,\n", "value"),
        ("dishing,abc,nm,4,copper,1 um,,,,\n", "value"),
        ("dishing,25,nm,4,tungsten,1 um,,,,\n", "process"),
        ("step_height,25,nm,4,copper,1 um,,,,\n", "process"),
        ("dishing,25,nm,-4,copper,1 um,,,,\n", "uncertainty"),
        ("dishing,25,nm,4,copper,1 um,1 s,,,\n", "line_space"),
        ("dishing,25,nm,4,copper,10 um,1 um,5 um,,\n", "structure_size"),
        ("erosion,25,nm,4,copper,1 um,1 um,,-5 s,\n", "time"),
        ("erosion,25,nm,4,copper,1 um,1 um,,5 s,0 nm/s\n", "blanket_rate"),
        ("dimples,25,nm,4,copper,1 um,,,,\n", "quantity"),
    ],
)
def test_a_bad_row_is_refused_naming_its_row_and_column(tmp_path, row, column):
    f = tmp_path / "bad.csv"
    f.write_text("# dataset: bad\n" + HEADER + GOOD + row)
    with pytest.raises(MeasurementError) as exc:
        read_measurements(f)
    msg = str(exc.value)
    assert f"bad.csv:4" in msg, msg  # the third line of the body (two comment/header lines before)
    assert f"'{column}'" in msg, msg


def test_unknown_column_and_missing_required_column_are_refused(tmp_path):
    f = tmp_path / "x.csv"
    f.write_text("quantity,value,unit,colour\ndishing,1,nm,red\n")
    with pytest.raises(MeasurementError, match=r"x.csv:1: unknown column 'colour'"):
        read_measurements(f)
    f.write_text("quantity,value\ndishing,1\n")
    with pytest.raises(MeasurementError, match=r"required column 'unit'"):
        read_measurements(f)


def test_shipped_files_read_in_si():
    paths = {p.name for p in shipped_measurement_paths("die")}
    assert {"die_tugbawa2002_dishing_width.csv", "die_tugbawa2002_erosion_time.csv"} <= paths
    d = read_measurements(WIDTHS)
    assert [r.line_width for r in d][:2] == pytest.approx([0.25e-6, 0.35e-6])
    assert d[0].value == pytest.approx(25e-9) and d[0].uncertainty == pytest.approx(4e-9)
    assert all(r.line_space is None and r.time is None for r in d)
    e = read_measurements(EROSION)
    assert e[0].time == pytest.approx(92.0) and e[0].blanket_rate == pytest.approx(15.9e-9)
    assert e[0].line_space == pytest.approx(1e-6) and e[0].density == pytest.approx(0.9)


# ----------------------------------------------------------------------------- the structure


def test_site_effective_density_of_a_block_equals_the_fft_of_its_layout():
    """Eq. C1 (the Gaussian weight of a square) against the die model's FFT on the structure's layout."""
    for size, L in ((2e-3, 1e-3), (0.5e-3, 2e-3), (4e-3, 1e-3)):
        st = TestStructure(1e-6, 1e-6, size)
        lay = st.layout(L, cells=257)
        eff = effective_density(lay.density, lay.cell_size, GaussianWeighting(L))
        c = lay.shape[0] // 2
        assert eff[c, c] == pytest.approx(st.site_effective_density(L), rel=2e-3, abs=1e-4)
    assert TestStructure(1e-6, 1e-6, None).site_effective_density(1e-3) == pytest.approx(0.5)


def test_a_block_smaller_than_the_planarization_length_erodes_less():
    recs = [StructureRecord("erosion", 1e-8, 1e-9, "copper", 9e-6, 1e-6, size, 110.0, 15.9e-9) for size in (0.2e-3, 1e-3, None)]
    m = predict_die(recs, {"planarization_length": 2e-3})
    assert m[0] < m[1] < m[2]


# ----------------------------------------------------------------------------- synthetic round trip

TRUE = {"contact_height": 60e-9, "summit_radius": 2e-6, "feature_modulus": 30e6}


def _synthetic(widths, noise=0.0, seed=1):
    base = [StructureRecord("dishing", 1.0, 2e-9, "copper", w * 1e-6, None, None, None, None, {"applied_pressure": 27579.0}) for w in widths]
    vals = predict_die(base, TRUE)
    rng = np.random.default_rng(seed)
    vals = vals + noise * rng.standard_normal(len(vals))
    return [StructureRecord(r.quantity, float(v), r.uncertainty, r.process, r.line_width, inputs=r.inputs) for r, v in zip(base, vals)]


def test_synthetic_round_trip_recovers_the_constants_within_their_intervals():
    recs = _synthetic([0.25, 0.5, 1, 2, 3, 5, 10, 20], noise=2e-9)
    cal = calibrate_die(recs, free=list(TRUE))
    for n, v in TRUE.items():
        lo, hi = cal.ci95[n]
        assert lo < v < hi, (n, v, lo, hi)
    assert cal.rms_after < 3e-9 < cal.rms_before
    assert cal.absolute_sigma and cal.dof == 5


def test_a_constant_the_data_do_not_see_is_refused_by_name():
    """Isolated-line dishing does not change with the oxide selectivity: asked for, it would come back at its
    start value with an interval [0, inf]; it is refused naming it, as the wafer-scale fit refuses such an input."""
    recs = _synthetic([0.25, 0.5, 1, 2, 5, 10])
    with pytest.raises(ValueError, match=r"free oxide_selectivity: these test structures do not change with it .*not identifiable"):
        calibrate_die(recs, free=["contact_height", "summit_radius", "oxide_selectivity"])


def test_without_degrees_of_freedom_the_intervals_need_the_uncertainties():
    """Two structures, two constants: with their uncertainties the covariance is (J^T J)^-1; without, no scatter
    is left to scale it by, and the intervals are undefined (printed [-, -], with a note), not [0, inf]."""
    from dataclasses import replace

    recs = _synthetic([0.5, 5])
    given = calibrate_die(recs, free=["contact_height", "summit_radius"])
    assert given.dof == 0 and given.absolute_sigma
    for n in given.free:
        lo, hi = given.ci95[n]
        assert 0 < lo < given.values[n] < hi < math.inf
    bare = calibrate_die([replace(r, uncertainty=None) for r in recs], free=["contact_height", "summit_radius"])
    assert bare.dof == 0 and not bare.absolute_sigma
    assert all(math.isnan(v) for n in bare.free for v in bare.ci95[n])
    assert any("no degrees of freedom left" in s for s in bare.identifiability) and "[-, -]" in bare.summary()


# ----------------------------------------------------------------------------- the shipped data, held out


def test_width_sweep_calibration_fits_and_reports_intervals():
    d = read_measurements(WIDTHS)
    cal = calibrate_die(d)
    assert cal.free == ["contact_height", "summit_radius", "feature_modulus"]
    assert cal.rms_before > 30e-9  # measured: 37.1 nm with the defaults
    assert cal.rms_after < 10e-9  # measured: 7.5 nm
    for n in cal.free:
        lo, hi = cal.ci95[n]
        assert 0 < lo < cal.values[n] < hi < math.inf
    assert cal.correlation.shape == (3, 3)
    assert set(cal.constants) == set(cal.free)
    assert "contact_height" in cal.summary()


def test_unseen_widths_are_predicted_within_25_nm_rms_in_the_right_order():
    """Fit on 0.25, 0.5, 2, 10 um; predict 0.35, 1, 5 um (measured: 9.8 nm RMS, order right)."""
    d = read_measurements(WIDTHS)
    train = [d[i] for i in (0, 2, 4, 6)]
    test = [d[i] for i in (1, 3, 5)]
    cal = calibrate_die(train)
    h = heldout_comparison(cal, test)
    assert h["rms"] < 25e-9, h
    assert h["order"]
    uncal = np.sqrt(np.mean((predict_die(test) - h["measured"]) ** 2))
    assert uncal > 25e-9  # the defaults miss: 31 nm


def test_leave_one_width_out_stays_within_25_nm():
    d = read_measurements(WIDTHS)
    err = []
    for i in range(len(d)):
        cal = calibrate_die([r for j, r in enumerate(d) if j != i])
        err.append(float(cal.predict([d[i]])[0] - d[i].value))
    assert np.sqrt(np.mean(np.square(err))) < 25e-9, err


@pytest.mark.xfail(strict=True, reason="erosion of Tugbawa's wide arrays at 92 s (both densities) does not fix the erosion rate: "
                   "the onset (copper thickness, barrier) and the oxide rate trade off (correlation +1.00 reported); predicted 110 s "
                   "erosion 213/38 nm against 285/54 nm measured, 52 nm RMS (docs/calibrate-die.md)")
def test_erosion_at_an_unseen_time_within_25_nm():
    e = read_measurements(EROSION)
    cal = calibrate_die([e[0], e[2]], free=["oxide_selectivity", "copper_thickness"])
    h = heldout_comparison(cal, [e[1], e[3]])
    assert h["rms"] < 25e-9 and h["order"]


# ----------------------------------------------------------------------------- hotspots with their uncertainty


def test_probability_is_in_0_1_and_falls_as_the_limit_rises():
    limits = np.linspace(10e-9, 200e-9, 60)
    p = exceedance_probability(100e-9, 15e-9, limits)
    assert np.all((p >= 0) & (p <= 1))
    assert np.all(np.diff(p) <= 0) and p[0] > 0.99 and p[-1] < 0.01
    assert exceedance_probability(100e-9, 0.0, 90e-9) == 1.0 and exceedance_probability(100e-9, 0.0, 110e-9) == 0.0
    assert exceedance_probability(-100e-9, 15e-9, 100e-9) == pytest.approx(0.5)  # magnitude compared


@pytest.fixture(scope="module")
def calibrated_run():
    cal = calibrate_die(read_measurements(WIDTHS))
    unc = cal.uncertainty()
    run = simulate("lines", process="copper", blanket_rate=15.9e-9, cell_size=200e-6, spec={"dishing": "100 nm"}, uncertainty=unc)
    return cal, unc, run


def test_hotspots_of_a_calibrated_run_carry_interval_and_probability(calibrated_run):
    cal, unc, run = calibrated_run
    hot = run.to_dict()["hotspots"]
    assert hot
    for h in hot:
        lo, hi = h["interval"]
        assert lo <= h["value"] <= hi
        assert 0.0 <= h["probability"] <= 1.0
        assert h["probability"] >= 0.5  # a hotspot is over its limit
    assert run.to_dict()["units"]["interval"] == "m"
    assert run.process.contact_height == pytest.approx(cal.values["contact_height"])
    plain = simulate("lines", process="copper", blanket_rate=15.9e-9, cell_size=200e-6, spec={"dishing": "100 nm"})
    assert all("interval" not in h and "probability" not in h for h in plain.to_dict()["hotspots"])


def test_hotspot_probability_falls_as_its_limit_rises(calibrated_run):
    _, _, run = calibrated_run
    worst = run.hotspots()[0]
    p = [run.hotspots({"dishing": lim})[0]["probability"] if run.hotspots({"dishing": lim}) else 0.0
         for lim in np.linspace(0.5, 0.999, 8) * abs(worst["value"])]
    assert np.all(np.diff(p) <= 1e-12)


def test_windows_under_their_limit_whose_interval_reaches_it_are_listed_at_risk(calibrated_run):
    """A calibrated run also lists the windows that pass but may fail: under the limit, 95 % interval
    reaching it (probability >= 0.025). With the limit just above the worst window every window is
    under it, and the worst is the likeliest; an uncalibrated run has no such list."""
    from cmpsim.die.hotspots import AT_RISK

    _, _, run = calibrated_run
    worst = run.hotspots()[0]
    limit = abs(worst["value"]) * 1.02
    risk = run.at_risk({"dishing": limit})
    assert not run.hotspots({"dishing": limit}) and risk
    assert risk[0]["value"] == pytest.approx(worst["value"]) and risk[0]["probability"] < 0.5
    for h in risk:
        lo, hi = h["interval"]
        assert abs(h["value"]) <= h["limit"] and hi >= h["limit"] * (1 - 1e-9) and AT_RISK <= h["probability"] < 0.5
    assert [h["probability"] for h in risk] == sorted((h["probability"] for h in risk), reverse=True)
    d = run.to_dict()
    assert d["at_risk_count"] == len(d["at_risk"]) and all("box" not in h for h in d["at_risk"])
    # every window over the limit is a hotspot, every one under it with p >= 0.025 at risk: no window is in both
    hot = {(h["x"], h["y"]) for h in d["hotspots"]}
    assert not hot & {(h["x"], h["y"]) for h in d["at_risk"]}
    plain = simulate("lines", process="copper", blanket_rate=15.9e-9, cell_size=200e-6, spec={"dishing": "100 nm"})
    assert plain.at_risk() == [] and "at_risk" not in plain.to_dict()


def test_a_calibrated_wafer_of_dies_counts_each_dies_sure_expected_and_at_risk_windows(calibrated_run):
    """simulate_wafer(uncertainty=) gives every die hotspot_expected, hotspot_sure and at_risk_count, the same
    numbers as the die polished alone at its blanket rate with the same calibration; the reference die's
    hotspots carry their intervals."""
    from cmpsim import Config
    from cmpsim.die import simulate_wafer
    from cmpsim.die.hotspots import SURE

    _, unc, _ = calibrated_run
    cfg = Config.default().replace(grid="coarse")
    w = simulate_wafer("lines", process="copper", config=cfg, spec={"dishing": "100 nm"}, cell_size=200e-6, uncertainty=unc)
    d = w.to_dict()
    assert w.reading == "exact" and "interval" in d["hotspots"][0]
    assert d["wafer_hotspot_expected"] == pytest.approx(float(np.sum(w.hotspot_expected)))
    i = int(np.argmin(w.blanket_rate))
    alone = simulate("lines", w.time, process="copper", config=cfg, blanket_rate=float(w.blanket_rate[i]), cell_size=200e-6,
                     spec={"dishing": "100 nm"}, uncertainty=unc)
    hot = alone.hotspots()
    assert w.hotspot_count[i] == len(hot)
    assert w.hotspot_sure[i] == sum(h["probability"] > SURE for h in hot) and w.at_risk_count[i] == len(alone.at_risk())
    v, sd = alone.fields()["dishing"], alone.sigma["dishing"]
    ok = np.isfinite(v)
    assert w.hotspot_expected[i] == pytest.approx(float(np.sum(exceedance_probability(v[ok], sd[ok], 100e-9))), rel=1e-12)
    assert w.hotspot_expected[i] > sum(h["probability"] for h in hot)  # windows under the limit add their small chances
    assert d["dies"][i]["hotspot_sure"] == w.hotspot_sure[i] and d["units"]["hotspot_expected"] == "1"
    plain = simulate_wafer("lines", process="copper", config=cfg, spec={"dishing": "100 nm"}, cell_size=200e-6)
    assert plain.hotspot_expected is None and "hotspot_expected" not in plain.to_dict()["dies"][0]


@pytest.mark.slow
def test_linearisation_agrees_with_a_sample_of_the_covariance(calibrated_run):
    """sigma of the worst window by linearisation against 200 draws of the covariance (within 20 %: the sample's
    own standard deviation is uncertain by 1/sqrt(2 x 200) = 5 %)."""
    _, unc, run = calibrated_run
    h = run.hotspots()[0]
    iy, ix = np.unravel_index(np.argmax(np.nan_to_num(run.evolution.dishing)), run.evolution.dishing.shape)
    rng = np.random.default_rng(3)
    z = rng.multivariate_normal(np.zeros(len(unc.names)), unc.covariance, size=200)
    vals = []
    for zi in z:
        draw = DieUncertainty(unc.names, tuple(v * math.exp(d) for v, d in zip(unc.values, zi)), unc.covariance * 1e-12)
        r = simulate("lines", process="copper", blanket_rate=15.9e-9, cell_size=200e-6, time=run.time,
                     **dict(zip(draw.names, draw.values)))
        vals.append(r.evolution.dishing[iy, ix])
    sd_sample = float(np.std(vals))
    sd_lin = (h["interval"][1] - h["interval"][0]) / (2 * 1.96)
    assert sd_lin == pytest.approx(sd_sample, rel=0.2)


def test_a_die_model_of_a_real_layout_carries_the_uncertainty(calibrated_run):
    """DieModel (the path of `cmpsim die CHIP.gds`) gives the same hotspots with their intervals as simulate."""
    from cmpsim.die import builtin_layout
    from cmpsim.die.chip import DieModel

    _, unc, run = calibrated_run
    model = DieModel(process="copper", blanket_rate=15.9e-9, spec={"dishing": "100 nm"}, uncertainty=unc)
    r = model.run(builtin_layout("lines", 200e-6), time=run.time)
    hot, ref = r.hotspots(), run.hotspots()
    assert len(hot) == len(ref) > 0
    assert hot[0]["interval"] == pytest.approx(ref[0]["interval"], rel=1e-9)
    assert hot[0]["probability"] == pytest.approx(ref[0]["probability"], abs=1e-12)


def test_die_uncertainty_round_trips_and_refuses_bad_input():
    u = DieUncertainty(("contact_height", "planarization_length"), (80e-9, 3e-3), np.diag([0.01, 0.04]))
    v = DieUncertainty.from_dict(u.to_dict())
    assert v.names == u.names and v.values == u.values and np.array_equal(v.covariance, u.covariance)
    with pytest.raises(ValueError, match="unknown die constant 'colour'"):
        DieUncertainty(("colour",), (1.0,), np.eye(1))
    with pytest.raises(ValueError, match="positive semi-definite"):
        DieUncertainty(("contact_height",), (1e-7,), -np.eye(1))
