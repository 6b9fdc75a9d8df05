"""Outputs of a solved equilibrium: stresses, removal rate, and every scalar and wafer map.

Pure post-processing of an :class:`~cmpsim.solver.equilibrium.EquilibriumSolution`: evaluates the
shear stress and the removal law on the solved pressure and film, and reduces the fields to
the scalars and radial profiles declared in :mod:`cmpsim.results.outputs` (wafer means, load
shares, rotation averages, within-wafer uniformity).
"""

from __future__ import annotations

import numpy as np

from ..results import outputs, uniformity
from ..inputs.config import Config
from ..models import removal_law as _removal_law
from ..physics.contact import contact_spot_density
from ..physics.removal import contact_shear_stress
from .setup import PhysicalSetup
from ..operators.state import EquilibriumSolution
from .wafer import WaferProblem

__all__ = ["evaluate_outputs", "reduce_outputs", "stress_fields", "removal_law_fields"]


def evaluate_outputs(config: Config, setup: PhysicalSetup, problem: WaferProblem, sol: EquilibriumSolution):
    """Scalars (SI), polar fields (cell centres) and radial profiles of a solved equilibrium.

    Every name is an entry of :data:`cmpsim.results.outputs.OUTPUTS`.
    """
    st = sol.state
    g = problem.grid
    f = stress_fields(config, problem, st, setup.kinematics, setup.lubrication)
    tau, sigma_n, p_normal = f["shear_stress_magnitude"], f["normal_stress"], f["granular_pressure"]
    law = setup.removal_law or _removal_law(config)
    fields = removal_law_fields(f, st, problem)
    rr = law.rate(**{name: fields[name]() for name in law.needs})
    # film thickness: centre, and minimum over the cell centres and the rim
    u = st.u
    h_rim = problem.film(u, *g.rim())
    polar = {
        "film_thickness": st.h,
        "slurry_pressure": st.p_fluid,
        "granular_pressure": p_normal,
        "contact_pressure": st.p_contact,
        "total_pressure": st.p_total,
        "contact_area_ratio_elastic": st.area_elastic,
        "contact_area_ratio_elastoplastic": st.area_elastoplastic,
        "contact_area_ratio_plastic": st.area_plastic,
        "normal_stress": sigma_n,
        "shear_stress": tau,
        "removal_rate": rr,
        # bulk deflection of the pad stack (0 on a rigid pad; compliance.py)
        "pad_deflection": st.deflection if st.deflection is not None else np.zeros_like(st.h),
        # bending of the wafer on a membrane carrier (0 on the rigid carrier; cmpsim.numerics.plate)
        "wafer_bending": problem.carrier.bending_field(problem),
    }
    if st.fill_fraction is not None:
        polar["fill_fraction"] = st.fill_fraction
    # the outputs that are not a reduction of a field; the rest follow from the registry
    explicit = {
        "film_thickness_center": float(problem.film(u, 0.0, 0.0)),
        "film_thickness_min": float(min(st.h.min(), h_rim.min())),
        "h0": float(u[0]),
        "attack_angle": float(u[1]),
        "cross_tilt": float(u[2]),
        # the slurry pressure at the wafer edge: p0 (granular), ambient = 0 gauge (Newtonian)
        "ambient_pressure": problem.slurry.edge_pressure(setup.ambient_pressure),
        "sliding_speed": setup.kinematics.sliding_speed,
        "load_residual": float(st.residual[0]),
        "moment_residual": float(max(abs(st.residual[1]), abs(st.residual[2]))),
        "flow_factor_floored_fraction": float(st.floored_fraction),
        "iterations": int(sol.iterations),
        "factorizations": int(sol.factorizations),
        "converged": bool(sol.converged),
    }
    scalars, profiles = reduce_outputs(polar, g, problem.load_scale, config.edge_exclusion, explicit)
    return scalars, polar, profiles



