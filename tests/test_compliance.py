"""Pad compliance (issue 16): the pad stack as a Winkler foundation, solved coupled with the film.

The rotation-averaged profile and its non-uniformity are computed here from
``result.polar["removal_rate"]`` (rings x sectors) by a small helper; once the results-schema
branch lands they should come from its ``removal_rate_profile`` / ``within_wafer_nonuniformity``.
"""

from __future__ import annotations

import numpy as np
import pytest

import cmpsim
from cmpsim.compliance import PadLayer, WinklerFoundation, constrained_modulus, foundation_stiffness, local_deflection
from cmpsim.config import PRESETS, Config
from cmpsim.geometry import film_thickness
from cmpsim.grid import PolarGrid
from cmpsim.model import build_problem
from cmpsim.setup import pad_foundation

COMPLIANT = {"pad_compliance": "winkler"}
#: Scalars that are solver diagnostics, not results.
DIAGNOSTICS = {"load_residual", "moment_residual", "iterations", "factorizations", "converged"}


def ring_profile(result) -> tuple[np.ndarray, np.ndarray]:
    """(ring-centre radii, ring-mean removal rate): the rotation-averaged profile, m and m/s."""
    return result.grid.r[:, 0], result.polar["removal_rate"].mean(axis=1)


def wiwnu(result, edge_exclusion: float = 3e-3) -> float:
    """Area-weighted std / mean of the ring means over the rings with r <= R_w - edge_exclusion."""
    r, rr = ring_profile(result)
    keep = r <= result.grid.radius - edge_exclusion
    a = r[keep]  # ring areas are proportional to r dr
    mean = np.sum(a * rr[keep]) / np.sum(a)
    return float(np.sqrt(np.sum(a * (rr[keep] - mean) ** 2) / np.sum(a)) / mean)


@pytest.fixture(scope="module")
def rigid():
    return cmpsim.solve(relative=False)


@pytest.fixture(scope="module")
def compliant():
    return cmpsim.solve(relative=False, **COMPLIANT)


# ---------------------------------------------------------------------------------- kernels
def test_constrained_modulus_is_the_uniaxial_strain_stiffness():
    assert constrained_modulus(1.0, 0.0) == 1.0
    assert constrained_modulus(100e6, 0.3) == pytest.approx(100e6 * 0.7 / (1.3 * 0.4), rel=1e-15)
    # it diverges as the layer becomes incompressible
    assert constrained_modulus(1.0, 0.4999) > 1e3


def test_layers_in_series_add_their_compliances():
    a, b = PadLayer(1e-3, 300e6, 0.3), PadLayer(2e-3, 2e6, 0.1)
    k = foundation_stiffness([a, b])
    assert 1.0 / k == pytest.approx(1e-3 / constrained_modulus(300e6, 0.3) + 2e-3 / constrained_modulus(2e6, 0.1), rel=1e-15)
    assert foundation_stiffness([PadLayer(0.0, 1e6, 0.2)]) == np.inf
    assert WinklerFoundation(2e9).deflection(4e4) == pytest.approx(2e-5, rel=1e-15)
    with pytest.raises(ValueError):
        WinklerFoundation(0.0)
    with pytest.raises(ValueError):
        PadLayer(1e-3, 1e6, 0.5)


def test_the_default_stack_is_ic1000_on_suba_iv_and_subpad_zero_means_none():
    c = Config.default().replace(**COMPLIANT)
    k = pad_foundation(c).stiffness
    k_top = constrained_modulus(c.pad_bulk_modulus, c.pad_poisson) / c.pad_thickness
    k_sub = constrained_modulus(c.subpad_modulus, c.subpad_poisson) / c.subpad_thickness
    assert 1.0 / k == pytest.approx(1.0 / k_top + 1.0 / k_sub, rel=1e-14)
    assert c.pad_thickness == pytest.approx(1.27e-3) and c.subpad_thickness == pytest.approx(1.27e-3)
    assert pad_foundation(c.replace(subpad_thickness=0)).stiffness == pytest.approx(k_top, rel=1e-14)
    assert pad_foundation(Config.default()) is None


def test_paper_preset_stays_rigid_and_hydrodynamic_or_jfo_refuse_a_compliant_pad():
    assert PRESETS["paper"]["pad_compliance"] == "rigid"
    assert Config.paper().replace(pad_bulk_modulus="200 MPa").pad_compliance == "rigid"
    with pytest.raises(ValueError, match="pad_compliance"):
        Config.default().replace(model="hydrodynamic", **COMPLIANT)
    with pytest.raises(ValueError, match="jfo"):
        Config.default().replace(slurry_model="newtonian", cavitation="jfo", **COMPLIANT)
    with pytest.raises(ValueError, match="pad_poisson"):
        Config.default().replace(pad_poisson=0.5, **COMPLIANT)
    with pytest.raises(ValueError, match="subpad_modulus"):
        Config.default().replace(subpad_modulus="-1 MPa")


