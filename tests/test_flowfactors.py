"""Verification of the average-flow factors (paper eq. 8-17) and of their regularisation.

The references here are transcriptions of the printed equations written independently of
the kernel (no call to ``orientation_coefficients`` or ``RoughnessGeometry.rotated``).
"""

from __future__ import annotations

import math

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from cmpsim.physics.flowfactors import (
    RoughnessGeometry,
    continue_pressure_eigenvalues,
    orientation_coefficients,
    perturbation_validity_limit,
    pressure_flow_factors,
    regularize_pressure_tensor,
    shear_flow_factors,
    shear_stress_factors,
)
from cmpsim.physics.grainflow import grain_coefficients
from cmpsim.testing.references import omega_eq16, printed_flow_factors, psi_eq17

SQRT_1_5 = math.sqrt(1.5)

angles = st.floats(min_value=-math.pi, max_value=math.pi)
gammas = st.floats(min_value=1e-2, max_value=1e2)
sigma_split = st.floats(min_value=0.0, max_value=1.0)  # sigma_wafer / sigma_pad
h_ratios = st.floats(min_value=0.5, max_value=1e3)
x_values = st.floats(min_value=1e-8, max_value=1e3)


def _fg(x):
    """f and g of grain_coefficients at damping ratio x (w/k = 1)."""
    _, f, g = grain_coefficients(x, 1.0)
    return float(f), float(g)


def _all_factors(hs, f, g, rough):
    pxx, pxy, pyy = pressure_flow_factors(hs, f, g, rough)
    sxx, sxy, syy = shear_flow_factors(hs, f, rough)
    fs, fp = shear_stress_factors(hs, f, rough)
    return {
        "p_xx": pxx, "p_xy": pxy, "p_yy": pyy,
        "s_xx": sxx, "s_xy": sxy, "s_yy": syy,
        "fs": fs, "fp": fp,
    }


# --- eq. 8-17 ----------------------------------------------------------------------------
@settings(max_examples=150, deadline=None)
@given(hs=h_ratios, x=x_values, split=sigma_split, g1=gammas, g2=gammas, t1=angles, t2=angles)
def test_every_flow_factor_matches_an_independent_transcription_of_printed_eq_8_to_17(
    hs, x, split, g1, g2, t1, t2
):
    f, g = _fg(x)
    s1 = 15e-6
    rough = RoughnessGeometry(s1, split * s1, g1, g2, t1, t2)
    got = _all_factors(hs, f, g, rough)
    ref = printed_flow_factors(hs, f, g, s1, split * s1, g1, g2, t1, t2)
    # each factor is 1 + (or just) a correction of size <= ~10 e^2 or ~3 e
    scale = 1.0 + 10.0 / hs**2 + 3.0 / hs
    for k in ref:
        assert abs(float(got[k]) - ref[k]) <= 1e-14 * scale, k


@settings(max_examples=150, deadline=None)
@given(hs=h_ratios, x=x_values, split=sigma_split, g1=gammas, g2=gammas, t1=angles, t2=angles)
def test_phi_yy_at_theta_equals_phi_xx_at_90_deg_minus_theta_for_pressure_eq_10_and_shear_eq_13(
    hs, x, split, g1, g2, t1, t2
):
    f, g = _fg(x)
    rough = RoughnessGeometry(15e-6, split * 15e-6, g1, g2, t1, t2)
    turned = RoughnessGeometry(15e-6, split * 15e-6, g1, g2, 0.5 * math.pi - t1, 0.5 * math.pi - t2)
    _, _, p_yy = pressure_flow_factors(hs, f, g, rough)
    p_xx_turned, _, _ = pressure_flow_factors(hs, f, g, turned)
    _, _, s_yy = shear_flow_factors(hs, f, rough)
    s_xx_turned, _, _ = shear_flow_factors(hs, f, turned)
    scale = 1.0 + 10.0 / hs**2 + 3.0 / hs
    assert abs(float(p_yy - p_xx_turned)) <= 1e-14 * scale
    assert abs(float(s_yy - s_xx_turned)) <= 1e-14 * scale


