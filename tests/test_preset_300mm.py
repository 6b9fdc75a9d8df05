"""The 300mm preset: a production head and recipe (issue 25; docs/model.md 13f, 'The 300mm preset')."""

import numpy as np
import pytest
from click.testing import CliRunner

from cmpsim.cli import PRESET_NAMES, load_config, main
from cmpsim.inputs.config import PRESETS, Config, zone_mean_pressure

PSI = 6894.757293168361
# Measured on the preset (default grid; docs/model.md 13f/13g and docs/validation.md quote them): the
# non-uniformity with the preset's 3 mm edge exclusion, each zone's share of its response inside
# itself and its local gain, and the 10-90 % response width at the four inner boundaries (mm).
# Since issue 32 the preset's pad is grooved (3.05/0.51 mm); the smooth pad's numbers, before -> now:
# 0.03722 -> 0.00785; shares 0.307/0.495/0.331/0.221/0.074 -> 0.842/0.883/0.729/0.542/0.555; gains
# 0.205/0.063/-0.508/0.945/2.094 -> 0.883/0.846/0.783/0.595/0.789; widths 35.8/30.6/17.7/7.1 -> 25.1/22.7/16.2/7.3 mm
# (the smooth pad's are kept in tests/test_grooves.py, the mechanism of model 13f).
NONUNIFORMITY_3MM = 0.00785
INSIDE_SHARES = (0.842, 0.883, 0.729, 0.542, 0.555)
GAINS = (0.883, 0.846, 0.783, 0.595, 0.789)
WIDTHS_MM = (25.1, 22.7, 16.2, 7.3)
# the contrast gain (the zone's rate against the rest of the wafer), the load stiffness (Pa/m) and the
# wafer's bending length (mm) of the same response (docs/model.md 13g; smooth pad: 0.15/0.03/-0.05/0.19/0.37,
# 1.29e9 Pa/m, 8.07 mm)
CONTRASTS = (0.87, 0.80, 0.70, 0.50, 0.76)
LOAD_STIFFNESS = 1.63e9
BENDING_LENGTH_MM = 7.61
#: The smooth pad (the preset before issue 32), for the analyses of the ungrooved film (model 13f).
UNGROOVED = dict(pad_groove_pitch=0.0, pad_groove_width=0.0)


def test_the_300mm_preset_is_a_300mm_wafer_in_a_five_zone_membrane_head_with_a_ring_on_the_layered_stack():
    c = Config.preset("300mm")
    # the production pad is grooved: the common concentric groove of the patent claims (docs/model.md 13g)
    assert c.pad_groove_pitch == pytest.approx(3.05e-3) and c.pad_groove_width == pytest.approx(0.51e-3)
    assert Config.default().pad_groove_pitch == 0.0 and Config.preset("paper").pad_groove_pitch == 0.0
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


# ---- the preset solved (default grid: the layered pad finds no equilibrium on the coarse 300 mm grid; slow) ----


@pytest.fixture(scope="module")
def response():
    """The zone response of the preset at uniform zones; its base solve is the preset's equilibrium."""
    from cmpsim.head.zone_response import zone_response

    return zone_response(Config.preset("300mm"))


def _nonuniformity(profile, faces, edge_exclusion=3e-3):
    from cmpsim.results.uniformity import uniformity

    return uniformity(profile["rate"], 0.15, edge_exclusion, edges=faces)[0]


@pytest.mark.slow
def test_the_300mm_preset_makes_an_edge_band_inside_the_outer_10_mm(response):
    """The profile's steepest changes lie in the outer 10 mm, and the rate there leaves the level
    it has 10 mm inside the edge by more than the whole interior varies over any 10 mm (grooved:
    a 312 nm/min dip at 144 mm, a fast rim of 380 nm/min in the rim ring)."""
    r, rate = response.profile["radius"], response.profile["rate"]
    slope = np.abs(np.diff(rate) / np.diff(r))
    assert np.all(r[1:][slope > 0.5 * slope.max()] > 0.14)
    edge = r > 0.14
    level = np.interp(0.14, r, rate)
    band = np.abs(rate[edge] - level).max()
    inner = r <= 0.14
    interior = max(np.ptp(rate[inner & (r >= a) & (r <= a + 0.01)]) for a in np.arange(0.0, 0.13, 0.005))
    assert band > 1.5 * interior
    # the documented profile (docs/validation.md): the slow ring near 144 mm, the fast band 146-150 mm
    assert _nonuniformity(response.profile, response.ring_faces) == pytest.approx(NONUNIFORMITY_3MM, abs=5e-5)


