"""Verification of the statistical asperity contact (paper eq. 20-29, corrected).

The reference :func:`cmpsim.testing.references.contact_reference_mp` re-implements the per-asperity laws (Hertz,
Zhao-Maietta-Chang, Abbott-Firestone) in mpmath, independently of the kernel, and
integrates them over the truncated, renormalised Gaussian summit-height density with
adaptive mpmath quadrature (tanh-sinh), broken at D, D + omega_e, D + omega_p and the
cutoff, and further where the Gaussian weight changes by large factors
(:func:`gaussian_breakpoints`), with the integrand scaled to O(1) because mp.quad's
tolerance is absolute.
"""

from __future__ import annotations

import math

import mpmath as mp
import numpy as np
import pytest

from cmpsim.physics.contact import ContactTable, PadSurface, asperity_contact, asperity_laws
from cmpsim.testing.references import _mp_pad, contact_reference_mp, laws_mp

#: The feasibility prototype's pad: omega_e = 0.20 sigma, omega_p = 11 sigma.
PAD_SOFT = PadSurface(15e-6, 1e8, 50e-6, 110e6, 20e6, 0.3)
#: A stiffer pad: omega_e = 0.0025 sigma, omega_p = 0.13 sigma (all three regimes in play).
PAD_STIFF = PadSurface(15e-6, 1e8, 50e-6, 1e9, 20e6, 0.3)
#: Another material (nu = 0.45), rougher and denser, untruncated heights.
PAD_OTHER_INF = PadSurface(20e-6, 3e8, 30e-6, 300e6, 25e6, 0.45, height_cutoff=np.inf)
PAD_SOFT_INF = PadSurface(15e-6, 1e8, 50e-6, 110e6, 20e6, 0.3, height_cutoff=np.inf)

PADS = {"soft": PAD_SOFT, "stiff": PAD_STIFF, "soft_inf": PAD_SOFT_INF, "other_inf": PAD_OTHER_INF}
MODELS = ("lep", "elastic")
QUANTITIES = ("pressure", "area_ratio_elastic", "area_ratio_elastoplastic", "area_ratio_plastic")


def _separations(pad: PadSurface) -> np.ndarray:
    """D / sigma from -10 to just below 3, with points straddling every band edge.

    The closest point is 3 - 1e-6: the pressure's condition number with respect to D,
    2.5 D / (3 sigma - D), times the 1.1e-16 rounding of D / sigma in any double-precision
    code bounds the agreement attainable closer in (8e-10 here, 8e-9 at 3 - 1e-7).
    """
    c = 3.0
    we, wp = pad.omega_e / pad.sigma_s, pad.omega_p / pad.sigma_s
    edges = [c - wp, c - we]
    extra = [e + d for e in edges for d in (-1e-3, 1e-3) if -10 < e + d < c]
    d = np.concatenate([np.linspace(-10.0, 2.5, 6), extra, [2.9, 2.99, 3.0 - 1e-4, 3.0 - 1e-6]])
    return np.sort(d)


def _rel(got: float, ref) -> float:
    if ref == 0:
        return 0.0 if got == 0 else math.inf
    return float(abs((mp.mpf(got) - ref) / ref))


