"""Issue 38 from the command line: one mixed file calibrated at every scale, the process file it writes, a die run
that carries its covariance into the hotspots, validate --config on every kind, and bad rows refused by row and column."""

from __future__ import annotations

import csv
import json
import tomllib
from pathlib import Path

import pytest
from click.testing import CliRunner

import cmpsim
from cmpsim.cli import main

CAL = Path(cmpsim.__file__).parent / "data" / "calibration"
BLANKET = CAL / "tugbawa2002_cu_blanket.csv"
DISHING = CAL / "die_tugbawa2002_dishing_width.csv"
WHITE = CAL / "pad_white2003.csv"

COLUMNS = ["dataset", "quantity", "value", "unit", "uncertainty", "comparison", "applied_pressure", "rotation_speed", "wafer_diameter", "film",
           "process", "line_width", "line_space", "structure_size", "time", "centre_distance", "sliding_speed", "wafer", "source"]


def _rows(path: Path) -> list[dict]:
    lines = [ln for ln in path.read_text().splitlines() if ln.strip() and not ln.startswith("#")]
    return list(csv.DictReader(lines))


def _mixed(tmp_path: Path, extra: list[dict] | None = None, name: str = "fab.csv") -> Path:
    """One file holding the shipped blanket rates, the dishing width sweep and White's pad rows (and ``extra`` rows)."""
    rows = _rows(BLANKET) + _rows(DISHING) + _rows(WHITE) + list(extra or [])
    p = tmp_path / name
    with open(p, "w", newline="") as fh:
        fh.write("# dataset: fab\n# note: a fab's measurements of every scale in one file\n")
        w = csv.DictWriter(fh, fieldnames=COLUMNS, extrasaction="ignore")
        w.writeheader()
        for r in rows:
            w.writerow({k: r.get(k, "") for k in COLUMNS})
    return p


@pytest.fixture(scope="module")
def calibrated(tmp_path_factory):
    tmp = tmp_path_factory.mktemp("cal")
    out = tmp / "calibrated.toml"
    res = CliRunner().invoke(main, ["calibrate", str(_mixed(tmp)), "--quiet", "--out", str(out)])
    assert res.exit_code == 0, res.output
    return res.output, out


@pytest.mark.slow
def test_a_mixed_file_calibrates_every_scale_and_prints_every_interval(calibrated):
    output, _ = calibrated
    for head in ("== pad:", "== films:", "== die (copper): 7 test structure(s)", "every constant calibrated (95 % intervals)"):
        assert head in output
    # the data chose the constants, each with why
    for name in ("friction_coefficient", "pad_heat_transfer_coefficient", "mechanical_factor_copper", "chemistry_rate_copper",
                 "contact_height", "summit_radius", "feature_modulus"):
        assert f"fit {name}:" in output, name
    assert "fixed chemistry_speed_copper: chemistry_speed_copper and chemistry_rate_copper cannot be separated" in output
    table = output[output.index("every constant calibrated"):].splitlines()
    row = {ln.split()[1]: ln for ln in table if ln.split() and ln.split()[0] in ("pad", "film", "die")}
    assert set(row) == {"friction_coefficient", "pad_heat_transfer_coefficient", "mechanical_factor_copper", "chemistry_rate_copper",
                        "contact_height", "summit_radius", "feature_modulus"}
    # the fitted value inside its printed 95 % interval, on every row
    for name, line in row.items():
        value = float(line.split()[2])
        lo, hi = (float(x) for x in line[line.index("[") + 1 : line.index("]")].split(","))
        assert lo < value < hi, name
    assert "RMS 37.1 nm -> 7.5 nm" in output  # the die's residuals before and after
    assert "0.215     0.4159  0.215" in output  # the pad's friction before and after


@pytest.mark.slow
def test_the_process_file_carries_every_scale(calibrated):
    _, out = calibrated
    data = tomllib.loads(out.read_text())
    cal = data["calibration"]
    assert cal["constants"] == ["mechanical_factor_copper", "chemistry_rate_copper", "friction_coefficient", "pad_heat_transfer_coefficient"]
    assert data["pad"]["friction_coefficient"] == pytest.approx(0.1994, rel=1e-3)  # the configuration carries the pad's constants
    assert data["pad"]["pad_heat_transfer_coefficient"] == pytest.approx(94.25, rel=1e-3)
    die = cal["die"]
    assert die["process"] == "copper" and set(die["constants"]) == {"contact_height", "summit_radius", "feature_modulus"}
    assert die["constants"]["contact_height"] == pytest.approx(84.6e-9, rel=2e-3)
    lo, hi = die["ci95"]["contact_height"]
    assert lo < die["constants"]["contact_height"] < hi
    cov = die["uncertainty"]["covariance_log"]
    assert die["uncertainty"]["names"] == die["fitted"] and len(cov) == 3 and all(cov[i][i] > 0 for i in range(3))
    assert cal["pad"]["base_preset"] == "300mm" and cal["pad"]["correlation"]["matrix"][0][1] == pytest.approx(0.829, abs=0.01)


