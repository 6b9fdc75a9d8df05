"""Pad life (issue 32): the glazing front's closed forms, exact wear-conditioning kinetics, limits, calibration and validation."""

from __future__ import annotations

import math

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st
from scipy.integrate import quad
from scipy.stats import norm

from cmpsim.physics import padlife as pl

J = pl.JEONG_2024
P, U = J["pressure"], J["sliding_speed"]


def at(t, conditioning="none", state=None):
    return pl.summit_constants(pl.advance_pad_life(state or pl.PadLifeState(), P, U, t, conditioning))


@pytest.mark.parametrize("zeta", [-2.0, -0.3, 0.0, 1.1, 2.5, 2.99])
def test_cap_volume_and_flat_area_closed_forms_match_quadrature(zeta):
    c = 3.0
    j2 = quad(lambda x: (x - zeta) ** 2 * norm.pdf(x), zeta, c, epsabs=1e-14, epsrel=1e-12)[0] / norm.cdf(c)
    j1 = quad(lambda x: (x - zeta) * norm.pdf(x), zeta, c, epsabs=1e-14, epsrel=1e-12)[0] / norm.cdf(c)
    assert pl.cap_volume(zeta, c) == pytest.approx(j2, rel=1e-9, abs=1e-15)
    assert pl.flat_area(zeta, c) == pytest.approx(j1, rel=1e-9, abs=1e-15)
    # dJ2/dzeta = -2 J1 (the front moves at dW/dt / (2 eta pi R sigma^2 J1))
    h = 1e-6
    assert (pl.cap_volume(zeta + h, c) - pl.cap_volume(zeta - h, c)) / (2 * h) == pytest.approx(-2 * j1, rel=1e-5, abs=1e-9)


def test_worn_moments_match_a_direct_evaluation():
    c, zf = 3.0, 0.4
    nc = norm.cdf(c)
    atom = (nc - norm.cdf(zf)) / nc
    m1 = quad(lambda x: x * norm.pdf(x), -40, zf)[0] / nc + atom * zf
    m2 = quad(lambda x: x * x * norm.pdf(x), -40, zf)[0] / nc + atom * zf**2
    mean, std = pl.worn_moments(zf, c)
    assert mean == pytest.approx(m1, rel=1e-10)
    assert std == pytest.approx(math.sqrt(m2 - m1**2), rel=1e-10)
    # fresh: the truncated normal's std (0.99331 for c = 3)
    assert pl.worn_moments(c, c)[1] == pytest.approx(0.99331, abs=1e-5)


def test_front_height_inverts_the_worn_volume():
    pad = pl.DEFAULT_PAD
    z = np.array([2.9, 1.5, 0.0, -1.0, -2.5])
    w = pad.volume_scale * pl.cap_volume(z, pad.cutoff)
    np.testing.assert_allclose(pl.front_height(w, pad), z, atol=1e-12)
    assert pl.front_height(0.0, pad) == pad.cutoff


def test_fresh_pad_is_unchanged_and_zero_speed_does_not_wear():
    c = pl.summit_constants(pl.PadLifeState())
    for name in ("sigma", "density", "radius", "rate_factor"):
        assert getattr(c, name) == pytest.approx(1.0, abs=1e-15)
    assert c.glazed_area == 0 and c.glazed_summits == 0
    s = pl.advance_pad_life(pl.PadLifeState(), P, 0.0, 600.0)
    assert s.worn_volume == 0.0
    s = pl.advance_pad_life(pl.PadLifeState(), 0.0, U, 600.0, "in_situ")
    assert s.worn_volume == 0.0


def test_advance_is_exact_over_substeps():
    one = pl.advance_pad_life(pl.PadLifeState(), P, U, 600.0, "in_situ")
    many = pl.PadLifeState()
    for _ in range(100):
        many = pl.advance_pad_life(many, P, U, 6.0, "in_situ")
    assert many.worn_volume == pytest.approx(float(one.worn_volume), rel=1e-12)
    assert many.polish_time == pytest.approx(600.0)


def test_without_conditioning_the_worn_volume_is_archard():
    s = pl.advance_pad_life(pl.PadLifeState(), P, U, 600.0)
    assert s.worn_volume == pytest.approx(pl.DEFAULT_PAD.wear_coefficient * P * U * 600.0, rel=1e-15)


def test_in_situ_conditioning_reaches_the_steady_wear_balance():
    r = pl.renewal_rate("in_situ")
    s = pl.advance_pad_life(pl.PadLifeState(), P, U, 50.0 / r, "in_situ")
    assert s.worn_volume == pytest.approx(pl.DEFAULT_PAD.wear_coefficient * P * U / r, rel=1e-15)
    # a glazed pad recovers towards the same balance
    glazed = pl.advance_pad_life(pl.PadLifeState(), P, U, 3600.0)
    rec = pl.advance_pad_life(glazed, P, U, 50.0 / r, "in_situ")
    assert rec.worn_volume == pytest.approx(float(s.worn_volume), rel=1e-12)


def test_ex_situ_conditioning_renews_between_wafers_only():
    worn = pl.advance_pad_life(pl.PadLifeState(), P, U, 600.0, "ex_situ")
    assert worn.worn_volume == pytest.approx(float(pl.advance_pad_life(pl.PadLifeState(), P, U, 600.0).worn_volume))
    cond = pl.condition_ex_situ(worn, J["conditioning_time"])
    assert cond.worn_volume == pytest.approx(0.05 * float(worn.worn_volume), rel=1e-12)  # the calibration target
    with pytest.raises(ValueError):
        pl.renewal_rate("sometimes")


