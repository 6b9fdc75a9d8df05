"""The zone response of a membrane head: shares, gains and response widths (cmpsim.zone_response; issue 25)."""

import math

import numpy as np
import pytest

import cmpsim
from cmpsim.config import Config
from cmpsim.zone_response import boundary_widths, inside_share, local_gains, zone_response

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
    assert set(out) >= {"response", "zone_response_inside", "zone_response_gain", "zone_response_width", "units"}
    assert len(out["zone_response_width"]) == 1 and out["units"]["response"] == "m/s/Pa"
