"""Configuration: units, ranges, TOML round trip, error messages."""

import math

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from cmpsim.inputs.config import GRID_PRESETS, PARAMETERS, Config, parameter_table_markdown, parse_value


def test_values_take_units_and_are_stored_in_si():
    c = Config.default().replace(applied_pressure="4psi", rotation_speed="60rpm", particle_diameter="100nm",
                                 pad_roughness="15um", wafer_diameter="3in", dome_height="5 um")
    assert c.applied_pressure == pytest.approx(27579.03, rel=1e-6)
    assert c.rotation_speed == pytest.approx(2 * math.pi)
    assert c.particle_diameter == pytest.approx(100e-9)
    assert c.wafer_diameter == pytest.approx(0.0762)
    assert Config.default().replace(applied_pressure="27.6kPa").applied_pressure == pytest.approx(27600)


def test_paper_preset_is_the_papers_base_case():
    """``Config.paper()`` is Table 1 of the paper with the paper's model (granular slurry, rigid pad, ...)."""
    c = Config.paper()
    assert c.applied_pressure == pytest.approx(parse_value("applied_pressure", "4 psi"))
    assert c.rotation_speed == pytest.approx(parse_value("rotation_speed", "60 rpm"))
    assert c.particle_diameter == pytest.approx(100e-9)
    assert c.pad_roughness == pytest.approx(15e-6)
    assert c.dome_height == pytest.approx(5e-6)
    assert c.wafer_diameter == pytest.approx(0.0762)
    assert (c.w_over_k, c.t_over_a, c.fluctuation_ratio) == (4e-6, 1.0, 3.0)
    assert c.model == "lep"
    assert (c.slurry_model, c.cavitation, c.pad_compliance, c.removal_law) == ("granular", "none", "rigid", "paper")


def test_default_is_the_papers_operating_point_with_the_predictive_physics():
    """The default model (issue 18) keeps the paper's operating point and changes only the physics of section 13d."""
    c = Config.default()
    assert c.applied_pressure == pytest.approx(parse_value("applied_pressure", "4 psi"))
    assert c.rotation_speed == pytest.approx(parse_value("rotation_speed", "60 rpm"))
    assert c.particle_diameter == pytest.approx(100e-9)
    assert c.dome_height == pytest.approx(5e-6)
    assert c.wafer_diameter == pytest.approx(0.0762)
    assert c.model == "lep"
    # issue 24: the abrasive removal law; the viscosity follows the loading and is 5 mPa s at the default loading
    assert (c.slurry_model, c.cavitation, c.pad_compliance, c.removal_law) == ("newtonian", "gumbel", "winkler", "abrasive")
    assert c.slurry_viscosity == 0.0 and c.newtonian_viscosity == pytest.approx(5e-3, rel=1e-14)
    assert (c.pad_modulus, c.pad_hardness) == (pytest.approx(0.5e9), pytest.approx(50e6))
    assert (c.asperity_radius, c.pad_roughness, c.reference_roughness) == (
        pytest.approx(7e-6), pytest.approx(5e-6), pytest.approx(5e-6))


@pytest.mark.parametrize(
    "name,value,match",
    [
        ("applied_pressure", "-1 psi", r"applied_pressure .*out of range: valid range \(0, inf\) Pa"),
        ("applied_pressure", 0.0, r"applied_pressure .*valid range"),
        ("applied_pressure", "4 m", r"applied_pressure: .*wrong dimension.*Pa"),
        ("applied_pressure", "4 zorks", r"applied_pressure: cannot read"),
        ("pad_roughness", "0um", r"pad_roughness .*valid range"),
        ("pad_poisson", 0.7, r"pad_poisson .*valid range \[0, 0.5\]"),
        ("model", "viscous", r"model must be one of 'lep', 'elastic', 'hydrodynamic'"),
        ("grid", "7x9", r"grid must be"),
        ("no_such_thing", 1.0, r"unknown parameter 'no_such_thing'"),
        ("particle_diameter", float("nan"), r"particle_diameter must be a finite number"),
    ],
)
def test_bad_values_raise_valueerror_naming_parameter_and_range(name, value, match):
    with pytest.raises(ValueError, match=match):
        Config.default().replace(**{name: value})


