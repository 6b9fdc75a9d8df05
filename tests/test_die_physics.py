"""cmpsim.die physics of issue 33: Ouma's elliptic weighting and the pad body's bulge into wide gaps.

Verification against independent closed forms (mpmath), then the comparisons with published data,
which are targets, not calibration: a failing comparison stays an xfail with its error.
"""

import json

import mpmath
import numpy as np
import pytest
from scipy.integrate import quad

import cmpsim
from cmpsim import die
from cmpsim.die.density import GaussianWeighting, effective_density
from cmpsim.die.elliptic import EllipticWeighting, elliptic_half_power, elliptic_profile, planarization_length_elliptic_from_pad
from cmpsim.die.layout import Layout
from cmpsim.die.pad import GAUSSIAN_HALF_POWER, top_layer
from cmpsim.die.reach import FeatureContact, clausen2, sin2_cubed_sum

K = 5e-9  # m/s


# ---------------------------------------------------------------------------- the elliptic kernel
@pytest.mark.parametrize("rho", [0.0, 0.3, 0.8, 0.999, 1.0, 1.001, 1.7, 4.0, 25.0])
def test_elliptic_profile_is_the_half_space_deflection_under_a_uniform_disc(rho):
    """Boussinesq's point-load deflection (1 - nu^2) F / (pi E r) summed over the unit disc, by mpmath:
    w(rho)/w(0) = (1/2 pi) int dA'/|x - x'| = (1/2 pi) int over directions of the chord length from x."""
    mpmath.mp.dps = 25
    if rho <= 1.0:
        ref = mpmath.quad(lambda p: -rho * mpmath.cos(p) + mpmath.sqrt(1 - (rho * mpmath.sin(p)) ** 2), mpmath.linspace(0, 2 * mpmath.pi, 5)) / (2 * mpmath.pi)
    else:
        edge = mpmath.asin(1 / mpmath.mpf(rho))
        ref = 2 * mpmath.quad(lambda p: 2 * mpmath.sqrt(max(0, 1 - (rho * mpmath.sin(p)) ** 2)), [0, edge]) / (2 * mpmath.pi)
    assert float(elliptic_profile(np.array([rho]))[0]) == pytest.approx(float(ref), rel=1e-12)


def test_elliptic_profile_limits():
    f = lambda r: float(elliptic_profile(np.array([r]))[0])  # noqa: E731
    assert f(0.0) == pytest.approx(1.0, rel=1e-15)
    assert f(1.0) == pytest.approx(2.0 / np.pi, rel=1e-15)  # L = 2a: the weight falls to 2/pi of its peak
    assert f(1e4) * 2e4 == pytest.approx(1.0, rel=1e-7)  # Boussinesq's point-load tail: w ~ q a^2 / (E* r) = w(0) a / 2r
    r = np.linspace(0, 5, 501)
    assert np.all(np.diff(elliptic_profile(r)) < 0)  # decreasing, continuous through r = a
    assert abs(f(1 - 1e-12) - f(1 + 1e-12)) < 1e-9


@pytest.mark.parametrize("truncation", [1.0, 2.0, 3.5])
def test_elliptic_weighting_has_unit_integral_and_transfer_one_at_zero(truncation):
    w = EllipticWeighting(4e-3, truncation)
    rt = truncation * w.radius
    total = 2 * np.pi * (quad(lambda r: float(w.weight(r)) * r, 0, w.radius, epsrel=1e-12)[0]
                         + (quad(lambda r: float(w.weight(r)) * r, w.radius, rt, epsrel=1e-12)[0] if truncation > 1 else 0.0))
    assert total == pytest.approx(1.0, rel=1e-10)
    assert float(w.weight(1.01 * rt)) == 0.0
    assert float(w.transfer(0.0)[0]) == pytest.approx(1.0, rel=1e-12)


def test_elliptic_grid_kernel_keeps_the_mean_the_bounds_and_the_continuous_transfer():
    rng = np.random.default_rng(3)
    rho = np.kron(rng.uniform(0.1, 0.9, (6, 6)), np.ones((20, 20)))
    w = EllipticWeighting(3e-3, 2.0)
    eff = effective_density(rho, 100e-6, w)
    assert abs(eff.mean() - rho.mean()) < 1e-14
    assert eff.min() >= rho.min() - 1e-12 and eff.max() <= rho.max() + 1e-12
    assert np.max(np.abs(effective_density(np.full((40, 40), 0.37), 100e-6, w) - 0.37)) < 1e-14
    # the cell-averaged kernel on a fine grid has the continuous Hankel transform at long waves
    n, cell = 256, 50e-6
    g = w.grid_transfer((n, n), cell)
    for m in (1, 3, 8):
        q = 2 * np.pi * m / (n * cell)
        assert g[0, m].real == pytest.approx(float(w.transfer(q)[0]), abs=2e-4)