@pytest.mark.parametrize("model", MODELS)
@pytest.mark.parametrize("pad_name", ["soft", "stiff", "other_inf"])
def test_pressure_and_area_ratios_match_adaptive_mpmath_quadrature_to_1e_8_from_minus_10_to_3_sigma(
    pad_name, model
):
    pad = PADS[pad_name]
    delta = _separations(pad)
    res = asperity_contact(delta * pad.sigma_s, pad, model)
    worst = {q: (0.0, None) for q in QUANTITIES}
    nonzero = {q: 0 for q in QUANTITIES}
    for i, dl in enumerate(delta):
        ref = contact_reference_mp(float(dl * pad.sigma_s), pad, model)
        for q in QUANTITIES:
            got = float(getattr(res, q)[i])
            nonzero[q] += ref[q] != 0
            r = _rel(got, ref[q])
            if r > worst[q][0]:
                worst[q] = (r, float(dl))
    assert max(w for w, _ in worst.values()) <= 1e-8, worst
    # the comparison exercised the regimes this pad and model can reach
    assert nonzero["pressure"] == len(delta) and nonzero["area_ratio_elastic"] == len(delta)
    if model == "lep":
        assert nonzero["area_ratio_elastoplastic"] > 0 and nonzero["area_ratio_plastic"] > 0
    else:
        assert nonzero["area_ratio_elastoplastic"] == nonzero["area_ratio_plastic"] == 0


def test_mpmath_reference_reproduces_the_closed_form_plastic_area_in_the_far_gaussian_tail():
    # guards the reference itself: plain tanh-sinh over [14, inf) is off by 4e-5 here
    pad, dl = PAD_SOFT_INF, 3.0 - 1e-6
    ref = contact_reference_mp(dl * pad.sigma_s, pad, "lep")["area_ratio_plastic"]
    with mp.workdps(30):
        delta = mp.mpf(dl * pad.sigma_s) / mp.mpf(pad.sigma_s)
        a = delta + _mp_pad(pad)["w_p"] / mp.mpf(pad.sigma_s)
        first_moment = mp.npdf(a) - delta * mp.ncdf(-a)  # int_a^inf (zeta - delta) phi
        exact = 2 * mp.pi * mp.mpf(pad.asperity_radius) * mp.mpf(pad.sigma_s) * pad.asperity_density * first_moment
    assert _rel(float(ref), exact) < 1e-14


@pytest.mark.parametrize("dl", [-2.0, 0.0, 3.0, 5.0, 8.0])
def test_plastic_area_in_the_upper_gaussian_tail_matches_the_closed_form_to_1e_12(dl):
    # int_a^inf (zeta - delta) phi = phi(a) - delta Q(a): computed as 1 - Phi(a) from the
    # lower tail it lost every digit once a = delta + omega_p / sigma exceeded ~8
    pad = PAD_SOFT_INF
    got = float(asperity_contact(dl * pad.sigma_s, pad, "lep").area_ratio_plastic)
    with mp.workdps(30):
        delta = mp.mpf(dl * pad.sigma_s) / mp.mpf(pad.sigma_s)
        a = delta + _mp_pad(pad)["w_p"] / mp.mpf(pad.sigma_s)
        first_moment = mp.npdf(a) - delta * mp.ncdf(-a)
        exact = 2 * mp.pi * mp.mpf(pad.asperity_radius) * mp.mpf(pad.sigma_s) * pad.asperity_density * first_moment
    assert _rel(got, exact) < 1e-12


@pytest.mark.parametrize("model", MODELS)
@pytest.mark.parametrize("pad_name", list(PADS))
def test_extreme_separations_give_finite_non_negative_results_ordered_like_the_separation(pad_name, model):
    pad = PADS[pad_name]
    d = np.array([-1e3, -40.0, -12.0, 0.0, 10.0, 40.0, 1e3]) * pad.sigma_s
    res = asperity_contact(d, pad, model)
    for q in QUANTITIES:
        v = getattr(res, q)
        assert np.all(np.isfinite(v) & (v >= 0)), q
    assert np.all(np.diff(res.pressure) <= 0) and res.pressure[0] > 1e3 * res.pressure[3]


# --- per-asperity laws ---------------------------------------------------------------------
@pytest.mark.parametrize("pad_name", ["soft", "stiff", "other_inf"])
def test_per_asperity_area_and_load_are_continuous_at_omega_e_and_omega_p(pad_name):
    pad = PADS[pad_name]
    for edge, regimes in ((pad.omega_e, (1, 2)), (pad.omega_p, (2, 3))):
        w = edge * np.array([1 - 1e-12, 1 + 1e-12])
        area, load, regime = asperity_laws(w, pad, "lep")
        assert tuple(regime) == regimes
        assert abs(area[1] - area[0]) <= 1e-9 * area[0]
        assert abs(load[1] - load[0]) <= 1e-9 * load[0]


