"""Cavitation of the Newtonian slurry: Gumbel and mass-conserving JFO against references and invariants."""

import numpy as np
import pytest
import scipy.sparse.linalg as spla

from cmpsim.operators.cavitation import CavitationSystem, solve_complementarity, upwind_couette_matrix
from cmpsim.inputs.config import Config
from cmpsim.solver.equilibrium import WaferProblem
from cmpsim.physics.flowfactors import RoughnessGeometry
from cmpsim.numerics.grid import PolarGrid
from cmpsim.physics.kinematics import Kinematics
from cmpsim.testing.lubrication import gumbel_load, jfo_diverging_slider, linear_film_pressure, strip_problem
from cmpsim.operators.reynolds import LubricationParameters, ReynoldsSystem, face_fluxes, flux_divergence
from cmpsim.solver.setup import build_problem

ETA, U, L = 5e-3, 0.6, 0.05
H1, H2 = 30e-6, 60e-6  # diverging slider: sub-ambient full-Sommerfeld pressure down to -41 kPa


def _lub(sigma=15e-6, mode="sliding"):
    kin = Kinematics(U / 0.1, U / 0.1, 0.1, mode)
    return LubricationParameters(100e-9, 4e-6, 1.0, 3 * U, RoughnessGeometry(sigma), kin, slurry_model="newtonian", viscosity=ETA)


def _strips():
    """The diverging slider on 100-800 cells, smooth surfaces (1-D finite volumes of the wafer's kernels)."""
    return [strip_problem(n, L, H1, H2, _lub(1e-12)) for n in (100, 200, 400, 800)]


@pytest.mark.parametrize("p_cav", [-5e3, -20e3])
def test_gumbel_slider_load_is_the_integral_of_the_clipped_analytic_pressure(p_cav):
    """Diverging plane slider, smooth surfaces: integral of max(p, p_cav) vs the analytic p."""
    exact = gumbel_load(L, H1, H2, ETA, U, p_cav)
    errs = []
    for s in _strips():
        p = spla.spsolve(s.A.tocsc(), s.rhs)
        np.testing.assert_allclose(p, linear_film_pressure(s.x, L, H1, H2, ETA, U), atol=2e-3 * abs(p).max() * (s.dx * 100 / L) ** 2)
        errs.append(abs(np.maximum(p, p_cav).sum() * s.dx / exact - 1))
    print(f"\nGumbel slider, p_cav = {p_cav:g} Pa: load errors {errs}")
    # the clipped integrand has kinks that fall anywhere in a cell: second order on average
    assert errs[-1] < 2e-5
    assert np.log2(errs[0] / errs[-1]) / 3 > 1.7


@pytest.mark.parametrize("p_cav", [-5e3, -20e3])
def test_jfo_slider_matches_the_semi_analytic_rupture_reformation_and_fill_fraction(p_cav):
    """Diverging slider: rupture (p = p_cav, p' = 0), cavitated zone theta = h_c/h, reformation."""
    ref = jfo_diverging_slider(L, H1, H2, ETA, U, p_cav)
    rows = []
    for s in _strips():
        p, r, cav, _, it = solve_complementarity(s.A, s.B, s.rhs, p_cav)
        theta = 1 - r
        assert np.all(p[cav] == p_cav) and np.all(r[~cav] == 0) and np.all(p >= p_cav) and np.all(theta[cav] < 1)
        assert abs(s.x[cav].min() - ref.rupture) < s.dx and abs(s.x[cav].max() - ref.reformation) < s.dx
        rows.append((
            np.abs(p - ref.pressure(s.x)).max() / abs(p_cav),
            abs(p.sum() * s.dx / ref.load() - 1),
            np.abs(theta - ref.fill_fraction(s.x)).sum() * s.dx / L,
            it,
        ))
    e = np.array(rows)
    orders = np.log2(e[0, :3] / e[-1, :3]) / 3
    print(f"\nJFO slider, p_cav = {p_cav:g} Pa: [max |p err|/|p_cav|, load err, L1 theta err, solves]\n{e}\nmean orders {orders}")
    assert e[-1, 0] < 1e-4 and e[-1, 1] < 2e-5 and e[-1, 2] < 2e-3
    assert orders[0] > 1.8 and orders[1] > 1.5 and orders[2] > 0.9  # theta jumps at reformation: first order
    assert e[:, 3].max() <= 12  # active-set solves


def test_jfo_slider_load_lies_above_gumbel_which_lies_above_full_sommerfeld():
    """Measured ordering (not the 'between' sometimes assumed): full < Gumbel < JFO. By the
    maximum principle p_JFO >= max(p_full, p_cav) wherever p_full <= p_cav on the JFO rupture
    boundary: JFO holds the cavitated zone at p_cav instead of letting it pull the film down."""
    p_cav = -20e3
    full = linear_film_pressure(np.linspace(0, L, 2001), L, H1, H2, ETA, U)
    w_full = np.trapezoid(full, dx=L / 2000)
    w_gumbel = gumbel_load(L, H1, H2, ETA, U, p_cav)
    w_jfo = jfo_diverging_slider(L, H1, H2, ETA, U, p_cav).load()
    print(f"\nloads per width: full {w_full:.5g}, Gumbel {w_gumbel:.5g}, JFO {w_jfo:.5g} N/m")
    assert w_full < w_gumbel < w_jfo