def test_the_elliptic_length_of_a_pad_matches_the_gaussian_one_at_the_half_power_point():
    c = cmpsim.Config.default()
    lg, le = die.planarization_length_from_pad(c), planarization_length_elliptic_from_pad(c)
    assert le / lg == pytest.approx(elliptic_half_power(1.0) / GAUSSIAN_HALF_POWER, rel=1e-12)
    # the numbers of docs/model.md 18.3: 6.93 mm Gaussian, 10.80 mm elliptic cut at r = a
    assert lg == pytest.approx(6.93e-3, rel=2e-3) and le == pytest.approx(10.80e-3, rel=2e-3)
    # a longer tail smooths more: the same pad needs a shorter elliptic L
    tails = [planarization_length_elliptic_from_pad(c, t) for t in (1.0, 1.5, 2.0, 3.0, 4.0)]
    assert all(b < a for a, b in zip(tails, tails[1:]))


def _half(transfer, lo=0.1, hi=8.0):
    from scipy.optimize import brentq

    return brentq(lambda q: transfer(q) - 0.5, lo, hi, xtol=1e-12)


def _square_half_power():
    th = np.linspace(0, np.pi / 2, 4001)
    return _half(lambda q: float(np.mean(np.sinc(q * np.cos(th) / (2 * np.pi)) * np.sinc(q * np.sin(th) / (2 * np.pi)))))


def test_cylinder_over_square_matches_ouma_table_5_3():
    """Convention check (not a model prediction): fitted to the same smoothing (half-power point; the
    square direction-averaged), a disc of diameter L and a square of side L compare as Ouma's fits
    of one data set (Table 5.3 [second-hand]: 5.85 / 5.25 = 1.114); ours 1.148, within 3.1 %."""
    from scipy.special import j1

    ratio = _half(lambda q: 2 * j1(q / 2) / (q / 2)) / _square_half_power()
    assert ratio == pytest.approx(5.85 / 5.25, rel=0.04)


@pytest.mark.xfail(strict=True, reason="Ouma's Table 5.3 (second-hand) has elliptic / square = 7.35 / 5.25 = 1.40; "
                   "the half-space kernel as transcribed gives at most 1.19 (cut at r = a), -15 %, and less with any tail: "
                   "his kernel or its truncation is not the one transcribed (docs/model.md 18.2)")
def test_elliptic_over_square_matches_ouma_table_5_3():
    ratio = elliptic_half_power(1.0) / _square_half_power()
    assert ratio == pytest.approx(7.35 / 5.25, rel=0.05)


PUBLISHED_LENGTHS = [3.00e-3, 2.72e-3, 2.80e-3, 2.66e-3, 3.75e-3, 4.50e-3, 3.60e-3, 2.90e-3]  # elliptic fits, IC1000/Suba IV class


def test_elliptic_length_of_ic1000_suba_iv_against_the_published_elliptic_lengths():
    """Like with like: the default stack's length in Ouma's convention is 10.8 mm against 2.66-4.50 mm
    fitted with his elliptic kernel (Ouma et al. 1997 Table 3; Ouma 1998 Table 5.2 [second-hand]):
    2.4-4.1 times too long (+140 to +306 %). Pinned here; the comparison itself is the xfail below."""
    le = planarization_length_elliptic_from_pad(cmpsim.Config.default())
    errors = [le / p - 1 for p in PUBLISHED_LENGTHS]
    assert 1.39 < min(errors) < 1.41 and 3.05 < max(errors) < 3.07


@pytest.mark.xfail(strict=True, reason="the pad-derived elliptic planarization length (10.8 mm) is 2.4-4.1 times the published "
                   "IC1000/Suba IV elliptic lengths (2.66-4.50 mm): docs/validation.md")
def test_elliptic_length_of_ic1000_suba_iv_lies_in_the_published_range():
    le = planarization_length_elliptic_from_pad(cmpsim.Config.default())
    assert min(PUBLISHED_LENGTHS) <= le <= max(PUBLISHED_LENGTHS)