@pytest.mark.parametrize("pad_name", ["soft", "stiff", "other_inf"])
def test_hertz_mean_pressure_at_omega_e_equals_k_times_hardness(pad_name):
    pad = PADS[pad_name]
    K = 0.454 + 0.41 * pad.poisson
    assert pad.k_factor == pytest.approx(K, rel=1e-15)
    # eq. 27 is exactly where (4 E' / (3 pi)) sqrt(omega / R) reaches K H
    hertz_pm = 4 * pad.e_star / (3 * math.pi) * math.sqrt(pad.omega_e / pad.asperity_radius)
    assert hertz_pm == pytest.approx(K * pad.hardness, rel=1e-14)
    area, load, regime = asperity_laws(pad.omega_e * (1 - 1e-12), pad, "lep")
    assert int(regime) == 1
    assert float(load / area) == pytest.approx(K * pad.hardness, rel=1e-11)
    assert pad.omega_p == pytest.approx(54 * pad.omega_e, rel=1e-15)


@pytest.mark.parametrize("model", MODELS)
def test_per_asperity_laws_match_the_mpmath_transcription_in_every_regime(model):
    pad = PAD_STIFF
    w = pad.omega_e * np.array([-1.0, 0.0, 1e-6, 0.5, 0.999, 1.0, 2.0, 30.0, 53.9, 54.0, 60.0, 1e3])
    area, load, regime = asperity_laws(w, pad, model)
    for i, wi in enumerate(w):
        a_ref, l_ref, r_ref = laws_mp(float(wi), pad, model)
        assert int(regime[i]) == r_ref
        assert _rel(float(area[i]), a_ref) <= 1e-13 and _rel(float(load[i]), l_ref) <= 1e-13


# --- the load as a function of the separation -----------------------------------------------
@pytest.mark.parametrize("model", MODELS)
@pytest.mark.parametrize("pad_name", ["soft", "stiff"])
def test_load_vanishes_continuously_like_distance_to_cutoff_to_the_5_2_and_is_zero_beyond(pad_name, model):
    pad = PADS[pad_name]
    s, c = pad.sigma_s, pad.height_cutoff
    eps = np.array([1e-4, 2e-4, 1e-7, 1e-12])
    p = asperity_contact((c - eps) * s, pad, model).pressure
    p_mid = float(asperity_contact(0.0, pad, model).pressure)
    assert np.all(p > 0)
    assert p[0] / p[1] == pytest.approx(2**-2.5, rel=1e-3)  # elastic summits, P ~ eps^(5/2)
    assert p[2] < 1e-15 * p_mid and p[3] < 1e-27 * p_mid
    beyond = asperity_contact(np.array([c, c + 1e-12, c + 0.5, 50.0]) * s, pad, model)
    for q in QUANTITIES:
        assert np.all(getattr(beyond, q) == 0.0), q


@pytest.mark.parametrize("model", MODELS)
@pytest.mark.parametrize("pad_name", list(PADS))
def test_pressure_and_real_area_strictly_decrease_with_separation(pad_name, model):
    pad = PADS[pad_name]
    top = 2.999 if np.isfinite(pad.height_cutoff) else 6.0
    d = np.linspace(-10.0, top, 3001) * pad.sigma_s
    res = asperity_contact(d, pad, model)
    assert np.all(np.diff(res.pressure) < 0)
    assert np.all(np.diff(res.area_ratio) < 0)


