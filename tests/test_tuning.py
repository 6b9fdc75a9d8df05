"""Zone tuning of the membrane head (cmpsim.tune_zones, cmpsim tune-zones; issue 25)."""

import json
import re

import numpy as np
import pytest
from click.testing import CliRunner

import cmpsim
from cmpsim.cli import main
from cmpsim.inputs.config import Config, zone_mean_pressure
from cmpsim.head.tuning import read_incoming

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


# ---- an incoming thickness profile flattened after a polish time (issue 25) ----
COARSE = dict(carrier="membrane", zone_radii="20,38.1 mm", grid="8x24")
EDGE_THICK = "radius_mm,thickness_nm\n" + "".join(f"{r:.4f},{1000 + 5 * (r / 38.1) ** 2:.6f}\n" for r in np.linspace(0.0, 38.1, 20))


@pytest.fixture(scope="module")
def incoming_pair(tmp_path_factory):
    path = tmp_path_factory.mktemp("incoming") / "edge_thick.csv"
    path.write_text(EDGE_THICK)
    cfg = Config.default().replace(**COARSE)
    flat = cmpsim.tune_zones(cfg)
    tuned = cmpsim.tune_zones(cfg, incoming=path, polish_time="1 min")
    return flat, tuned, path


def test_a_film_thicker_at_the_edge_raises_the_tuned_edge_zone_and_flattens_what_is_left(incoming_pair):
    flat, tuned, _ = incoming_pair
    # the outer zone must remove more: its pressure relative to the inner zone's rises over the flat-profile tuning
    # (docs/model.md 13f: 0.90 -> 2.95; the zones' weak grip sends the inner zone to its lower bound)
    assert tuned.zone_pressures[1] / tuned.zone_pressures[0] > 2.0 * flat.zone_pressures[1] / flat.zone_pressures[0]
    assert tuned.remaining_nonuniformity < tuned.before["remaining_nonuniformity"] / 2.0
    assert tuned.polish_time == 60.0
    # what is reported is t_in - RR T of the tuned profile, and its non-uniformity is the one the output weighs
    radius = tuned.remaining_thickness["radius"]
    r_csv = np.linspace(0.0, 0.0381, 20)  # t_in interpolated linearly from the file's points
    t_in = np.interp(radius, r_csv, 1e-9 * (1000 + 5 * (r_csv / 0.0381) ** 2))
    assert tuned.remaining_thickness["thickness"] == pytest.approx(t_in - 60.0 * tuned.profile["rate"], rel=1e-6)
    again = cmpsim.solve(Config.default().replace(**COARSE, zone_pressures=tuned.zone_pressures), relative=False)
    assert again.scalars["within_wafer_nonuniformity"] == pytest.approx(tuned.within_wafer_nonuniformity, abs=1e-6, rel=0)
    data = tuned.to_dict()
    assert set(data["remaining_thickness"]) == {"radius", "thickness"}
    assert data["remaining_nonuniformity"] == tuned.remaining_nonuniformity and data["units"]["thickness"] == "m"
    assert "remaining_thickness" not in flat.to_dict()


def test_incoming_needs_a_polish_time_that_leaves_film_everywhere(incoming_pair):
    _, _, path = incoming_pair
    cfg = Config.default().replace(**COARSE)
    with pytest.raises(ValueError, match="incoming and polish_time go together"):
        cmpsim.tune_zones(cfg, incoming=path)
    with pytest.raises(ValueError, match="incoming and polish_time go together"):
        cmpsim.tune_zones(cfg, polish_time="60 s")
    with pytest.raises(ValueError, match=r"a \(radius, thickness\) pair of arrays in m; got 3 items"):
        cmpsim.tune_zones(cfg, incoming=([0.0, 0.04],) * 3, polish_time=60.0)
    with pytest.raises(ValueError, match="polish_time must be > 0 s"):
        cmpsim.tune_zones(cfg, incoming=path, polish_time="0 s")
    with pytest.raises(ValueError, match=r"polish_time = 600 s removes more than the incoming thickness at the start"):
        cmpsim.tune_zones(cfg, incoming=path, polish_time="10 min")
    with pytest.raises(ValueError, match=r"covers radii 0-30 mm; it must cover 2.38125-35.7188 mm"):
        cmpsim.tune_zones(cfg, incoming=(np.array([0.0, 0.03]), np.array([1e-6, 1e-6])), polish_time=60.0)


