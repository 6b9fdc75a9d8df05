"""The physical setup of one operating point: from a Config to the objects of the kernels.

Turns the user's inputs (:class:`~cmpsim.inputs.config.Config`, SI) into the pad surface, the
roughness, the kinematics, the lubrication parameters, the ambient pressure and the grid,
picks the models of the four axes by name (:mod:`cmpsim.models`, the registry: pad, slurry
with its cavitation, removal law, carrier), and builds the
:class:`~cmpsim.solver.wafer.WaferProblem` that the equilibrium solver takes.
"""

from __future__ import annotations

from dataclasses import dataclass

from .. import models
from ..inputs.config import Config
from ..physics.contact import PadSurface
from ..physics.flowfactors import RoughnessGeometry
from ..physics.geometry import check_geometry
from ..physics.grainflow import granular_pressure
from ..physics.grooves import groove_venting
from ..numerics.grid import PolarGrid
from ..physics.kinematics import Kinematics
from ..physics.padstack import LayeredFoundation, WinklerFoundation
from ..operators.reynolds import LubricationParameters
from .wafer import WaferProblem

__all__ = ["PhysicalSetup", "physical_setup", "summit_geometry", "build_problem", "effective_modulus", "pad_foundation", "HAFF_T"]

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
    foundation: WinklerFoundation | LayeredFoundation | None = None  # pad stack under the asperities; None = rigid
    pad_model: models.PadModel | None = None  # picked by pad_compliance (cmpsim.models)
    removal_law: models.RemovalLaw | None = None  # picked by removal_law (cmpsim.models)


def effective_modulus(e1: float, nu1: float, e2: float, nu2: float) -> float:
    """Effective modulus E' of eq. 22: 1/E' = (1 - nu1^2)/E1 + (1 - nu2^2)/E2, Pa."""
    return 1.0 / ((1.0 - nu1**2) / e1 + (1.0 - nu2**2) / e2)


def pad_foundation(config: Config) -> WinklerFoundation | LayeredFoundation | None:
    """The elastic foundation of the pad stack (top pad + subpad), or None if rigid."""
    return models.pad_model(config).foundation


def summit_geometry(config: Config) -> tuple:
    """The pad summits the solver sets up: (summit-height std sigma_s (m), summit radius R (m),
    summit density eta (1/m^2)). ``roughness_scaling = "self_similar"`` scales the radius and density
    given at ``reference_roughness`` with r = sigma_s / sigma_ref (R r, eta / r^2); ``"fixed_summits"``
    takes them as given (docs/model.md, "Changing the pad roughness")."""
    c = config
    sigma = c.pad_roughness
    if c.roughness_scaling == "self_similar":
        ratio = sigma / c.reference_roughness
        return sigma, c.asperity_radius * ratio, c.asperity_density / ratio**2
    return sigma, c.asperity_radius, c.asperity_density


def physical_setup(config: Config) -> PhysicalSetup:
    """Pad, roughness, kinematics, grain-flow parameters, edge pressure and grid of a Config."""
    c = config
    sigma, radius, density = summit_geometry(c)
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
        flow_factor_continuation=c.flow_factor_continuation,
        slurry_model=c.slurry_model,
        viscosity=c.newtonian_viscosity,
        groove_venting=groove_venting(c.pad_groove_pitch, c.pad_groove_width),
    )
    p0 = float(granular_pressure(c.grain_bulk_density, c.diameter_gap_ratio, v, t=HAFF_T))
    grid = c.polar_grid()
    pad_model = models.pad_model(config)
    return PhysicalSetup(pad, rough, kin, lub, p0, grid, pad_model.foundation, pad_model, models.removal_law(config))


def build_problem(config: Config, setup: PhysicalSetup | None = None) -> WaferProblem:
    """The :class:`~cmpsim.solver.wafer.WaferProblem` of a Config (``setup`` if already built)."""
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
        cavitation=config.cavitation,
        cavitation_pressure=config.cavitation_pressure,
        foundation=s.foundation,
        pad_model=s.pad_model,
        slurry=models.slurry_model(config.slurry_model, config.cavitation, config.cavitation_pressure, s.ambient_pressure),
        carrier=models.carrier(config),
    )