def test_orientation_coefficients_are_eq_16_and_17_and_isotropic_gives_half_and_zero():
    theta = np.linspace(-3.0, 3.0, 13)
    for gamma in (0.1, 1.0, 6.0):
        om, ps = orientation_coefficients(theta, gamma)
        np.testing.assert_allclose(om, [omega_eq16(t, gamma) for t in theta], rtol=1e-15, atol=1e-16)
        np.testing.assert_allclose(ps, [psi_eq17(t, gamma) for t in theta], rtol=1e-15, atol=1e-16)
    om, ps = orientation_coefficients(theta, 1.0)
    np.testing.assert_allclose(om, 0.5, rtol=1e-15)
    assert np.all(ps == 0.0)


@settings(max_examples=100, deadline=None)
@given(hs=h_ratios, x=x_values, split=sigma_split, t1=angles, t2=angles)
def test_isotropic_roughness_gives_zero_cross_terms_phi_fs_0_and_phi_fp_1(hs, x, split, t1, t2):
    f, g = _fg(x)
    rough = RoughnessGeometry(15e-6, split * 15e-6, 1.0, 1.0, t1, t2)
    _, p_xy, _ = pressure_flow_factors(hs, f, g, rough)
    _, s_xy, _ = shear_flow_factors(hs, f, rough)
    fs, fp = shear_stress_factors(hs, f, rough)
    assert p_xy == 0.0 and s_xy == 0.0 and fs == 0.0 and fp == 1.0


@pytest.mark.parametrize("x", [1e-8, 0.3, 5.0, 1e3])
def test_isotropic_pad_only_phi_p_is_1_plus_sigma_over_h_squared_times_g_minus_f2_over_2(x):
    f, g = _fg(x)
    hs = np.logspace(-0.2, 3, 30)
    rough = RoughnessGeometry(15e-6, 0.0, 1.0, 1.0, 0.3, 1.1)
    p_xx, p_xy, p_yy = pressure_flow_factors(hs, f, g, rough)
    expected = 1.0 + (g - f * f / 2.0) / hs**2
    np.testing.assert_allclose(p_xx, expected, rtol=1e-14, atol=1e-14)
    np.testing.assert_allclose(p_yy, expected, rtol=1e-14, atol=1e-14)
    assert np.all(p_xy == 0.0)


@pytest.mark.parametrize(
    "rough",
    [
        RoughnessGeometry(15e-6),
        RoughnessGeometry(15e-6, 5e-6, 0.2, 4.0, 0.4, -1.0),
        RoughnessGeometry(1e-6, 15e-6, 9.0, 0.5, 2.0, 0.1),
    ],
)
def test_flow_factors_tend_to_identity_and_zero_as_h_over_sigma_tends_to_infinity(rough):
    f, g = _fg(0.7)
    hs = np.logspace(1, 8, 15)
    p_xx, p_xy, p_yy = pressure_flow_factors(hs, f, g, rough)
    s_xx, s_xy, s_yy = shear_flow_factors(hs, f, rough)
    fs, fp = shear_stress_factors(hs, f, rough)
    # pressure factors -> I at rate (sigma/h)^2, shear factors -> 0 at rate sigma/h
    for dev in (p_xx - 1.0, p_xy, p_yy - 1.0, fs, fp - 1.0):
        assert np.all(np.abs(dev) * hs**2 <= 3.0 * f * f + g)
    for dev in (s_xx, s_xy, s_yy):
        assert np.all(np.abs(dev) * hs <= f)
    assert abs(p_xx[-1] - 1.0) < 1e-15 and abs(p_yy[-1] - 1.0) < 1e-15 and abs(s_xx[-1]) < 1e-7


def test_shear_flow_factor_sign_convention_pad_rough_along_x_gives_positive_phi_s_xx():
    f, _ = _fg(0.7)
    s_xx, _, _ = shear_flow_factors(2.0, f, RoughnessGeometry(15e-6, 0.0))
    assert s_xx == pytest.approx(f / 2.0 / 2.0, rel=1e-15)  # -e f (0 - Omega_1), Omega_1 = 1/2