# what a bad incoming file must be refused with -> the file
BAD_INCOMING = {
    "is empty": "",
    "unit 'furlong' not known; use one of m, mm, um, nm, angstrom": "radius_mm,thickness_furlong\n0,1\n38.1,1\n",
    "header column 'r_mm' is not radius_<unit> or thickness_<unit>": "r_mm,thickness_nm\n0,1\n38.1,1\n",
    "names the radius column twice": "radius_mm,radius_nm\n0,1\n38.1,1\n",
    "has 1 data rows": "radius_mm,thickness_nm\n0,1\n",
    "row 3 is not two numbers": "radius_mm,thickness_nm\n0,1\n38.1,x\n",
    "row 2 has 3 values": "radius_mm,thickness_nm\n0,1,2\n38.1,1\n",
    "strictly increasing": "radius_mm,thickness_nm\n10,1\n5,1\n",
    "thickness must be positive": "radius_mm,thickness_nm\n0,1\n38.1,-1\n",
}


@pytest.mark.parametrize("message", BAD_INCOMING)
def test_bad_incoming_files_are_named(tmp_path, message):
    bad = tmp_path / "in.csv"
    bad.write_text(BAD_INCOMING[message])
    with pytest.raises(ValueError, match=re.escape(message)):
        read_incoming(bad)


def test_the_thickness_column_may_come_first_in_any_known_unit(tmp_path):
    path = tmp_path / "in.csv"
    path.write_text("thickness_um,radius_m\n1.0,0\n1.2,0.05\n")
    r, t = read_incoming(path)
    assert r == pytest.approx([0.0, 0.05]) and t == pytest.approx([1e-6, 1.2e-6])


def test_the_command_flattens_an_incoming_profile_and_refuses_one_without_the_other(tmp_path):
    path = tmp_path / "in.csv"
    path.write_text(EDGE_THICK)
    base = ["tune-zones", "--grid", "8x24", "--set", "carrier=membrane", "--set", "zone_radii=20,38.1 mm"]
    r = CliRunner().invoke(main, base + ["--json", "--incoming", str(path), "--polish-time", "60 s"])
    assert r.exit_code == 0, r.output
    data = json.loads(r.output)
    assert data["remaining_nonuniformity"] < data["before"]["remaining_nonuniformity"] and data["polish_time"] == 60.0
    assert len(data["remaining_thickness"]["thickness"]) == 8
    r = CliRunner().invoke(main, base + ["--incoming", str(path)])
    assert r.exit_code != 0 and "--incoming needs --polish-time" in r.output and "Traceback" not in r.output
    r = CliRunner().invoke(main, base + ["--incoming", str(tmp_path / "missing.csv"), "--polish-time", "60 s"])
    assert r.exit_code != 0 and "cannot read" in r.output


# ---- the retaining ring tuned with the zones (issue 32: the edge band is the ring's to shape) ----
RINGED = dict(carrier="membrane", zone_radii="20,38.1 mm", pad_compliance="layer", retaining_ring_pressure="4 psi", grid="coarse")


def test_the_ring_is_tuned_with_the_zones_and_reported_with_its_start():
    """One trust-region step on a 3-inch layered head: the ring pressure is a fourth unknown of the least
    squares (its response by the same finite differences), kept within its bounds (default 1.5-9 psi)."""
    from cmpsim.head.tuning import DEFAULT_RING_BOUNDS

    cfg = Config.default().replace(**RINGED)
    tuned = cmpsim.tune_zones(cfg, ring=True, max_steps=1)
    assert DEFAULT_RING_BOUNDS == pytest.approx((1.5 * PSI, 9 * PSI))
    assert tuned.within_wafer_nonuniformity < tuned.before["within_wafer_nonuniformity"]
    assert tuned.before["ring_pressure"] == pytest.approx(4 * PSI) and tuned.ring_pressure != tuned.before["ring_pressure"]
    assert 1.5 * PSI <= tuned.ring_pressure <= 9 * PSI
    assert tuned.config.retaining_ring_pressure == tuned.ring_pressure
    rings = len(tuned.profile["radius"])
    assert tuned.response.shape == (rings, 2) and tuned.ring_response.shape == (rings,)
    data = tuned.to_dict()
    assert data["ring_pressure"] == tuned.ring_pressure and data["before"]["ring_pressure"] == tuned.before["ring_pressure"]
    assert data["units"]["ring_pressure"] == "Pa"
    # the default leaves the ring alone and says nothing of it
    assert "ring_pressure" not in cmpsim.tune_zones(Config.default().replace(**COARSE), max_steps=1).to_dict()


def test_tuning_the_ring_needs_a_ring_to_start_from_and_bounds_around_it():
    with pytest.raises(ValueError, match=r"ring=True tunes the retaining ring's pressure but the configuration has none"):
        cmpsim.tune_zones(Config.default().replace(**HEAD), ring=True)
    with pytest.raises(ValueError, match=r"ring_bounds needs ring=True"):
        cmpsim.tune_zones(Config.default().replace(**RINGED), ring_bounds=("1 psi", "5 psi"))
    with pytest.raises(ValueError, match=r"ring_bounds must be 0 < low < high"):
        cmpsim.tune_zones(Config.default().replace(**RINGED), ring=True, ring_bounds=("5 psi", "1 psi"))
    with pytest.raises(ValueError, match=r"retaining_ring_pressure .* lies outside the ring bounds"):
        cmpsim.tune_zones(Config.default().replace(**RINGED), ring=True, ring_bounds=("5 psi", "9 psi"))