def stress_fields(config: Config, problem: WaferProblem, state, kinematics, lubrication) -> dict:
    """The stresses on the wafer of a solved state (arrays on the cell centres, SI).

    ``relative_velocity`` (dux, duy) m/s, ``shear_stress`` (tau_x, tau_y) Pa (slurry plus summit
    friction with ``removal_shear = "total"``), ``shear_stress_magnitude``, ``fluid_shear_stress``,
    ``granular_pressure`` (the normal stress the slurry puts on the removal law) and
    ``normal_stress``, Pa. Shared by :func:`evaluate_outputs` and the studies that evaluate a
    removal law again on a solved equilibrium (``cmpsim.polisher``).
    """
    st = state
    _, _, dux, duy = kinematics.mean_and_relative(problem.xc, problem.yc)
    ar = st.area_ratio
    slurry = problem.slurry
    # the slurry's shear on the wafer and the normal stress the removal law sees (for a
    # Newtonian slurry the compressive part of the gauge pressure; docs/model.md)
    tsx, tsy = slurry.shear_stress(st, problem.grid, lubrication, (dux, duy))
    p_normal = slurry.normal_pressure(st.p_slurry)
    tau_x = (1.0 - ar) * tsx
    tau_y = (1.0 - ar) * tsy
    if config.removal_shear == "total":
        tcx, tcy = contact_shear_stress(st.p_contact, (dux, duy), config.friction_coefficient)
        tau_x, tau_y = tau_x + tcx, tau_y + tcy
    return {
        "relative_velocity": (dux, duy),
        "shear_stress": (tau_x, tau_y),
        "shear_stress_magnitude": np.hypot(tau_x, tau_y),
        "fluid_shear_stress": ((1.0 - ar) * tsx, (1.0 - ar) * tsy),
        "granular_pressure": p_normal,
        "normal_stress": (1.0 - ar) * p_normal + st.p_contact,
    }


def removal_law_fields(stresses: dict, state, problem: WaferProblem) -> dict:
    """The fields a removal law may ask for (:data:`cmpsim.models.removal_laws.REMOVAL_FIELDS`), as
    callables (evaluated only if the law ``needs`` them), from :func:`stress_fields` and the state."""
    st = state
    dux, duy = stresses["relative_velocity"]
    return {
        "normal_stress": lambda: stresses["normal_stress"],
        "shear_stress": lambda: stresses["shear_stress"],
        "contact_pressure": lambda: st.p_contact,
        "fluid_shear_stress": lambda: stresses["fluid_shear_stress"],
        "relative_speed": lambda: np.hypot(dux, duy),
        "contact_area_ratio": lambda: st.area_ratio,
        "film_thickness": lambda: st.h,
        "contact_spot_density": lambda: contact_spot_density(st.h - problem.separation_offset, problem.pad),
    }

def reduce_outputs(polar: dict, grid, load: float, edge_exclusion: float, explicit: dict):
    """The scalars and profiles of the registry (:mod:`cmpsim.results.outputs`) from the polar fields.

    ``explicit`` holds the scalars that are not reductions of a field (centre and minimum film,
    equilibrium state, setup values, solver diagnostics). Returns ``(scalars, profiles)``,
    scalars in registry order, profiles ``{"radius": r_i, NAME_profile: ring means}``.
    """
    area = np.pi * grid.radius**2
    profiles = {"radius": grid.r[:, 0].copy()}
    for name in outputs.profile_names():
        profiles[name] = uniformity.ring_mean(polar[outputs.profile(name).of[0]])
    computed = dict(explicit)
    for name in outputs.scalar_names():
        o = outputs.scalar(name)
        if o.reduction == "wafer_mean":
            computed[name] = grid.integrate(polar[o.of[0]]) / area
        elif o.reduction == "load_share":
            computed[name] = grid.integrate(polar[o.of[0]]) / load
        elif o.reduction == "profile_std_over_mean":
            computed[name] = uniformity.uniformity(profiles[o.of[0]], grid.radius, edge_exclusion, grid.ring_faces)[0]
        elif o.reduction == "profile_range":
            computed[name] = uniformity.uniformity(profiles[o.of[0]], grid.radius, edge_exclusion, grid.ring_faces)[1]
    for name in outputs.scalar_names():
        o = outputs.scalar(name)
        if o.reduction == "sum":
            total = 0.0
            for part in o.of:
                total = total + computed[part]
            computed[name] = total
    scalars = {name: computed[name] for name in outputs.scalar_names() if name in computed}
    return scalars, profiles
