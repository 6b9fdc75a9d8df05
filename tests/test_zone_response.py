"""The zone response of a membrane head: shares, gains and response widths (cmpsim.head.zone_response; issue 25)."""

import math

import numpy as np
import pytest

import cmpsim
from cmpsim.inputs.config import Config
from cmpsim.numerics.grid import PolarGrid
from cmpsim.numerics.plate import KirchhoffPlate, PlateOperator, zone_load
from cmpsim.testing.plates import hetenyi_step_width, winkler_step_load
from cmpsim.results.uniformity import ring_mean
from cmpsim.head.zone_response import ZoneSolver, boundary_widths, contrast_gains, inside_share, local_gains, zone_response

RADII = (0.05, 0.10, 0.13, 0.145, 0.15)  # the five zones of the 300mm preset, m
FACES = np.linspace(0.0, 0.15, 3001)  # 0.05 mm rings
CENTRES = 0.5 * (FACES[1:] + FACES[:-1])


def _logistic(x):
    return 1.0 / (1.0 + np.exp(x))


def _smeared_response(scale):
    """J_k(r) = L((r - R_k)/s) - L((r - R_{k-1})/s): zone k's ideal step smeared by a logistic of scale s (m)."""
    edges = (0.0,) + RADII
    return np.stack([_logistic((CENTRES - b) / scale) - _logistic((CENTRES - a) / scale) for a, b in zip(edges[:-1], edges[1:])], axis=1)


def test_an_ideal_head_has_a_step_response_no_wider_than_a_ring():
    edges = (0.0,) + RADII
    J = np.stack([((CENTRES >= a) & (CENTRES < b)).astype(float) for a, b in zip(edges[:-1], edges[1:])], axis=1)
    for b in boundary_widths(J, CENTRES, FACES, RADII):
        assert b.width <= b.ring_width + 1e-15
        assert abs(b.centre - b.boundary) <= b.ring_width
    assert inside_share(J, CENTRES, FACES, RADII) == pytest.approx((1.0,) * 5)


@pytest.mark.parametrize("scale", [0.5e-3, 2e-3])
def test_a_logistic_smear_has_its_closed_form_10_90_width(scale):
    """A step smeared as 1/(1 + exp((r - R_b)/s)) falls from 0.9 to 0.1 over 2 s ln 9, where both
    zone middles lie five scales or more from the boundary (the levels are then the plateaus)."""
    widths = boundary_widths(_smeared_response(scale), CENTRES, FACES, RADII)
    assert len(widths) == 4
    edges = (0.0,) + RADII
    for k, b in enumerate(widths):
        assert b.start < b.boundary < b.end
        room = min(b.boundary - 0.5 * (edges[k] + edges[k + 1]), 0.5 * (edges[k + 1] + edges[k + 2]) - b.boundary)
        if room >= 5 * scale:
            assert b.centre == pytest.approx(b.boundary, abs=0.05e-3)
            assert b.width == pytest.approx(2.0 * scale * math.log(9.0), rel=2e-2)
        else:  # the fall is measured between the zone middles: a narrow zone bounds the width
            window = 0.5 * (edges[k + 2] - edges[k])  # between the two zone middles
            assert b.width < window and abs(b.centre - b.boundary) < window


def test_a_boundary_across_which_the_response_does_not_fall_has_no_width():
    J = np.ones((CENTRES.size, len(RADII)))  # every zone moves the wafer as a whole
    widths = boundary_widths(J, CENTRES, FACES, RADII)
    assert all(b.width is None and b.start is None for b in widths)
    assert [b.to_dict()["width"] for b in widths] == [None] * 4
    area = np.diff(np.square((0.0,) + RADII)) / 0.15**2
    assert inside_share(J, CENTRES, FACES, RADII) == pytest.approx(tuple(area), abs=2e-3)  # the zones' area shares