@pytest.mark.slow
def test_each_zones_response_and_its_width_at_each_boundary_are_as_documented(response):
    """Not tuned: the numbers of docs/model.md 13g, computed here; issue 32's 'each zone moves the rate
    mostly inside itself' holds on the grooved preset for all five zones (the smooth pad's: none)."""
    assert response.inside == pytest.approx(INSIDE_SHARES, abs=0.01)
    assert min(response.inside) > 0.5
    assert response.gains == pytest.approx(GAINS, rel=0.02, abs=1e-3)
    widths = [b.width for b in response.boundaries]
    assert len(widths) == 4
    assert [None if w is None else round(1e3 * w, 1) for w in widths] == pytest.approx(WIDTHS_MM, abs=0.2)


@pytest.mark.slow
def test_the_contrast_gains_and_the_bending_length_of_the_preset_are_as_documented(response):
    assert response.contrast == pytest.approx(CONTRASTS, abs=0.0051)
    assert response.load_stiffness == pytest.approx(LOAD_STIFFNESS, rel=5e-3)
    assert 1e3 * response.bending_length == pytest.approx(BENDING_LENGTH_MM, abs=0.0051)


@pytest.mark.slow
def test_without_the_slurrys_hydrodynamic_stiffness_the_preset_zones_steer_their_own_rate():
    """docs/model.md 13f: the smooth-pad preset with the slurry 5000 times thinner; the plate's step on its bed."""
    from cmpsim.head.zone_response import zone_response

    thin = zone_response(Config.preset("300mm").replace(slurry_viscosity=1e-6, **UNGROOVED))
    assert [1e3 * b.width for b in thin.boundaries] == pytest.approx([24.5, 22.1, 16.0, 7.2], abs=0.051)
    assert thin.inside == pytest.approx([0.84, 0.89, 0.74, 0.55, 0.54], abs=0.0051)
    assert thin.gains == pytest.approx([0.89, 0.85, 0.8, 0.6, 0.65], abs=0.0051)
    # the response starts 11-13 mm inside the inner three boundaries (Lee, Lee & Jeong: 10-15 mm)
    assert [1e3 * (b.boundary - b.start) for b in thin.boundaries[:3]] == pytest.approx([13, 13, 11], abs=0.51)


@pytest.fixture(scope="module")
def tuned():
    """``cmpsim tune-zones --preset 300mm --ring``: the zones and the retaining ring tuned together at the kept
    mean removal rate, the default with the ring (issue 32)."""
    import cmpsim

    return cmpsim.tune_zones(Config.preset("300mm"), ring=True)


# Measured (docs/model.md 13f, "Tuning the 300mm preset"): 0.785 % -> 0.3457 % in 24 solves at the kept rate
# (321.71 -> 321.71 nm/min inside the edge exclusion), zones 2.995/2.996/2.988/2.989/3.187 psi, ring 2.968 psi
# (inside its 1.5-9 psi bounds). Converged: 12 steps at rtol 1e-6 end at 0.3457 % too, the bounded least-squares
# optimum of the last linearisation with the rate as an equality is 0.3453 %, and keeping the load instead gives
# 0.3458 %. The residual lies outside 139 mm (93 % of the variance; 67 % in 145-147 mm, the inner flank of the fast
# rim), where no zone's response bends fast enough and the ring's response inside 147 mm is weak (<= 6 nm/min/psi).
TUNED_NONUNIFORMITY = 0.003457
#: Without a kept rate (``keep="none"``, flatness alone) the tuner lowers the load fourfold to get 0.195 %.
UNKEPT_NONUNIFORMITY = 0.00195