@settings(max_examples=40, deadline=None)
@given(t1=st.floats(0.0, 7200.0), t2=st.floats(0.0, 7200.0))
def test_glazing_is_monotone_in_polish_time(t1, t2):
    a, b = sorted((t1, t2))
    ca, cb = at(a), at(b)
    assert cb.sigma <= ca.sigma + 1e-12
    assert cb.cutoff <= ca.cutoff + 1e-12
    assert cb.rate_factor <= ca.rate_factor + 1e-12
    assert cb.glazed_area >= ca.glazed_area - 1e-15


@settings(max_examples=40, deadline=None)
@given(w=st.floats(0.0, 1e-6), dt=st.floats(0.0, 600.0), force=st.floats(0.0, 100.0))
def test_conditioning_never_increases_the_glazing(w, dt, force):
    disk = pl.ConditionerDisk(down_force=force, rate_constant=pl.CALIBRATION["conditioner_rate_constant"])
    s = pl.condition_ex_situ(pl.PadLifeState(w), dt, disk)
    assert 0.0 <= s.worn_volume <= w
    # in situ the worn volume stays between its start and the balance W* (or grows to it)
    st_ = pl.advance_pad_life(pl.PadLifeState(w), P, U, dt, "in_situ", disk)
    ws = pl.DEFAULT_PAD.wear_coefficient * P * U / max(disk.rate_constant * force, 1e-300)
    assert min(w, ws) - 1e-18 <= st_.worn_volume <= max(w, ws) + 1e-18


def test_calibration_reproduces_jeong():
    """k_w from the spread, G_c from the rate, k_c from the recovery: all three targets of Jeong et al."""
    t1, t2 = J["times"]
    c1, c2 = at(t1), at(t2)
    assert c2.sigma / c1.sigma == pytest.approx(J["spread"][1] / J["spread"][0], rel=1e-9)
    assert c2.rate_factor / c1.rate_factor == pytest.approx(J["rate"][1] / J["rate"][0], rel=1e-9)
    lo, hi = J["spread_range"]
    assert lo / J["spread"][0] <= c2.sigma / c1.sigma <= hi / J["spread"][0]


def test_validation_against_lawing_is_recorded():
    """Lawing (2004), the other curve: measured fall over 31 min (fumed) and 20 min (colloidal)
    against the model at Jeong's P U (Lawing's were not in the transcription). The fumed curve's
    fall is matched within 4 points; the colloidal curve's is not (the model falls 4x more)."""
    fumed = pl.LAWING_2004["fumed"]
    coll = pl.LAWING_2004["colloidal"]
    m_f = float(at(fumed["times"][1]).rate_factor)
    m_c = float(at(coll["times"][1]).rate_factor)
    meas_f = fumed["rate"][1] / fumed["rate"][0]
    meas_c = coll["rate"][1] / coll["rate"][0]
    assert abs(m_f - meas_f) < 0.04  # 0.630 vs 0.649
    assert (1 - m_c) > 3 * (1 - meas_c)  # 0.705 vs 0.925: not reproduced
    # Lawing: "about logarithmic"; the model from 1 to 31 min: R^2 of RR against ln t
    t = np.linspace(60.0, 31 * 60.0, 31)
    rf = np.array([float(at(x).rate_factor) for x in t])
    A = np.vstack([np.ones_like(t), np.log(t)]).T
    res = rf - A @ np.linalg.lstsq(A, rf, rcond=None)[0]
    r2 = 1 - np.sum(res**2) / np.sum((rf - rf.mean()) ** 2)
    assert 0.94 < r2 < 0.96  # 0.949: roughly logarithmic, not exactly


def test_lot_targets_of_the_issue():
    """25 one-minute wafers: without conditioning the rate proxy falls by >= 5 %, with in-situ conditioning by < 2 %."""
    none = pl.PadLifeState()
    insitu = pl.PadLifeState()
    for _ in range(25):
        none = pl.advance_pad_life(none, P, U, 60.0, "none")
        insitu = pl.advance_pad_life(insitu, P, U, 60.0, "in_situ")
    assert pl.summit_constants(none).rate_factor < 0.95
    assert pl.summit_constants(insitu).rate_factor > 0.98


def test_batch_over_pad_radii():
    Ps = np.array([0.0, P, 2 * P])
    s = pl.advance_pad_life(pl.PadLifeState(np.zeros(3)), Ps, U, 300.0)
    c = pl.summit_constants(s)
    assert c.sigma.shape == (3,)
    assert c.sigma[0] == pytest.approx(1.0) and c.sigma[2] < c.sigma[1] < 1.0


def test_bad_inputs():
    with pytest.raises(ValueError):
        pl.advance_pad_life(pl.PadLifeState(), -1.0, U, 1.0)
    with pytest.raises(ValueError):
        pl.advance_pad_life(pl.PadLifeState(), P, U, -1.0)
    with pytest.raises(ValueError):
        pl.FreshPad(sigma=0.0)
    with pytest.raises(ValueError):
        pl.ConditionerDisk(sweep_duty=1.5)