def test_untruncated_pad_has_contact_beyond_3_sigma_and_truncated_pad_has_none():
    d = np.array([3.5, 5.0]) * PAD_SOFT.sigma_s
    assert np.all(asperity_contact(d, PAD_SOFT_INF).pressure > 0)
    assert np.all(asperity_contact(d, PAD_SOFT).pressure == 0)


@pytest.mark.parametrize("pad_name", list(PADS))
def test_elastic_model_has_identically_zero_elastoplastic_and_plastic_parts(pad_name):
    pad = PADS[pad_name]
    res = asperity_contact(np.linspace(-10, 3, 50) * pad.sigma_s, pad, "elastic")
    for q in ("area_ratio_elastoplastic", "area_ratio_plastic", "pressure_elastoplastic", "pressure_plastic"):
        assert np.all(getattr(res, q) == 0.0), q
    np.testing.assert_array_equal(res.pressure, res.pressure_elastic)
    np.testing.assert_array_equal(res.area_ratio, res.area_ratio_elastic)


@pytest.mark.parametrize("pad_name", ["soft", "stiff"])
def test_pressure_is_the_sum_of_its_parts_and_plastic_pressure_is_hardness_times_plastic_area(pad_name):
    pad = PADS[pad_name]
    res = asperity_contact(np.linspace(-10, 3, 50) * pad.sigma_s, pad, "lep")
    np.testing.assert_allclose(
        res.pressure, res.pressure_elastic + res.pressure_elastoplastic + res.pressure_plastic, rtol=1e-15
    )
    np.testing.assert_allclose(res.pressure_plastic, pad.hardness * res.area_ratio_plastic, rtol=1e-15)
    # the elastoplastic mean pressure lies between K H and H
    ep = res.area_ratio_elastoplastic > 0
    pm = res.pressure_elastoplastic[ep] / res.area_ratio_elastoplastic[ep]
    assert np.all((pm >= pad.k_factor * pad.hardness) & (pm <= pad.hardness))


@pytest.mark.parametrize("model", MODELS)
def test_output_shapes_follow_the_separation_shape_scalar_1d_2d(model):
    pad = PAD_STIFF
    grid = np.linspace(-2.0, 2.9, 12).reshape(3, 4) * pad.sigma_s
    res2 = asperity_contact(grid, pad, model)
    res1 = asperity_contact(grid.ravel(), pad, model)
    res0 = asperity_contact(float(grid[1, 2]), pad, model)
    for q in QUANTITIES + ("pressure_elastic", "pressure_elastoplastic", "pressure_plastic", "area_ratio"):
        a2, a1, a0 = getattr(res2, q), getattr(res1, q), getattr(res0, q)
        assert a2.shape == (3, 4) and a1.shape == (12,) and np.shape(a0) == ()
        np.testing.assert_array_equal(a2.ravel(), a1)
        assert float(a0) == a2[1, 2]
    area, load, regime = asperity_laws(np.ones((2, 5)) * pad.omega_e, pad, model)
    assert area.shape == load.shape == regime.shape == (2, 5)


