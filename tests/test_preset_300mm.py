"""The 300mm preset: a production head and recipe (issue 25; docs/model.md 13f, 'The 300mm preset')."""

import pytest
from click.testing import CliRunner

from cmpsim.cli import PRESET_NAMES, load_config, main
from cmpsim.config import PRESETS, Config, zone_mean_pressure

PSI = 6894.757293168361


def test_the_300mm_preset_is_a_300mm_wafer_in_a_five_zone_membrane_head_with_a_ring_on_the_layered_stack():
    c = Config.preset("300mm")
    assert c.wafer_diameter == pytest.approx(0.3) and c.wafer_thickness == pytest.approx(775e-6)
    assert c.carrier == "membrane" and c.zone_radii == pytest.approx((0.05, 0.10, 0.13, 0.145, 0.15))
    assert c.retaining_ring_pressure == pytest.approx(3 * PSI) and c.pad_compliance == "layer"
    # IC1000 on Suba IV: the defaults of the stack, with their sources
    assert (c.pad_thickness, c.subpad_thickness) == (Config.default().pad_thickness, Config.default().subpad_thickness)
    assert c.applied_pressure == pytest.approx(3 * PSI) and c.rotation_speed == pytest.approx(93 * 2 * 3.141592653589793 / 60)
    assert c.wafer_speed_ratio == pytest.approx(87 / 93) and c.edge_exclusion == pytest.approx(3e-3)


def test_presets_leave_zone_pressures_unset_so_applied_pressure_fills_every_zone():
    c = Config.preset("300mm")
    assert c.zone_pressures == () and "zone_pressures" not in PRESETS["300mm"]
    assert c.zone_pressure_values == (c.applied_pressure,) * 5
    lower = c.replace(applied_pressure="2 psi")
    assert lower.zone_pressure_values == pytest.approx((2 * PSI,) * 5)
    zoned = c.replace(zone_pressures="3,3,3.5,4,2 psi")
    assert zoned.applied_pressure == pytest.approx(zone_mean_pressure(c.zone_radii, zoned.zone_pressure_values))


def test_the_command_line_offers_every_preset_and_a_file_may_start_from_300mm(tmp_path):
    assert tuple(PRESETS) == PRESET_NAMES
    assert load_config(None, [], "300mm") == Config.preset("300mm")
    path = tmp_path / "head.toml"
    path.write_text('preset = "300mm"\n[process]\nretaining_ring_pressure = "4 psi"\n')
    assert Config.from_toml(path).retaining_ring_pressure == pytest.approx(4 * PSI)
    r = CliRunner().invoke(main, ["run", "--preset", "300mm", "--set", "carrier=rigid"])
    assert r.exit_code == 2 and "zone_radii needs carrier = 'membrane'" in r.output
    r = CliRunner().invoke(main, ["run", "--preset", "450mm"])
    assert r.exit_code == 2 and "'300mm'" in r.output


def test_the_ring_of_the_300mm_preset_is_refused_on_a_local_pad():
    with pytest.raises(ValueError, match="retaining_ring_pressure = .* cannot act on the wafer with pad_compliance = 'winkler'"):
        Config.preset("300mm").replace(pad_compliance="winkler")