# --- validity of the perturbation expansion ----------------------------------------------
def test_isotropic_phi_p_xx_at_x_to_0_is_non_positive_below_h_over_sigma_sqrt_1_5():
    f, g = _fg(1e-8)
    assert f == 3.0 and g == 3.0
    rough = RoughnessGeometry(15e-6, 0.0, 1.0, 1.0)
    limit = perturbation_validity_limit(f, g, rough)
    assert limit == pytest.approx(SQRT_1_5, rel=1e-15)
    assert abs(SQRT_1_5 - 1.2247) < 1e-4
    below = SQRT_1_5 * np.array([0.5, 0.9, 1.0 - 1e-9])
    above = SQRT_1_5 * np.array([1.0 + 1e-9, 1.1, 10.0])
    p_below, _, _ = pressure_flow_factors(below, f, g, rough)
    p_above, _, _ = pressure_flow_factors(above, f, g, rough)
    assert np.all(p_below < 0.0) and np.all(p_above > 0.0)
    p_at, _, _ = pressure_flow_factors(SQRT_1_5, f, g, rough)
    assert abs(float(p_at)) < 1e-15


@settings(max_examples=100, deadline=None)
@given(
    x=x_values, split=sigma_split, g1=gammas, g2=gammas, t1=angles, t2=angles,
    floor=st.sampled_from([0.0, 1e-3, 0.1, 0.5]),
)
def test_validity_limit_is_where_min_of_phi_p_xx_phi_p_yy_reaches_the_floor(x, split, g1, g2, t1, t2, floor):
    f, g = _fg(x)
    rough = RoughnessGeometry(15e-6, split * 15e-6, g1, g2, t1, t2)
    limit = float(perturbation_validity_limit(f, g, rough, floor=floor))
    probe = np.array([1.0001, 1.5, 10.0]) * max(limit, 1e-3)
    p_xx, _, p_yy = pressure_flow_factors(probe, f, g, rough)
    assert np.all(np.minimum(p_xx, p_yy) >= floor)
    if limit > 0:
        p_xx, _, p_yy = pressure_flow_factors(limit, f, g, rough)
        assert float(min(p_xx, p_yy)) == pytest.approx(floor, abs=1e-13)
        p_xx, _, p_yy = pressure_flow_factors(0.999 * limit, f, g, rough)
        assert float(min(p_xx, p_yy)) < floor


# --- regularize_pressure_tensor ----------------------------------------------------------
components = st.floats(min_value=-1e3, max_value=1e3, allow_nan=False)
floors = st.floats(min_value=1e-6, max_value=1.0)


def _eig(a, b, c):
    return np.linalg.eigvalsh(np.array([[a, b], [b, c]]))


@settings(max_examples=300, deadline=None)
@given(a=components, b=components, c=components, floor=floors)
def test_regularized_tensor_has_eigenvalues_max_of_old_and_floor_and_keeps_eigenvectors(a, b, c, floor):
    na, nb, nc, floored = regularize_pressure_tensor(a, b, c, floor)
    lam = _eig(a, b, c)  # ascending
    new = _eig(float(na), float(nb), float(nc))
    scale = max(abs(a), abs(b), abs(c), floor)
    tol = 8 * np.finfo(float).eps * scale
    # every output eigenvalue is >= floor (up to round-off of the reconstruction) and > 0
    assert new[0] >= floor - tol and new[0] > 0.0 or floor <= tol
    # spectrum: each eigenvalue raised to the floor, none lowered
    np.testing.assert_allclose(new, np.maximum(lam, floor), rtol=0, atol=tol)
    # floored mask is exactly "smallest eigenvalue below floor" (away from round-off ties)
    if abs(lam[0] - floor) > tol:
        assert bool(floored) == (lam[0] < floor)
    if not floored:
        assert (na, nb, nc) == (a, b, c)
    else:
        # eigenvectors kept: the old and new tensors commute
        old_m = np.array([[a, b], [b, c]])
        new_m = np.array([[float(na), float(nb)], [float(nb), float(nc)]])
        comm = old_m @ new_m - new_m @ old_m
        assert np.max(np.abs(comm)) <= 16 * np.finfo(float).eps * scale * max(scale, 1.0)


