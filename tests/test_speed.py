"""Behaviour behind the speed-ups of issue 15 (the speed itself is measured in benchmarks/).

- iterative refinement against another position's LU gives the fresh-LU pressure to round-off;
- one equilibrium costs at most 2 factorisations on average, and ``factorizations`` counts
  real calls of the solver (``WaferProblem(solver=...)`` is used for every pressure solve);
- the one-evaluation Jacobian (dc/dh times the geometric dh/du) is the derivative of the
  residuals;
- the coarse-grid warm start converges to the position of the cold start, and so does the
  cold start whose first Newton step is taken on 8x24;
- refinement started from the linearised pressure of the last Jacobian gives the same
  pressure in fewer back-substitutions;
- the chord step (the last Jacobian kept near convergence) is taken only there and lands on
  the same position;
- the per-grid assembly map gives the matrix of the entries it was built from;
- on the compliant pad the joint Newton on (pressure, deflection, position) takes 2 LU for a
  cold default equilibrium and lands on the nested solve's equilibrium, which takes over when
  the joint one does not converge (issue 23).
"""

from __future__ import annotations

import numpy as np
import pytest
import scipy.sparse as sp

import cmpsim
from cmpsim.inputs.config import Config
from cmpsim.solver.equilibrium import solve_equilibrium
from cmpsim.numerics.fvassembly import _operator_entries
from cmpsim.operators.reynolds import (
    LinearSolveStats,
    ReynoldsSystem,
    assemble_operator,
    assembly_map,
    factorize,
    refine,
)
from cmpsim.solver.setup import build_problem


def _problem(**settings):
    return build_problem(Config.paper().replace(**settings))


@pytest.mark.parametrize("settings", [{}, {"grid": "48x128"}, {"slurry_model": "newtonian"}])
@pytest.mark.parametrize("du", [(0.005, 0.0, 0.0), (0.0, 1e-6, 0.0), (1e-6, 0.0, 1e-7)])
def test_refinement_against_a_neighbours_lu_gives_the_fresh_lu_pressure(settings, du):
    pr = _problem(**settings)
    u = pr.contact_only_start()
    near = ReynoldsSystem(pr.grid, pr.face_coefficients(u))
    near.solve()
    v = u + np.asarray(du) * np.array([pr.sigma, 1.0, 1.0])
    coeffs = pr.face_coefficients(v)
    fresh = ReynoldsSystem(pr.grid, coeffs).solve()
    stats = LinearSolveStats()
    refined = ReynoldsSystem(pr.grid, coeffs, reference=near.factor, stats=stats)
    phi = refined.solve()
    assert stats.factorizations == 0 and refined.own_factor is None  # no new LU was needed
    assert np.max(np.abs(phi - fresh)) <= 1e-12 * np.max(np.abs(fresh))


def test_refinement_gives_up_on_a_distant_matrix_and_the_system_factorises():
    pr = _problem()
    u = pr.contact_only_start()
    far = ReynoldsSystem(pr.grid, pr.face_coefficients(u + np.array([3.0 * pr.sigma, 0.0, 0.0])))
    coeffs = pr.face_coefficients(u)
    A = assemble_operator(pr.grid, coeffs)
    stats = LinearSolveStats()
    assert refine(A, far.factor, np.ones(pr.grid.size), stats=stats) is None
    assert stats.back_substitutions <= 16
    system = ReynoldsSystem(pr.grid, coeffs, reference=far.factor, stats=stats)
    phi = system.solve()
    assert stats.factorizations == 1 and system.own_factor is not None
    np.testing.assert_allclose(phi, ReynoldsSystem(pr.grid, coeffs).solve(), rtol=0, atol=1e-13 * np.abs(phi).max())


def test_an_equilibrium_costs_at_most_two_factorisations_on_average():
    cases = [{}, {"model": "elastic"}, {"applied_pressure": "2 psi"}, {"rotation_speed": "90 rpm"}, {"particle_diameter": "200 nm", "pad_roughness": "20 um"}]
    counts = [int(cmpsim.solve(Config.paper().replace(**c), relative=False).scalars["factorizations"]) for c in cases]
    assert np.mean(counts) <= 2.0, counts


