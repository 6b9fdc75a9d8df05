"""The abrasive removal law (issue 24): kernels checked by hand, limits, continuity, zero loading."""

from __future__ import annotations

import math
import warnings

import mpmath
import numpy as np
import pytest

import cmpsim
from cmpsim.physics.abrasion import (
    AbrasiveContact,
    abrasive_removal_rate,
    groove_area,
    interference,
    pad_force,
    pad_gap,
    size_nodes,
    sphere_load,
    size_hardness,
    summit_sharing,
)
from cmpsim.physics.contact import PadSurface, asperity_contact, asperity_laws, contact_spot_density
from cmpsim.physics.kinetics import chemical_rate, flash_temperature, series_rate
from cmpsim.models.removal_laws import abrasive_contact

# silica (E 72 GPa, nu 0.17, H 9 GPa) on oxide (the same constants): the default pair
E_SIO2, NU_SIO2, H_SIO2 = 72e9, 0.17, 9e9


def silica_on_oxide(**kw):
    c = (1 - NU_SIO2**2) / E_SIO2
    args = dict(diameter=100e-9, diameter_std=0.0, volume_fraction=0.06, pad_pressure=50e6, e_star=1 / (2 * c),
                hardness=H_SIO2, k_factor=0.454 + 0.41 * NU_SIO2, film_share=0.5, efficiency=0.1)
    args.update(kw)
    return AbrasiveContact(**args)


def test_a_single_hertz_summit_removes_what_the_hand_calculation_gives():
    """One elastic pad summit (R = 7 um, interference 1 um, E' = 0.55 GPa) on 1e-10 m^2 of wafer,
    100 nm silica at phi = 0.06 on oxide, 0.63 m/s, worked by hand step by step."""
    R, w, e_pad, area_n = 7e-6, 1e-6, 0.55e9, 1e-10
    a_real = math.pi * R * w  # Hertz contact area, m^2
    load = 4 / 3 * e_pad * math.sqrt(R) * w**1.5  # N
    p_c, a_r = load / area_n, a_real / area_n
    p_r = load / a_real  # 1.94 mN on 22.0 um^2: 88.2 MPa mean real pressure on the summit
    # 1. trapped particles per unit real area: n = phi / (pi d^3/6) * d = 6 phi / (pi d^2)
    d, phi = 100e-9, 0.06
    n = 6 * phi / (math.pi * d**2)  # 1.146e13 1/m^2
    # 2. sparse? the particles could carry n * 50 MPa * pi r^2 = 1.5 phi * 50 MPa = 4.5 MPa < p_r: the pad touches the wafer
    assert n * 50e6 * math.pi * (d / 2) ** 2 < p_r
    F = 50e6 * math.pi * (d / 2) ** 2  # 3.927e-7 N per particle
    # 3. elastic? Hertz load at omega_e = (3 pi K H / 4 E*)^2 r exceeds F
    e_star = E_SIO2 / (2 * (1 - NU_SIO2**2))
    K = 0.454 + 0.41 * NU_SIO2
    omega_e = (3 * math.pi * K * H_SIO2 / (4 * e_star)) ** 2 * (d / 2)
    assert 4 / 3 * e_star * math.sqrt(d / 2) * omega_e**1.5 > F
    omega = (3 * F / (4 * e_star * math.sqrt(d / 2))) ** (2 / 3)  # Hertz interference, 1.08 nm
    depth = omega / 2  # equal compliances: the film takes half
    # 4. circular segment of depth `depth` of a circle of radius d/2
    r = d / 2
    segment = r**2 * math.acos(1 - depth / r) - (r - depth) * math.sqrt(2 * r * depth - depth**2)
    # 5. rate
    expected = 0.1 * a_r * 0.63 * n * segment
    got = abrasive_removal_rate(np.array([p_c]), np.array([a_r]), np.array([0.63]), silica_on_oxide())
    assert got.rate[0] == pytest.approx(expected, rel=1e-9)
    # by hand: n = 1.146e13 1/m^2, F = 0.393 uN, omega = 1.082 nm, segment ~ (4/3) sqrt(2r) (0.541 nm)^1.5 = 5.30e-18 m^2: RR = 0.1 x 0.2199 x 0.63 m/s x 1.146e13 x 5.30e-18 = 8.42e-7 m/s = 5.05e4 nm/min
    assert got.rate[0] * 6e10 == pytest.approx(5.05e4, rel=0.01)
    assert got.gap[0] == 0.0 and got.depth[0] == pytest.approx(depth, rel=1e-12)
    assert got.active_particles[0] == pytest.approx(a_r * n, rel=1e-12)
    # counted summit by summit (one summit on area_n): M = n A_1 = 252 particles in the contact,
    # and it would take k* = 1.94 mN / 0.393 uN = 4.9e3 of them to prop it: the same rate
    summit = abrasive_removal_rate(np.array([p_c]), np.array([a_r]), np.array([0.63]), silica_on_oxide(), np.array([1 / area_n]))
    assert n * a_real == pytest.approx(252.0, rel=1e-3) and load / F > 4900
    assert summit.rate[0] == pytest.approx(expected, rel=1e-12)


