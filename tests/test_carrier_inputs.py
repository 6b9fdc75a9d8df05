"""Inputs of the polishing head (issue 25): carrier, zone radii and pressures, wafer thickness, ring."""

import math

import pytest
from click.testing import CliRunner

from cmpsim.cli import load_config, main
from cmpsim.inputs.config import PARAMETERS, PRESETS, Config, zone_mean_pressure

PSI = 6894.757293168361
FIVE_ZONES = dict(carrier="membrane", wafer_diameter="300 mm", zone_radii="50,100,130,145,150 mm")


def test_list_inputs_read_comma_separated_numbers_and_one_unit():
    c = Config.default().replace(**FIVE_ZONES, zone_pressures="3,3,3.5,4,2 psi")
    assert c.zone_radii == pytest.approx((0.05, 0.1, 0.13, 0.145, 0.15), rel=1e-15)
    assert c.zone_pressures == pytest.approx(tuple(v * PSI for v in (3, 3, 3.5, 4, 2)), rel=1e-15)
    assert all(isinstance(v, float) for v in c.zone_radii + c.zone_pressures)


def test_list_inputs_take_toml_strings_and_si_arrays(tmp_path):
    (tmp_path / "a.toml").write_text(
        'carrier = "membrane"\nwafer_diameter = "300 mm"\nzone_radii = "50,100,130,145,150 mm"\nzone_pressures = "3,3,3.5,4,2 psi"\n'
    )
    (tmp_path / "b.toml").write_text(
        '[wafer]\nwafer_diameter = 0.3\n[process]\ncarrier = "membrane"\nzone_radii = [0.05, 0.1, 0.13, 0.145, 0.15]\n'
        f"zone_pressures = {[v * PSI for v in (3, 3, 3.5, 4, 2)]}\n"
    )
    a, b = Config.from_toml(tmp_path / "a.toml"), Config.from_toml(tmp_path / "b.toml")
    assert a.zone_radii == pytest.approx(b.zone_radii, rel=1e-15)
    assert a.zone_pressures == pytest.approx(b.zone_pressures, rel=1e-15)


def test_zone_pressures_set_applied_pressure_to_their_area_mean():
    c = Config.default().replace(**FIVE_ZONES, zone_pressures="3,3,3.5,4,2 psi")
    areas = [0.05**2, 0.1**2 - 0.05**2, 0.13**2 - 0.1**2, 0.145**2 - 0.13**2, 0.15**2 - 0.145**2]
    mean = sum(a * p for a, p in zip(areas, (3, 3, 3.5, 4, 2))) / 0.15**2 * PSI
    assert c.applied_pressure == pytest.approx(mean, rel=1e-13)
    assert zone_mean_pressure((1.0,), (5.0,)) == 5.0


def test_without_zone_pressures_every_zone_gets_applied_pressure():
    c = Config.default().replace(**FIVE_ZONES, applied_pressure="3 psi")
    assert c.zone_pressures == ()
    assert c.zone_pressure_values == pytest.approx((3 * PSI,) * 5)
    assert c.zone_outer_radii == c.zone_radii
    one = Config.default().replace(carrier="membrane")
    assert one.zone_outer_radii == (0.5 * one.wafer_diameter,)
    assert one.zone_pressure_values == (one.applied_pressure,)


def test_an_input_that_sets_applied_pressure_and_zone_pressures_is_refused():
    with pytest.raises(ValueError, match=r"applied_pressure = .* conflicts with zone_pressures .*set one of them"):
        Config.default().replace(**FIVE_ZONES, zone_pressures="3,3,3.5,4,2 psi", applied_pressure="4 psi")
    zoned = Config.default().replace(**FIVE_ZONES, zone_pressures="3,3,3.5,4,2 psi")
    with pytest.raises(ValueError, match=r"zone_pressures are already set"):
        zoned.replace(applied_pressure="5 psi")
    with pytest.raises(ValueError, match="set one of them"):
        load_config(None, ["carrier=membrane", "zone_pressures=3 psi", "applied_pressure=4 psi"])
    # clearing the zones goes back to one pressure everywhere
    uniform = zoned.replace(zone_pressures="", applied_pressure="5 psi")
    assert uniform.zone_pressure_values == pytest.approx((5 * PSI,) * 5)


def test_toml_round_trip_of_a_zoned_head_is_exact(tmp_path):
    c = Config.default().replace(**FIVE_ZONES, zone_pressures="3,3,3.5,4,2 psi", wafer_thickness="775 um")
    c.to_toml(tmp_path / "c.toml")
    assert Config.from_toml(tmp_path / "c.toml") == c
    Config.default().to_toml(tmp_path / "d.toml")
    assert Config.from_toml(tmp_path / "d.toml") == Config.default()