def test_regularize_leaves_entries_with_eigenvalues_at_or_above_floor_bit_for_bit_unchanged():
    rng = np.random.default_rng(7)
    a = rng.uniform(-2, 3, (40, 30))
    b = rng.uniform(-1, 1, (40, 30))
    c = rng.uniform(-2, 3, (40, 30))
    floor = 0.05
    na, nb, nc, floored = regularize_pressure_tensor(a, b, c, floor)
    assert na.shape == nb.shape == nc.shape == floored.shape == a.shape
    lam_min = 0.5 * (a + c) - np.hypot(0.5 * (a - c), b)
    np.testing.assert_array_equal(floored, lam_min < floor)
    assert 0 < floored.sum() < floored.size
    keep = ~floored
    assert np.array_equal(na[keep], a[keep]) and np.array_equal(nb[keep], b[keep])
    assert np.array_equal(nc[keep], c[keep])
    new_min = 0.5 * (na + nc) - np.hypot(0.5 * (na - nc), nb)
    assert np.all(new_min[floored] >= floor * (1 - 1e-12))
    # inputs are not modified in place
    na2, *_ = regularize_pressure_tensor(a, b, c, floor)
    np.testing.assert_array_equal(na, na2)


def test_regularize_handles_a_negative_isotropic_tensor_and_an_all_valid_field():
    na, nb, nc, floored = regularize_pressure_tensor(-1.0, 0.0, -1.0, 0.01)
    assert (float(na), float(nb), float(nc), bool(floored)) == (0.01, 0.0, 0.01, True)
    a = np.ones(5)
    na, nb, nc, floored = regularize_pressure_tensor(a, 0.0, a, 0.5)
    assert not floored.any() and np.array_equal(na, a) and np.all(nb == 0.0)


@pytest.mark.parametrize("floor", [0.0, -1.0, np.nan, np.inf])
def test_regularize_rejects_a_floor_that_is_not_finite_and_positive(floor):
    with pytest.raises(ValueError, match="floor"):
        regularize_pressure_tensor(1.0, 0.0, 1.0, floor)


# --- continuation of eq. 8 below its validity (flow_factor_continuation) ------------------
@pytest.mark.parametrize("start", [0.25, 0.4, 0.5, 0.8])
def test_the_continued_eigenvalue_is_the_power_law_in_the_film_that_joins_eq_8_with_its_slope(start):
    # isotropic roughness at x -> 0: eq. 8 is 1 - 1.5 (sigma/h)^2; below lam_c (at H_c) the continuation
    # is lam_c (H / H_c)^n with n = 2 (1 - lam_c) / lam_c, written independently of the kernel
    beta = -1.5
    H = np.linspace(0.05, 4.0, 4001)
    lam = 1.0 + beta / H**2
    Hc = math.sqrt(-beta / (1.0 - start))
    n = 2.0 * (1.0 - start) / start
    want = np.where(H < Hc, start * (H / Hc) ** n, lam)
    got = continue_pressure_eigenvalues(lam, start)
    np.testing.assert_allclose(got, want, rtol=1e-12, atol=0.0)
    # positive everywhere, increasing with the film, and C1 across H_c (one-sided slopes in H agree)
    assert np.all(got > 0.0) and np.all(np.diff(got) > 0.0)
    eps = 1e-6 * Hc
    f = lambda x: float(continue_pressure_eigenvalues(1.0 + beta / x**2, start))  # noqa: E731
    left, right = (f(Hc) - f(Hc - eps)) / eps, (f(Hc + eps) - f(Hc)) / eps
    assert left == pytest.approx(right, rel=1e-4) and left == pytest.approx(-2.0 * beta / Hc**3, rel=1e-4)