def _few_particle_summit(p_scale=1.0):
    """One Hertz summit (R = 7 um, interference 0.1 um, E' = 0.55 GPa) on 1e-10 m^2, 1 um silica at phi = 0.06."""
    R, w, e_pad, area_n = 7e-6, 0.1e-6, 0.55e9, 1e-10
    a_real = math.pi * R * w
    load = 4 / 3 * e_pad * math.sqrt(R) * w**1.5 * p_scale
    return load, a_real, area_n


def test_a_summit_holding_few_large_particles_shares_its_load_as_worked_by_hand():
    """Step 2b (docs/model.md, 13e.1) by hand: k ~ Poisson(M) particles in the summit contact; one is
    wrapped by the pad (F_w = p_pad pi r^2), two or more prop the summit and share its load F_s."""
    load, a_real, area_n = _few_particle_summit()
    d, phi, p_pad = 1e-6, 0.06, 50e6
    n = 6 * phi / (math.pi * d**2)
    M = n * a_real  # 0.252 particles per summit contact
    F_w = p_pad * math.pi * (d / 2) ** 2  # 39.3 uN
    k_star = load / F_w  # 1.56: one particle is wrapped, two prop the summit
    assert 0.25 < M < 0.26 and 1 < k_star < 2
    e_star = E_SIO2 / (2 * (1 - NU_SIO2**2))

    def segment(F):  # elastic (checked below), film takes half the Hertz interference
        r = d / 2
        omega = (3 * F / (4 * e_star * math.sqrt(r))) ** (2 / 3)
        assert omega < (3 * math.pi * (0.454 + 0.41 * NU_SIO2) * H_SIO2 / (4 * e_star)) ** 2 * r
        depth = omega / 2
        return r**2 * math.acos(1 - depth / r) - (r - depth) * math.sqrt(2 * r * depth - depth**2)

    per_real_area = sum(math.exp(-M) * M**k / math.factorial(k) * (k / M) * n * segment(F_w if k <= k_star else load / k)
                        for k in range(1, 40))
    expected = 0.1 * (a_real / area_n) * 0.63 * per_real_area
    got = abrasive_removal_rate(np.array([load / area_n]), np.array([a_real / area_n]), np.array([0.63]),
                                silica_on_oxide(diameter=d), np.array([1 / area_n])).rate[0]
    assert got == pytest.approx(expected, rel=1e-9)
    # the summits with two or more particles carry F_s / k < F_w each: counted summit by summit the
    # rate is lower than the continuum rule (every particle wrapped, M << k* on average)
    continuum = abrasive_removal_rate(np.array([load / area_n]), np.array([a_real / area_n]), np.array([0.63]), silica_on_oxide(diameter=d)).rate[0]
    assert got < continuum


def test_the_rate_is_continuous_where_a_summit_starts_to_rest_on_its_particles():
    """Crossing k* = 2 (two wrapped particles carry exactly the summit load) changes nothing abruptly."""
    load, a_real, area_n = _few_particle_summit()
    F_w = 50e6 * math.pi * (0.5e-6) ** 2
    scale = 2 * F_w / load  # summit load at which k* = 2 exactly
    rates = [abrasive_removal_rate(np.array([scale * (1 + eps) * load / area_n]), np.array([a_real / area_n]), np.array([0.63]),
                                   silica_on_oxide(diameter=1e-6), np.array([1 / area_n])).rate[0] for eps in (-1e-10, 1e-10)]
    assert rates[1] / rates[0] - 1 == pytest.approx(0.0, abs=1e-8)


@pytest.mark.parametrize("phi, p_pad", [(0.06, 50e6), (0.5, 100e6)])  # pad touches the wafer / particles carry p_r
def test_summit_counting_tends_to_the_continuum_rule_for_large_summit_contacts(phi, p_pad):
    pc, ar, u = np.array([48e3, 20e3]), np.array([1e-3, 4e-4]), np.array([1.0, 0.63])
    c = silica_on_oxide(volume_fraction=phi, pad_pressure=p_pad)
    continuum = abrasive_removal_rate(pc, ar, u, c).rate
    summits = abrasive_removal_rate(pc, ar, u, c, np.array([1e5, 1e5])).rate  # A_1 = 4-10 mm^2
    np.testing.assert_allclose(summits, continuum, rtol=1e-7)


