"""The wafer solver: equilibrium residuals, grid independence, robustness, the paper's trends.

Most claims here are about the paper's model and are made on ``Config.paper()`` (``PAPER``); the
default model (docs/model.md section 13d) has its own convergence test below.
"""

import itertools

import numpy as np
import pytest

import cmpsim
from cmpsim.solver.equilibrium import EquilibriumError, solve_equilibrium
from cmpsim.solver.model import build_problem

PAPER = cmpsim.Config.paper()


@pytest.fixture(scope="module")
def base():
    """The paper's base case, solved with the paper's model."""
    return cmpsim.solve(PAPER)


def test_load_residual_below_1e_6_at_equilibrium(base):
    assert base.converged
    assert abs(base.load_residual) < 1e-6
    assert abs(base.moment_residual) < 1e-6
    # and the residual is what it claims: integrate the pressure field independently
    st = base.solution.state
    g = base.grid
    total = g.integrate(st.p_fluid + st.p_contact)
    assert total / (base.config.applied_pressure * np.pi * g.radius**2) - 1 == pytest.approx(base.load_residual, abs=1e-12)


def test_load_fractions_add_up_to_one(base):
    assert base.fluid_load_fraction + base.contact_load_fraction == pytest.approx(1.0, abs=1e-6)


def test_centre_film_changes_less_than_1_percent_under_2x_refinement(base):
    fine = cmpsim.solve(PAPER, grid="48x128", relative=False)
    for key in ("film_thickness_center", "attack_angle", "fluid_load_fraction", "contact_area_ratio_elastic"):
        change = abs(base.scalars[key] - fine.scalars[key]) / abs(fine.scalars[key])
        print(f"\n{key}: default {base.scalars[key]:.6g}, 2x refined {fine.scalars[key]:.6g}, change {100 * change:.3f} %")
        assert change < 0.01


def test_newton_cost_is_a_handful_of_factorizations(base):
    assert base.iterations <= 8
    assert base.factorizations <= 12


@pytest.mark.parametrize(
    "pressure,speed,diameter,roughness",
    list(itertools.product(["2psi", "6psi"], ["30rpm", "90rpm"], ["100nm", "200nm"], ["10um", "15um", "20um"])),
)
def test_lep_converges_from_the_default_start_over_the_papers_range(pressure, speed, diameter, roughness):
    r = cmpsim.solve(
        PAPER,
        applied_pressure=pressure, rotation_speed=speed, particle_diameter=diameter, pad_roughness=roughness, relative=False
    )
    assert r.converged and abs(r.load_residual) < 1e-6 and r.moment_residual < 1e-6
    assert r.film_thickness_min > 0


@pytest.mark.parametrize("model", ["elastic", "hydrodynamic"])
def test_other_variants_of_the_paper_converge_at_the_base_case(model):
    r = cmpsim.solve(PAPER, model=model, relative=False)
    assert r.converged and abs(r.load_residual) < 1e-6
    if model == "hydrodynamic":
        assert r.contact_load_fraction == 0 and r.fluid_load_fraction == pytest.approx(1, abs=1e-6)


def test_sliding_kinematics_have_zero_cross_tilt_by_symmetry():
    r = cmpsim.solve(kinematics="sliding", relative=False)
    assert abs(r.cross_tilt) < 1e-6 * abs(r.attack_angle)


def test_warm_start_reuses_a_neighbouring_equilibrium(base):
    cold = cmpsim.solve(PAPER, applied_pressure="4.2psi", relative=False)
    warm = cmpsim.solve(PAPER, applied_pressure="4.2psi", start=base.solution.state.u, relative=False)
    assert warm.factorizations <= cold.factorizations
    assert warm.film_thickness_center == pytest.approx(cold.film_thickness_center, rel=1e-8)


def test_impossible_start_is_diagnosed_not_nan():
    cfg = cmpsim.Config.default().replace(applied_pressure="4psi", max_iterations=1, tolerance=1e-15)
    with pytest.raises(EquilibriumError, match="did not converge"):
        solve_equilibrium(build_problem(cfg), tol=1e-15, max_iter=1)


