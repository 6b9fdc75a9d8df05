"""The wafer as a free Kirchhoff plate on the polar grid (cmpsim.numerics.plate; issue 25)."""

import numpy as np
import pytest
from scipy.special import jv

from cmpsim.numerics.grid import PolarGrid
from cmpsim.numerics.plate import KirchhoffPlate, PlateOperator, bending_stiffness, zone_load
from cmpsim.testing.plates import free_plate_balanced_load, winkler_bessel_mode

WAFER = KirchhoffPlate(381e-6, 130e9, 0.28)  # 3-inch silicon wafer (SEMI M1; Hopcroft et al. 2010)
A = 0.0381


def _observed_orders(errors):
    e = np.asarray(errors)
    return np.log2(e[:-1] / e[1:])


def test_bending_stiffness_is_e_t_cubed_over_12_one_minus_nu_squared():
    assert bending_stiffness(1e-3, 12e9, 0.0) == pytest.approx(1.0, rel=1e-15)
    assert WAFER.bending_stiffness == pytest.approx(130e9 * 381e-6**3 / (12 * (1 - 0.28**2)), rel=1e-14)
    assert WAFER.bending_length(WAFER.bending_stiffness) == pytest.approx(1.0)


@pytest.mark.parametrize("n", [0, 1, 2])
def test_plate_on_a_winkler_bed_converges_to_the_closed_form_at_second_order(n):
    """q = q0 J_n(beta r) cos n theta on a free plate on a Winkler bed; bending length a/1.5."""
    k = 2e6  # Pa/m: ell = (D/k)^(1/4) = 24 mm, comparable to the 38 mm radius
    beta = 5.0 / A
    errors = []
    for n_r in (8, 16, 32, 64):
        g = PolarGrid(A, n_r, 16)
        w = PlateOperator(WAFER, g, k).deflection(1e4 * jv(n, beta * g.r) * np.cos(n * g.theta))
        ref = winkler_bessel_mode(g.r, n, beta, 1e4, A, WAFER.bending_stiffness, WAFER.poisson, k) * np.cos(n * g.theta)
        errors.append(np.max(np.abs(w - ref)) / np.max(np.abs(ref)))
    orders = _observed_orders(errors)
    assert errors[-1] < 3e-3
    assert orders[-1] == pytest.approx(2.0, abs=0.1), (errors, orders)


def test_free_plate_under_a_self_balanced_load_converges_at_second_order():
    p0 = 1e4
    errors = []
    for n_r in (8, 16, 32, 64):
        g = PolarGrid(A, n_r, 8)
        q = p0 * (1 - 2 * g.r**2 / A**2) * np.ones_like(g.theta)
        w = PlateOperator(WAFER, g).deflection(q)
        ref = free_plate_balanced_load(g.r, p0, A, WAFER.bending_stiffness, WAFER.poisson) * np.ones_like(g.theta)
        errors.append(np.max(np.abs(w - ref)) / np.max(np.abs(ref)))
    assert _observed_orders(errors)[-1] == pytest.approx(2.0, abs=0.05), errors


def _load(g):
    x, y = g.centres
    return 1e4 * (1 + 0.3 * np.sin(7 * x / A) + 0.2 * (y / A) ** 2 + 0.1 * np.cos(3 * g.theta) + 0.05 * x / A)


def _rigid_fit(g, q):
    """Least-squares fit c0 + c1 x + c2 y of a cell field (the modes are orthogonal on the grid)."""
    x, y = g.centres
    a = g.area
    return np.sum(q * a) / np.sum(a) + np.sum(q * x * a) / np.sum(x * x * a) * x + np.sum(q * y * a) / np.sum(y * y * a) * y


def test_the_free_plate_bends_only_and_returns_the_rigid_body_load_as_its_relief():
    """Force and moment balance are the free plate's solvability conditions: what is not balanced
    comes back as the rigid-body (relief) load, and the bending has no mean and no mean tilt."""
    g = PolarGrid(A, 24, 32)
    x, y = g.centres
    q = _load(g)
    sol = PlateOperator(WAFER, g).solve(q)
    assert np.max(np.abs(sol.relief - _rigid_fit(g, q))) < 1e-12 * np.max(np.abs(q))
    w = sol.deflection
    scale = np.max(np.abs(w)) * g.integrate(np.ones_like(w))
    for mode in (np.ones_like(x), x / A, y / A):
        assert abs(g.integrate(w * mode)) < 1e-12 * scale
    balanced = PlateOperator(WAFER, g).solve(q - _rigid_fit(g, q))
    assert np.max(np.abs(balanced.relief)) < 1e-12 * np.max(np.abs(q))
    assert np.max(np.abs(balanced.deflection - w)) < 1e-10 * np.max(np.abs(w))