def test_particle_size_matters_only_against_the_summit_contact():
    """At the default contact state (48 kPa: A_r/A_n = 1e-3, 1.42e7 summits/m^2, A_1 = 72 um^2) the
    summit length is ~5 um: up to 2 um nothing changes; particles as large as the contact remove less."""
    pc, ar, N = np.array([48e3]), np.array([1e-3]), np.array([1.42e7])

    def rate(d, summits):
        return abrasive_removal_rate(pc, ar, np.array([1.0]), silica_on_oxide(diameter=d), summits).rate[0]

    for d in (50e-9, 300e-9, 1e-6, 2e-6):
        assert rate(d, N) == pytest.approx(rate(d, None), rel=1e-12)
    assert rate(5e-6, N) < rate(2e-6, N) and rate(10e-6, N) < 0.9 * rate(5e-6, N)


def test_contact_spot_density_counts_the_summits_above_the_separation():
    pad = PadSurface(sigma_s=5e-6, asperity_density=2e8, asperity_radius=7e-6, e_star=0.55e9, hardness=50e6, poisson=0.3)
    D = np.array([-40e-6, 0.0, 7.3e-6, 15e-6, 16e-6])
    got = contact_spot_density(D, pad)
    mp = [mpmath.quad(lambda z: mpmath.npdf(z), [d / 5e-6, 3]) / mpmath.ncdf(3) * 2e8 if d < 15e-6 else 0 for d in D]
    np.testing.assert_allclose(got, [float(v) for v in mp], rtol=1e-12, atol=1e-300)
    assert got[0] == pytest.approx(2e8, rel=1e-12) and got[-1] == 0.0
    # every summit in contact has a contact: with the real area it gives a positive mean contact area
    assert np.all(asperity_contact(D[:3], pad).area_ratio > 0)


def test_the_sphere_law_is_the_per_summit_law_of_the_contact_module():
    pad = PadSurface(sigma_s=1e-6, asperity_density=1e8, asperity_radius=50e-9, e_star=37e9, hardness=9e9, poisson=0.17)
    omega = np.geomspace(1e-3, 200, 400) * pad.omega_e
    area, load, regime = asperity_laws(omega, pad)
    assert set(regime) == {1, 2, 3}
    np.testing.assert_allclose(sphere_load(omega, 50e-9, 37e9, 9e9, pad.k_factor), load, rtol=1e-13)


def test_the_interference_inverts_the_sphere_law_in_every_regime():
    r, e, h, k = 50e-9, 37e9, 9e9, 0.52
    we = (3 * math.pi * k * h / (4 * e)) ** 2 * r
    omega = np.geomspace(1e-3, 300, 500) * we
    loads = sphere_load(omega, r, e, h, k)
    np.testing.assert_allclose(interference(loads, r, e, h, k), omega, rtol=1e-12)
    assert interference(np.array([0.0]), r, e, h, k)[0] == 0.0


def test_the_groove_section_is_the_circular_segment_to_mpmath_precision():
    r = 50e-9
    with mpmath.workdps(40):
        for depth in [1e-15, 1e-12, 3e-10, 2.4e-9, 1e-8, 5e-8, 9e-8]:
            rr, dd = mpmath.mpf(r), mpmath.mpf(depth)
            exact = rr**2 * mpmath.acos(1 - dd / rr) - (rr - dd) * mpmath.sqrt(2 * rr * dd - dd**2)
            assert float(groove_area(r, depth)) == pytest.approx(float(exact), rel=1e-13)


def test_the_rate_is_continuous_across_the_elastic_plastic_indentation_boundaries():
    """Vary the pad's pressure on the particles so that their load crosses the film's first
    yield (omega_e) and full plasticity (54 omega_e): the rate has no jump at either."""
    base = silica_on_oxide()
    r = base.diameter / 2
    we = (3 * math.pi * base.k_factor * base.hardness / (4 * base.e_star)) ** 2 * r
    for omega_b in (we, 54 * we):
        f_b = float(sphere_load(omega_b * (1 - 1e-15), r, base.e_star, base.hardness, base.k_factor))
        p_b = f_b / (math.pi * r**2)  # pad pressure at which a particle carries exactly f_b
        rates = []
        for eps in (-1e-9, 1e-9):
            c = silica_on_oxide(pad_pressure=p_b * (1 + eps))
            rates.append(abrasive_removal_rate(np.array([1e5]), np.array([1e-3]), np.array([1.0]), c).rate[0])
        assert rates[1] / rates[0] - 1 == pytest.approx(0.0, abs=1e-8)
    # and it is increasing across the whole range (no step down either)
    p = np.geomspace(0.1, 1e3, 300) * 1e6
    rr = [abrasive_removal_rate(np.array([1e5]), np.array([1e-3]), np.array([1.0]), silica_on_oxide(pad_pressure=q)).rate[0] for q in p]
    assert np.all(np.diff(rr) > 0)