@pytest.mark.slow
def test_die_config_gives_every_hotspot_an_interval_and_a_probability(calibrated, tmp_path):
    _, out = calibrated
    args = ["die", "lines", "--process", "copper", "--spec", "dishing=100nm", "--cell-size", "200um"]
    res = CliRunner().invoke(main, args + ["--config", str(out), "--json"])
    assert res.exit_code == 0, res.output
    d = json.loads(res.stdout)
    assert d["hotspots"] and d["uncertainty"]["names"] == ["contact_height", "summit_radius", "feature_modulus"]
    for h in d["hotspots"]:
        lo, hi = h["interval"]
        assert lo <= h["value"] <= hi and 0.0 <= h["probability"] <= 1.0
    probs = [h["probability"] for h in d["hotspots"]]
    assert max(probs) > 0.975 and min(probs) < 0.975  # windows that fail for sure and windows that only might
    # hotspots.csv and the terminal table carry them too
    res = CliRunner().invoke(main, args + ["--config", str(out), "--out", str(tmp_path / "d")])
    assert res.exit_code == 0, res.output
    assert "interval nm" in res.output and "probability" in res.output and "95 % intervals" in res.output
    rows = list(csv.DictReader(open(tmp_path / "d" / "hotspots.csv")))
    assert len(rows) == len(d["hotspots"]) and all(float(r["interval_low_m"]) <= float(r["value_m"]) <= float(r["interval_high_m"]) for r in rows)
    # uncalibrated: the same run without the file keeps its keys
    plain = json.loads(CliRunner().invoke(main, args + ["--json"]).stdout)
    assert plain["hotspots"] and not any("interval" in h or "probability" in h for h in plain["hotspots"])
    # a run that disagrees with the calibration is refused naming the option, nothing written
    bad = CliRunner().invoke(main, ["die", "lines", "--process", "oxide", "--config", str(out), "--out", str(tmp_path / "x")])
    assert bad.exit_code == 2 and "--process oxide" in bad.output and not (tmp_path / "x").exists()
    bad = CliRunner().invoke(main, args + ["--config", str(out), "--param", "contact_height=50nm"])
    assert bad.exit_code == 2 and "--param contact_height" in bad.output
    # a wafer of dies: each die's expected, sure and at-risk counts, said in the terminal
    wafer = CliRunner().invoke(main, args + ["--config", str(out), "--wafer", "--set", "grid=coarse"])
    assert wafer.exit_code == 0, wafer.output
    assert "hotspots expected on the wafer" in wafer.output and "fail for sure" in wafer.output


@pytest.mark.slow
def test_validate_config_writes_points_of_every_kind(calibrated, tmp_path):
    _, out = calibrated
    held = [{"dataset": "fab_heldout", "quantity": "dishing", "value": "27", "unit": "nm", "uncertainty": "4", "process": "copper",
             "line_width": "0.35 um", "applied_pressure": "4 psi"},
            {"dataset": "fab_heldout", "quantity": "dishing", "value": "122", "unit": "nm", "uncertainty": "4", "process": "copper",
             "line_width": "5 um", "applied_pressure": "4 psi"},
            {"dataset": "fab_lot", "quantity": "thickness", "value": "500", "unit": "nm", "wafer": "1"}]
    p = tmp_path / "heldout.csv"
    rows = _rows(BLANKET)[:1] + _rows(CAL / "pad_shin2025.csv") + held
    with open(p, "w", newline="") as fh:
        w = csv.DictWriter(fh, fieldnames=COLUMNS, extrasaction="ignore")
        w.writeheader()
        for r in rows:
            w.writerow({k: r.get(k, "") for k in COLUMNS})
    res = CliRunner().invoke(main, ["validate", str(p), "--config", str(out), "--grid", "coarse", "--out", str(tmp_path / "v")])
    assert res.exit_code == 0, res.output
    pts = list(csv.DictReader(open(tmp_path / "v" / "points.csv")))
    kinds = {r["quantity"]: r for r in pts}
    assert set(kinds) == {"removal_rate", "pad_temperature_rise", "dishing", "thickness"}
    for q in ("removal_rate", "pad_temperature_rise", "dishing"):
        assert kinds[q]["measured"] and kinds[q]["model"], q
    assert float(kinds["pad_temperature_rise"]["model"]) == pytest.approx(8.8, abs=0.1)  # Shin's rise, held out (docs/calibrate.md)
    dishing = [float(r["model"]) for r in pts if r["quantity"] == "dishing"]
    assert dishing[0] == pytest.approx(18.8, abs=0.5) and dishing[1] == pytest.approx(116.9, abs=0.5)  # the calibrated die model
    assert kinds["thickness"]["status"] == "not compared" and kinds["thickness"]["model"] == ""
    # without the process file the die and the pad are the uncalibrated models
    res = CliRunner().invoke(main, ["validate", str(p), "--grid", "coarse", "--out", str(tmp_path / "u")])
    plain = list(csv.DictReader(open(tmp_path / "u" / "points.csv")))
    assert float(next(r for r in plain if r["quantity"] == "pad_temperature_rise")["model"]) == pytest.approx(26.5, abs=0.1)
    assert [float(r["model"]) for r in plain if r["quantity"] == "dishing"] == [pytest.approx(2.2, abs=0.1), pytest.approx(94.9, abs=0.1)]