def test_toml_round_trip_is_exact(tmp_path):
    c = Config.default().replace(applied_pressure="3.3 psi", particle_diameter="137nm", model="elastic", grid="10x24",
                                 kinematics="sliding")
    c.to_toml(tmp_path / "c.toml")
    assert Config.from_toml(tmp_path / "c.toml") == c


def test_toml_accepts_flat_keys_with_units(tmp_path):
    (tmp_path / "c.toml").write_text('applied_pressure = "2 psi"\n[slurry]\nparticle_diameter = "200 nm"\n')
    c = Config.from_toml(tmp_path / "c.toml")
    assert c.applied_pressure == pytest.approx(2 * 6894.757293168361)
    assert c.particle_diameter == pytest.approx(200e-9)


@pytest.mark.parametrize(
    "text,match",
    [("x = [", "not valid TOML"), ("[pad]\napplied_pressure = 3.0\n", "belongs in \\[process\\]"), ("[pad]\nfoo = 1\n", "unknown parameter 'foo'")],
)
def test_malformed_toml_is_rejected_with_the_reason(tmp_path, text, match):
    (tmp_path / "c.toml").write_text(text)
    with pytest.raises(ValueError, match=match):
        Config.from_toml(tmp_path / "c.toml")


@settings(max_examples=40, deadline=None)
@given(st.floats(min_value=1e-3, max_value=1e3))
def test_any_positive_pressure_in_kpa_round_trips_through_the_si_value(kpa):
    c = Config.default().replace(applied_pressure=f"{kpa!r} kPa")
    assert c.applied_pressure == pytest.approx(kpa * 1e3, rel=1e-12)


def test_every_parameter_has_a_source_and_a_valid_default():
    for name, p in PARAMETERS.items():
        assert p.source, name
        assert parse_value(name, p.default) == p.default


def test_grid_presets_are_valid_polar_grids():
    for nr, nt in GRID_PRESETS.values():
        assert nr >= 3 and nt >= 8 and nt % 2 == 0
    assert Config.default().replace(grid="fine", grid_grading="uniform").grid_shape == GRID_PRESETS["fine"]
    assert Config.paper().replace(grid="fine").grid_shape == GRID_PRESETS["fine"]  # the paper preset: equal rings
    assert Config.default().replace(grid="48x128").grid_shape == (48, 128)  # rings x sectors: equal rings


def test_a_named_grid_means_one_rim_ring_width_on_every_wafer():
    """Issue 23: the named grids are graded towards the edge with the rim ring of GRID_EDGE on
    3-inch and 300 mm wafers alike; the central rings are R/GRID_PRESETS rings wide; each
    preset halves the rings of the coarser one (same ring map)."""
    from cmpsim.inputs.config import GRID_EDGE

    for name, (edge, growth) in GRID_EDGE.items():
        for d, c in ((0.0762, 0.1524), (0.3, 0.2)):
            g = Config.default().replace(grid=name, wafer_diameter=d, centre_distance=c).polar_grid()
            w = g.widths[:, 0]
            assert g.graded and g.n_theta == GRID_PRESETS[name][1]
            assert w[-1] == pytest.approx(edge * (1 + growth / 2), rel=0.1), (name, d)  # the mean width over the rim ring
            assert w[0] == pytest.approx(g.radius / GRID_PRESETS[name][0], rel=0.15), (name, d)
            assert np.all(np.diff(w) <= 1e-12)  # narrowing monotonically towards the rim
    for d in (0.0762, 0.3):
        g1, g2 = (Config.default().replace(grid=n, wafer_diameter=d, centre_distance=0.2).polar_grid() for n in ("default", "fine"))
        assert abs(g2.n_r - 2 * g1.n_r) <= 1 and g2.n_theta == 2 * g1.n_theta
        assert (g1.edge_ratio, g1.edge_length) == pytest.approx((g2.edge_ratio, g2.edge_length), rel=1e-12)


def test_parameter_table_in_model_document_is_generated_from_the_registry():
    from pathlib import Path

    doc = (Path(__file__).parents[1] / "docs" / "model.md").read_text()
    assert parameter_table_markdown() in doc, "regenerate the table with `cmpsim params --markdown`"