def test_the_continuation_leaves_eigenvalues_at_or_above_its_start_bit_for_bit_and_zero_switches_it_off():
    lam = np.array([-50.0, -1.0, 0.0, 0.1, 0.3999, 0.4, 0.7, 1.0, 3.0])
    got = continue_pressure_eigenvalues(lam, 0.4)
    assert np.array_equal(got[5:], lam[5:]) and np.all(got[:5] > 0.0) and np.all(got[:5] < 0.4)
    assert np.array_equal(continue_pressure_eigenvalues(lam, 0.0), lam)
    # -> 0 only as the film closes: eq. 8's eigenvalue -> -inf
    assert continue_pressure_eigenvalues(np.array([-1e12]), 0.4)[0] < 1e-15
    for bad in (1.0, 1.5, np.nan, np.inf):
        with pytest.raises(ValueError, match="flow_factor_continuation"):
            continue_pressure_eigenvalues(lam, bad)


@settings(max_examples=200, deadline=None)
@given(a=components, b=components, c=components, floor=floors, start=st.floats(min_value=0.05, max_value=0.95))
def test_the_continued_tensor_keeps_its_eigenvectors_with_eigenvalues_max_of_continued_and_floor(a, b, c, floor, start):
    na, nb, nc, changed = regularize_pressure_tensor(a, b, c, floor, start)
    lam = _eig(a, b, c)
    new = _eig(float(na), float(nb), float(nc))
    scale = max(abs(a), abs(b), abs(c), floor, 1.0)
    want = np.sort(np.maximum(continue_pressure_eigenvalues(lam, start), floor))
    np.testing.assert_allclose(new, want, rtol=0, atol=16 * np.finfo(float).eps * scale)
    if abs(lam[0] - max(floor, start)) > 8 * np.finfo(float).eps * scale:
        assert bool(changed) == (lam[0] < max(floor, start))
    if not changed:
        assert (na, nb, nc) == (a, b, c)


def test_without_continuation_the_regularisation_is_the_floor_alone_bit_for_bit():
    rng = np.random.default_rng(11)
    a, b, c = rng.uniform(-2, 3, (3, 40, 30))
    for x, y in zip(regularize_pressure_tensor(a, b, c, 0.05), regularize_pressure_tensor(a, b, c, 0.05, 0.0)):
        assert np.array_equal(x, y)


# --- argument checking -------------------------------------------------------------------
@pytest.mark.parametrize(
    "kwargs, name",
    [
        (dict(sigma_pad=-1e-6), "sigma_pad"),
        (dict(sigma_pad=np.nan), "sigma_pad"),
        (dict(sigma_pad=np.inf), "sigma_pad"),
        (dict(sigma_pad=1e-6, sigma_wafer=-1e-6), "sigma_wafer"),
        (dict(sigma_pad=1e-6, sigma_wafer=np.nan), "sigma_wafer"),
        (dict(sigma_pad=0.0, sigma_wafer=0.0), "sigma_pad and sigma_wafer"),
        (dict(sigma_pad=1e-6, gamma_pad=0.0), "gamma_pad"),
        (dict(sigma_pad=1e-6, gamma_pad=-2.0), "gamma_pad"),
        (dict(sigma_pad=1e-6, gamma_wafer=np.inf), "gamma_wafer"),
        (dict(sigma_pad=1e-6, theta_pad=np.nan), "theta_pad"),
        (dict(sigma_pad=1e-6, theta_wafer=np.inf), "theta_wafer"),
    ],
)
def test_invalid_roughness_geometry_raises_value_error_naming_the_argument(kwargs, name):
    with pytest.raises(ValueError, match=name):
        RoughnessGeometry(**kwargs)


def test_wafer_only_roughness_is_accepted_and_combined_sigma_is_the_rms_sum():
    assert RoughnessGeometry(0.0, 2e-6).sigma == 2e-6
    assert RoughnessGeometry(3e-6, 4e-6).sigma == pytest.approx(5e-6, rel=1e-15)


@pytest.mark.parametrize("hs", [0.0, -1.0, np.nan, np.inf])
def test_invalid_h_over_sigma_raises_value_error_naming_it(hs):
    rough = RoughnessGeometry(15e-6)
    with pytest.raises(ValueError, match="h_over_sigma"):
        pressure_flow_factors(hs, 3.0, 3.0, rough)
    with pytest.raises(ValueError, match="h_over_sigma"):
        shear_flow_factors(hs, 3.0, rough)
    with pytest.raises(ValueError, match="h_over_sigma"):
        shear_stress_factors(hs, 3.0, rough)