def test_local_deflection_balances_the_foundation_cell_by_cell():
    problem = build_problem(Config.default().replace(**COMPLIANT))
    h_rigid = np.linspace(-10e-6, 50e-6, 41)
    w = local_deflection(problem, h_rigid, 0.0)
    p = problem.contact(h_rigid + w)[0]
    assert np.max(np.abs(problem.foundation.stiffness * w - p)) < 1e-9 * problem.applied_pressure
    assert np.all(h_rigid + w > 0)


def test_polar_interpolation_is_exact_at_cell_centres_and_second_order():
    errors = []
    for n in (8, 16, 32):
        g = PolarGrid(0.04, n, 3 * n)
        x, y = g.centres
        field = np.cos(40 * x) * np.exp(30 * y)
        assert np.allclose(g.interpolate(field, x, y), field, rtol=0, atol=1e-14)
        t = np.linspace(0, 2 * np.pi, 37)
        xs, ys = 0.03 * np.cos(t) + 0.003, 0.03 * np.sin(t)
        errors.append(np.max(np.abs(g.interpolate(field, xs, ys) - np.cos(40 * xs) * np.exp(30 * ys))))
    orders = np.log2(np.array(errors[:-1]) / np.array(errors[1:]))
    assert np.all(orders > 1.8), orders


# ---------------------------------------------------------------------------------- limits
def test_rigid_setting_takes_the_unchanged_rigid_path(rigid):
    assert build_problem(Config.default()).foundation is None
    assert rigid.solution.state.deflection is None and rigid.solution.state.system is not None
    assert np.all(rigid.polar["pad_deflection"] == 0.0)


def test_huge_stiffness_reproduces_the_rigid_pad_to_1e_8(rigid):
    stiff = cmpsim.solve(relative=False, subpad_thickness=0, pad_bulk_modulus="1e22 Pa", **COMPLIANT)
    assert stiff.problem.foundation.stiffness > 1e24
    angle = abs(rigid.attack_angle_rad)
    for name, want in rigid.scalars.items():
        if name in DIAGNOSTICS:
            continue
        atol = 1e-8 * angle if name == "cross_tilt_rad" else 0.0
        assert stiff.scalars[name] == pytest.approx(want, rel=1e-8, abs=atol), name
    for name, want in rigid.polar.items():
        scale = np.max(np.abs(want)) or 1.0
        assert np.max(np.abs(stiff.polar[name] - want)) <= 1e-8 * scale, name


def test_flat_wafer_under_uniform_speed_on_a_winkler_pad_has_uniform_pressure_and_zero_nonuniformity():
    # A flat wafer at zero tilt under a uniform sliding speed: uniform film, the Couette and shear
    # flow fluxes are uniform and the finite volumes preserve them exactly (zero divergence), so
    # p = p0, the contact pressure and the deflection are uniform and the moments vanish by the
    # symmetry of the grid. The uniform state solves the discrete equations exactly: what is left
    # is round-off, not discretisation error.
    r = cmpsim.solve(relative=False, dome_height=0.0, kinematics="sliding", **COMPLIANT)
    st = r.solution.state
    R, sigma = r.grid.radius, r.config.pad_roughness
    assert abs(r.attack_angle_rad) * R / sigma < 1e-12 and abs(r.cross_tilt_rad) * R / sigma < 1e-12
    p = st.p_total
    assert np.ptp(p) / p.mean() < 1e-12
    assert np.ptp(st.deflection) / st.deflection.mean() < 1e-12
    assert np.ptp(st.h) / st.h.mean() < 1e-12
    assert wiwnu(r) < 1e-12 and wiwnu(r, edge_exclusion=0.0) < 1e-12
    assert p.mean() == pytest.approx(r.config.applied_pressure, rel=1e-9)


