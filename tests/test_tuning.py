"""Zone tuning of the membrane head (cmpsim.tune_zones, cmpsim tune-zones; issue 25)."""

import json

import numpy as np
import pytest
from click.testing import CliRunner

import cmpsim
from cmpsim.cli import main
from cmpsim.config import Config, zone_mean_pressure

PSI = 6894.757293168361
HEAD = dict(carrier="membrane", zone_radii="10,20,30,38.1 mm")  # the default (edge-graded) grid


@pytest.fixture(scope="module")
def tuned():
    return cmpsim.tune_zones(Config.default().replace(**HEAD))


def test_tuning_flattens_the_profile_to_below_a_third_of_the_untuned_non_uniformity(tuned):
    assert tuned.within_wafer_nonuniformity < tuned.before["within_wafer_nonuniformity"] / 3.0
    assert all(0.5 * PSI <= p <= 8 * PSI for p in tuned.zone_pressures)
    assert tuned.response.shape == (len(tuned.profile["radius"]), 4)
    # how much of each zone's response stays under the zone (docs/model.md 13f: the zones' grip is weak)
    inside = tuned.response_inside
    assert len(inside) == 4 and all(0.0 <= v <= 1.0 for v in inside)
    assert tuned.to_dict()["zone_response_inside"] == list(inside)
    assert inside == pytest.approx((0.28, 0.04, 0.13, 0.38), abs=0.02)  # zones' area shares: 0.07, 0.21, 0.34, 0.38


def test_rerunning_the_tuned_pressures_reproduces_the_reported_non_uniformity_to_1e_6(tuned):
    again = cmpsim.solve(Config.default().replace(**HEAD, zone_pressures=tuned.zone_pressures), relative=False)
    # to 1e-6 as a fraction (the contract); relative to the small tuned value, the bending's tolerance shows at 1e-5
    assert again.scalars["within_wafer_nonuniformity"] == pytest.approx(tuned.within_wafer_nonuniformity, abs=1e-6, rel=0)
    assert again.scalars["within_wafer_nonuniformity"] == pytest.approx(tuned.within_wafer_nonuniformity, rel=1e-4)
    assert np.asarray(again.profiles["removal_rate_profile"]) == pytest.approx(tuned.profile["rate"], rel=1e-6)


def test_keeping_the_pressure_keeps_the_load():
    start = Config.default().replace(**HEAD)
    kept = cmpsim.tune_zones(start, keep="pressure", max_steps=1)
    assert zone_mean_pressure(kept.zone_radii, kept.zone_pressures) == pytest.approx(start.applied_pressure, rel=1e-3)
    assert kept.within_wafer_nonuniformity < kept.before["within_wafer_nonuniformity"]


def test_tuning_refuses_a_rigid_head_and_bad_bounds():
    with pytest.raises(ValueError, match="tune_zones needs carrier = 'membrane'"):
        cmpsim.tune_zones(Config.default())
    with pytest.raises(ValueError, match=r"bounds must be 0 < low < high"):
        cmpsim.tune_zones(Config.default().replace(**HEAD), bounds=(8 * PSI, 0.5 * PSI))
    with pytest.raises(ValueError, match="lie outside the bounds"):
        cmpsim.tune_zones(Config.default().replace(**HEAD), bounds=("1 psi", "3 psi"))
    r = CliRunner().invoke(main, ["tune-zones", "--bounds", "1 psi"])
    assert r.exit_code == 2 and "--bounds takes two pressures" in r.output


def test_the_command_prints_one_json_object_with_the_contracted_keys():
    r = CliRunner().invoke(main, ["tune-zones", "--json", "--grid", "8x24", "--set", "carrier=membrane", "--set", "zone_radii=20,38.1 mm"])
    assert r.exit_code == 0, r.output
    data = json.loads(r.output)
    assert set(data) >= {"zone_pressures", "within_wafer_nonuniformity", "profile"}
    assert set(data["profile"]) == {"radius", "rate"}
    assert len(data["zone_pressures"]) == 2 and data["units"]["zone_pressures"] == "Pa"
    assert len(data["profile"]["radius"]) == len(data["profile"]["rate"]) == 8
    assert 0 <= data["within_wafer_nonuniformity"] <= data["before"]["within_wafer_nonuniformity"]