def test_factorizations_counts_the_calls_of_the_injected_solver():
    calls = []

    def solver(A):
        calls.append(A.shape)
        return factorize(A)

    cfg = Config.paper()
    base = build_problem(cfg)
    from cmpsim.solver.equilibrium import WaferProblem

    pr = WaferProblem(base.grid, solver=solver, **base._init_args)
    sol = solve_equilibrium(pr)
    assert len(calls) == sol.factorizations >= 1
    assert sol.back_substitutions > sol.factorizations
    ref = solve_equilibrium(build_problem(cfg))
    np.testing.assert_allclose(sol.state.u, ref.state.u, rtol=1e-12)


@pytest.mark.parametrize("settings", [{}, {"model": "hydrodynamic"}, {"slurry_model": "newtonian", "cavitation": "gumbel", "cavitation_pressure": "-20 kPa"}])
def test_one_evaluation_jacobian_is_the_derivative_of_the_residuals(settings):
    pr = _problem(**settings)
    sol = solve_equilibrium(pr)
    st = sol.state
    J = pr.jacobian(st)
    for k in range(3):
        du = np.zeros(3)
        du[k] = 1e-5 * pr.u_scale[k]
        fd = (pr.state(st.u + du).residual - pr.state(st.u - du).residual) / (2 * du[k])
        scale = np.max(np.abs(J[:, k]))
        np.testing.assert_allclose(J[:, k], fd, rtol=0, atol=2e-4 * scale)


@pytest.mark.parametrize("settings", [{"model": "hydrodynamic"}, {"grid": "48x128"}])
def test_coarse_grid_warm_start_converges_to_the_cold_start_position(settings):
    cold = solve_equilibrium(_problem(**settings), warm_start=False).state.u
    warm = solve_equilibrium(_problem(**settings), warm_start=True).state.u
    np.testing.assert_allclose(warm[:2], cold[:2], rtol=1e-8)
    assert abs(warm[2] - cold[2]) <= 1e-8 * abs(cold[1])


def test_assembly_map_sums_the_entries_it_was_built_from():
    pr = _problem(grid="coarse")
    coeffs = pr.face_coefficients(pr.contact_only_start())
    rows, cols, src, w = _operator_entries(pr.grid)
    amap = assembly_map(pr.grid)
    from cmpsim.numerics.fvassembly import _stacked_components

    c = _stacked_components(amap, coeffs)
    N = pr.grid.size
    direct = sp.coo_matrix((w * c[src], (rows, cols)), shape=(N, N)).tocsr()
    A = assemble_operator(pr.grid, coeffs)
    assert abs(A - direct).max() <= 1e-14 * abs(direct).max()


def test_refinement_from_the_linearised_pressure_gives_the_fresh_lu_pressure_in_fewer_steps():
    # the Newton trial positions start the refinement at phi + (dphi/du) du (issue 15)
    pr = _problem()
    u = pr.contact_only_start()
    st = pr.state(u)
    pr.jacobian(st)
    assert st.dphi_du is not None and st.dphi_du.shape == (pr.grid.size, 3)
    du = np.array([1e-3 * pr.sigma, 2e-7, 1e-8])
    coeffs = pr.face_coefficients(u + du)
    fresh = ReynoldsSystem(pr.grid, coeffs).solve()
    plain, guessed = LinearSolveStats(), LinearSolveStats()
    phi_plain = ReynoldsSystem(pr.grid, coeffs, reference=st.system.factor, stats=plain).solve()
    guess = st.phi.ravel() + st.dphi_du @ du
    phi_guess = ReynoldsSystem(pr.grid, coeffs, reference=st.system.factor, stats=guessed).solve(x0=guess)
    scale = np.max(np.abs(fresh))
    assert np.max(np.abs(phi_plain - fresh)) <= 1e-12 * scale
    assert np.max(np.abs(phi_guess - fresh)) <= 1e-12 * scale
    assert guessed.factorizations == plain.factorizations == 0
    assert guessed.back_substitutions < plain.back_substitutions