def test_load_beyond_what_the_pad_can_carry_is_reported():
    cfg = cmpsim.Config.default().replace(applied_pressure="2000psi")
    with pytest.raises(EquilibriumError, match="exceeds what the pad asperities can carry"):
        build_problem(cfg).contact_only_start()


# ---------------------------------------------------------------- the paper's trends (Figs. 3-12), with the paper's model
@pytest.fixture(scope="module")
def trends():
    out = {}
    for p in ("2psi", "4psi", "6psi"):
        out["P", p] = cmpsim.solve(PAPER, applied_pressure=p)
    for w in ("30rpm", "60rpm", "90rpm"):
        out["w", w] = cmpsim.solve(PAPER, rotation_speed=w)
    for d, s in (("100nm", "15um"), ("200nm", "15um"), ("100nm", "20um"), ("200nm", "20um")):
        out["ds", d, s] = cmpsim.solve(PAPER, particle_diameter=d, pad_roughness=s)
    return out


def _series(trends, kind, key):
    labels = ("2psi", "4psi", "6psi") if kind == "P" else ("30rpm", "60rpm", "90rpm")
    return np.array([trends[kind, lab].scalars[key] for lab in labels])


def test_film_thickness_falls_with_load_and_rises_with_speed(trends):
    assert np.all(np.diff(_series(trends, "P", "film_thickness_center")) < 0)
    assert np.all(np.diff(_series(trends, "w", "film_thickness_center")) > 0)


def test_larger_particles_give_thicker_films_and_larger_attack_angles(trends):
    small, large = trends["ds", "100nm", "15um"], trends["ds", "200nm", "15um"]
    assert large.film_thickness_center > small.film_thickness_center
    assert large.attack_angle > small.attack_angle


def test_attack_angle_falls_with_load_and_rises_with_speed(trends):
    assert np.all(np.diff(_series(trends, "P", "attack_angle")) < 0)
    assert np.all(np.diff(_series(trends, "w", "attack_angle")) > 0)


def test_contact_area_ratios_rise_with_load_and_fall_with_speed(trends):
    for key in ("contact_area_ratio_elastic", "contact_area_ratio_elastoplastic"):
        assert np.all(np.diff(_series(trends, "P", key)) > 0)
        assert np.all(np.diff(_series(trends, "w", key)) < 0)


def test_smaller_particles_and_rougher_pads_give_higher_contact_ratios(trends):
    for key in ("contact_area_ratio_elastic", "contact_area_ratio_elastoplastic"):
        assert trends["ds", "100nm", "15um"].scalars[key] > trends["ds", "200nm", "15um"].scalars[key]
        assert trends["ds", "100nm", "20um"].scalars[key] > trends["ds", "100nm", "15um"].scalars[key]


def test_removal_rate_rises_with_load_and_speed_and_load_matters_more(trends):
    rr_p = _series(trends, "P", "removal_rate_relative")
    rr_w = _series(trends, "w", "removal_rate_relative")
    assert np.all(np.diff(rr_p) > 0) and np.all(np.diff(rr_w) > 0)
    assert rr_p[-1] / rr_p[0] > rr_w[-1] / rr_w[0]


def test_removal_rate_falls_with_pad_roughness_at_the_base_point(trends):
    assert trends["ds", "100nm", "20um"].removal_rate_mean < trends["ds", "100nm", "15um"].removal_rate_mean


def test_removal_rate_with_particle_size_is_documented_as_not_reproduced(trends):
    """The paper: larger particles remove faster. With tau dominated by pad-summit friction the
    thicker film of larger particles lowers the contact and the removal rate (docs/model.md,
    'Removal rate'); this test guards that the documentation stays true."""
    assert trends["ds", "200nm", "15um"].removal_rate_mean < trends["ds", "100nm", "15um"].removal_rate_mean
    slurry_small = cmpsim.solve(PAPER, removal_shear="slurry")
    slurry_large = cmpsim.solve(PAPER, removal_shear="slurry", particle_diameter="200nm")
    assert slurry_large.removal_rate_mean > slurry_small.removal_rate_mean