@pytest.mark.parametrize(
    "row, line, row_no, column",
    [
        ({"dataset": "bad", "quantity": "dishing", "value": "30", "unit": "nm", "process": "copper", "line_width": ""}, 17, 14, "line_width"),
        ({"dataset": "bad", "quantity": "dishing", "value": "30", "unit": "nm", "process": "copper", "line_width": "1 um",
          "rotation_speed": "60 rpm"}, 17, 14, "rotation_speed"),
        ({"dataset": "bad", "quantity": "pad_temperature_rise", "value": "9", "unit": "K", "time": "-3 s"}, 17, 14, "time"),
        ({"dataset": "bad", "quantity": "removal_rate", "value": "100", "unit": "nm/min", "applied_pressure": "-3 psi", "film": "copper"},
         17, 14, "applied_pressure"),
        ({"dataset": "bad", "quantity": "thickness", "value": "500", "unit": "nm", "wafer": "0"}, 17, 14, "wafer"),
        ({"dataset": "bad", "quantity": "thickness", "value": "500", "unit": "nm/s", "wafer": "2"}, 17, 14, "unit"),
        ({"dataset": "bad", "quantity": "dishing", "value": "30", "unit": "nm", "process": "copper", "line_width": "1 um", "wafer": "3"},
         17, 14, "process"),
    ],
)
def test_a_bad_row_is_refused_by_row_and_column_and_nothing_is_written(tmp_path, row, line, row_no, column):
    p = _mixed(tmp_path, [row])
    out = tmp_path / "c.toml"
    res = CliRunner().invoke(main, ["calibrate", str(p), "--quiet", "--out", str(out)])
    assert res.exit_code == 2, res.output
    assert f"fab.csv:{line}: row {row_no}, column '{column}'" in res.output, res.output
    assert not out.exists()
    v = tmp_path / "v"
    res = CliRunner().invoke(main, ["validate", str(p), "--grid", "coarse", "--out", str(v)])
    assert res.exit_code == 2 and f"row {row_no}, column '{column}'" in res.output and not v.exists()


@pytest.mark.slow
def test_validate_compares_lot_rows_with_cmpsim_lot_of_the_recipe(tmp_path):
    recipe = Path(cmpsim.__file__).parent / "data" / "recipe_oxide.toml"
    lot = CliRunner().invoke(main, ["lot", str(recipe), "--wafers", "2", "--seed", "0", "--set", "grid=coarse", "--json"])
    assert lot.exit_code == 0, lot.output
    w = json.loads(lot.stdout)["wafers"]
    p = tmp_path / "lot.csv"
    p.write_text("dataset,quantity,value,unit,uncertainty,wafer,film\nlot,thickness,690,nm,5,1,oxide\nlot,removal,300,nm,5,2,\n")
    res = CliRunner().invoke(main, ["validate", str(p), "--recipe", str(recipe), "--grid", "coarse", "--out", str(tmp_path / "v")])
    assert res.exit_code == 0, res.output
    pts = list(csv.DictReader(open(tmp_path / "v" / "points.csv")))
    assert float(pts[0]["model"]) == pytest.approx(w[0]["final_thickness_mean"] * 1e9, rel=1e-6)
    assert float(pts[1]["model"]) == pytest.approx((w[1]["incoming_mean"] - w[1]["final_thickness_mean"]) * 1e9, rel=1e-6)
    bad = CliRunner().invoke(main, ["validate", str(BLANKET), "--recipe", str(recipe), "--out", str(tmp_path / "b")])
    assert bad.exit_code == 2 and "--recipe" in bad.output and not (tmp_path / "b").exists()


