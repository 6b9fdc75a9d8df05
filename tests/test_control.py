"""The rate estimators of a lot's run-to-run control and the incoming profiles (cmpsim.polisher.control, .incoming).
The double EWMA's drift, the zone feedback and the checkpoint are in tests/test_lot_control.py."""

import numpy as np
import pytest

from cmpsim.polisher.control import CONTROL, ESTIMATORS, DoubleEWMA, RateEstimator, SingleEWMA, feed_forward_time, make_estimator
from cmpsim.polisher.incoming import incoming_profiles
from cmpsim.polisher.zones import area_weights


def test_the_single_ewma_closes_on_a_step_change_of_the_rate_geometrically():
    """Eq. C1: after the rate jumps from r0 to r1 the estimate's error shrinks by (1 - lambda) per wafer."""
    est, true_rate, w = SingleEWMA(level=4e-9, weight=0.3), 3e-9, 0.3
    errors = []
    for _ in range(8):
        est = est.update(true_rate)
        errors.append(est.predict() - true_rate)
    np.testing.assert_allclose(np.array(errors[1:]) / np.array(errors[:-1]), 1 - w, rtol=1e-12)


def test_the_single_ewma_lags_a_linear_drift_by_delta_over_lambda():
    """The lag the double EWMA removes (Chen & Guo 2001): on r_k = r_0 + delta k the single EWMA's
    prediction for wafer k+1 settles at r_(k+1) - delta / lambda."""
    delta, est = -2e-11, SingleEWMA(level=5e-9, weight=0.3)
    for k in range(1, 200):
        est = est.update(5e-9 + delta * k)
    assert est.predict() - (5e-9 + delta * 200) == pytest.approx(-delta / 0.3, rel=1e-9)


def test_feed_forward_hits_the_target_when_the_rate_is_known():
    for incoming in (0.9e-6, 1.0e-6, 1.1e-6):
        time = feed_forward_time(5e-9, incoming, 0.5e-6)
        assert incoming - 5e-9 * time == pytest.approx(0.5e-6, rel=1e-12)
    assert feed_forward_time(5e-9, 0.4e-6, 0.5e-6) == 0.0  # already below target: no polish


def test_the_estimators_are_one_family_picked_by_name_in_one_place():
    assert CONTROL == ("none", "ewma", "single_ewma")
    for name, cls in ESTIMATORS.items():
        est = make_estimator(name, 4e-9)
        assert isinstance(est, cls) and isinstance(est, RateEstimator) and est.name == name
        assert type(est)(**est.to_dict()) == est  # a checkpoint's round trip
    assert isinstance(make_estimator("ewma", 4e-9), DoubleEWMA)  # the contract: --control ewma is the double EWMA


def test_the_controller_refuses_bad_settings():
    with pytest.raises(ValueError, match="weight"):
        make_estimator("ewma", 4e-9, weight=0.0)
    with pytest.raises(ValueError, match="drift_weight"):
        make_estimator("ewma", 4e-9, drift_weight=1.5)
    with pytest.raises(ValueError, match="clock"):
        make_estimator("ewma", 4e-9, clock="moon")
    with pytest.raises(ValueError, match="control must be one of"):
        make_estimator("pid", 4e-9)
    with pytest.raises(ValueError, match="rate"):
        feed_forward_time(0.0, 1e-6, 5e-7)
    with pytest.raises(ValueError, match="first rate estimate"):
        SingleEWMA(level=-1.0)


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