def test_the_law_is_prestons_where_the_real_contact_area_follows_the_load():
    """Luo & Dornfeld's limit: with summits of constant mean real pressure (fully plastic pad
    summits, A_r = p_c / H_pad, or Greenwood-Williamson's exponential heights) and particles
    that do not carry the whole real pressure, RR = k_p p_c |du| with one k_p."""
    h_pad = 50e6
    pc = np.array([5e3, 14e3, 27.6e3, 41e3])
    u = np.array([0.3, 0.63, 1.0, 1.75])
    P, U = np.meshgrid(pc, u)
    rr = abrasive_removal_rate(P, P / h_pad, U, silica_on_oxide()).rate
    k_p = rr / (P * U)
    np.testing.assert_allclose(k_p, k_p.flat[0], rtol=1e-12)


@pytest.mark.parametrize("summits", [None, np.array([1.4e7, 0.0])])
def test_zero_loading_removes_nothing_without_a_division_by_zero(summits):
    with np.errstate(all="raise"):
        got = abrasive_removal_rate(np.array([27e3, 0.0]), np.array([1e-3, 0.0]), np.array([0.63, 0.63]), silica_on_oxide(volume_fraction=0.0), summits)
    assert np.all(got.rate == 0.0) and np.all(got.active_particles == 0.0)


def test_summit_sharing_rejects_negative_counts():
    with pytest.raises(ValueError, match="mean_count"):
        summit_sharing(np.array([-1.0]), np.array([1.0]), np.array([1e6]), np.array([1e-7]), np.array([1e12]), 50e6, lambda f, x: f * 0)


def test_zero_loading_in_a_solve_gives_zero_removal_and_says_so():
    with pytest.warns(RuntimeWarning, match="solids_loading = 0: no abrasive particles"):
        r = cmpsim.solve(solids_loading=0, grid="coarse", relative=False)
    assert r.removal_rate_mean == 0.0
    assert r.contact_load_fraction > 0  # the pad still touches the wafer


def test_at_fixed_mass_loading_the_rate_does_not_depend_on_the_particle_size():
    """The model's size law (docs/model.md, 'How the rate depends on size and loading'): n ~ 1/d^2
    particles each carrying F ~ d^2 and ploughing a groove ~ d^2: the product is size-free."""
    rates = [abrasive_removal_rate(np.array([27e3]), np.array([6e-4]), np.array([0.63]), silica_on_oxide(diameter=d)).rate[0]
             for d in (20e-9, 100e-9, 1e-6, 2e-6)]
    np.testing.assert_allclose(rates, rates[0], rtol=1e-9)
    # and while the pad touches the wafer, a spread of sizes changes nothing either (sum n A_g ~ <x^3>/<x^3>)
    spread = abrasive_removal_rate(np.array([27e3]), np.array([6e-4]), np.array([0.63]), silica_on_oxide(diameter_std=40e-9)).rate[0]
    assert spread == pytest.approx(rates[0], rel=1e-9)


def test_while_the_pad_touches_the_wafer_the_rate_is_proportional_to_the_loading():
    rr = [abrasive_removal_rate(np.array([27e3]), np.array([6e-4]), np.array([0.63]), silica_on_oxide(volume_fraction=phi)).rate[0]
          for phi in (0.01, 0.02, 0.04)]
    np.testing.assert_allclose(np.array(rr) / rr[0], [1, 2, 4], rtol=1e-12)