@pytest.mark.parametrize("settings", [{}, {"model": "elastic", "applied_pressure": "6 psi"}, {"grid": "48x128"}])
def test_the_coarse_first_step_lands_on_the_equilibrium_of_the_target_grid(settings):
    # a cold start's first Newton step on 8x24: one LU on the target grid, the same position
    first = solve_equilibrium(_problem(**settings))
    plain = solve_equilibrium(_problem(**settings), warm_start=False)  # no coarse step at all
    assert first.factorizations == 2  # one on 8x24, one on the target grid
    assert first.iterations <= plain.iterations
    np.testing.assert_allclose(first.state.u[:2], plain.state.u[:2], rtol=1e-8)
    assert abs(first.state.u[2] - plain.state.u[2]) <= 1e-8 * abs(plain.state.u[1])
    assert np.max(np.abs(first.state.residual)) < 1e-9


def test_the_chord_step_keeps_the_last_jacobian_only_near_convergence(monkeypatch):
    # at 96x256 the residual after the first step is ~1e-7 (within CHORD_MERIT x tol): one
    # Jacobian for two steps; the converged residual is still below the tolerance
    from cmpsim.solver import equilibrium

    pr = _problem(grid="96x256")
    calls = []
    real = equilibrium.WaferProblem.jacobian
    monkeypatch.setattr(equilibrium.WaferProblem, "jacobian", lambda self, st, *a: calls.append(self.grid.size) or real(self, st, *a))
    sol = solve_equilibrium(pr)
    fine = [n for n in calls if n == pr.grid.size]
    assert sol.iterations == 2 and len(fine) == 1
    assert np.max(np.abs(sol.state.residual)) < 1e-9
    monkeypatch.setattr(equilibrium, "CHORD_MERIT", 0.0)  # a Jacobian at every step
    calls.clear()
    exact = solve_equilibrium(_problem(grid="96x256"))
    assert len([n for n in calls if n == pr.grid.size]) == 2
    np.testing.assert_allclose(sol.state.u[:2], exact.state.u[:2], rtol=1e-8)


def test_a_coarse_first_step_that_leads_nowhere_falls_back_to_the_plain_cold_start(monkeypatch):
    from cmpsim.solver import equilibrium

    pr = _problem()
    # a start tilted so far that the wafer edge would cut through the pad: no load balance there
    monkeypatch.setattr(equilibrium, "_coarse_first_step", lambda problem, max_step: np.array([problem.sigma, 1e-2, 0.0]))
    got = solve_equilibrium(pr)
    plain = solve_equilibrium(_problem(), warm_start=False)
    np.testing.assert_allclose(got.state.u[:2], plain.state.u[:2], rtol=1e-8)
    assert np.max(np.abs(got.state.residual)) < 1e-9


def test_a_warm_chain_on_the_compliant_pad_starts_from_the_last_equilibrium():
    """Issue 23: along a chain of warm starts (sweeps), the coupled solve starts from the last
    equilibrium's slurry pressure and deflection: no more factorisations and fewer Newton steps
    than the same points solved alone (the joint Newton takes 2 LU a point either way), the
    same positions (to the Newton tolerance)."""
    import cmpsim
    from cmpsim.inputs.config import Config

    base = Config.default().replace(grid="coarse")
    psi = (3.0, 3.3, 3.6, 3.9)
    cold = [cmpsim.solve(base.replace(applied_pressure=f"{p} psi"), relative=False) for p in psi]
    u, chain = None, []
    for p in psi:
        r = cmpsim.solve(base.replace(applied_pressure=f"{p} psi"), relative=False, start=u)
        u = [r.h0, r.attack_angle, r.cross_tilt]
        chain.append(r)
    lu_cold = sum(int(r.scalars["factorizations"]) for r in cold[1:])
    lu_chain = sum(int(r.scalars["factorizations"]) for r in chain[1:])
    assert lu_chain <= lu_cold, (lu_chain, lu_cold)
    steps_cold = sum(int(r.scalars["iterations"]) for r in cold[1:])
    steps_chain = sum(int(r.scalars["iterations"]) for r in chain[1:])
    assert steps_chain < steps_cold, (steps_chain, steps_cold)
    for a, b in zip(cold, chain):
        assert b.h0 == pytest.approx(a.h0, rel=1e-7)
        assert b.attack_angle == pytest.approx(a.attack_angle, rel=1e-6)
        assert b.removal_rate_mean == pytest.approx(a.removal_rate_mean, rel=1e-7)