@pytest.mark.parametrize(
    "overrides",
    [
        {},
        {"applied_pressure": "2 psi"},
        {"applied_pressure": "6 psi", "rotation_speed": "90 rpm"},
        {"subpad_modulus": "0.5 MPa"},
        {"slurry_model": "newtonian"},
        {"slurry_model": "newtonian", "cavitation": "gumbel", "cavitation_pressure": 0.0},
    ],
    ids=["base", "2psi", "6psi-90rpm", "soft-subpad", "newtonian", "newtonian-gumbel"],
)
def test_load_and_moment_balance_to_1e_9_with_compliance(overrides):
    r = cmpsim.solve(relative=False, **COMPLIANT, **overrides)
    st = r.solution.state
    assert r.converged and abs(r.load_residual) < 1e-9 and r.moment_residual < 1e-9
    # the residual is what it claims: integrate the pressure field independently
    g = r.grid
    load = g.integrate(st.p_total) / (r.config.applied_pressure * np.pi * g.radius**2) - 1.0
    assert load == pytest.approx(r.load_residual, abs=1e-12)
    # and the deflection is the foundation's response to that pressure, cell by cell
    k = r.problem.foundation.stiffness
    assert np.max(np.abs(k * st.deflection - st.p_total)) < 1e-9 * r.config.applied_pressure
    # the film the outputs report is the deformed one: the rigid film plus the deflection
    u, c = st.u, r.config
    rigid_centre = film_thickness(0.0, 0.0, u[0], u[1], c.dome_height, g.radius, cross_tilt=u[2])
    assert r.film_thickness_center_m == pytest.approx(rigid_centre + float(g.interpolate(st.deflection, 0.0, 0.0)), rel=1e-14)


def test_equilibrium_jacobian_includes_the_compliance_central_difference(compliant):
    problem = build_problem(compliant.config)
    sol_u = compliant.solution.state.u
    u = sol_u + np.array([0.05, 0.3, -0.2]) * problem.u_scale  # off equilibrium
    st = problem.state(u)
    J = problem.jacobian(st)
    fd = np.empty((3, 3))
    for k in range(3):
        du = np.zeros(3)
        du[k] = 1e-4 * problem.u_scale[k]
        fd[:, k] = (problem.state(u + du).residual - problem.state(u - du).residual) / (2 * du[k])
    scale = np.max(np.abs(fd), axis=0)
    assert np.max(np.abs(J - fd) / scale) < 1e-4, (J, fd)
    # a rigid pad at the same position has a much stiffer load response: the compliance is in J
    rigid = build_problem(compliant.config.replace(pad_compliance="rigid"))
    h_shift = st.deflection.mean()  # same mean film
    J_rigid = rigid.jacobian(rigid.state(u + np.array([h_shift, 0.0, 0.0])))
    assert abs(J[0, 0]) < 0.8 * abs(J_rigid[0, 0])


def test_deflection_converges_at_second_order_with_the_grid():
    grids = ((10, 24), (20, 48), (40, 96))
    w = [cmpsim.solve(relative=False, grid=f"{n}x{m}", **COMPLIANT).solution.state.deflection for n, m in grids]
    g0 = PolarGrid(1.0, *grids[0])

    def restrict(field, levels):
        for _ in range(levels):  # area-weighted mean of the 2 x 2 children of each cell
            n_r = field.shape[0]
            a = (np.arange(n_r) + 0.5)[:, None]
            field = (field * a).reshape(n_r // 2, 2, field.shape[1] // 2, 2).sum(axis=(1, 3))
            field /= 2.0 * a.reshape(n_r // 2, 2).sum(axis=1)[:, None]
        return field

    d1 = restrict(w[1], 1) - w[0]
    d2 = restrict(w[2], 2) - restrict(w[1], 1)
    area = g0.area / g0.area.sum()
    l2 = np.sqrt(np.sum(area * d1**2) / np.sum(area * d2**2))
    order_l2 = np.log2(l2)
    order_max = np.log2(np.max(np.abs(d1)) / np.max(np.abs(d2)))
    print(f"\nobserved order of the deflection: L2 {order_l2:.2f}, max {order_max:.2f}")
    assert 1.7 < order_l2 < 2.5 and 1.7 < order_max < 2.5


# ---------------------------------------------------------------------------------- physics
def test_compliance_flattens_the_removal_profile_and_a_softer_stack_flattens_it_more(rigid, compliant):
    soft = cmpsim.solve(relative=False, subpad_thickness="2.54 mm", **COMPLIANT)
    w_rigid, w_default, w_soft = wiwnu(rigid), wiwnu(compliant), wiwnu(soft)
    print(f"\nWIWNU (3 mm edge exclusion): rigid {w_rigid:.3f}, default stack {w_default:.3f}, 2x subpad {w_soft:.3f}")
    assert w_rigid > w_default > w_soft
    # the wafer sinks into the pad: the deflection is of the order of P / k
    k = compliant.problem.foundation.stiffness
    assert compliant.polar["pad_deflection"].mean() == pytest.approx(compliant.config.applied_pressure / k, rel=0.2)