def test_die_command_reports_both_conventions_and_runs_the_elliptic_weighting():
    from click.testing import CliRunner

    from cmpsim.cli import main

    c = cmpsim.Config.default()
    args = ["die", "uniform", "--json", "--time", "1 min", "--blanket-rate", "100 nm/min"]
    ell = json.loads(CliRunner().invoke(main, args + ["--weighting", "elliptic"]).stdout)
    gau = json.loads(CliRunner().invoke(main, args).stdout)
    for d in (ell, gau):
        assert d["planarization_length_gaussian_from_pad"] == pytest.approx(die.planarization_length_from_pad(c), rel=1e-12)
        assert d["planarization_length_elliptic_from_pad"] == pytest.approx(planarization_length_elliptic_from_pad(c), rel=1e-12)
        assert d["units"]["planarization_length_elliptic_from_pad"] == "m" and d["elliptic_truncation"] == 1.0
    assert ell["weighting"] == "elliptic" and "2/pi" in ell["weighting_definition"]
    assert ell["planarization_length"] == pytest.approx(ell["planarization_length_elliptic_from_pad"])
    assert ell["planarization_length_from_pad"] == pytest.approx(ell["planarization_length_elliptic_from_pad"])
    assert gau["planarization_length"] == pytest.approx(gau["planarization_length_gaussian_from_pad"])
    user = json.loads(CliRunner().invoke(main, args + ["--weighting", "elliptic", "--planarization-length", "3 mm"]).stdout)
    assert user["planarization_length"] == pytest.approx(3e-3)


def test_elliptic_and_gaussian_at_matched_lengths_give_close_effective_densities():
    lay = die.builtin_layout("density", 250e-6)
    c = cmpsim.Config.default()
    g = die.simulate(lay, 0.0, config=c, blanket_rate=K).effective_density
    e = die.simulate(lay, 0.0, config=c, blanket_rate=K, weighting="elliptic").effective_density
    assert np.max(np.abs(e - g)) < 0.05  # same half-power point, different shapes: up to 4.8 % of density


# ---------------------------------------------------------------------------- the bulge into a gap
@pytest.mark.parametrize("theta", [1e-7, 0.02, 0.5, 1.3, np.pi / 2, 2.2, 3.1])
def test_clausen_sums_to_round_off(theta):
    mpmath.mp.dps = 30
    cl2 = mpmath.clsin(2, theta)
    s3 = (mpmath.zeta(3) - mpmath.re(mpmath.polylog(3, mpmath.exp(2j * theta)))) / 2
    assert float(clausen2(theta)) == pytest.approx(float(cl2), rel=1e-13, abs=1e-300)
    assert float(sin2_cubed_sum(theta)) == pytest.approx(float(s3), rel=1e-12, abs=1e-300)


@pytest.mark.parametrize("b, pitch", [(10e-6, 20e-6), (100e-6, 200e-6), (2e-6, 40e-6), (50e-6, 3e-3), (1e-6, 10e-3)])
def test_bulge_equals_the_direct_fourier_series(b, pitch):
    """G against the strip pattern's Fourier series summed term by term with the layer's own C(q) (10^6 terms, plus the half-space tail)."""
    c = cmpsim.Config.default()
    fc = FeatureContact.from_config(c)
    n = np.arange(1, 1_000_001, dtype=float)
    q = 2 * np.pi * n / pitch
    beta = b / pitch
    terms = np.sin(n * np.pi * beta) ** 2 / (np.pi**2 * n**2 * (1 - beta)) + np.sin(n * np.pi * beta) / (np.pi * n)
    direct = 2 * np.sum(top_layer(c).compliance(q) * terms)
    assert float(fc.compliance_difference(b, pitch)) == pytest.approx(direct, rel=2e-6)


def test_bulge_limits():
    hs = FeatureContact(27.6e3, 300e6, 0.3, 1.27e-3)  # half space
    e_star = 300e6 / 0.91
    b, lam = 1e-6, 1.0  # an isolated strip: G -> (2 b / pi E*) (1 + ln(lambda / pi b))
    assert float(hs.compliance_difference(b, lam)) == pytest.approx(2 * b / (np.pi * e_star) * (1 + np.log(lam / (np.pi * b))), rel=1e-5)
    # at fixed density the half-space bulge scales with the width
    g = hs.compliance_difference(np.array([1e-6, 1e-5, 1e-4]), np.array([2e-6, 2e-5, 2e-4]))
    assert np.allclose(g / g[0], [1, 10, 100], rtol=1e-12)
    # the finite pad cuts the logarithm of an isolated line off at about its thickness
    fc = FeatureContact.from_config(cmpsim.Config.default())
    iso = fc.compliance_difference(100e-6, np.array([1e-2, 1e-1, 1.0]))
    assert abs(iso[2] / iso[1] - 1) < 5e-3 and iso[0] < hs.compliance_difference(100e-6, 1e-2)
    assert np.isnan(fc.compliance_difference(np.nan, 1e-4)) and float(fc.bulge(np.nan, 1e-4, 0.5)) == 0.0


def _blocks(rhos, widths, block=8, cell=250e-6):
    return Layout(np.kron(np.asarray([rhos], float), np.ones((block, block))), cell,
                  np.kron(np.asarray([widths], float), np.ones((block, block))), "blocks")