def test_when_the_particles_hold_the_pad_off_the_wafer_they_share_the_real_pressure():
    """Dense slurry, mean real pressure low: the pad rests on the particles at a gap g where
    they carry p_r together; with a size spread the largest ones carry most (Luo & Dornfeld 2003)."""
    x, w = size_nodes(100e-9, 30e-9)
    assert np.sum(w) == pytest.approx(1.0) and np.sum(w * x) == pytest.approx(100e-9, rel=1e-9)
    assert np.sqrt(np.sum(w * (x - 100e-9) ** 2)) == pytest.approx(30e-9, rel=1e-6)
    n = 0.4 / np.sum(w * np.pi * x**3 / 6) * w * x
    p_r = np.array([5e6])
    g = pad_gap(p_r, x, n, 50e6)
    assert g[0] > 0
    carried = np.sum(n * pad_force(x - g[0], x / 2, 50e6))
    assert carried == pytest.approx(p_r[0], rel=1e-9)
    loads = pad_force(x - g[0], x / 2, 50e6)
    assert np.all(np.diff(loads) >= 0) and loads[0] == 0.0  # the smallest are idle


def test_the_default_model_uses_the_abrasive_law_of_its_config():
    c = cmpsim.Config.default()
    a = abrasive_contact(c)
    assert (c.removal_law, c.abrasive, c.film) == ("abrasive", "silica", "oxide")
    assert a.pad_pressure == c.pad_hardness  # IC1000 flows around the particles: 4 E'/(3 pi) = 0.23 GPa > H
    assert a.film_share == pytest.approx(0.5)
    cu = abrasive_contact(c.replace(film="copper", abrasive="alumina"))
    assert cu.hardness == 1.5e9 and cu.film_share > 0.5  # copper is the softer, more compliant body


def test_the_chemical_step_limits_the_rate_in_series():
    mech = np.array([1e-9, 1e-9, 0.0, 0.0])
    chem = np.array([1e-9, 1e-6, 1e-9, 0.0])
    np.testing.assert_allclose(series_rate(chem, mech), [0.5e-9, 1e-9 / (1 + 1e-3), 0.0, 0.0], rtol=1e-12)
    t = flash_temperature(298.15, 0.4, 27.6e3, 0.63, 1e-3)
    assert t == pytest.approx(298.15 + 1e-3 * 0.4 * 27.6e3 * 0.63)
    assert chemical_rate(298.15, 3e-9, 50e3, 298.15) == pytest.approx(3e-9)
    assert chemical_rate(t, 3e-9, 50e3, 298.15) > 3e-9  # friction heats, the chemistry speeds up


def test_two_step_kinetics_in_a_solve_is_slower_than_either_step_alone():
    mech = cmpsim.solve(grid="coarse", relative=False)
    both = cmpsim.solve(grid="coarse", relative=False, removal_kinetics="two_step")
    assert 0 < both.removal_rate_mean < mech.removal_rate_mean
    assert both.removal_rate_mean < both.config.chemical_rate * 1.1  # below the (slightly heated) chemical rate


def test_the_new_inputs_sweep_with_units_and_choices(tmp_path):
    """Every new input is an ordinary registry input: a sweep takes solids_loading in % and the abrasive by name."""
    import tomllib

    from cmpsim.sweeps import SweepSpec, sweep

    spec = SweepSpec.from_mapping(tomllib.loads('[base]\ngrid = "coarse"\n[axes]\nsolids_loading = ["2 %", "4 %"]\nabrasive = ["silica", "alumina"]\n'))
    ds = sweep(spec, workers=0, progress=False)
    assert ds["solids_loading"].values.tolist() == [pytest.approx(0.02), pytest.approx(0.04)]
    rr = ds["removal_rate_mean"]
    ratio = (rr.sel(abrasive="silica").isel(solids_loading=1) / rr.sel(abrasive="silica").isel(solids_loading=0)).item()
    assert ratio == pytest.approx(2.0, rel=0.03)  # proportional to the loading (docs/model.md, 13e.6)
    assert rr.sel(abrasive="alumina").isel(solids_loading=0).item() != rr.sel(abrasive="silica").isel(solids_loading=0).item()


def test_the_two_step_constants_can_be_calibrated(tmp_path):
    """`cmpsim calibrate --free chemical_rate` fits the chemical step to data it limits."""
    truth = cmpsim.Config.default().replace(grid="coarse", removal_kinetics="two_step", chemical_rate="60 nm/min")
    fit = _recalibrate(tmp_path, truth, "applied_pressure", ("2 psi", "4 psi", "6 psi"), "chemical_rate", "150 nm/min")
    assert fit.values["chemical_rate"] * 6e10 == pytest.approx(60.0, rel=1e-3)


