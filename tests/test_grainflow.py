"""Verification of the grain-flow kernels (paper eq. 6, 7, 18, 19).

The reference is the PRINTED form of each equation, in R1 = exp(x) - exp(-x) and
R2 = exp(x) + exp(-x) with x = sqrt(w/k) h/d, evaluated with 50-digit mpmath: the kernel's
stable rewrite must agree with it, not with another rewrite.
"""

from __future__ import annotations

import warnings

import mpmath as mp
import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from cmpsim.physics.grainflow import damping_ratio, grain_coefficients
from cmpsim.testing.references import printed_forms_mp

X_GRID = np.logspace(-8, 3, 40)
W_OVER_K = (4e-6, 0.25)  # the paper's base value, and an O(1) ratio
#: Minimum of g over x > 0: g(5.3329463865609...) = 0.96698679749239571955 (mpmath, below).
G_MIN = 0.9669867974923957


@pytest.mark.parametrize("w_over_k", W_OVER_K)
def test_psi_f_g_match_50_digit_mpmath_printed_forms_to_1e_12_from_x_1e_8_to_1e3(w_over_k):
    h_over_d = X_GRID / np.sqrt(w_over_k)
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        with np.errstate(all="raise"):
            psi, f, g = grain_coefficients(h_over_d, w_over_k)
    for name, got in (("psi", psi), ("f", f), ("g", g)):
        assert got.shape == X_GRID.shape, name
        assert np.all(np.isfinite(got)), name
    worst = {"psi": 0.0, "f": 0.0, "g": 0.0}
    for i, hd in enumerate(h_over_d):
        ref = printed_forms_mp(float(hd), w_over_k)
        for name, got, r in zip(("psi", "f", "g"), (psi, f, g), ref):
            rel = float(abs((mp.mpf(float(got[i])) - r) / r))
            worst[name] = max(worst[name], rel)
    assert max(worst.values()) <= 1e-12, worst


def test_no_overflow_underflow_or_warning_for_x_from_1e_8_to_1e3_nor_far_beyond():
    x = np.concatenate([X_GRID, [700.0, 700.0000001, 5e3, 1e160, 1e300]])
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        with np.errstate(all="raise"):
            psi, f, g = grain_coefficients(x / 2e-3, 4e-6)
    assert np.all(np.isfinite(psi)) and np.all(np.isfinite(f)) and np.all(np.isfinite(g))
    assert not np.any(np.isnan(psi) | np.isnan(f) | np.isnan(g))
    # far beyond the physical range the exact limits are returned
    assert np.all(f[-4:] == 2.0) and np.all(g[-4:] == 1.0)
    assert np.allclose(psi[-4:], 1.0 / np.sqrt(4e-6), rtol=1e-15, atol=0)


@pytest.mark.parametrize("w_over_k", W_OVER_K)
def test_f_and_g_tend_to_3_and_psi_to_half_h_over_d_as_x_tends_to_0(w_over_k):
    x = np.array([1e-8, 1e-6, 1e-4])
    h_over_d = x / np.sqrt(w_over_k)
    psi, f, g = grain_coefficients(h_over_d, w_over_k)
    # series: f = 3 - x^2/6, g = 3 - 7 x^2 / 12, Psi = h/(2d) (1 - x^2/12)
    np.testing.assert_allclose(3.0 - f, x**2 / 6, rtol=1e-3, atol=1e-15)
    np.testing.assert_allclose(3.0 - g, 7 * x**2 / 12, rtol=1e-3, atol=1e-15)
    np.testing.assert_allclose(psi / (0.5 * h_over_d), 1.0 - x**2 / 12, rtol=1e-15)
    assert abs(f[0] - 3.0) <= 1e-15 and abs(g[0] - 3.0) <= 1e-15


@pytest.mark.parametrize("w_over_k", W_OVER_K)
def test_f_tends_to_2_g_to_1_and_psi_to_sqrt_k_over_w_as_x_tends_to_infinity(w_over_k):
    x = np.array([40.0, 100.0, 1e3])
    psi, f, g = grain_coefficients(x / np.sqrt(w_over_k), w_over_k)
    np.testing.assert_allclose(f, 2.0, rtol=0, atol=1e-15)
    np.testing.assert_allclose(g, 1.0, rtol=0, atol=1e-14)
    np.testing.assert_allclose(psi, 1.0 / np.sqrt(w_over_k), rtol=1e-15)