WIDTHS = np.array([0.25, 0.35, 0.5, 1.0, 2.0, 5.0, 10.0, 25.0, 50.0, 100.0]) / 1e6


def _dishing(rhos, feature_contact="elastic"):
    regs = die.simulate(_blocks(rhos, WIDTHS), None, config=cmpsim.Config.default(), blanket_rate=K, planarization_length=0.5e-3,
                        process="copper", feature_contact=feature_contact).to_dict()["regions"]
    by = {r["line_width"]: r["dishing"] for r in regs}
    return np.array([by[w] for w in WIDTHS])


def test_dishing_keeps_growing_from_10_to_100_um_lines():
    d = _dishing([0.5] * len(WIDTHS))
    wide = d[WIDTHS >= 10e-6]
    assert np.all(np.diff(wide) > 0)
    # measured on this die (50 %, 30 % over-polish): 97.1 / 98.6 / 101.2 / 106.4 nm at 10 / 25 / 50 / 100 um
    assert wide * 1e9 == pytest.approx([97.1, 98.6, 101.2, 106.4], abs=0.1)
    # the summit sagitta alone (cmpsim 0.3, feature_contact="summit") saturates: 96.06 nm from 10 um
    old = _dishing([0.5] * len(WIDTHS), "summit")
    assert np.ptp(old[WIDTHS >= 10e-6]) < 1e-12 and old[-1] * 1e9 == pytest.approx(96.06, abs=0.01)
    assert np.all(d >= old)


# Tugbawa, PhD MIT 2002, Fig. 3.12, isolated lines, read off the figure (+-4 nm) [second-hand]
TUGBAWA_ISOLATED = {0.25e-6: 25e-9, 0.35e-6: 27e-9, 0.5e-6: 33e-9, 1e-6: 66e-9, 2e-6: 100e-9, 5e-6: 122e-9, 10e-6: 140e-9}


def _isolated():
    """Isolated lines: width w in a space of 100 um (Tugbawa's fit stops depending on the space near 100 um)."""
    d = _dishing(WIDTHS / (WIDTHS + 100e-6))
    return {w: (float(d[np.argmin(np.abs(WIDTHS - w))]), ref) for w, ref in TUGBAWA_ISOLATED.items()}


def test_isolated_line_dishing_against_tugbawa_fig_3_12_errors():
    """The errors, pinned (they are the validation page's table): -95 % at 0.25 um, -29 % at 10 um."""
    err = {w: m / ref - 1 for w, (m, ref) in _isolated().items()}
    assert err[0.25e-6] == pytest.approx(-0.954, abs=0.005) and err[10e-6] == pytest.approx(-0.291, abs=0.005)
    assert all(e < 0 for e in err.values())


@pytest.mark.xfail(strict=True, reason="isolated-line dishing 1.2-99 nm for 0.25-10 um lines against Tugbawa's 25-140 nm "
                   "(Fig. 3.12): -95 % to -20 %, the narrow lines far too shallow (docs/validation.md)")
def test_isolated_line_dishing_within_20_percent_of_tugbawa_fig_3_12():
    for w, (m, ref) in _isolated().items():
        assert m == pytest.approx(ref, rel=0.2), w


@pytest.mark.xfail(strict=True, reason="dishing at 50 % density grows 97 -> 106 nm from 10 to 100 um lines; Tugbawa's fit "
                   "d = B w^a2 s^b2 (B = 31 nm, a2 = 0.303, b2 = 0.275, [second-hand]) gives 117 -> 444 nm: -17 % to -76 %")
def test_wide_line_dishing_within_20_percent_of_tugbawas_fit():
    d = _dishing([0.5] * len(WIDTHS))
    for w, m in zip(WIDTHS, d):
        if w >= 10e-6:
            fit = 31e-9 * (w / 1e-6) ** 0.303 * (w / 1e-6) ** 0.275
            assert m == pytest.approx(fit, rel=0.2), w


def test_the_spline_tables_of_the_clausen_sums_equal_the_quadrature():
    """Above TABLE_ABOVE points (a whole chip's windows) the smooth integrals come from spline tables:
    the sums agree with the quadrature, point by point, to 1e-14 absolute (values up to about 1)."""
    from cmpsim.die import reach

    theta = np.random.default_rng(3).uniform(0.0, np.pi, reach.TABLE_ABOVE + 1000)
    exact_cl2 = np.array([float(clausen2(t)) for t in theta[:2000]])
    exact_s3 = np.array([float(sin2_cubed_sum(t)) for t in theta[:2000]])
    np.testing.assert_allclose(clausen2(theta)[:2000], exact_cl2, rtol=0, atol=1e-14)
    np.testing.assert_allclose(sin2_cubed_sum(theta)[:2000], exact_s3, rtol=0, atol=1e-14)