def _recalibrate(tmp_path, truth, column, values, free, start):
    """Write the removal rates `truth` computes at `column` = each of `values` as a data file and
    calibrate `free` on it from `start` (a round trip through `cmpsim calibrate`)."""
    from cmpsim import calibrate

    rows = []
    for v in values:
        r = cmpsim.solve(truth, **{column: v}, relative=False)
        rows.append(f"synthetic,removal_rate,{r.removal_rate_mean * 6e10:.6f},nm/min,0.1,absolute,{v}")
    path = tmp_path / "synthetic.csv"
    path.write_text("# dataset: synthetic\n# citation: made by the model\n# provenance: test\n# conditions: default\n"
                    f"dataset,quantity,value,unit,uncertainty,comparison,{column}\n" + "\n".join(rows) + "\n")
    return calibrate(path, free=[free], config=truth.replace(**{free: start}), progress=False)


def test_the_removal_rates_quoted_in_the_docs_are_what_the_default_model_computes():
    """docs/model.md 13e.6, CHANGELOG: base case 117.53 nm/min with the abrasive law (88.41 with the
    shear-power law, the default before issue 24); 187.38 nm/min at Lai's conditions for copper and alumina
    (187.31 before eq. 8 was continued below 0.4: docs/model.md, section 5).
    On the equal-ring 24x64 grid, where the docs quote them (the edge-graded default grid of issue 23
    gives 118.10, 88.85 and 188.42)."""
    base = cmpsim.solve(relative=False, grid="24x64")
    old = cmpsim.solve(relative=False, removal_law="shear_power", grid="24x64")
    lai = cmpsim.solve(relative=False, film="copper", abrasive="alumina", applied_pressure="48 kPa", rotation_speed="75 rpm",
                       centre_distance="89.13 mm", wafer_diameter="100 mm", particle_diameter="300 nm", grid="24x64")
    assert round(base.removal_rate_mean * 6e10, 2) == 117.53
    assert round(old.removal_rate_mean * 6e10, 2) == 88.41
    assert round(lai.removal_rate_mean * 6e10, 2) == 187.38
    # the film, pressure and contact of the default did not move (only the removal law changed)
    assert base.film_thickness_center == old.film_thickness_center and base.contact_load_fraction == old.contact_load_fraction


# ------------------------------------------------------------------ indentation size effect (13e.8)
# alpha-alumina on copper (cmpsim.physics.materials): the particle-film contact of Lai's size series
def alumina_on_copper(**kw):
    ca, cf = (1 - 0.231**2) / 416e9, (1 - 0.34**2) / 128e9
    args = dict(diameter=300e-9, diameter_std=0.0, volume_fraction=0.03, pad_pressure=50e6, e_star=1 / (ca + cf),
                hardness=1.5e9, k_factor=0.454 + 0.41 * 0.34, film_share=cf / (ca + cf), efficiency=0.1, hardness_limit=15e9)
    args.update(kw)
    return AbrasiveContact(**args)


def test_the_size_hardness_is_nix_gao_for_a_sphere_to_mpmath_precision():
    r = np.array([10e-9, 25e-9, 150e-9, 500e-9, 1e-3])
    got = size_hardness(r, 0.58e9, 8.3e-6)
    with mpmath.workdps(40):
        ref = [float(mpmath.mpf("0.58e9") * mpmath.sqrt(1 + mpmath.mpf("8.3e-6") / mpmath.mpf(x))) for x in r]
    np.testing.assert_allclose(got, ref, rtol=1e-15)
    # R* = 0 is the hardness itself, bit for bit; the limit caps it (the other body yields beyond it)
    assert np.array_equal(size_hardness(r, 1.5e9, 0.0), np.full(5, 1.5e9))
    capped = size_hardness(r, 0.58e9, 8.3e-6, limit=5e9)
    assert capped.max() == 5e9 and np.array_equal(capped[2:], got[2:])


def test_the_indentation_with_a_size_dependent_hardness_matches_an_mpmath_root():
    """Solve sphere_load(omega; r, E*, H(r), K) = F at 40 digits (the law written out: Hertz, ZMC,
    plastic) for particles loaded by the pad, each size with its own hardness, and compare."""
    c = alumina_on_copper(size_length=1e-6)
    x = np.array([50e-9, 300e-9, 1000e-9])
    F = pad_force(x, 0.5 * x, c.pad_pressure)
    H = c.hardness_at(x)
    got = interference(F, 0.5 * x, c.e_star, H, c.k_factor)
    regimes = set()
    with mpmath.workdps(40):
        for Fi, xi, Hi, gi in zip(F, x, H, got):
            R, E, K, Hm = mpmath.mpf(xi) / 2, mpmath.mpf(c.e_star), mpmath.mpf(c.k_factor), mpmath.mpf(Hi)
            we = (3 * mpmath.pi * K * Hm / (4 * E)) ** 2 * R
            wp = 54 * we

            def load(w):
                if w < we:
                    return mpmath.mpf(4) / 3 * E * mpmath.sqrt(R) * w**1.5
                if w < wp:
                    u = (w - we) / (wp - we)
                    area = mpmath.pi * R * w * (1 + u * u * (3 - 2 * u))
                    return Hm * (1 - (1 - K) * mpmath.log(wp / w) / mpmath.log(54)) * area
                return 2 * mpmath.pi * R * w * Hm

            w = mpmath.findroot(lambda w: load(w) - mpmath.mpf(Fi), (we * mpmath.mpf("1.0000001"), wp), solver="anderson") if load(we) < Fi < load(wp) else mpmath.findroot(lambda w: load(w) - mpmath.mpf(Fi), mpmath.mpf(gi))
            regimes.add("elastic" if w < we else "elastoplastic" if w < wp else "plastic")
            assert gi == pytest.approx(float(w), rel=1e-11)
    assert "elastoplastic" in regimes