@pytest.mark.slow
def test_tune_zones_with_the_ring_keeps_the_rate_flattens_and_reproduces(tuned):
    """At the kept rate the ring tuning more than halves the non-uniformity (0.785 % -> 0.346 %), keeps the mean
    removal rate to 0.1 %, keeps the ring inside its bounds; a cold solve at the returned pressures gives the
    reported non-uniformity back to 1e-6."""
    import cmpsim
    from cmpsim.head.tuning import RATE_TOLERANCE

    before = tuned.before["within_wafer_nonuniformity"]
    assert before == pytest.approx(NONUNIFORMITY_3MM, abs=5e-5)
    assert tuned.keep == "rate"
    assert tuned.mean_rate == pytest.approx(tuned.before["mean_rate"], rel=RATE_TOLERANCE)
    assert tuned.within_wafer_nonuniformity <= before and tuned.within_wafer_nonuniformity < 0.01  # below 1 %: met
    assert tuned.within_wafer_nonuniformity == pytest.approx(TUNED_NONUNIFORMITY, abs=1e-4)
    assert tuned.before["ring_pressure"] == pytest.approx(3 * PSI)
    assert 1.5 * PSI <= tuned.ring_pressure <= 9 * PSI and tuned.config.retaining_ring_pressure == tuned.ring_pressure
    assert all(0.5 * PSI <= p <= 8 * PSI for p in tuned.zone_pressures)
    again = cmpsim.solve(tuned.config, relative=False)
    assert again.scalars["within_wafer_nonuniformity"] == pytest.approx(tuned.within_wafer_nonuniformity, abs=1e-6, rel=0)
    assert again.config.zone_pressure_values == pytest.approx(tuned.zone_pressures, rel=1e-12)


@pytest.mark.slow
@pytest.mark.xfail(
    strict=True,
    reason="measured: at the kept rate the zones and the ring reach 0.346 % (converged; keeping the load: 0.346 %), "
    "above a third of 0.785 % (0.262 %); the residual is the 139-147 mm band, the inner flank of the fast rim, which "
    "no zone response bends fast enough to follow and the ring barely reaches inside the 3 mm edge exclusion "
    "(docs/model.md 13f). Below 1 % it is.",
)
def test_issue_32_criterion_at_the_kept_rate_below_a_third_and_below_1_percent(tuned):
    before = tuned.before["within_wafer_nonuniformity"]
    assert tuned.within_wafer_nonuniformity < 0.01
    assert tuned.within_wafer_nonuniformity < before / 3.0


@pytest.mark.slow
def test_flatness_alone_reaches_a_third_only_by_quartering_the_rate():
    """``keep="none"`` (``--keep none``), kept available, not the path that claims the criterion: 0.195 % at a
    mean rate of 77 against 322 nm/min (every zone lowered to about 0.7 psi, the ring to its 1.5 psi bound)."""
    import cmpsim

    free = cmpsim.tune_zones(Config.preset("300mm"), ring=True, keep="none")
    assert free.within_wafer_nonuniformity == pytest.approx(UNKEPT_NONUNIFORMITY, abs=1e-4)
    assert free.mean_rate < 0.3 * free.before["mean_rate"]


@pytest.mark.slow
def test_the_tuned_json_reports_the_ring_pressure_and_the_zone_response(tuned):
    data = tuned.to_dict()
    assert data["ring_pressure"] == tuned.ring_pressure and data["units"]["ring_pressure"] == "Pa"
    assert data["before"]["ring_pressure"] == pytest.approx(3 * PSI)
    assert len(data["zone_pressures"]) == 5 and tuned.response.shape == (len(tuned.profile["radius"]), 5)
    # the ring's response lies in the edge band: most of it in the outer 10 mm
    r, area = tuned.profile["radius"], np.diff(tuned.ring_faces**2)
    weight = np.abs(tuned.ring_response) * area
    assert weight[r > 0.14].sum() > 0.5 * weight.sum()
    # the zone response at the tuned pressures, as the zone response reports it (docs/model.md 13g)
    assert len(data["zone_response_inside"]) == 5 and len(data["zone_response_width"]) == 4
    assert data["zone_response_inside"][:4] == pytest.approx([0.83, 0.87, 0.72, 0.54], abs=0.02)
