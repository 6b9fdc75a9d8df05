"""`cmpsim calibrate`: recovers known parameters from the model's own synthetic data."""

import numpy as np
import pytest
from click.testing import CliRunner

from cmpsim.calibration import CalibrationError, calibrate
from cmpsim.cli import main
from cmpsim.inputs.config import Config
from cmpsim.testing import synthetic_dataset

BASE = Config.default().replace(grid="coarse")
POINTS = [{"applied_pressure": f"{p} psi", "rotation_speed": f"{w} rpm"} for p in (2, 4, 6) for w in (30, 90)]
TRUTH = {"asperity_density": 3.0e8, "pad_modulus": 150e6}


@pytest.fixture(scope="module")
def synthetic(tmp_path_factory):
    path = tmp_path_factory.mktemp("cal") / "synthetic.csv"
    synthetic_dataset(path, TRUTH, POINTS, ["film_thickness", "contact_area_ratio", "fluid_load_fraction"], config=BASE, relative_noise=0.01, seed=1)
    return path


@pytest.fixture(scope="module")
def fit(synthetic):
    return calibrate(synthetic, ["asperity_density", "pad_modulus"], config=BASE)


def test_recovers_known_parameters_within_the_reported_uncertainty(fit):
    for name, truth in TRUTH.items():
        v, se = fit.values[name], fit.stderr[name]
        assert v != pytest.approx(BASE.to_dict()[name], rel=0.05)  # it moved from the start
        assert abs(v - truth) <= 3.0 * se, (name, v, truth, se)
        lo, hi = fit.ci95[name]
        assert lo < truth < hi
        assert se / v < 0.1
    assert fit.success and fit.absolute_sigma and fit.dof == 18 - 2


def test_reports_correlations_and_residuals_before_and_after(fit):
    c = fit.correlation
    assert c.shape == (2, 2) and np.allclose(np.diag(c), 1.0) and abs(c[0, 1]) <= 1.0
    assert fit.residuals_before.shape == fit.residuals_after.shape == (18,)
    assert fit.rms_after < 0.2 * fit.rms_before
    assert 0.05 < fit.reduced_chi2 < 3.0  # noise of 1 % with 1 % uncertainty
    text = fit.summary()
    assert "asperity_density" in text and "correlation matrix" in text and "resid. after" in text


def test_fitted_config_is_written_and_read_back(fit, tmp_path):
    path = fit.to_toml(tmp_path / "fitted.toml")
    cfg = Config.from_toml(path)
    assert cfg.asperity_density == pytest.approx(fit.values["asperity_density"], rel=1e-12)
    assert cfg.pad_modulus == pytest.approx(fit.values["pad_modulus"], rel=1e-12)
    res = CliRunner().invoke(main, ["run", str(path), "--json"])
    assert res.exit_code == 0, res.output


def test_cli_calibrate_one_parameter(synthetic, tmp_path):
    out = tmp_path / "cal.toml"
    res = CliRunner().invoke(
        main,
        ["calibrate", str(synthetic), "--free", "asperity_density", "--set", "pad_modulus=150MPa", "--grid", "coarse", "--out", str(out), "--quiet"],
    )
    assert res.exit_code == 0, res.output
    assert "asperity_density" in res.output and "chi-square" in res.output
    cfg = Config.from_toml(out)
    assert cfg.asperity_density == pytest.approx(3e8, rel=0.05)
    res = CliRunner().invoke(main, ["validate", str(synthetic), "--config", str(out), "--out", str(tmp_path / "v"), "--markdown"])
    assert res.exit_code == 0, res.output


def test_free_takes_several_names_after_one_flag(synthetic, tmp_path, monkeypatch):
    seen = {}

    def fake(data, free, **kw):
        seen["free"] = free
        raise CalibrationError("stop here")

    monkeypatch.setattr("cmpsim.calibration.calibrate", fake)
    res = CliRunner().invoke(main, ["calibrate", str(synthetic), "--free", "asperity_density", "asperity_radius", "pad_modulus"])
    assert seen["free"] == ["asperity_density", "asperity_radius", "pad_modulus"]
    assert res.exit_code == 2
    res = CliRunner().invoke(main, ["calibrate", "--free", "asperity_density", str(synthetic)])
    assert seen["free"] == ["asperity_density"]
    CliRunner().invoke(main, ["calibrate", str(synthetic), "--free", "asperity_density,pad_modulus", "--free", "asperity_radius"])
    assert seen["free"] == ["asperity_density", "pad_modulus", "asperity_radius"]


