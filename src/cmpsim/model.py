"""One operating point: from a :class:`~cmpsim.config.Config` to a :class:`~cmpsim.result.Result`.

This is the layer that turns the user's inputs into the physical objects of the kernels
(pad surface, roughness, kinematics, grain-flow parameters), solves the equilibrium and
evaluates every output. ``cmpsim.solve`` and ``cmpsim run`` both call :func:`solve`.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from .config import Config
from .contact import PadSurface
from .equilibrium import EquilibriumError, EquilibriumSolution, WaferProblem, scan_moment_roots, solve_equilibrium
from .flowfactors import RoughnessGeometry, shear_stress_factors
from .geometry import check_geometry
from .grainflow import grain_coefficients, granular_pressure
from .grid import PolarGrid
from .kinematics import Kinematics
from .removal import contact_shear_stress, removal_rate, slurry_shear_stress
from .reynolds import LubricationParameters

__all__ = ["build_problem", "solve", "PhysicalSetup", "physical_setup", "EquilibriumError", "REFERENCE_CASE", "HAFF_T"]

#: The paper's normalisation point of the relative removal rate (Figs. 11-12) with its base
#: load and speed (Table 1).
REFERENCE_CASE = {"particle_diameter": 100e-9, "pad_roughness": 15e-6, "applied_pressure": "4 psi", "rotation_speed": "60 rpm"}
#: Haff's pressure constant t; the paper gives only t/a = 1, so t = a = 1 (docs/model.md).
HAFF_T = 1.0


@dataclass(frozen=True)
class PhysicalSetup:
    """The physical objects derived from a Config (all SI)."""

    pad: PadSurface
    roughness: RoughnessGeometry
    kinematics: Kinematics
    lubrication: LubricationParameters
    ambient_pressure: float  # p0, Pa
    grid: PolarGrid


def effective_modulus(e1: float, nu1: float, e2: float, nu2: float) -> float:
    """Effective modulus E' of eq. 22: 1/E' = (1 - nu1^2)/E1 + (1 - nu2^2)/E2, Pa."""
    return 1.0 / ((1.0 - nu1**2) / e1 + (1.0 - nu2**2) / e2)


def physical_setup(config: Config) -> PhysicalSetup:
    """Pad, roughness, kinematics, grain-flow parameters, edge pressure and grid of a Config."""
    c = config
    sigma = c.pad_roughness
    if c.roughness_scaling == "self_similar":
        ratio = sigma / c.reference_roughness
        radius, density = c.asperity_radius * ratio, c.asperity_density / ratio**2
    else:
        radius, density = c.asperity_radius, c.asperity_density
    pad = PadSurface(
        sigma_s=sigma,
        asperity_density=density,
        asperity_radius=radius,
        e_star=effective_modulus(c.pad_modulus, c.pad_poisson, c.wafer_modulus, c.wafer_poisson),
        hardness=c.pad_hardness,
        poisson=c.pad_poisson,
        height_cutoff=c.contact_cutoff,
    )
    rough = RoughnessGeometry(
        sigma_pad=sigma,
        sigma_wafer=c.wafer_roughness,
        gamma_pad=c.peklenik_number,
        gamma_wafer=1.0,
        theta_pad=c.roughness_angle,
    )
    kin = Kinematics(c.rotation_speed, c.rotation_speed * c.wafer_speed_ratio, c.centre_distance, c.kinematics)
    v = c.fluctuation_ratio * kin.sliding_speed
    lub = LubricationParameters(
        particle_diameter=c.particle_diameter,
        w_over_k=c.w_over_k,
        t_over_a=c.t_over_a,
        fluctuation_velocity=v,
        roughness=rough,
        kinematics=kin,
        flow_factor_floor=c.flow_factor_floor,
    )
    p0 = float(granular_pressure(c.granular_density, c.particle_diameter, c.diameter_gap_ratio, v, t=HAFF_T))
    n_r, n_t = c.grid_shape
    grid = PolarGrid(0.5 * c.wafer_diameter, n_r, n_t)
    return PhysicalSetup(pad, rough, kin, lub, p0, grid)


def build_problem(config: Config, setup: PhysicalSetup | None = None) -> WaferProblem:
    """The :class:`~cmpsim.equilibrium.WaferProblem` of a Config (``setup`` if already built)."""
    s = setup or physical_setup(config)
    check_geometry(config.dome_height, s.grid.radius)
    return WaferProblem(
        s.grid,
        config.dome_height,
        config.applied_pressure,
        s.ambient_pressure,
        s.lubrication,
        s.pad,
        config.model,
    )


def _outputs(config: Config, setup: PhysicalSetup, problem: WaferProblem, sol: EquilibriumSolution):
    """Scalars and polar fields of a solved equilibrium."""
    st = sol.state
    g = problem.grid
    area = np.pi * g.radius**2
    lub = setup.lubrication
    xc, yc = problem.xc, problem.yc
    # shear stress and removal rate
    grad_phi = g.gradient(st.phi, 0.0)
    grad_p = (st.p_slurry * grad_phi[0], st.p_slurry * grad_phi[1])
    _, f, _ = grain_coefficients(st.h / lub.particle_diameter, lub.w_over_k)
    phi_fs, phi_fp = shear_stress_factors(st.h / setup.roughness.sigma, f, setup.roughness)
    _, _, dux, duy = setup.kinematics.mean_and_relative(xc, yc)
    ar = st.area_ratio
    tsx, tsy = slurry_shear_stress(
        st.p_slurry, grad_p, st.h, (dux, duy), lub.particle_diameter, lub.fluctuation_velocity, lub.t_over_a, phi_fs, phi_fp
    )
    tau_x = (1.0 - ar) * tsx
    tau_y = (1.0 - ar) * tsy
    if config.removal_shear == "total":
        tcx, tcy = contact_shear_stress(st.p_contact, (dux, duy), config.friction_coefficient)
        tau_x, tau_y = tau_x + tcx, tau_y + tcy
    tau = np.hypot(tau_x, tau_y)
    sigma_n = (1.0 - ar) * st.p_slurry + st.p_contact
    rr = removal_rate(sigma_n, (tau_x, tau_y), config.preston_coefficient)
    # film thickness: centre, and minimum over the cell centres and the rim
    u = st.u
    rim_t = np.linspace(0.0, 2.0 * np.pi, 4 * g.n_theta, endpoint=False)
    h_rim = problem.film(u, g.radius * np.cos(rim_t), g.radius * np.sin(rim_t))
    h_center = float(problem.film(u, 0.0, 0.0))
    load = problem.load_scale
    scalars = {
        "film_thickness_center_m": h_center,
        "film_thickness_min_m": float(min(st.h.min(), h_rim.min())),
        "h0_m": float(u[0]),
        "attack_angle_rad": float(u[1]),
        "cross_tilt_rad": float(u[2]),
        "fluid_load_fraction": g.integrate(st.p_fluid) / load,
        "contact_load_fraction": g.integrate(st.p_contact) / load,
        "contact_area_ratio_elastic": g.integrate(st.area_elastic) / area,
        "contact_area_ratio_elastoplastic": g.integrate(st.area_elastoplastic) / area,
        "contact_area_ratio_plastic": g.integrate(st.area_plastic) / area,
        "mean_normal_stress_pa": g.integrate(sigma_n) / area,
        "mean_shear_stress_pa": g.integrate(tau) / area,
        "removal_rate": g.integrate(rr) / area,
        "ambient_pressure_pa": setup.ambient_pressure,
        "sliding_speed_m_s": setup.kinematics.sliding_speed,
        "load_residual": float(st.residual[0]),
        "moment_residual": float(max(abs(st.residual[1]), abs(st.residual[2]))),
        "flow_factor_floored_fraction": float(st.floored_fraction),
        "iterations": int(sol.iterations),
        "factorizations": int(sol.factorizations),
        "converged": bool(sol.converged),
    }
    scalars["removal_rate_nm_per_min"] = scalars["removal_rate"] * 1e9 * 60.0
    polar = {
        "film_thickness": st.h,
        "slurry_pressure": st.p_fluid,
        "granular_pressure": st.p_slurry,
        "contact_pressure": st.p_contact,
        "total_pressure": st.p_total,
        "area_ratio_elastic": st.area_elastic,
        "area_ratio_elastoplastic": st.area_elastoplastic,
        "area_ratio_plastic": st.area_plastic,
        "normal_stress": sigma_n,
        "shear_stress": tau,
        "removal_rate": rr,
    }
    return scalars, polar


_REFERENCE_CACHE: dict[tuple, float] = {}


def _reference_removal_rate(config: Config) -> float:
    ref = config.replace(model="lep", **REFERENCE_CASE)
    key = tuple(sorted(ref.to_dict().items()))
    if key not in _REFERENCE_CACHE:
        if len(_REFERENCE_CACHE) > 256:
            _REFERENCE_CACHE.clear()
        _REFERENCE_CACHE[key] = solve(ref, relative=False).removal_rate
    return _REFERENCE_CACHE[key]


def solve(config: Config | None = None, start=None, relative: bool = True, check_roots: bool = False, **overrides):
    """Solve one operating point and evaluate every output.

    Parameters
    ----------
    config : Config, optional
        Inputs; default :meth:`Config.default` (the paper's base case).
    start : array_like, optional
        Initial (h0 [m], attack angle [rad], cross tilt [rad]) for Newton (warm start).
    relative : bool
        Also solve the reference case (LEP model, d = 100 nm, sigma = 15 um, 4 psi, 60 rpm,
        other inputs equal) for ``removal_rate_relative`` (cached).
    check_roots : bool
        Also scan the attack angle for other moment roots (about 13 load balances); adds
        the scalar ``moment_roots_found`` and ``result.root_scan``.
    **overrides
        Inputs to change, by name (``applied_pressure="3 psi"``).

    Returns
    -------
    cmpsim.result.Result

    Raises
    ------
    ValueError
        Bad input (names the parameter and its valid range).
    cmpsim.equilibrium.EquilibriumError
        No equilibrium exists or none was found; the message says why.
    """
    from .result import Result

    config = config or Config.default()
    if overrides:
        config = config.replace(**overrides)
    setup = physical_setup(config)
    problem = build_problem(config, setup)
    sol = solve_equilibrium(problem, start=start, tol=config.tolerance, max_iter=config.max_iterations)
    scalars, polar = _outputs(config, setup, problem, sol)
    if relative:
        scalars["removal_rate_relative"] = scalars["removal_rate"] / _reference_removal_rate(config)
    scan = None
    if check_roots:
        scan = scan_moment_roots(problem, sol)
        scalars["moment_roots_found"] = len(scan.roots)
    result = Result(config=config, scalars=scalars, polar=polar, grid=setup.grid, problem=problem, solution=sol)
    result.root_scan = scan
    return result