def test_structures_of_one_sweep_predict_unseen_widths_from_the_command_line(tmp_path):
    """Issue 38's done-when from the CLI: calibrated on 0.25, 0.5, 2, 10 um (no --free), the unseen 0.35, 1, 5 um within 25 nm RMS, in order."""
    text = DISHING.read_text().splitlines()
    keep = [ln for ln in text if not any(f",{w} um," in ln for w in ("0.35", "1", "5"))]
    held = [ln for ln in text if ln.startswith("#") or ln.startswith("dataset") or any(f",{w} um," in ln for w in ("0.35", "1", "5"))]
    (tmp_path / "fit.csv").write_text("\n".join(keep) + "\n")
    (tmp_path / "held.csv").write_text("\n".join(held) + "\n")
    out = tmp_path / "die.toml"
    res = CliRunner().invoke(main, ["calibrate", str(tmp_path / "fit.csv"), "--quiet", "--out", str(out)])
    assert res.exit_code == 0, res.output
    # the start's Jacobian cannot tell the feature modulus from the contact height; the fitted constants can
    assert "fixed feature_modulus" not in res.output and "chosen again at the first fit's values" in res.output
    assert "fit feature_modulus" in res.output
    res = CliRunner().invoke(main, ["validate", str(tmp_path / "held.csv"), "--config", str(out), "--out", str(tmp_path / "v")])
    assert res.exit_code == 0, res.output
    pts = list(csv.DictReader(open(tmp_path / "v" / "points.csv")))
    model = [float(r["model"]) for r in pts]
    measured = [float(r["measured"]) for r in pts]
    rms = (sum((m - y) ** 2 for m, y in zip(model, measured)) / 3) ** 0.5
    assert rms == pytest.approx(9.8, abs=0.2) and rms < 25 and model == sorted(model)


def test_lot_rows_are_read_in_si():
    from cmpsim.calibration.lotdata import read_lot_rows

    text = "dataset,quantity,value,unit,uncertainty,wafer\nlot,thickness,5000,angstrom,50,3\nlot,removal,0.7,um,,4\n"
    a, b = read_lot_rows("lot.csv", text)
    assert (a.wafer, a.quantity, a.value, a.uncertainty) == (3, "thickness", pytest.approx(500e-9), pytest.approx(5e-9))
    assert (b.wafer, b.value, b.uncertainty) == (4, pytest.approx(700e-9), None)


def test_the_web_die_takes_a_process_file_as_its_inputs(tmp_path):
    pytest.importorskip("fastapi")
    pytest.importorskip("httpx")
    gdstk = pytest.importorskip("gdstk")
    from fastapi.testclient import TestClient

    from cmpsim.calibration.processfile import die_constants
    from cmpsim.web.app import create_app
    from cmpsim.web.limits import Limits

    # a process file with a die calibration (constants and covariance of ln value), as `cmpsim calibrate` writes it
    process_file = {"numerics": {"grid": "coarse"}, "calibration": {"constants": [], "settings": [], "die": {
        "process": "copper", "constants": {"contact_height": 84.6e-9, "feature_modulus": 13.1e6},
        "uncertainty": {"names": ["contact_height", "feature_modulus"], "values": [84.6e-9, 13.1e6],
                        "covariance_log": [[0.0042, 0.0050], [0.0050, 0.0137]]}}}}
    assert die_constants(process_file).uncertainty.names == ("contact_height", "feature_modulus")
    lib = gdstk.Library(unit=1e-6, precision=1e-9)
    cell = gdstk.Cell("CHIP")
    for i in range(20):
        cell.add(gdstk.rectangle((i * 10.0, 0), (i * 10.0 + 8.0, 200.0), layer=1))
    lib.add(cell)
    path = tmp_path / "chip.gds"
    lib.write_gds(str(path))
    query = {"layer": "1/0", "process": "copper", "spec": ["dishing=20nm"], "filename": "chip.gds"}
    with TestClient(create_app(Limits(max_grid="default"), workers=1)) as client:
        def post(inputs, **q):
            return client.post("/api/die", params={**query, **q, "inputs": json.dumps(inputs)}, content=path.read_bytes(),
                               headers={"content-type": "application/octet-stream"})

        r = post(process_file)
        assert r.status_code == 200, r.text
        hot = r.json()["hotspots"]
        assert hot and all(h["interval"][0] <= h["value"] <= h["interval"][1] and 0 <= h["probability"] <= 1 for h in hot)
        plain = post({"grid": "coarse"}).json()["hotspots"]
        assert plain and not any("probability" in h for h in plain)
        solved = client.post("/api/solve", json=process_file)  # the other routes read its inputs and leave the table
        assert solved.status_code == 200, solved.text
        bad = post(process_file, process="oxide")
        assert bad.status_code == 422 and bad.json()["parameter"] == "process"