def test_a_zone_whose_rate_follows_its_pressure_like_preston_has_gain_one():
    edges = (0.0,) + RADII
    pressures = (2e4, 2.1e4, 2.2e4, 2.3e4, 2.4e4)
    rate = 1e-9 * (1.0 + CENTRES / 0.15)
    J = np.stack([np.where((CENTRES >= a) & (CENTRES < b), rate / p, 0.0) for a, b, p in zip(edges[:-1], edges[1:], pressures)], axis=1)
    assert local_gains(J, rate, FACES, CENTRES, RADII, pressures) == pytest.approx((1.0,) * 5, rel=1e-12)


def test_zone_response_refuses_a_rigid_head_and_a_bad_step():
    with pytest.raises(ValueError, match="zone_response needs carrier = 'membrane'"):
        zone_response(Config.default())
    with pytest.raises(ValueError, match=r"step must be a relative pressure step in \(0, 0.5\]"):
        zone_response(Config.default().replace(carrier="membrane", zone_radii="20,38.1 mm"), step=0.0)


def test_the_measured_response_matches_a_finite_difference_of_two_solves():
    """zone_response's column k is (RR(P + dP_k) - RR(P)) / dP_k of two solves (3-inch default, coarse grid)."""
    head = Config.default().replace(carrier="membrane", zone_radii="20,38.1 mm", grid="coarse")
    resp = zone_response(head, step=0.05)
    assert resp.solves == 3 and resp.response.shape == (len(resp.profile["radius"]), 2)
    p = np.array(head.zone_pressure_values)
    raised = cmpsim.solve(head.replace(zone_pressures=tuple(p * np.array([1.05, 1.0]))), relative=False)
    fd = (np.asarray(raised.profiles["removal_rate_profile"]) - resp.profile["rate"]) / (0.05 * p[0])
    assert resp.response[:, 0] == pytest.approx(fd, rel=1e-4, abs=1e-6 * np.abs(fd).max())
    out = resp.to_dict()
    assert set(out) >= {"response", "zone_response_inside", "zone_response_gain", "zone_response_width", "zone_response_contrast", "load_stiffness", "bending_length", "units"}
    assert out["load_stiffness"] > 0 and out["bending_length"] == pytest.approx((resp.bending_stiffness / out["load_stiffness"]) ** 0.25)
    assert out["units"]["load_stiffness"] == "Pa/m" and out["units"]["bending_length"] == "m"
    assert len(out["zone_response_width"]) == 1 and out["units"]["response"] == "m/s/Pa"


def test_a_single_zone_has_no_contrast_and_says_so_in_json():
    rate = 1e-9 * np.ones_like(CENTRES)
    assert math.isnan(contrast_gains(np.ones((CENTRES.size, 1)), rate, FACES, CENTRES, (0.15,), (2e4,))[0])
    resp = zone_response(Config.default().replace(carrier="membrane", grid="coarse"))
    assert resp.to_dict()["zone_response_contrast"] == [None]


def test_the_contrast_gain_ignores_a_change_common_to_the_wafer_and_equals_the_local_gain_of_a_local_zone():
    edges = (0.0,) + RADII
    pressures = (2e4, 2.1e4, 2.2e4, 2.3e4, 2.4e4)
    rate = 1e-9 * (1.0 + CENTRES / 0.15)
    common = np.stack([0.3 * rate / p for p in pressures], axis=1)  # every ring +0.3 x the zone's relative step
    assert contrast_gains(common, rate, FACES, CENTRES, RADII, pressures) == pytest.approx((0.0,) * 5, abs=1e-12)
    assert local_gains(common, rate, FACES, CENTRES, RADII, pressures) == pytest.approx((0.3,) * 5, rel=1e-12)
    local = np.stack([np.where((CENTRES >= a) & (CENTRES < b), rate / p, 0.0) for a, b, p in zip(edges[:-1], edges[1:], pressures)], axis=1)
    assert contrast_gains(local, rate, FACES, CENTRES, RADII, pressures) == pytest.approx(local_gains(local, rate, FACES, CENTRES, RADII, pressures), rel=1e-12)
    assert contrast_gains(local + common, rate, FACES, CENTRES, RADII, pressures) == pytest.approx((1.0,) * 5, rel=1e-12)