@pytest.mark.parametrize(
    "args, needle",
    [
        (["--free", "asperity_densty"], "unknown parameter 'asperity_densty'"),
        (["--free", "model"], "cannot be fitted"),
        (["--free", "applied_pressure"], "set per point"),
        (["--free", "pad_modulus", "--bounds", "pad_modulus=5"], "NAME=LOW:HIGH"),
        (["--free", "pad_modulus", "--bounds", "pad_modulus=500MPa:20MPa"], "must be below"),
        (["--free", "pad_modulus", "--bounds", "pad_modulus=1m:2m"], "wrong dimension"),
        (["--free", "pad_modulus", "--bounds", "asperity_radius=1um:2um"], "not free"),
        (["--free", "pad_modulus", "pad_modulus"], "repeated"),
    ],
)
def test_bad_requests_name_the_problem(synthetic, args, needle):
    res = CliRunner().invoke(main, ["calibrate", str(synthetic), "--grid", "coarse", *args])
    assert res.exit_code == 2
    assert needle in res.output


def test_refuses_to_calibrate_against_another_models_prediction():
    from cmpsim.validation import shipped_dataset_paths

    thakurta = [p for p in shipped_dataset_paths() if "thakurta" in p.name]
    with pytest.raises(CalibrationError, match="another model's predictions"):
        calibrate(thakurta, ["pad_modulus"], config=BASE)


def test_one_test_says_which_columns_of_the_jacobian_are_zero():
    """Every fit (wafer, die, pad, pad life) and the data's choice read "the data do not change with it" through
    zero_columns: absolutely (1e-9 of the residuals' uncertainties per unit fit variable, which alone catches
    a single free input's round-off column) or relative to the largest column above 1."""
    from cmpsim.calibration.identify import ZERO_JACOBIAN, choose, zero_columns

    J = np.array([[1.0, 1e-12, 0.0, np.nan], [2.0, -1e-12, 0.0, 1.0]])
    assert zero_columns(J).tolist() == [False, True, True, False]  # a column the model gave no value for is not called zero
    assert zero_columns(np.array([[3e-12], [4e-12]])).tolist() == [True]  # one input: there is no other column to compare with
    big = np.array([[1e3, 0.5 * ZERO_JACOBIAN * 1e3], [0.0, 0.0]])
    assert zero_columns(big).tolist() == [False, True]  # 1e-9 of what the other input does
    assert zero_columns(np.array([[1.0, 2 * ZERO_JACOBIAN]])).tolist() == [False, False]
    left = dict(choose(J[:, :3], ["a", "b", "c"], ["", "", ""], 2).left)
    assert set(left) == {"b", "c"} and all("column of the Jacobian is zero" in w for w in left.values())


def test_one_covariance_for_every_fit_undefined_without_a_scatter_to_scale_by():
    """(J^T J)^-1 with absolute uncertainties whatever the degrees of freedom; without them scaled by the reduced
    chi-square, and undefined (NaN, with a note) at no degree of freedom or an exact fit, not infinite or shrunk."""
    from cmpsim.calibration.uncertainty import covariance

    J = np.array([[1.0, 0.0], [0.0, 2.0], [1.0, 1.0]])
    inv = np.linalg.inv(J.T @ J)
    for dof in (0, 1):
        notes = []
        assert np.allclose(covariance(J, 3.0, dof, True, notes), inv) and notes == []
    notes = []
    assert np.isnan(covariance(J[:2], 0.0, 0, False, notes)).all() and "no degrees of freedom left" in notes[0]
    notes = []
    assert np.isnan(covariance(J, 1e-14, 1, False, notes)).all() and "fitted exactly" in notes[0]
    assert np.allclose(covariance(J, 3.0, 1, False, []), 3.0 * inv)
    notes = []
    assert np.isinf(covariance(np.array([[1.0, 1.0], [2.0, 2.0]]), 3.0, 0, True, notes)).all() and "singular" in notes[0]


def test_a_wafer_fit_without_degrees_of_freedom_gives_its_intervals_only_with_uncertainties(tmp_path):
    path = synthetic_dataset(tmp_path / "one.csv", TRUTH, POINTS[:1], ["film_thickness"], config=BASE, relative_noise=0.01, seed=1)
    given = calibrate(path, ["asperity_density"], config=BASE)
    lo, hi = given.ci95["asperity_density"]
    assert given.dof == 0 and given.absolute_sigma and 0 < lo < given.values["asperity_density"] < hi < np.inf
    lines = path.read_text().splitlines()
    at = lines[4].split(",").index("uncertainty")  # the header, after the four comment lines
    bare = tmp_path / "bare.csv"
    bare.write_text("\n".join(lines[:5] + [",".join("" if k == at else c for k, c in enumerate(ln.split(","))) for ln in lines[5:]]) + "\n")
    none = calibrate(bare, ["asperity_density"], config=BASE)
    assert none.dof == 0 and not none.absolute_sigma
    assert all(np.isnan(none.ci95["asperity_density"])) and any("no degrees of freedom left" in n for n in none.notes)