# ---------------------------------------------------------------- on the wafer
def _disk(cavitation, p_cav, dome=5e-6, mode="sliding"):
    grid = PolarGrid(0.0381, 24, 64)
    return WaferProblem(grid, dome, 27579.0, 3.2e4, _lub(mode=mode), None, "hydrodynamic",
                        cavitation=cavitation, cavitation_pressure=p_cav)


def test_upwind_couette_flux_of_a_full_film_is_the_flux_divergence():
    pb = _disk("jfo", 0.0, mode="rotating")
    coeffs = pb.face_coefficients([33e-6, 2e-5, 1e-6])
    B, c = upwind_couette_matrix(pb.grid, coeffs)
    div = flux_divergence(pb.grid, coeffs)
    face = max(np.abs(f).max() for f in face_fluxes(pb.grid, coeffs))  # the divergence cancels these
    np.testing.assert_allclose(B @ np.ones(pb.grid.size) + c, div, rtol=0, atol=1e-14 * face)


def test_jfo_pressure_is_the_full_film_solution_when_nothing_cavitates():
    pb = _disk("jfo", -98.2e3, mode="rotating")
    u = [33e-6, 2e-5, 1e-6]
    st = pb.state(u)
    full = ReynoldsSystem(pb.grid, pb.face_coefficients(u)).solve()
    assert not st.cavitated.any() and np.all(st.fill_fraction == 1.0)
    np.testing.assert_array_equal(st.p_slurry, full)


@pytest.mark.parametrize("mode", ["sliding", "rotating"])
def test_jfo_mass_balance_per_cell_and_through_the_edge_to_1e_10(mode):
    pb = _disk("jfo", 0.0, mode=mode)
    st = pb.state([33e-6, 1e-5, 0.0])
    sysm = st.system
    assert isinstance(sysm, CavitationSystem) and st.cavitated.sum() > 20
    p, theta = st.p_slurry.ravel(), st.fill_fraction.ravel()
    cell = sysm.mass_residual(p, theta)
    scale = np.abs(sysm.full_film_rhs).max()  # the largest Couette flux imbalance of a cell
    inflow = -sysm.edge_inflow.sum()  # volume flux entering through the flooded edge
    print(f"\n{mode}: max cell residual {np.abs(cell).max() / scale:.2e}, edge net flux {sysm.boundary_flux(p, theta) / inflow:.2e} "
          f"of the inflow; {st.cavitated.sum()} cells cavitated, theta down to {theta.min():.4f}")
    assert np.abs(cell).max() < 1e-10 * scale
    assert abs(sysm.boundary_flux(p, theta)) < 1e-10 * inflow


def test_cavitated_cells_hold_p_cav_exactly_with_fill_fraction_below_one():
    p_cav = -2e3
    pb = _disk("jfo", p_cav)
    st = pb.state([33e-6, 0.0, 0.0])
    cav = st.cavitated
    assert cav.any() and (~cav).any()
    assert np.all(st.p_slurry[cav] == p_cav) and np.all(st.fill_fraction[cav] < 1)
    assert np.all(st.fill_fraction[~cav] == 1) and np.all(st.p_slurry[~cav] >= p_cav)
    assert np.all(st.fill_fraction > 0)


def test_jfo_load_on_a_symmetric_film_lies_above_gumbel_which_lies_above_full_sommerfeld():
    """Domed wafer at zero tilt, uniform sliding, p_cav = 0: full Sommerfeld carries nothing, Gumbel
    (half-Sommerfeld) half of the gross load; JFO more, pointwise above Gumbel (maximum principle)."""
    u = [33e-6, 0.0, 0.0]
    states = {cav: _disk(cav, 0.0).state(u) for cav in ("none", "gumbel", "jfo")}
    g = PolarGrid(0.0381, 24, 64)
    w = {k: g.integrate(s.p_slurry) for k, s in states.items()}
    gross = g.integrate(np.abs(states["none"].p_slurry))
    print(f"\nsymmetric film loads: {w} N (gross full-Sommerfeld {gross:.4g} N)")
    assert abs(w["none"]) < 1e-13 * gross
    assert w["gumbel"] == pytest.approx(0.5 * gross, rel=1e-12)
    assert w["jfo"] > w["gumbel"]
    assert np.all(states["jfo"].p_slurry >= states["gumbel"].p_slurry - 1e-9 * gross)


def test_default_cavitation_pressure_is_water_vapour_pressure_below_one_atmosphere():
    assert Config.default().cavitation_pressure == pytest.approx(-101.325e3 + 3.17e3, abs=50)


def test_cavitation_pressure_above_ambient_is_refused_by_the_problem_too():
    c = Config.paper().replace(slurry_model="newtonian", cavitation="jfo")  # JFO needs the rigid pad of the paper
    setup_problem = build_problem(c)
    with pytest.raises(ValueError, match=r"cavitation_pressure must be a gauge pressure in \[-101325, 0\] Pa"):
        WaferProblem(setup_problem.grid, 5e-6, 27579.0, 3.2e4, setup_problem.lub, setup_problem.pad,
                     cavitation="jfo", cavitation_pressure=1e3)