# --- the solver's tabulation -----------------------------------------------------------------
@pytest.mark.parametrize("model", MODELS)
@pytest.mark.parametrize("pad_name", ["soft", "stiff"])
def test_contact_table_matches_the_kernel_to_1e_8_of_the_values_at_zero_separation(pad_name, model):
    pad = PADS[pad_name]
    table = ContactTable(pad, model)
    assert table.error_bound < 1e-8
    rng = np.random.default_rng(11)
    d = np.concatenate([rng.uniform(-8.0, 3.0, 4000), [-6.0, 3.0 - 1e-9, 3.0, 3.5]]) * pad.sigma_s
    got, ref = table(d), asperity_contact(d, pad, model)
    at0 = asperity_contact(0.0, pad, model)
    for q in QUANTITIES + ("pressure_elastic", "pressure_elastoplastic", "pressure_plastic"):
        scale = float(at0.pressure) if q.startswith("pressure") else float(at0.area_ratio)
        assert np.max(np.abs(getattr(got, q) - getattr(ref, q))) <= 1e-8 * scale, q
    assert np.all(got.pressure[d >= pad.height_cutoff * pad.sigma_s] == 0.0)
    assert table(d.reshape(4, -1)).pressure.shape == (4, d.size // 4)
    with pytest.raises(ValueError, match="height_cutoff"):
        ContactTable(PAD_SOFT_INF, model)


# --- argument checking -----------------------------------------------------------------------
_GOOD = dict(sigma_s=15e-6, asperity_density=1e8, asperity_radius=50e-6, e_star=110e6, hardness=20e6, poisson=0.3)


@pytest.mark.parametrize(
    "name, bad",
    [
        ("sigma_s", 0.0), ("sigma_s", -1e-6), ("sigma_s", np.nan), ("sigma_s", np.inf),
        ("asperity_density", 0.0), ("asperity_density", np.nan),
        ("asperity_radius", -50e-6), ("asperity_radius", np.inf),
        ("e_star", 0.0), ("e_star", np.nan),
        ("hardness", -20e6), ("hardness", np.inf),
        ("poisson", -0.1), ("poisson", 0.51), ("poisson", np.nan),
        ("height_cutoff", 0.4), ("height_cutoff", -3.0), ("height_cutoff", np.nan),
    ],
)
def test_invalid_pad_surface_argument_raises_value_error_naming_it(name, bad):
    with pytest.raises(ValueError, match=name):
        PadSurface(**{**_GOOD, name: bad})


def test_unknown_model_non_finite_separation_and_non_pad_raise_value_error_naming_the_argument():
    with pytest.raises(ValueError, match="model"):
        asperity_contact(0.0, PAD_SOFT, "plastic")
    with pytest.raises(ValueError, match="model"):
        asperity_laws(1e-6, PAD_SOFT, "hertz")
    with pytest.raises(ValueError, match="separation"):
        asperity_contact(np.array([0.0, np.nan]), PAD_SOFT)
    with pytest.raises(ValueError, match="pad"):
        asperity_contact(0.0, _GOOD)


def test_the_contact_tables_spline_is_scipys_not_a_knot_spline():
    """The contact table's own spline (so that a solve does not load scipy.interpolate: issue 31)
    is CubicSpline(x, y, axis=0): equal to round-off on random data and ends (bit for bit with
    scipy 1.17, measured), exact on cubics (the not-a-knot spline reproduces them) and at the nodes."""
    from scipy.interpolate import CubicSpline

    from cmpsim.physics.contact import _NotAKnotSpline

    rng = np.random.default_rng(7)
    for n in (4, 5, 17, 600):
        x = np.sort(rng.uniform(-3.0, 2.0, n))
        y = rng.normal(size=(n, 3)) * 1e-6
        q = np.concatenate([rng.uniform(x[0] - 0.2, x[-1] + 0.2, 400), x])
        mine, ref = _NotAKnotSpline(x, y)(q), CubicSpline(x, y, axis=0)(q)
        np.testing.assert_allclose(mine, ref, rtol=1e-12, atol=1e-12 * np.max(np.abs(y)))
        cubic = np.stack([2.0 - x + 0.5 * x**2 - 0.25 * x**3, 3.0 * x**3], axis=1)
        exact = np.stack([2.0 - q + 0.5 * q**2 - 0.25 * q**3, 3.0 * q**3], axis=1)
        np.testing.assert_allclose(_NotAKnotSpline(x, cubic)(q), exact, rtol=1e-9, atol=1e-9)
        np.testing.assert_allclose(_NotAKnotSpline(x, y)(x), y, rtol=1e-13, atol=1e-13 * np.max(np.abs(y)))
    with pytest.raises(ValueError, match="strictly increasing"):
        _NotAKnotSpline(np.array([0.0, 1.0, 1.0, 2.0]), np.zeros((4, 1)))