def test_without_a_size_length_the_law_is_todays_bit_for_bit_and_tends_to_it_continuously():
    args = (np.array([2e4, 8e4]), np.array([4e-4, 1.7e-3]), np.array([0.7, 0.7]))
    for x in (50e-9, 300e-9, 1000e-9):
        plain = abrasive_removal_rate(*args, alumina_on_copper(diameter=x, hardness_limit=np.inf))
        zero = abrasive_removal_rate(*args, alumina_on_copper(diameter=x, size_length=0.0))
        assert np.array_equal(plain.rate, zero.rate) and np.array_equal(plain.depth, zero.depth)
        # R* -> 0: the rate tends to today's, with the first-order change of H = H_0 (1 + R*/2r)
        for length in (1e-12, 1e-14):
            small = abrasive_removal_rate(*args, alumina_on_copper(diameter=x, size_length=length)).rate
            assert np.all(small < plain.rate) and np.allclose(small / plain.rate - 1, 0.0, atol=2 * length / x)


def test_with_a_size_length_copper_is_harder_under_small_particles_and_the_rate_rises_with_size():
    """The mechanism, not a comparison with data: at a fixed mass loading today's law is flat in
    size; with R* > 0 small particles meet a harder film, sink less and plough less."""
    args = (np.array([3e4]), np.array([6e-4]), np.array([0.7]))
    sizes = np.array([50e-9, 100e-9, 300e-9, 1000e-9, 2000e-9])
    flat = [abrasive_removal_rate(*args, alumina_on_copper(diameter=x)).rate[0] for x in sizes]
    np.testing.assert_allclose(flat, flat[0], rtol=1e-9)
    rising = [abrasive_removal_rate(*args, alumina_on_copper(diameter=x, size_length=1e-6)).rate[0] for x in sizes]
    assert np.all(np.diff(rising[:4]) > 0) and rising[0] < 0.5 * flat[0]
    # 1 -> 2 um: H = 2.6 -> 2.1 GPa, inside the Zhao-Maietta-Chang band, where the indentation at a
    # fixed load does not fall as the hardness rises (next test): the rate dips by 0.6 %
    assert rising[4] / rising[3] - 1 == pytest.approx(-0.006, abs=0.002)
    # the rate cannot fall below that of a purely elastic film: the hardness only sets the yield
    very_hard = abrasive_removal_rate(*args, alumina_on_copper(diameter=50e-9, size_length=1.0, hardness_limit=np.inf)).rate[0]
    assert 0.3 * flat[0] < very_hard == pytest.approx(rising[0], rel=1e-12)  # 9.6 GPa at 50 nm: already elastic


def test_the_rate_is_continuous_where_the_films_size_hardness_reaches_the_abrasives():
    """Where H_0 sqrt(1 + R*/r) reaches the limit the hardness is capped: no jump in the rate."""
    base = alumina_on_copper(diameter=100e-9, size_length=1e-6)
    r = 50e-9
    length_b = ((base.hardness_limit / base.hardness) ** 2 - 1) * r  # R* at which H(r) = limit exactly
    args = (np.array([3e4]), np.array([6e-4]), np.array([0.7]))
    rates = [abrasive_removal_rate(*args, alumina_on_copper(diameter=100e-9, size_length=length_b * (1 + eps))).rate[0] for eps in (-1e-9, 1e-9)]
    assert rates[1] / rates[0] - 1 == pytest.approx(0.0, abs=1e-8)


