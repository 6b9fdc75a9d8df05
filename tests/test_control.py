"""The run-to-run controller of a lot and the incoming profiles (cmpsim.polisher.control, .incoming)."""

import numpy as np
import pytest

from cmpsim.polisher.control import ControllerState, EWMAController, area_weights, feed_forward_time, update_rate, zone_correction
from cmpsim.polisher.incoming import incoming_profiles

PSI = 6894.757293168361


def test_the_ewma_estimate_closes_on_a_step_change_of_the_rate_geometrically():
    """After the rate jumps from r0 to r1 the estimate's error shrinks by (1 - lambda) per wafer."""
    state, true_rate, w = ControllerState(rate=4e-9, zone_pressures=(3 * PSI,)), 3e-9, 0.3
    errors = []
    for _ in range(8):
        time = feed_forward_time(state, 1.0e-6, 0.5e-6)
        state = update_rate(state, true_rate * time, time, w)
        errors.append(state.rate - true_rate)
    np.testing.assert_allclose(np.array(errors[1:]) / np.array(errors[:-1]), 1 - w, rtol=1e-12)


def test_feed_forward_hits_the_target_when_the_rate_is_known():
    state = ControllerState(rate=5e-9, zone_pressures=(2 * PSI,))
    for incoming in (0.9e-6, 1.0e-6, 1.1e-6):
        time = feed_forward_time(state, incoming, 0.5e-6)
        assert incoming - 5e-9 * time == pytest.approx(0.5e-6, rel=1e-12)
    assert feed_forward_time(state, 0.4e-6, 0.5e-6) == 0.0  # already below target: no polish


def test_the_zone_feedback_flattens_a_linear_plant():
    """On a plant whose rate is exactly linear in the zone pressures, repeated feedback removes the
    shape of the remaining thickness that the zones can reach (the mean is the polish time's job)."""
    r = np.linspace(0.0, 0.15, 61)
    centres = np.array([0.0, 0.05, 0.1, 0.14])
    response = np.exp(-(((r[:, None] - centres[None, :]) / 0.03) ** 2)) * 1e-13  # m/s/Pa, overlapping
    base = 4e-9 + response @ np.array([-0.1, 0.05, -0.35, 0.4]) * PSI  # the edge polishes fast: a shape the zones can undo at equal load
    controller = EWMAController(target=0.5e-6, zone_weight=1.0, regularisation=1e-6)
    state = ControllerState(rate=4e-9, zone_pressures=(3 * PSI,) * 4)
    time, w = 60.0, area_weights(r)
    spreads = []
    for _ in range(6):
        rate = base + response @ (np.array(state.zone_pressures) - 3 * PSI)
        final = 1e-6 - rate * time
        spreads.append(np.sqrt(np.sum(w * (final - np.sum(w * final)) ** 2)))
        state = zone_correction(controller, state, w, final, response, time)
    assert spreads[-1] < 1e-3 * spreads[0], spreads
    assert state.zone_pressures != (3 * PSI,) * 4  # the controller moved the zones
    assert sum(state.zone_pressures) == pytest.approx(4 * 3 * PSI, rel=1e-12)  # and kept the load (equal zone areas)


def test_the_controller_refuses_bad_settings():
    with pytest.raises(ValueError, match="weight"):
        EWMAController(target=5e-7, weight=0.0)
    with pytest.raises(ValueError, match="target"):
        EWMAController(target=-1e-9)
    with pytest.raises(ValueError, match="bounds"):
        EWMAController(target=5e-7, bounds=(3e4, 1e4))
    with pytest.raises(ValueError, match="rate"):
        feed_forward_time(ControllerState(rate=0.0, zone_pressures=()), 1e-6, 5e-7)


def test_incoming_profiles_are_reproducible_and_spread_as_asked():
    r = np.linspace(0.0, 0.15, 31)
    a = incoming_profiles(2000, r, 1e-6, seed=4)
    assert np.array_equal(a, incoming_profiles(2000, r, 1e-6, seed=4))
    assert not np.array_equal(a, incoming_profiles(2000, r, 1e-6, seed=5))
    means = a @ area_weights(r)
    assert np.std(means) / 1e-6 == pytest.approx(0.02, rel=0.1)
    assert np.mean(means) / 1e-6 == pytest.approx(1.0, abs=0.003)
    tilt = (a[:, -1] - a[:, 0]) / a.mean(axis=1)
    assert np.std(tilt) == pytest.approx(0.01, rel=0.1)
    with pytest.raises(ValueError, match="at least 1 wafer"):
        incoming_profiles(0, r, 1e-6)