def test_root_scan_finds_the_unique_lep_equilibrium(base):
    from cmpsim.solver.equilibrium import scan_moment_roots

    scan = scan_moment_roots(base.problem, base.solution)
    assert len(scan.roots) == 1
    # the bracketed root is polished with Brent: it is Newton's root, not a scan estimate
    assert scan.roots[0] == pytest.approx(base.attack_angle, rel=1e-4)


def test_root_scan_reports_multiple_hydrodynamic_equilibria():
    """Paper's model: without contact at sigma = 10 um the moment has several roots (as the prototype found)."""
    r = cmpsim.solve(PAPER, model="hydrodynamic", pad_roughness="10um", relative=False, check_roots=True)
    assert r.moment_roots_found >= 2
    assert r.flow_factor_floored_fraction > 0.5  # and they all live outside eq. 8's validity


def test_anisotropic_roughness_converges_and_is_flagged_outside_eq8_validity():
    """Documented in docs/limitations.md: gamma = 3 at 30 deg needs regularisation at h/sigma ~ 1.85
    (the paper's base case)."""
    r = cmpsim.solve(PAPER, peklenik_number=3, roughness_angle="30 deg", relative=False)
    assert r.converged and abs(r.load_residual) < 1e-6
    assert r.flow_factor_floored_fraction > 0.5
    iso = cmpsim.solve(PAPER, relative=False)
    assert iso.flow_factor_floored_fraction == 0


def test_a_diverging_trial_film_in_the_hydrodynamic_start_is_not_reported_as_bad_input():
    """Paper's model: a low fluctuation velocity makes the thinnest trial film's pressure diverge; the
    start must step past it (found by review: it used to escape as a ValueError, exit status 2)."""
    from click.testing import CliRunner

    from cmpsim.cli import main

    res = CliRunner().invoke(main, ["run", "--json", "--preset", "paper", "--set", "model=hydrodynamic", "--set", "fluctuation_ratio=0.1", "--set", "grid=coarse"])
    assert res.exit_code in (0, 3), res.output
    if res.exit_code == 0:
        import json

        data = json.loads(res.stdout)
        assert data["solver"]["converged"] and abs(data["solver"]["load_residual"]) < 1e-6


@pytest.mark.parametrize("preset", ["paper", "default"])
def test_wafer_problem_solves_every_pressure_with_the_injected_solver_and_solve_reuses_a_built_problem(preset):
    """Also on the default's compliant pad with Gumbel cavitation (the coupled pad solve used to
    ignore the injected solver)."""
    from cmpsim.solver.equilibrium import WaferProblem
    from cmpsim.operators.reynolds import factorize
    from cmpsim.solver.setup import physical_setup

    calls = []

    def counting(A):
        calls.append(A.shape)
        return factorize(A)

    cfg = cmpsim.Config.preset(preset).replace(grid="coarse")
    s = physical_setup(cfg)
    problem = WaferProblem(s.grid, cfg.dome_height, cfg.applied_pressure, s.ambient_pressure, s.lubrication, s.pad, cfg.model,
                           cavitation=cfg.cavitation, cavitation_pressure=cfg.cavitation_pressure, foundation=s.foundation,
                           solver=counting)
    reused = cmpsim.solve(cfg, problem=problem, relative=False)
    assert reused.problem is problem and len(calls) == reused.factorizations > 0
    fresh = cmpsim.solve(cfg, relative=False)
    assert fresh.to_dict() == reused.to_dict()


# ---------------------------------------------------------------- Newtonian slurry with cavitation, on the paper's (rigid) pad
NEWTONIAN_CASES = [("none", "-98.2 kPa"), ("gumbel", "-98.2 kPa"), ("jfo", "-98.2 kPa"), ("gumbel", "0 kPa"), ("jfo", "0 kPa")]