def test_g_is_not_monotone_it_dips_to_0_966987_at_x_5_3329_before_rising_to_1():
    # minimum of the printed g(x), located with 30-digit mpmath
    with mp.workdps(30):
        def g_of(x):
            return printed_forms_mp(x, 1, dps=None)[2]

        x_min = mp.findroot(lambda x: mp.diff(g_of, x), 5.3)
        g_min = g_of(x_min)
    assert abs(float(x_min) - 5.3329463865609) < 1e-12, x_min
    assert abs(float(g_min) - G_MIN) < 1e-16, g_min
    _, _, g = grain_coefficients(np.array([1.0, float(x_min), 20.0]), 1.0)
    assert g[0] > g[1] < g[2] < 1.0
    assert abs(g[1] - G_MIN) <= 1e-15


@settings(max_examples=200, deadline=None)
@given(
    log_x=st.floats(min_value=-8.0, max_value=3.0),
    w_over_k=st.sampled_from([4e-6, 1e-3, 0.25, 1.0, 7.0]),
)
def test_f_in_2_3_decreasing_and_g_in_0_966987_3_for_any_x_in_1e_8_1e3(log_x, w_over_k):
    x = 10.0**log_x
    x2 = x * 1.01
    hd = np.array([x, x2]) / np.sqrt(w_over_k)
    psi, f, g = grain_coefficients(hd, w_over_k)
    assert np.all((f >= 2.0) & (f <= 3.0))
    if x < 30.0:  # beyond, x / sinh x < 2e-12 and f may round to 2 exactly
        assert f[0] > 2.0
    assert f[1] <= f[0] + 4.5e-16  # f decreases monotonically (to 1 ulp of 3: x/sinh x ~ 1 - x^2/6)
    # g is NOT monotone (see above): it only stays within [g_min, 3]
    assert np.all((g >= G_MIN * (1 - 4e-16)) & (g <= 3.0))
    assert np.all((psi > 0) & (psi <= 1.0 / np.sqrt(w_over_k)))


@pytest.mark.parametrize(
    "h_over_d, w_over_k, name",
    [
        (0.0, 4e-6, "h_over_d"),
        (-1.0, 4e-6, "h_over_d"),
        (np.nan, 4e-6, "h_over_d"),
        (np.inf, 4e-6, "h_over_d"),
        (np.array([1.0, -2.0]), 4e-6, "h_over_d"),
        (100.0, 0.0, "w_over_k"),
        (100.0, -4e-6, "w_over_k"),
        (100.0, np.nan, "w_over_k"),
    ],
)
def test_invalid_h_over_d_or_w_over_k_raises_value_error_naming_the_argument(h_over_d, w_over_k, name):
    with pytest.raises(ValueError, match=name):
        grain_coefficients(h_over_d, w_over_k)
    with pytest.raises(ValueError, match=name):
        damping_ratio(h_over_d, w_over_k)


def test_outputs_broadcast_h_over_d_against_w_over_k():
    psi, f, g = grain_coefficients(np.array([[10.0], [100.0]]), np.array([4e-6, 1e-4, 1e-2]))
    assert psi.shape == f.shape == g.shape == (2, 3)
    psi0, f0, g0 = grain_coefficients(100.0, 1e-4)
    assert psi0.shape == () and psi[1, 1] == psi0 and f[1, 1] == f0 and g[1, 1] == g0


def test_grain_flow_object_gives_haffs_laws_with_viscosity_over_pressure_equal_to_a_d_over_t_v():
    from cmpsim.physics.grainflow import GrainFlow, granular_pressure

    gf = GrainFlow(particle_diameter=100e-9, w_over_k=4e-6, t_over_a=2.0, fluctuation_velocity=1.9)
    p = gf.pressure(134.0, 67.0, t=1.0)
    assert p == pytest.approx(134.0 * 67.0 * 1.9**2, rel=1e-15)
    assert p == granular_pressure(134.0, 67.0, 1.9, t=1.0)
    assert gf.viscosity(p) / p == pytest.approx(100e-9 / (2.0 * 1.9), rel=1e-15)  # eta / p = (a/t) d / v
    h = np.array([5e-6, 20e-6])
    for got, want in zip(gf.coefficients(h), grain_coefficients(h / 100e-9, 4e-6)):
        np.testing.assert_array_equal(got, want)
    with pytest.raises(TypeError):  # the old call, with the particle diameter that did nothing, fails loudly
        granular_pressure(134.0, 100e-9, 67.0, 1.9)