def test_paper_preset_differs_from_the_defaults_exactly_in_the_listed_inputs():
    from cmpsim.inputs.config import PRESETS

    paper, default = Config.paper().to_dict(), Config.default().to_dict()
    changed = {k for k in default if paper[k] != default[k]}
    # the paper's granular_density (134 kg/m^3) sets its solids_loading (issue 24: one setting, two names)
    assert changed == set(PRESETS["paper"]) | {"solids_loading"}
    assert PRESETS["default"] == {} and Config.preset("default") == Config.default()
    assert Config.preset("paper") == Config.paper()
    with pytest.raises(ValueError, match="preset must be one of 'default', 'paper'"):
        Config.preset("fast")


def test_a_config_file_may_start_from_a_preset(tmp_path):
    path = tmp_path / "c.toml"
    path.write_text('preset = "paper"\n[process]\napplied_pressure = "3 psi"\n')
    assert Config.from_toml(path) == Config.paper().replace(applied_pressure="3 psi")


@pytest.mark.parametrize("value", ["1 m", "5 um"])
def test_a_particle_larger_than_the_roughness_allows_is_refused_by_name_before_solving(value):
    with pytest.raises(ValueError, match=r"particle_diameter .*(out of range|too large for pad_roughness).*valid range"):
        Config.paper().replace(particle_diameter=value, pad_roughness="15 um")


def test_the_grain_flow_size_limit_applies_to_the_granular_slurry_only_and_says_why():
    assert Config.default().replace(particle_diameter="1 um").particle_diameter == pytest.approx(1e-6)
    assert Config.default().replace(particle_diameter="2 um").particle_diameter == pytest.approx(2e-6)
    with pytest.raises(ValueError, match=r"slurry_model = 'granular'.*averages over many grains"):
        Config.paper().replace(particle_diameter="1.5 um")
    with pytest.raises(ValueError, match=r"particle_diameter .*out of range"):
        Config.default().replace(particle_diameter="2.5 um")


def test_solids_loading_reads_percent_and_derives_the_granular_density():
    c = Config.default().replace(solids_loading="3 %")
    assert c.solids_loading == pytest.approx(0.03) and c.granular_density == 0.0
    phi = (0.03 / 2200) / (0.03 / 2200 + 0.97 / 1000)
    assert c.grain_bulk_density == pytest.approx(phi * 2200, rel=1e-12)
    assert c.solid_volume_fraction == pytest.approx(phi, rel=1e-12)


def test_an_old_granular_density_sets_the_solids_loading_and_a_contradiction_is_refused():
    old = Config.default().replace(granular_density="30.5 kg/m^3")
    assert old.grain_bulk_density == 30.5
    assert old.solids_loading == pytest.approx(0.0300009, rel=1e-5)
    # a later solids_loading wins and the density is derived again
    assert old.replace(solids_loading="5 %").granular_density == 0.0
    # both at once: consistent is fine, contradictory names both
    assert Config.default().replace(granular_density=30.5, solids_loading=old.solids_loading).grain_bulk_density == 30.5
    with pytest.raises(ValueError, match=r"granular_density = 30.5 kg/m\^3 and solids_loading = 0.125 contradict"):
        Config.default().replace(granular_density=30.5, solids_loading="12.5 %")
    # a TOML round trip keeps the pair
    assert Config.from_mapping(old.to_sections()) == old


def test_the_viscosity_follows_the_loading_by_krieger_dougherty_unless_set():
    from cmpsim.physics.materials import krieger_dougherty

    c = Config.default()
    dense = c.replace(solids_loading="30 %")
    phi = dense.solid_volume_fraction
    assert dense.newtonian_viscosity == pytest.approx(c.carrier_viscosity * (1 - phi / 0.71) ** (-2.5 * 0.71), rel=1e-14)
    assert dense.newtonian_viscosity > c.newtonian_viscosity
    assert float(krieger_dougherty(1e-6, 1.0)) == pytest.approx(1 + 2.5e-6, rel=1e-9)  # Einstein's limit
    assert c.replace(slurry_viscosity="30 mPa*s", solids_loading="30 %").newtonian_viscosity == pytest.approx(0.03)


def test_the_paper_preset_holds_exactly_the_si_values_of_cmpsim_0_1():
    """No round-off from unit parsing: identical configs must compare (and cache) equal."""
    c = Config.paper()
    assert (c.pad_modulus, c.pad_hardness, c.asperity_radius, c.pad_roughness, c.reference_roughness) == (100e6, 9.4e6, 50e-6, 15e-6, 15e-6)