def test_the_command_frees_the_ring_with_ring_and_its_bounds_with_ring_bounds(monkeypatch):
    import cmpsim.head.tuning

    seen = {}

    class Stub:
        def to_dict(self):
            return {"ring_pressure": 1.0}

    def stub(cfg, **options):
        seen.update(options)
        return Stub()

    monkeypatch.setattr(cmpsim.head.tuning, "tune_zones", stub)
    base = ["tune-zones", "--json", "--grid", "coarse", "--set", "carrier=membrane", "--set", "zone_radii=20,38.1 mm"]
    r = CliRunner().invoke(main, base)
    assert r.exit_code == 0, r.output
    assert seen["ring"] is False and seen["ring_bounds"] is None
    r = CliRunner().invoke(main, base + ["--ring", "--ring-bounds", "2,6 psi"])
    assert r.exit_code == 0, r.output
    assert seen["ring"] is True and seen["ring_bounds"] == pytest.approx([2 * PSI, 6 * PSI])
    r = CliRunner().invoke(main, base + ["--ring-bounds", "2,6 psi"])
    assert r.exit_code == 2 and "--ring-bounds needs --ring" in r.output
    r = CliRunner().invoke(main, base + ["--ring", "--ring-bounds", "2 psi"])
    assert r.exit_code == 2 and "--ring-bounds takes two pressures" in r.output


# ---- the kept rate: with the ring, the tuning keeps the mean removal rate by default (issue 32) ----
def test_tuning_the_ring_keeps_the_mean_rate_by_default_and_keep_none_lets_it_fall_only_when_asked():
    """One trust-region step on the 3-inch layered head: the default with the ring is keep="rate" (a fab tunes
    the profile at its rate). The mean removal rate inside the edge exclusion stays the start's to
    RATE_TOLERANCE (0.1 %), the non-uniformity is not worse, and the ring stays inside its bounds."""
    from cmpsim.head.tuning import RATE_TOLERANCE

    cfg = Config.default().replace(**RINGED)
    tuned = cmpsim.tune_zones(cfg, ring=True, max_steps=1)
    assert tuned.keep == "rate" and tuned.to_dict()["keep"] == "rate"
    assert tuned.mean_rate == pytest.approx(tuned.before["mean_rate"], rel=RATE_TOLERANCE)
    assert tuned.within_wafer_nonuniformity <= tuned.before["within_wafer_nonuniformity"]
    assert 1.5 * PSI <= tuned.ring_pressure <= 9 * PSI
    data = tuned.to_dict()
    assert data["mean_rate"] == tuned.mean_rate and data["before"]["mean_rate"] == tuned.before["mean_rate"]
    assert data["units"]["mean_rate"] == "m/s" and data["units"]["wafer_mean_rate"] == "m/s"
    # the zones alone keep their former default (nothing kept), and "none" is that default spelt out
    assert cmpsim.tune_zones(Config.default().replace(**COARSE), max_steps=0).keep == "none"
    assert cmpsim.tune_zones(cfg, ring=True, keep="none", max_steps=0).keep == "none"
    with pytest.raises(ValueError, match=r"keep must be one of \('none', 'pressure', 'rate'\)"):
        cmpsim.tune_zones(cfg, keep="load")


def test_the_command_prints_the_mean_rate_before_and_after_in_nm_per_min(monkeypatch):
    """The table output of ``tune-zones --ring`` (one step, to stay quick) states the kept mean rate, with units."""
    import functools

    import cmpsim.head.tuning

    monkeypatch.setattr(cmpsim.head.tuning, "tune_zones", functools.partial(cmpsim.head.tuning.tune_zones, max_steps=1))
    args = ["tune-zones", "--ring", "--grid", "coarse", "--set", "carrier=membrane", "--set", "zone_radii=20,38.1 mm", "--set", "pad_compliance=layer", "--set", "retaining_ring_pressure=4 psi"]
    r = CliRunner().invoke(main, args)
    assert r.exit_code == 0, r.output
    text = " ".join(r.output.split())  # rich wraps the line at the terminal's width
    line = re.search(r"mean removal rate inside the edge exclusion \(kept\): ([\d.]+) nm/min -> ([\d.]+) nm/min", text)
    assert line, r.output
    assert float(line.group(2)) == pytest.approx(float(line.group(1)), rel=1e-3)
    assert re.search(r"over the whole wafer [\d.]+ nm/min -> [\d.]+ nm/min", text)
    r = CliRunner().invoke(main, args + ["--keep", "none", "--json"])
    assert r.exit_code == 0, r.output
    assert json.loads(r.output)["keep"] == "none"