def test_a_negative_size_length_is_refused_naming_it():
    with pytest.raises(ValueError, match="size_length"):
        alumina_on_copper(size_length=-1e-9)
    with pytest.raises(ValueError, match="film_size_length"):
        cmpsim.Config.default().replace(film_size_length=-1e-6)
    with pytest.raises(ValueError, match="film_hardness"):
        cmpsim.Config.default().replace(film_hardness=-1.0)


def test_the_film_hardness_and_size_length_reach_the_abrasive_law():
    cfg = cmpsim.Config.default().replace(film="copper", abrasive="alumina")
    c0 = abrasive_contact(cfg)
    assert c0.size_length == 0.0 and c0.hardness == 1.5e9 and c0.hardness_limit == 15e9
    c1 = abrasive_contact(cfg.replace(film_hardness=0.58e9, film_size_length=8.3e-6))
    assert c1.hardness == 0.58e9 and c1.size_length == 8.3e-6
    # ceria on oxide: the particle is the softer body, so the film's size effect does not enter
    c2 = abrasive_contact(cfg.replace(film="oxide", abrasive="ceria", film_size_length=1e-6))
    assert c2.size_length == 0.0 and c2.hardness == 6e9


def test_inside_the_zmc_band_a_harder_film_is_not_indented_less():
    """A limitation of the elastic-plastic law (docs/model.md 13e.8), pinned so that it is seen: at a
    fixed load the Zhao-Maietta-Chang interpolation gives an interference that rises with the
    hardness from omega/omega_e ~ 47 to ~ 21 (H = 1.5 -> 2.3 GPa, 500 nm alumina on copper at the
    pad's 50 MPa) before it falls towards the Hertz value; only the elastic and plastic ends are
    monotonic."""
    c = alumina_on_copper()
    r = 0.5e-6
    F = np.array([c.pad_pressure * math.pi * r * r])
    omega = [interference(F, r, c.e_star, h, c.k_factor)[0] / r for h in (1.5e9, 2.0e9, 2.3e9, 3e9, 6e9, 15e9)]
    assert omega[0] < omega[1] < omega[2] and omega[2] > omega[3] > omega[4] >= omega[5]
    hertz = (3 * F[0] / (4 * c.e_star * math.sqrt(r))) ** (2 / 3) / r
    assert omega[5] == pytest.approx(hertz, rel=1e-12)


def test_the_size_length_sweeps_in_micrometres_and_calibrates_from_a_size_series(tmp_path):
    """film_size_length is an ordinary registry input: a sweep takes it in um, and `cmpsim calibrate
    --free film_size_length` recovers it from a (synthetic) size series of the user's own film."""
    import tomllib

    from cmpsim.sweeps import SweepSpec, sweep

    base = '[base]\ngrid = "coarse"\nfilm = "copper"\nabrasive = "alumina"\nparticle_diameter = "100 nm"\n'
    ds = sweep(SweepSpec.from_mapping(tomllib.loads(base + '[axes]\nfilm_size_length = ["0 um", "1 um"]\n')), workers=0, progress=False)
    assert ds["film_size_length"].values.tolist() == [0.0, pytest.approx(1e-6)]
    rr = ds["removal_rate_mean"].values
    assert rr[1] < 0.7 * rr[0]  # 100 nm alumina on copper: H = 1.5 GPa x sqrt(21) = 6.9 GPa, a shallower groove

    truth = cmpsim.Config.default().replace(grid="coarse", film="copper", abrasive="alumina", film_size_length="1 um")
    fit = _recalibrate(tmp_path, truth, "particle_diameter", ("100 nm", "400 nm", "1500 nm"), "film_size_length", "0.6 um")
    assert fit.values["film_size_length"] == pytest.approx(1e-6, rel=1e-3)


def test_the_poisson_probabilities_equal_scipy_stats_bit_for_bit():
    """The abrasive law's Poisson pmf and cdf (two scipy.special functions, so that a solve does
    not load scipy.stats: issue 31) are scipy.stats.poisson's, bit for bit, on the range used."""
    from scipy.stats import poisson

    from cmpsim.physics.abrasion import poisson_cdf, poisson_pmf

    k = np.arange(-3.0, 400.0)[:, None]
    mean = np.concatenate([np.logspace(-6, 2.5, 60), [1.0, 2.0, 37.5]])[None, :]
    assert np.array_equal(poisson_pmf(np.maximum(k, 0.0), mean), poisson.pmf(np.maximum(k, 0.0), mean))
    assert np.array_equal(poisson_cdf(k, mean), poisson.cdf(k, mean))
    assert np.array_equal(poisson_cdf(k + 0.5, mean), poisson.cdf(k + 0.5, mean))  # floors like scipy