@pytest.mark.parametrize("cavitation,p_cav", NEWTONIAN_CASES)
def test_newtonian_equilibrium_converges_at_the_base_case_with_each_cavitation_model(cavitation, p_cav):
    r = cmpsim.solve(PAPER, slurry_model="newtonian", cavitation=cavitation, cavitation_pressure=p_cav, relative=False)
    st = r.solution.state
    print(f"\n{cavitation} p_cav={p_cav}: fluid {100 * r.fluid_load_fraction:.3f} %, centre film "
          f"{r.film_thickness_center * 1e6:.4f} um, attack {r.attack_angle:.4g} rad, {r.iterations} Newton steps, "
          f"{r.factorizations} solves, cavitated cells {0 if st.cavitated is None else int(st.cavitated.sum())}")
    assert r.converged and abs(r.load_residual) < 1e-9 and r.moment_residual < 1e-9
    assert r.iterations <= 8
    if p_cav == "0 kPa":  # the ambient cavitation pressure is reached under the wafer's diverging side
        assert st.cavitated.sum() > 50
        assert st.p_slurry.min() == 0.0
    if cavitation == "jfo":
        assert ("fill_fraction" in r.polar) and r.polar["fill_fraction"].max() == 1.0


@pytest.mark.parametrize("cavitation", ["none", "gumbel", "jfo"])
def test_newton_jacobian_on_the_frozen_cavitated_set_matches_a_central_difference(cavitation):
    cfg = PAPER.replace(slurry_model="newtonian", cavitation=cavitation, cavitation_pressure="0 kPa")
    r = cmpsim.solve(cfg, relative=False)
    problem, st = r.problem, r.solution.state
    J = problem.jacobian(st)
    for k in range(3):
        du = np.zeros(3)
        du[k] = 1e-4 * problem.u_scale[k]
        plus, minus = problem.state(st.u + du), problem.state(st.u - du)
        if st.cavitated is not None:  # the step keeps the cavitated set: the derivative is the frozen one
            assert np.array_equal(plus.cavitated, st.cavitated) and np.array_equal(minus.cavitated, st.cavitated)
        central = (plus.residual - minus.residual) / (2 * du[k])
        assert np.abs(J[:, k] - central).max() < 1e-5 * np.abs(central).max(), (k, J[:, k], central)


def test_newtonian_hydroplaning_equilibrium_is_found_from_an_attack_angle_scan():
    """IC1000-like summits (sigma 5 um, R 7 um, H 50 MPa, E 0.5 GPa) on the paper's rigid pad: the wafer hydroplanes. With full
    Sommerfeld the zero-tilt film carries no net fluid load, Newton from the contact-only start
    stalls near a sucked-down film, and the solver restarts from an attack-angle scan; it finds
    the root that Gumbel cavitation (no cell below p_cav there) reaches directly."""
    pad = dict(pad_modulus="0.5 GPa", pad_hardness="50 MPa", asperity_radius="7 um", pad_roughness="5 um",
               reference_roughness="5 um", asperity_density=1e8, grid="12x32", max_iterations=12)
    full = cmpsim.solve(PAPER, slurry_model="newtonian", cavitation="none", relative=False, **pad)
    gumbel = cmpsim.solve(PAPER, slurry_model="newtonian", cavitation="gumbel", relative=False, **pad)
    assert full.converged and abs(full.load_residual) < 1e-9
    assert full.fluid_load_fraction == pytest.approx(1.0, abs=1e-9)
    assert not gumbel.solution.state.cavitated.any()
    assert full.attack_angle == pytest.approx(gumbel.attack_angle, rel=1e-6)
    assert full.film_thickness_center == pytest.approx(gumbel.film_thickness_center, rel=1e-8)


# ---------------------------------------------------------------- the default model (docs/model.md section 13d)
@pytest.mark.parametrize("pressure,speed", list(itertools.product(["2psi", "4psi", "6psi"], ["30rpm", "60rpm", "90rpm"])))
def test_default_model_converges_across_the_papers_load_and_speed_range(pressure, speed):
    """Newtonian slurry, Gumbel cavitation, compliant IC1000-on-Suba IV stack, measured summits."""
    r = cmpsim.solve(applied_pressure=pressure, rotation_speed=speed, grid="coarse", relative=False)
    assert r.config.to_dict() == cmpsim.Config.default().replace(applied_pressure=pressure, rotation_speed=speed,
                                                                 grid="coarse").to_dict()
    assert r.converged and abs(r.load_residual) < 1e-9 and abs(r.moment_residual) < 1e-9
    assert r.film_thickness_min > 0