@pytest.mark.parametrize(
    "changes,match",
    [
        (dict(zone_radii="50,40,150 mm"), r"zone_radii must increase"),
        (dict(zone_radii="50,100,140 mm"), r"zone_radii: the last zone must end at the wafer rim, 0.15 m .*Valid: increasing radii in \(0, 0.15\] m"),
        (dict(zone_radii="-50,100,150 mm"), r"zone_radii .*out of range: valid range \(0, inf\) m"),
        (dict(zone_pressures="3,3 psi"), r"zone_pressures has 2 values but there are 5 zones"),
        (dict(zone_pressures="3,3,0,4,2 psi"), r"zone_pressures = 0 Pa is out of range"),
        (dict(zone_pressures="3,3,3,4,2 m"), r"zone_pressures: .*wrong dimension"),
        (dict(zone_pressures="3,,3 psi"), r"zone_pressures: .*empty item"),
        (dict(carrier="rigid", zone_pressures="3,3,3,4,2 psi"), r"zone_pressures needs carrier = 'membrane'"),
        (dict(wafer_thickness="0 um"), r"wafer_thickness .*valid range"),
    ],
)
def test_bad_zone_inputs_are_refused_naming_the_parameter_and_range(changes, match):
    with pytest.raises(ValueError, match=match):
        Config.default().replace(**(FIVE_ZONES | changes))


def test_zone_pressures_without_zone_radii_take_one_value():
    c = Config.default().replace(carrier="membrane", zone_pressures="3 psi")
    assert c.applied_pressure == pytest.approx(3 * PSI, rel=1e-15)
    with pytest.raises(ValueError, match=r"zone_pressures has 2 values but there are 1 zones \(zone_radii unset"):
        Config.default().replace(carrier="membrane", zone_pressures="3,4 psi")


def test_a_ring_on_a_local_pad_is_refused_saying_it_cannot_act_on_the_wafer():
    with pytest.raises(ValueError, match=r"retaining_ring_pressure .*cannot act on the wafer with pad_compliance = 'winkler'"):
        Config.default().replace(retaining_ring_pressure="5 psi")
    with pytest.raises(ValueError, match=r"retaining_ring_pressure .*cannot act on the wafer with pad_compliance = 'rigid'"):
        Config.default().replace(pad_compliance="rigid", retaining_ring_pressure="5 psi")
    assert Config.default().replace(pad_compliance="layer", retaining_ring_pressure="5 psi").retaining_ring_pressure > 0


def test_presets_leave_zone_pressures_unset_and_keep_the_rigid_carrier_of_the_paper():
    for name in PRESETS:
        assert Config.preset(name).zone_pressures == ()
    assert Config.paper().carrier == "rigid"
    assert Config.default().carrier == "rigid"


def test_every_head_input_has_a_unit_and_a_source():
    for name in ("carrier", "zone_radii", "zone_pressures", "wafer_thickness", "retaining_ring_gap", "retaining_ring_width", "retaining_ring_pressure"):
        p = PARAMETERS[name]
        assert p.source and p.description
    assert PARAMETERS["wafer_thickness"].default == pytest.approx(381e-6)  # SEMI M1, 3-inch wafer
    assert math.isclose(PARAMETERS["retaining_ring_pressure"].default, 0.0)


def test_cmpsim_params_shows_the_head_inputs():
    out = CliRunner().invoke(main, ["params"], env={"COLUMNS": "200"}).output
    for name in ("carrier", "zone_radii", "zone_pressures", "wafer_thickness", "retaining_ring_gap", "retaining_ring_width", "retaining_ring_pressure"):
        assert name in out
    assert "unset" in out
    md = CliRunner().invoke(main, ["params", "--markdown"]).output
    assert "| `zone_pressures` | P_k | Pa | unset | unset | a list of numbers, each in (0, inf) Pa |" in md


def test_set_on_the_command_line_reads_a_zone_list_and_the_error_has_no_traceback():
    c = load_config(None, ["carrier=membrane", "wafer_diameter=300mm", "zone_radii=50,100,130,145,150 mm", "zone_pressures=3,3,3.5,4,2 psi"])
    assert c.zone_pressures[2] == pytest.approx(3.5 * PSI)
    r = CliRunner().invoke(main, ["run", "--set", "carrier=membrane", "--set", "zone_radii=10,20 mm"])
    assert r.exit_code == 2
    assert "zone_radii: the last zone must end at the wafer rim" in r.output
    assert "Traceback" not in r.output