# ---- the plate's smoothing: Hetenyi's step on a Winkler bed (docs/model.md 13f, 'Why the zones spread') ----

SILICON_300 = KirchhoffPlate(775e-6, 130e9, 0.28)  # SEMI M1 thickness; Hopcroft, Nix & Kenny (2010)


def test_the_step_load_closed_form_carries_its_load_and_tends_to_hetenyis_beam_far_from_centre_and_edge():
    d, nu, k, a, b = SILICON_300.bending_stiffness, 0.28, 1.6e9, 0.15, 0.075
    # the free plate on the bed carries exactly the load q pi b^2 (Gauss-Legendre on each smooth piece)
    x, wts = np.polynomial.legendre.leggauss(60)
    load = 0.0
    for lo, hi in ((0.0, b), (b, a)):
        r = 0.5 * (hi - lo) * x + 0.5 * (hi + lo)
        load += 0.5 * (hi - lo) * np.sum(wts * k * winkler_step_load(r, b, 1e3, a, d, nu, k) * 2 * np.pi * r)
    assert load == pytest.approx(1e3 * np.pi * b * b, rel=1e-9)
    assert winkler_step_load(np.linspace(0, a, 5), a, 1e3, a, d, nu, k) == pytest.approx(np.full(5, 1e3 / k), rel=1e-15)
    # a stiff bed (ell = 1.3 mm << b, a - b): the fall is Hetenyi's, 1 - exp(-y) cos(y) / 2
    stiff = 1e11
    r = np.linspace(b - 0.01, b + 0.01, 401)
    s = winkler_step_load(r, b, 1.0, a, d, nu, stiff) * stiff
    width = np.interp(0.1, s[::-1], r[::-1]) - np.interp(0.9, s[::-1], r[::-1])
    assert width == pytest.approx(hetenyi_step_width(d, stiff), rel=1e-3)
    assert hetenyi_step_width(d, stiff) == pytest.approx(2.0 * 0.997576 * (4 * d / stiff) ** 0.25, rel=1e-5)


def test_the_plate_under_a_zone_step_on_a_winkler_bed_converges_to_the_closed_form_at_second_order():
    """The reference against cmpsim.numerics.plate (an independent discretisation): a boundary inside a cell."""
    k, a, b = 1.6e9, 0.15, 0.0731
    errors = []
    for n_r in (15, 30, 60, 120):
        g = PolarGrid(a, n_r, 8)
        w = PlateOperator(SILICON_300, g, k).deflection(zone_load(g, (b, a), (1e3, 0.0)))
        ref = winkler_step_load(g.r[:, 0], b, 1e3, a, SILICON_300.bending_stiffness, SILICON_300.poisson, k)
        errors.append(np.max(np.abs(w[:, 0] - ref)) / np.max(np.abs(ref)))
    assert errors[-1] < 5e-4
    assert np.all(np.log2(np.asarray(errors[:-1]) / errors[1:]) > 1.9), errors


#: The smooth pad: the analysis below is of the ungrooved, fully flooded film (docs/model.md 13f); the
#: 300mm preset's pad is grooved since issue 32, and its grooves vent what is measured here (model 13g).
UNGROOVED = dict(pad_groove_pitch=0.0, pad_groove_width=0.0)


def _winkler_head(**changes):
    """The 300mm preset's head on the smooth Winkler pad (no ring: it cannot act there; no grooves: see UNGROOVED)."""
    return Config.preset("300mm").replace(pad_compliance="winkler", retaining_ring_pressure=0.0, **UNGROOVED, **changes)


def _closed_form_response(resp, poisson=0.28):
    """The zones' pressure responses k w / q of the plate on the bed k of the solve (closed form), at its ring centres."""
    r, a = resp.profile["radius"], resp.zone_radii[-1]
    steps = [np.zeros_like(r)] + [resp.load_stiffness * winkler_step_load(r, b, 1.0, a, resp.bending_stiffness, poisson, resp.load_stiffness) for b in resp.zone_radii]
    return np.stack([hi - lo for lo, hi in zip(steps[:-1], steps[1:])], axis=1)