def test_a_very_stiff_plate_on_a_foundation_moves_as_a_rigid_body():
    g = PolarGrid(A, 24, 32)
    q = _load(g)
    k = 1.8e9
    rigid = _rigid_fit(g, q) / k  # force and moment balance of a rigid plate on the bed
    gaps = []
    for scale in (1.0, 1e4, 1e6, 1e12):
        stiff = KirchhoffPlate(WAFER.thickness, WAFER.modulus * scale, WAFER.poisson)
        w = PlateOperator(stiff, g, k).deflection(q)
        gaps.append(np.max(np.abs(w - rigid)) / np.max(np.abs(rigid)))
    assert gaps[0] > 0.1  # the real wafer bends over its 4 mm bending length
    assert gaps[3] < 1e-6
    assert gaps[1] / gaps[2] == pytest.approx(100.0, rel=0.05)  # the bending falls as 1/D


def test_a_flat_plate_on_a_winkler_bed_under_uniform_pressure_presses_uniformly():
    g = PolarGrid(A, 24, 32)
    k = 1.8e9
    w = PlateOperator(WAFER, g, k).deflection(np.full((24, 32), 3e4))
    assert np.max(np.abs(k * w - 3e4)) < 1e-9 * 3e4


def test_bad_plate_inputs_are_refused_by_name():
    with pytest.raises(ValueError, match="wafer_thickness"):
        KirchhoffPlate(0.0, 130e9, 0.28)
    with pytest.raises(ValueError, match="wafer_poisson"):
        KirchhoffPlate(1e-3, 130e9, 0.5)
    with pytest.raises(ValueError, match="foundation stiffness"):
        PlateOperator(WAFER, PolarGrid(A, 8, 8), -1.0)


def test_zone_load_carries_the_membranes_load_exactly_wherever_the_zone_boundaries_fall():
    g = PolarGrid(0.15, 24, 16)  # ring width 6.25 mm: boundaries at 50 and 100 mm on faces, 130 and 145 mm inside rings
    radii, pressures = (0.05, 0.1, 0.13, 0.145, 0.15), (2e4, 2e4, 2.4e4, 2.8e4, 1.4e4)
    q = zone_load(g, radii, pressures)
    load = sum(p * np.pi * (b * b - a * a) for p, a, b in zip(pressures, (0.0,) + radii[:-1], radii))
    assert g.integrate(q) == pytest.approx(load, rel=1e-14)
    assert q[:16] == pytest.approx(np.full((16, 16), 2e4), rel=1e-14)  # zones 1 and 2 end on faces (50 and 100 mm)
    last = (2.8e4 * (0.145**2 - 0.14375**2) + 1.4e4 * (0.15**2 - 0.145**2)) / (0.15**2 - 0.14375**2)
    assert q[-1] == pytest.approx(np.full(16, last), rel=1e-14)
    assert 2.4e4 < q[20, 0] < 2.8e4  # ring 20 spans 125-131.25 mm: part of zones 3 and 4


def test_on_an_edge_graded_grid_the_balances_stay_the_solvability_conditions_and_the_error_falls():
    """The default grid narrows its rings towards the rim (issue 23): the closure still makes the
    relief the exact rigid-body part of the load, and the error against the Winkler closed form
    falls under refinement (0.12 % to 0.017 %; the graded family does not refine uniformly, so the
    observed order, 0.7-1.3, is not a clean second order: docs/model.md, section 13f)."""
    from cmpsim.numerics.grid import edge_graded_grid

    g = edge_graded_grid(A, 24, 32, 0.3e-3, 0.15)
    q = _load(g)
    sol = PlateOperator(WAFER, g).solve(q)
    assert np.max(np.abs(sol.relief - _rigid_fit(g, q))) < 1e-12 * np.max(np.abs(q))
    k, beta, errors = 2e6, 5.0 / A, []
    for rings, edge in ((8, 1.2e-3), (16, 0.6e-3), (32, 0.3e-3), (64, 0.15e-3)):
        g = edge_graded_grid(A, rings, 16, edge, 0.15)
        w = PlateOperator(WAFER, g, k).deflection(1e4 * jv(2, beta * g.r) * np.cos(2 * g.theta))
        ref = winkler_bessel_mode(g.r, 2, beta, 1e4, A, WAFER.bending_stiffness, WAFER.poisson, k) * np.cos(2 * g.theta)
        errors.append(np.max(np.abs(w - ref)) / np.max(np.abs(ref)))
    assert all(b < a for a, b in zip(errors, errors[1:])), errors
    assert errors[-1] < 3e-4