#: Outputs compared between the joint and the nested solve of the compliant pad.
_COMPARED = ("h0", "attack_angle", "cross_tilt", "removal_rate_mean", "within_wafer_nonuniformity", "fluid_load_fraction", "film_thickness_min")


def _agree(a, b, rtol):
    for k in _COMPARED:
        if np.isnan(a.scalars[k]) and np.isnan(b.scalars[k]):  # e.g. no removal on a hydroplaning wafer: no non-uniformity
            continue
        scale = abs(a.attack_angle) if k == "cross_tilt" else abs(a.scalars[k])
        assert abs(b.scalars[k] - a.scalars[k]) <= rtol * scale, (k, a.scalars[k], b.scalars[k])


def test_the_joint_newton_solves_the_cold_default_in_two_factorisations_on_the_nested_solution(monkeypatch):
    """Issue 23 (3-inch criterion): film, pad deflection and wafer position solved by one Newton
    iteration on all three (``cmpsim.operators.compliance.joint_equilibrium``) take 2 LU where the nested
    solve (a coupled state at every trial position, a factorisation for each Jacobian) takes 5,
    and land on the nested solve's equilibrium to its tolerances."""
    from cmpsim.models.pads import WinklerPad

    cfg = Config.default().replace(grid="24x64")
    joint = cmpsim.solve(cfg, relative=False)
    monkeypatch.setattr(WinklerPad, "joint", False)
    nested = cmpsim.solve(cfg, relative=False)
    assert joint.scalars["factorizations"] == 2
    assert nested.scalars["factorizations"] > joint.scalars["factorizations"]
    assert max(abs(joint.scalars["load_residual"]), abs(joint.scalars["moment_residual"])) < cfg.tolerance
    _agree(nested, joint, 1e-7)


def test_a_joint_newton_that_does_not_converge_hands_over_to_the_nested_solve():
    """With fewer Newton steps allowed than the joint iteration needs (it takes 6 on the default
    grid, the nested outer Newton 2), the nested solve takes over from the start the joint one
    had, with the memory the joint one found: the same equilibrium, the joint LUs counted."""
    cfg = Config.default().replace(grid="24x64")
    full = cmpsim.solve(cfg, relative=False)
    short = cmpsim.solve(cfg.replace(max_iterations=3), relative=False)
    assert full.scalars["iterations"] > 3 >= short.scalars["iterations"]
    assert short.scalars["factorizations"] > full.scalars["factorizations"]
    _agree(full, short, 1e-7)


def test_a_joint_newton_that_crawls_hands_over_after_a_bounded_number_of_factorisations(monkeypatch):
    """Near hydroplaning on a stiff stack (subpad 50 MPa, 20x the default's) the joint steps,
    without the nested solve's load bracketing and line search, crawl: after
    ``_MAX_FACTORISATIONS`` LU the nested solve takes over and gives its own answers."""
    from cmpsim.operators.jointnewton import _MAX_FACTORISATIONS
    from cmpsim.models.pads import WinklerPad

    cfg = Config.default().replace(grid="24x64", subpad_modulus="50 MPa")
    bounded = cmpsim.solve(cfg, relative=False)
    monkeypatch.setattr(WinklerPad, "joint", False)
    nested = cmpsim.solve(cfg, relative=False)
    assert bounded.scalars["factorizations"] == nested.scalars["factorizations"] + _MAX_FACTORISATIONS
    _agree(nested, bounded, 1e-12)