def test_without_the_slurrys_hydrodynamic_stiffness_the_zone_response_is_the_plates_step_on_its_bed():
    """At 1e-6 Pa s (5000 times thinner than the default slurry) the film carries 1e-7 of the load and the
    zone response is the plate on the Winkler bed of the pad and the asperity contact in series: shares,
    widths and response shapes equal the closed form (Hetenyi's step on the plate) to the grid's error,
    which falls as the rings are refined."""
    errors = []
    for grid in ("30x16", "60x16"):
        resp = zone_response(_winkler_head(slurry_viscosity=1e-6, grid=grid))
        exact = _closed_form_response(resp)
        r, faces = resp.profile["radius"], resp.ring_faces
        shape = resp.response / resp.response[0, 0] * exact[0, 0]  # the rate follows p_c with one elasticity
        errors.append(np.abs(shape - exact).max())
    assert errors[1] < 1e-2 and errors[0] > 2.0 * errors[1], errors
    assert resp.inside == pytest.approx(inside_share(exact, r, faces, resp.zone_radii), abs=5e-3)
    solved = [b.width for b in resp.boundaries]
    closed = [b.width for b in boundary_widths(exact, r, faces, resp.zone_radii)]
    assert solved == pytest.approx(closed, abs=0.3e-3)
    # the bed: the pad's Winkler stiffness and the summits' -dp_c/dh in series; ell = 7.6 mm
    assert resp.bending_length == pytest.approx((resp.bending_stiffness / resp.load_stiffness) ** 0.25)
    assert resp.bending_length == pytest.approx(7.64e-3, rel=2e-3)
    assert hetenyi_step_width(resp.bending_stiffness, resp.load_stiffness) == pytest.approx(21.6e-3, rel=2e-3)
    # the inner two boundaries (zones 30-50 mm wide) keep most of their response; the 5 mm rim zone cannot
    assert resp.inside[:3] > (0.7, 0.7, 0.7) and resp.inside[4] < 0.5


@pytest.fixture(scope="module")
def winkler_head_zone_3():
    """The default slurry on the Winkler head: the base and zone 3 (100-130 mm) raised by 2 %."""
    head = _winkler_head()
    run = ZoneSolver(head)
    p = np.array(head.zone_pressure_values)
    base = run(p)
    run.adopt(base)
    raised = p.copy()
    raised[2] *= 1.02
    return base, run(raised), raised[2] - p[2]


def test_the_default_slurry_takes_a_zones_extra_load_and_the_contact_falls_everywhere(winkler_head_zone_3):
    """Why zone 3's local gain is negative (docs/model.md 13f): the 8.8 um Newtonian film resists any
    change of its shape along the sliding direction far more stiffly than the summits resist a change of
    its thickness, so the pad's surface follows the bent wafer, the film's thickness moves nearly
    uniformly and the slurry carries the zone's extra load; the contact, and the abrasive removal,
    change by one level over the wafer, set where the slurry pressure is ambient (the rim)."""
    base, up, dp = winkler_head_zone_3
    b, u = base.solution.state, up.solution.state
    r = np.asarray(base.profiles["radius"])
    zone = (r >= 0.10) & (r < 0.13)
    fluid = ring_mean(u.p_fluid - b.p_fluid) / dp
    contact = ring_mean(u.p_contact - b.p_contact) / dp
    film = ring_mean(u.h - b.h) / dp
    pad = ring_mean(u.deflection - b.deflection) / dp
    area = np.diff(np.asarray(base.grid.ring_faces) ** 2)[zone]
    total = ring_mean(u.p_total - b.p_total) / dp
    assert np.sum(area * fluid[zone]) > np.sum(area * total[zone]) > 0.8 * np.sum(area)  # the slurry takes more than all of it
    assert contact.max() < -0.1 and contact.min() > -0.2  # the contact falls on every ring, by 10-20 %
    assert film.min() > 0 and film.max() < 2 * film.min()  # the film thickens nearly uniformly
    assert np.sum(area * pad[zone]) > 20 * film.max() * np.sum(area)  # the pad's surface follows the wafer's bending
    rate = np.asarray(base.profiles["removal_rate_profile"])
    change = np.asarray(up.profiles["removal_rate_profile"]) / rate - 1
    assert np.all(change < 0)  # the abrasive removal follows the contact: down everywhere
    # the level: where the slurry pressure is ambient (the rim) the contact takes the whole change of the
    # total pressure, which is the plate's on the bed of the pad alone (the film, held uniform, bypasses
    # the summits): Hetenyi's negative lobe 20 mm outside zone 3's boundary at 130 mm
    d, k_pad = base.problem.carrier.plate.bending_stiffness, base.problem.foundation.stiffness
    rim = k_pad * (winkler_step_load(r[-1:], 0.13, 1.0, 0.15, d, 0.28, k_pad) - winkler_step_load(r[-1:], 0.10, 1.0, 0.15, d, 0.28, k_pad))[0]
    assert rim < -0.1
    assert contact[-1] == pytest.approx(rim, abs=0.004) and (ring_mean(u.p_total - b.p_total) / dp)[-1] == pytest.approx(rim, abs=0.004)
    relative_contact = ring_mean(u.p_contact - b.p_contact) / ring_mean(b.p_contact)
    assert change == pytest.approx(relative_contact, rel=0.05)  # the rate's elasticity to the contact is about 1


def test_the_zone_response_is_linear_over_the_finite_difference_steps():
    """The response is far above the bending's tolerance: 0.1 %, 2 % and 3 % steps give the same gains."""
    head = _winkler_head()
    gains = [zone_response(head, step=s).gains for s in (1e-3, 2e-2, 3e-2)]
    assert gains[0] == pytest.approx(gains[1], abs=2e-3)
    assert gains[2] == pytest.approx(gains[1], abs=2e-3)
    assert gains[1][2] < 0 < gains[1][4]


def test_with_a_thin_slurry_the_zones_steer_their_own_rate():
    """The same head with the slurry's viscosity 5000 times lower: every local gain is positive, and the
    wide zones move their own rate like Preston's law, up to the share the plate spreads to neighbours."""
    default, thin = zone_response(_winkler_head()), zone_response(_winkler_head(slurry_viscosity=1e-6))
    assert min(thin.gains) > 0.5 and thin.gains[2] > 0.7
    assert default.gains[2] < 0 and max(default.contrast) < 0.2
    assert min(thin.contrast) > 0.5
    assert default.load_stiffness == pytest.approx(thin.load_stiffness, rel=1e-3)  # the film adds no stiffness to a uniform approach


def test_the_numbers_of_the_model_document_on_the_winkler_head():
    """docs/model.md 13f ('Why the zones spread', 'Why zone 3 moves its rate the wrong way'), computed."""
    thin, default = zone_response(_winkler_head(slurry_viscosity=1e-6)), zone_response(_winkler_head())
    assert [1e3 * b.width for b in thin.boundaries] == pytest.approx([24.6, 22.3, 16.1, 7.8], abs=0.051)
    assert thin.inside == pytest.approx([0.84, 0.88, 0.74, 0.57, 0.45], abs=0.0051)
    assert thin.contrast == pytest.approx([0.87, 0.81, 0.71, 0.52, 0.57], abs=0.0051)
    assert default.contrast == pytest.approx([0.13, 0.05, 0.03, 0.06, 0.07], abs=0.0051)
    assert default.load_stiffness == pytest.approx(1.605e9, abs=0.51e6) and 1e3 * default.bending_length == pytest.approx(7.64, abs=0.0051)
    # the closed form on 0.5 mm rings
    faces = np.linspace(0.0, 0.15, 301)
    centres = 0.5 * (faces[1:] + faces[:-1])
    d, k = default.bending_stiffness, default.load_stiffness
    steps = [np.zeros_like(centres)] + [k * winkler_step_load(centres, b, 1.0, 0.15, d, 0.28, k) for b in RADII]
    exact = np.stack([hi - lo for lo, hi in zip(steps[:-1], steps[1:])], axis=1)
    assert [1e3 * b.width for b in boundary_widths(exact, centres, faces, RADII)] == pytest.approx([24.4, 22.3, 16.1, 7.8], abs=0.051)
    assert inside_share(exact, centres, faces, RADII) == pytest.approx([0.85, 0.85, 0.75, 0.59, 0.48], abs=0.0051)
    # the rim's contact change per zone, and the plate's on the pad's bed there
    head = _winkler_head()
    run = ZoneSolver(head)
    p = np.array(head.zone_pressure_values)
    base = run(p)
    run.adopt(base)
    k_pad, rim = base.problem.foundation.stiffness, np.asarray(base.profiles["radius"])[-1:]
    solved, plate = [], []
    for zone, (lo, hi) in enumerate(zip((0.0,) + RADII[:-1], RADII)):
        raised = p.copy()
        raised[zone] *= 1.02
        up = run(raised)
        solved.append(ring_mean(up.solution.state.p_contact - base.solution.state.p_contact)[-1] / (raised[zone] - p[zone]))
        plate.append(k_pad * (winkler_step_load(rim, hi, 1.0, 0.15, d, 0.28, k_pad) - winkler_step_load(rim, lo, 1.0, 0.15, d, 0.28, k_pad))[0])
    assert solved == pytest.approx([0.0, 0.006, -0.18, 0.434, 0.739], abs=0.00051)
    assert plate == pytest.approx([0.0, 0.007, -0.18, 0.438, 0.735], abs=0.00051)


def test_the_three_inch_default_head_behaves_alike():
    """docs/model.md 13f: four zones at 3 in; the inner zones hardly move their rate and the rim zone moves
    the wafer's level with the default slurry, every zone steers its own rate without its hydrodynamic stiffness."""
    head = Config.default().replace(carrier="membrane", zone_radii="10,20,30,38.1 mm")
    default, thin = zone_response(head), zone_response(head.replace(slurry_viscosity=1e-6))
    assert default.gains == pytest.approx([0.04, 0.0, 0.01, 1.09], abs=0.0051)
    assert thin.gains == pytest.approx([0.65, 0.6, 0.63, 0.86], abs=0.0051)
    assert 1e3 * default.bending_length == pytest.approx(4.5, abs=0.051)


def test_the_zones_turn_local_as_the_slurrys_hydrodynamic_stiffness_falls_below_the_summits():
    """docs/model.md 13f ('The crossover, measured', its table): the slurry's viscosity swept on the Winkler
    head; its film stiffness 6 eta U lambda / h^3 meets the summits' near eta* = 7e-5 Pa s."""
    rows = {"gain": [], "contrast": [], "inside": [], "width": []}
    for eta in (5e-3, 1e-3, 3e-4, 1e-4, 3e-5, 1e-5, 1e-6):
        resp = zone_response(_winkler_head(slurry_viscosity=eta))
        rows["gain"].append(resp.gains[2])
        rows["contrast"].append(resp.contrast[2])
        rows["inside"].append(resp.inside[0])
        rows["width"].append(1e3 * resp.boundaries[0].width)
    assert rows["gain"] == pytest.approx([-0.13, -0.09, 0.04, 0.35, 0.72, 0.79, 0.80], abs=0.0051)
    assert rows["contrast"] == pytest.approx([0.03, 0.04, 0.11, 0.32, 0.60, 0.69, 0.71], abs=0.0051)
    assert rows["inside"] == pytest.approx([0.29, 0.30, 0.36, 0.63, 0.77, 0.81, 0.84], abs=0.0051)
    assert rows["width"] == pytest.approx([35.4, 28.0, 12.0, 13.2, 19.8, 23.8, 24.6], abs=0.051)
