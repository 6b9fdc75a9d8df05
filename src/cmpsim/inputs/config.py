"""Inputs of one operating point: frozen dataclasses, the parameter registry, parsing with units.

Every input has one entry in :data:`PARAMETERS` with its section, symbol, SI unit, display
unit, default, valid range and source. Values are stored in SI. They may be given as a
string with units (``"4 psi"``, ``"60rpm"``, ``"100nm"``), a pint Quantity, or a plain
number taken as SI. Every bad value raises ``ValueError`` naming the parameter and its valid
range; the same text reaches the command line.

An entry of the registry is a :class:`cmpsim.inputs.param.Param` (its range check lives there), the
named grids are in :mod:`cmpsim.numerics.grid` and the inputs that another input sets in
:mod:`cmpsim.inputs.derived`; their public names are importable from here as before.
"""

from __future__ import annotations

import dataclasses
import math
import tomllib
from dataclasses import dataclass
from pathlib import Path
from typing import Any

from . import units
from .derived import MATCH_RTOL as _MATCH_RTOL
from .derived import loading_overrides as _loading_overrides
from .derived import with_zone_load as _with_zone_load
from .derived import zone_mean_pressure
from ..numerics.grid import GRID_EDGE, GRID_PRESETS
from ..physics.chemistry import input_names as chemistry_input_names
from ..physics.materials import ABRASIVES, FILMS, krieger_dougherty, volume_fraction
from .param import Param, did_you_mean

__all__ = [
    "Param",
    "PARAMETERS",
    "Wafer",
    "Pad",
    "Slurry",
    "Process",
    "Numerics",
    "Config",
    "parse_value",
    "parameter",
    "parameter_table_markdown",
    "zone_mean_pressure",
    "GRID_PRESETS",
    "GRID_EDGE",
    "PRESETS",
]

#: Carrier viscosity that gives Thakurta et al.'s 0.005 Pa s at the default loading (12.5 wt% silica)
#: through the Krieger-Dougherty law (docs/model.md, 'Slurry viscosity').
_CARRIER_VISCOSITY = 5e-3 / float(krieger_dougherty(volume_fraction(0.125, ABRASIVES["silica"].density), 1.0))

_P = Param


def _chemistry_params() -> list[Param]:
    """The three constants of eq. 13h.2 for every film of :data:`cmpsim.physics.materials.FILMS`."""
    out = []
    for film in FILMS:
        factor, speed, rate = chemistry_input_names(film)
        why = f"film_chemistry = 'additive', film = '{film}'"
        out += [
            Param(factor, "process", f"k_{film}", "", "", 1.0, f"Factor k_F on the mechanical removal rate of {film} ({why}): RR = k_F RR_m + B_F |du| + R_c,F", "1: the removal law's own rate (no calibration); fitted by `cmpsim calibrate` to removal rates of the film (docs/model.md, 13h)", 0.0, None, False, typical=1.0, linear=True),
            Param(speed, "process", f"B_{film}", "", "nm/m", 0.0, f"Chemical removal per unit sliding distance B_F of {film} ({why}): the term B_F |du| of the rate", "0: no chemistry (no sourced value for any slurry here); fitted by `cmpsim calibrate` to removal rates of the film at several sliding speeds (Babu's group's law RR = K P V + B V + R_c, docs/model.md, 13h)", 0.0, None, False, typical=1e-8, linear=True),
            Param(rate, "process", f"R_c,{film}", "m/s", "nm/min", 0.0, f"Chemical removal rate R_c,F of {film} that needs no sliding ({why}): the constant term of the rate", "0: no chemistry (no sourced value for any slurry here); fitted by `cmpsim calibrate` to removal rates of the film (Babu's group's law RR = K P V + B V + R_c, docs/model.md, 13h)", 0.0, None, False, typical=1e-8, linear=True),
        ]
    return out


PARAMETERS: dict[str, Param] = {
    p.name: p
    for p in [
        # ---------------------------------------------------------------- wafer
        _P("wafer_diameter", "wafer", "2 R_w", "m", "in", 0.0762, "Wafer diameter", "Paper Table 1 (3 in)", 0.0),
        _P("dome_height", "wafer", "delta_d", "m", "um", 5e-6, "Dome height of the convex wafer (0 = flat)", "Paper Table 1", 0.0, None, False),
        _P("wafer_thickness", "wafer", "t_w", "m", "um", 381e-6, "Thickness of the wafer: its bending stiffness D = E t^3 / 12(1 - nu^2) on a membrane carrier (carrier = 'membrane')", "SEMI M1 (polished silicon wafers): 381 um for 76.2 mm (3 in) wafers; 725 um for 200 mm, 775 um for 300 mm", 0.0),
        _P("edge_exclusion", "wafer", "EE", "m", "mm", 3e-3, "Metrology edge exclusion: the outer annulus left out of the within-wafer uniformity (also < wafer_diameter / 2)", "Wafer metrology convention: flatness and thickness are specified over a fixed quality area inside a nominal edge exclusion, 3 mm for 100-200 mm wafers (SEMI M1; SEMI MF1530), 2 mm and less for 300 mm (ITRS); see docs/model.md ('Within-wafer uniformity')", 0.0, None, False),
        _P("film", "wafer", "-", "choice", "", "oxide", "Film being polished (its modulus, Poisson ratio and hardness enter the abrasive removal law)", "cmpsim.physics.materials.FILMS (each entry with its source); docs/model.md ('Abrasive removal')", choices=tuple(FILMS)),
        _P("film_hardness", "wafer", "H_0", "Pa", "GPa", 0.0, "Hardness of the film against large particles (abrasive removal law); 0 = the film's value in cmpsim.physics.materials.FILMS", "0: the film table (each entry with its source); set it with film_size_length from the same measurement (docs/model.md, 'Particle size and the film's hardness')", 0.0, None, False),
        _P("film_size_length", "wafer", "R*", "m", "um", 0.0, "Indentation size length of the film's hardness under a sphere: a particle of radius r meets H = H_0 sqrt(1 + R*/r) (abrasive removal law); 0 = no size effect", "Nix & Gao, J. Mech. Phys. Solids 46, 411 (1998); Swadener, George & Pharr, J. Mech. Phys. Solids 50, 681 (2002). 0: no measurement at particle radii of 25 nm - 1 um exists for any film here; bulk fits do not transfer (docs/model.md, 'Particle size and the film's hardness')", 0.0, None, False),
        # ---------------------------------------------------------------- process
        _P("applied_pressure", "process", "P", "Pa", "psi", 4 * 6894.757293168361, "Applied load over wafer area", "Paper Table 1 (4 psi; range 2-6 psi)", 0.0),
        _P("carrier", "process", "-", "choice", "", "rigid", "Wafer carrier: a rigid wafer held at a pivot at the centre of its face under one uniform applied pressure (the paper), or a multi-zone membrane pressing a wafer that bends as a free elastic plate", "Paper eq. 30-31 (rigid); docs/model.md ('Force and moment balance', 'Carrier')", choices=("rigid", "membrane")),
        _P("zone_radii", "process", "R_k", "m", "mm", (), "Outer radius of each pressure zone of the membrane, increasing, the last at the wafer rim; unset = one zone over the whole wafer", "Head geometry of the user's tool; five-zone 300 mm heads: docs/model.md ('Carrier')", 0.0, items=True),
        _P("zone_pressures", "process", "P_k", "Pa", "psi", (), "Membrane pressure of each zone (one per zone_radii); unset = applied_pressure in every zone. When set, applied_pressure is their area-weighted mean", "The user's recipe (production membrane heads run zones at about 1-8 psi); unset reproduces the uniform load", 0.0, items=True),
        _P("retaining_ring_gap", "process", "g_r", "m", "mm", 1e-3, "Radial gap between the wafer edge and the inner edge of the retaining ring", "Assumption [A]: a ring must hold the wafer with a small clearance; about 1 mm (ring inner diameter ~302 mm for 300 mm wafers). See docs/model.md ('Carrier')", 0.0, None, False),
        _P("retaining_ring_width", "process", "w_r", "m", "mm", 20e-3, "Radial width of the retaining ring's face on the pad", "Assumption [A]: of the order of 20 mm; see docs/model.md ('Carrier')", 0.0),
        _P("retaining_ring_pressure", "process", "P_r", "Pa", "psi", 0.0, "Pressure of the retaining ring's face on the pad (0 = no ring)", "0 = no ring, the paper's head; acts through the laterally coupled pad (pad_compliance = 'layer') only: docs/model.md ('Carrier')", 0.0, None, False),
        _P("rotation_speed", "process", "Omega_p", "rad/s", "rpm", 2 * math.pi, "Pad (relative) rotation speed", "Paper Table 1 (60 rpm; range 30-90 rpm)", 0.0),
        _P("wafer_speed_ratio", "process", "Omega_w/Omega_p", "", "", 1.0, "Wafer over pad rotation speed (1 = uniform relative velocity)", "Assumption: the paper quotes one relative rotation speed; equal speeds as in Thakurta et al. 2001 (60/60 rpm)", 0.0),
        _P("centre_distance", "process", "e", "m", "m", 0.1, "Pad-centre to wafer-centre distance", "Not in the paper; assumed so that 60 rpm gives 0.63 m/s, inside the 0.3-1.75 m/s of CMP practice (Mariscal et al. 2020). See docs/model.md", 0.0),
        _P("kinematics", "process", "-", "choice", "", "rotating", "Surface velocities: rigid rotations of pad and wafer, or uniform sliding", "docs/model.md, 'Kinematics'", choices=("rotating", "sliding")),
        _P("preston_coefficient", "process", "K", "m/(s*Pa^2)", "m/(s*Pa^2)", 2.5e-18, "Runnels-Eyman coefficient in RR = K sigma_n tau", "Scale only (relative RR is independent of it): about 100 nm/min at the base case, as Preston k_p = 1e-13 1/Pa gives at 4 psi and 0.63 m/s; see docs/model.md", 0.0),
        _P("removal_law", "process", "-", "choice", "", "abrasive", "Removal law: the paper's RR = K sigma_n tau; the shear-power law RR = k_s (mu p_c + chi tau_f) |du|; or abrasive particles trapped in the real contact ploughing the film", "docs/model.md ('Removal rate', 'Abrasive removal'); Borucki et al., ECS J. Solid State Sci. Technol. 12, 044004 (2023); Luo & Dornfeld, IEEE Trans. Semicond. Manuf. 14, 112 (2001)", choices=("paper", "shear_power", "abrasive")),
        _P("abrasion_efficiency", "process", "k_a", "", "", 0.1, "Share of the groove ploughed by a trapped particle that leaves as debris (abrasive removal law)", "Three-body abrasion (particles free between two surfaces) wears about ten times less than two-body abrasion, which cuts the whole groove (Rabinowicz, Dunn & Russell, Wear 4, 345 (1961)); scale of the law, see docs/model.md ('Abrasive removal')", 0.0, 1.0, False, False),
        _P("removal_kinetics", "process", "-", "choice", "", "mechanical", "Removal kinetics: the mechanical removal alone, or a thermally activated chemical step in series with it (two-step, flash heating)", "docs/model.md ('Two-step kinetics'); Sorooshian, Philipossian, Borucki et al. (2004-2006); Mariscal et al., ECS J. Solid State Sci. Technol. 9, 044008 (2020)", choices=("mechanical", "two_step")),
        _P("chemical_rate", "process", "c_0", "m/s", "nm/min", 200.0 / 6e10, "Rate of the chemical step at slurry_temperature (removal_kinetics = 'two_step')", "No published two-step constants for oxide, copper or tungsten were available to this project: an order of magnitude (200 nm/min, the rates of the shipped oxide series), to be calibrated (`cmpsim calibrate --free chemical_rate`); docs/model.md ('Two-step kinetics')", 0.0),
        _P("activation_energy", "process", "E_a", "J/mol", "kJ/mol", 50e3, "Activation energy of the chemical step (removal_kinetics = 'two_step')", "Middle of the 20-80 kJ/mol of CMP Arrhenius fits (second-hand; Sorooshian et al. 2004-2006); to be calibrated; docs/model.md ('Two-step kinetics')", 0.0, None, False),
        _P("flash_heating_coefficient", "process", "beta", "K*m^2/W", "K*m^2/W", 1e-3, "Temperature rise of the surface per unit friction power per area, T = T_0 + beta mu p_c |du| (removal_kinetics = 'two_step')", "Order of magnitude: pad surface temperatures rise by 10-20 K at friction powers of 1e4 W/m^2 (IR measurements of the Philipossian group, second-hand); docs/model.md ('Two-step kinetics')", 0.0, None, False),
        _P("slurry_temperature", "process", "T_0", "K", "K", 298.15, "Temperature of slurry and pad away from the contacts (removal_kinetics = 'two_step')", "Room temperature, 25 C", 200.0, 400.0),
        _P("shear_power_coefficient", "process", "k_s", "1/Pa", "1/Pa", 2.5e-13, "Scale k_s of the shear-power removal law", "Scale only: k_s mu = 1e-13 1/Pa, the order of oxide Preston constants (Preston's k_p P U gives ~100 nm/min at 4 psi and 0.63 m/s); see docs/model.md", 0.0),
        _P("fluid_shear_weight", "process", "chi", "", "", 0.0, "Share chi of the slurry's shear power that removes material in the shear-power law", "docs/model.md ('Removal rate'): removal needs abrasive contact pressure, which the slurry's bulk shear does not give", 0.0, 1.0, False, False),
        _P("removal_shear", "process", "-", "choice", "", "total", "Shear stress tau of the removal law: slurry plus pad-summit friction, or slurry only (Runnels & Eyman)", "docs/model.md ('Removal rate')", choices=("total", "slurry")),
        _P("pad_temperature", "process", "T_pad", "K", "K", 0.0, "Temperature of the pad surface under the wafer, the base of the chemical step's flash temperature T = T_pad + beta mu p_c |du| (removal_kinetics = 'two_step'; chemical_rate stays the rate at slurry_temperature); 0 = slurry_temperature. Set through time by cmpsim polish from the pad's heat balance", "cmpsim.physics.thermal (the pad's heat balance, docs/polisher.md); 0: the pad at the slurry's temperature, the steady model before issue 32", 0.0, 400.0, False, False),
        # film chemistry (docs/model.md, 13h): RR = k_F RR_m + B_F |du| + R_c,F per film, picked by film_chemistry
        _P("film_chemistry", "process", "-", "choice", "", "none", "What the slurry's chemistry adds to the mechanical removal rate of the film polished: nothing (the removal law alone), or the additive law RR = k_F RR_m + B_F |du| + R_c,F with the film's constants mechanical_factor_<film>, chemistry_speed_<film>, chemistry_rate_<film>", "none: the mechanical model, uncalibrated (no sourced chemistry constants for any slurry here); additive: the empirical law RR = K P V + B V + R_c of S. V. Babu's group (read in a transcription), with cmpsim's mechanical rate for K P V; set by `cmpsim calibrate` (docs/model.md, 13h)", choices=("none", "additive")),
        *_chemistry_params(),
        # ---------------------------------------------------------------- slurry
        _P("slurry_model", "slurry", "-", "choice", "", "newtonian", "Slurry rheology: Haff grain flow (the paper, solved in ln p) or a Newtonian liquid (solved in p)", "docs/model.md ('Newtonian slurry and cavitation')", choices=("granular", "newtonian")),
        _P("slurry_viscosity", "slurry", "eta", "Pa*s", "mPa*s", 0.0, "Viscosity of the Newtonian slurry (slurry_model = 'newtonian'); 0 = from solids_loading by the Krieger-Dougherty law on carrier_viscosity", "Set: a measured value (Thakurta et al., J. Electrochem. Soc. 148(4) G207 (2001): 0.005 Pa s; CMP slurries 1-30 mPa s; Lai, PhD MIT 2001: 0.03 Pa s); 0: Krieger & Dougherty, Trans. Soc. Rheol. 3, 137 (1959), docs/model.md ('Slurry viscosity'); the range stops at 10 Pa s, far beyond any slurry", 0.0, 10.0, False, False),
        _P("carrier_viscosity", "slurry", "eta_c", "Pa*s", "mPa*s", _CARRIER_VISCOSITY, "Viscosity of the liquid that carries the particles (used when slurry_viscosity = 0)", "Thakurta et al.'s 0.005 Pa s taken as the slurry viscosity at the default loading (12.5 wt% silica): the carrier viscosity the Krieger-Dougherty law implies for it (water: 0.89 mPa s at 25 C; slurry additives raise it); docs/model.md ('Slurry viscosity')", 0.0, 10.0, True, False),
        _P("abrasive", "slurry", "-", "choice", "", "silica", "Abrasive material (its density, modulus, Poisson ratio and hardness)", "cmpsim.physics.materials.ABRASIVES (each entry with its source); docs/model.md ('Abrasive removal')", choices=tuple(ABRASIVES)),
        _P("solids_loading", "slurry", "w", "", "%", 0.125, "Abrasive solids loading, mass fraction (e.g. '12.5 %'); sets the particle count, the granular bulk density and the slurry viscosity", "12.5 wt% silica, a typical oxide slurry (US 9,499,721 B2); the range stops at 60 wt%, beyond any CMP slurry", 0.0, 0.6, False, True),
        _P("particle_size_std", "slurry", "s_d", "m", "nm", 0.0, "Standard deviation of the particle diameters (log-normal number distribution of mean particle_diameter); 0 = all particles alike", "Not printed for the shipped data sets: 0 (the paper and every shipped series quote one size); Luo & Dornfeld, IEEE Trans. Semicond. Manuf. 16, 469 (2003) on its role", 0.0, 2e-6, False, False),
        _P("cavitation", "slurry", "-", "choice", "", "gumbel", "Cavitation of the Newtonian slurry: none (full Sommerfeld), Gumbel (p -> max(p, p_cav)) or mass-conserving JFO; the granular slurry takes only 'none'", "docs/model.md ('Newtonian slurry and cavitation'); Elrod, J. Lubr. Technol. 103, 350 (1981); Giacopini et al., J. Tribol. 132, 041702 (2010)", choices=("none", "gumbel", "jfo")),
        _P("cavitation_pressure", "slurry", "p_cav", "Pa", "kPa", -98.2e3, "Gauge pressure at which the Newtonian slurry cavitates (used by cavitation = 'gumbel' or 'jfo')", "Vapour pressure of water at 25 C (3.17 kPa, CRC Handbook) minus one atmosphere; consistent with the sub-ambient film pressures of tens of kPa measured by Shan, Levert, Meade, Tichy & Danyluk, J. Tribol. 122 (2000); see docs/model.md", -101325.0, 0.0, False, False),
        # ---------------------------------------------------------------- slurry (Haff grain flow)
        _P("particle_diameter", "slurry", "d", "m", "nm", 100e-9, "Abrasive particle diameter, number mean (with the granular slurry also < pad_roughness / 10: grains must fit many times in the roughness layer that forms the film)", "Paper Table 1 (100 nm; 200 nm studied); CMP abrasives are 10 nm - 1 um (Lai 2001 used up to 1 um alumina), so the range stops at 2 um", 0.0, 2e-6, True, False),
        _P("w_over_k", "slurry", "w/k", "", "", 4e-6, "Haff dissipation over conductivity constant", "Paper Table 1 (see docs/model.md on w/k vs k/w)", 0.0),
        _P("t_over_a", "slurry", "t/a", "", "", 1.0, "Haff pressure over viscosity constant", "Paper Table 1; Dai et al.", 0.0),
        _P("fluctuation_ratio", "slurry", "v/U", "", "", 3.0, "Granular fluctuation velocity over sliding speed", "Paper Table 1 (V/U = 3)", 0.0),
        _P("granular_density", "slurry", "rho", "kg/m^3", "kg/m^3", 0.0, "Bulk density of the abrasive grains (solid volume fraction x particle density) of the granular slurry; 0 = from solids_loading and the abrasive's density. Older input: a value > 0 sets solids_loading", "phi rho_a; 134 kg/m^3 for 12.5 wt% silica (2200 kg/m^3) in water (US 9,499,721 B2; the paper preset's value); see docs/model.md ('Solids loading')", 0.0, None, False),
        _P("diameter_gap_ratio", "slurry", "d/s", "", "", 67.0, "Particle diameter over mean gap between grains (Haff: s << d)", "Calibrated, not measured: sets the edge granular pressure to ~32 kPa at 60 rpm; see docs/model.md ('Ambient granular pressure')", 0.0),
        # ---------------------------------------------------------------- pad
        _P("pad_roughness", "pad", "sigma", "m", "um", 5e-6, "Std of pad summit heights (R_q)", "Summit-height std of CMP pads: 5 um (Bozkaya & Mueftue, JES 156 H890, 2009), 5.24 um fitted to a pad compression test (Suzuki et al., CIRP Ann. 2017); conditioned IC1000 Ra about 5 um (Saka et al. 2008). Paper preset: 15 um (paper Table 1; 10, 20 um studied)", 0.0),
        _P("asperity_density", "pad", "eta_a", "1/m^2", "1/mm^2", 2.0e8, "Areal density of pad summits at the reference roughness", "Bozkaya & Mueftue, JES 156 H890 (2009); Shi & Ring, Microelectron. Eng. 87, 2368 (2010); Suzuki et al. (2017)", 0.0),
        _P("asperity_radius", "pad", "R", "m", "um", 7e-6, "Summit radius of curvature at the reference roughness", "Conditioned IC1000: 5-9 um (Jeong et al., Materials 17, 1817, 2024, doi 10.3390/ma17081817). Paper preset: 50 um (Bozkaya & Mueftue, JES 156 H890, 2009; Suzuki et al., CIRP Ann. 2017)", 0.0),
        _P("pad_modulus", "pad", "E_1", "Pa", "MPa", 0.5e9, "Young's modulus of the pad asperities", "Wet IC1000: 0.53 GPa (Eusner, Saka, Chun et al., J. Electrochem. Soc. 156, H528, 2009); 0.5 GPa (Saka, Eusner & Chun, CIRP Ann. 57, 341, 2008). Paper preset: 100 MPa (Bozkaya & Mueftue, JES 156 H890, 2009)", 0.0),
        _P("pad_poisson", "pad", "nu_1", "", "", 0.3, "Poisson ratio of the pad", "Suzuki et al., CIRP Ann. (2017)", 0.0, 0.5, False, False),
        _P("pad_hardness", "pad", "H", "Pa", "MPa", 50e6, "Hardness of the pad asperities", "Wet IC1000: 0.05 GPa (Eusner et al., J. Electrochem. Soc. 156, H528, 2009; Saka et al., CIRP Ann. 57, 341, 2008); it bounds the mean real contact pressure (A_r >= P/H). Paper preset: 9.4 MPa (H/E = 0.094 of wet IC1000 times 100 MPa)", 0.0),
        _P("wafer_modulus", "pad", "E_2", "Pa", "GPa", 130e9, "Young's modulus of the wafer (silicon)", "Hopcroft, Nix & Kenny, JMEMS 19, 229 (2010)", 0.0),
        _P("wafer_poisson", "pad", "nu_2", "", "", 0.28, "Poisson ratio of the wafer (silicon)", "Hopcroft, Nix & Kenny (2010)", 0.0, 0.5, False, False),
        _P("contact_cutoff", "pad", "z_max/sigma", "", "", 3.0, "Summit heights truncated at this many sigma (paper: contact below 3 R_q)", "Paper section 2.2; Yu et al. [30]", 0.5, None, False),
        _P("roughness_scaling", "pad", "-", "choice", "", "self_similar", "How summit radius and density follow pad_roughness", "docs/model.md ('Changing the pad roughness')", choices=("self_similar", "fixed_summits")),
        _P("reference_roughness", "pad", "sigma_ref", "m", "um", 5e-6, "Roughness at which asperity_density and asperity_radius are given", "The roughness of the sources of asperity_density and asperity_radius (paper preset: 15 um, the paper's base case)", 0.0),
        _P("wafer_roughness", "pad", "sigma_2", "m", "um", 0.0, "Std of wafer surface heights", "Paper: wafer smooth (sigma_2 << sigma_1)", 0.0, None, False),
        _P("peklenik_number", "pad", "gamma", "", "", 1.0, "Peklenik number of the pad roughness (1 = isotropic)", "Paper section 3.1", 0.0),
        _P("roughness_angle", "pad", "theta_1", "rad", "deg", 0.0, "Orientation of the pad roughness from the sliding direction", "Paper (isotropic: irrelevant)"),
        # pad stack under the asperity layer (pad compliance; docs/model.md, "Pad compliance")
        _P("pad_compliance", "pad", "-", "choice", "", "winkler", "Bulk deformation of the pad: none (the paper); a local elastic (Winkler) foundation of the pad and subpad layers in series; or elastic layers with lateral coupling (top pad as a plate on an elastic subpad layer, by FFT)", "docs/model.md ('Pad compliance'); 'rigid' is the paper's model", choices=("rigid", "winkler", "layer")),
        _P("pad_thickness", "pad", "t_1", "m", "mm", 1.27e-3, "Thickness of the top pad (bulk under the asperities)", "IC1000: 50 mil = 1.27 mm (Pureon IC1000/IC1010 datasheet 2024, read in a transcription); see docs/model.md", 0.0),
        _P("pad_bulk_modulus", "pad", "E_b", "Pa", "MPa", 300e6, "Young's modulus of the top pad's bulk (porous polyurethane)", "Wet IC1000: 0.3-0.5 GPa (Eusner et al., JES 156 H528, 2009; Saka et al., CIRP Ann. 57, 341, 2008), lower end; see docs/model.md", 0.0),
        _P("subpad_thickness", "pad", "t_2", "m", "mm", 1.27e-3, "Thickness of the subpad (0 = no subpad)", "Suba IV sub-pad, 50 mil as commonly stacked under IC1000 (assumed: no datasheet found); see docs/model.md", 0.0, None, False),
        _P("subpad_modulus", "pad", "E_2s", "Pa", "MPa", 2.3e6, "Young's modulus of the subpad", "Order of magnitude of a Suba IV-class felt: 2.29 MPa soft-pad layer of Wang et al., JES 144, 1121 (1997), as used by Lo & Lin, J. Mater. Process. Technol. 168, 250 (2005) (second-hand); see docs/model.md", 0.0),
        _P("subpad_poisson", "pad", "nu_2s", "", "", 0.1, "Poisson ratio of the subpad", "Wang et al. (1997) via Lo & Lin (2005) (second-hand): 0.1 for the soft pad layer", 0.0, 0.5, False, True),
        # grooves of the pad (docs/model.md, 13g "Grooved pad: venting of the film")
        _P("pad_groove_pitch", "pad", "lambda_g", "m", "mm", 0.0, "Pitch of the pad's concentric grooves (0 = ungrooved): grooves at ambient pressure vent the slurry film over each land", "0 = the smooth pad of the paper; concentric grooves of CMP pads: about 0.12 in = 3.05 mm (0.09-0.24 in; Applied Materials patent claims, docs/model.md 13g), the 300mm preset's value (issue 32); IC1000's K-groove dimensions are not published", 0.0, None, False),
        _P("pad_groove_width", "pad", "w_g", "m", "mm", 0.0, "Width of the pad's grooves (land = pitch - width), in [0, pitch); 0 with pitch 0", "About 0.02 in = 0.51 mm (0.015-0.04 in; same patent claims, docs/model.md 13g), the 300mm preset's value (issue 32)", 0.0, None, False),
        _P("friction_coefficient", "pad", "mu", "", "", 0.4, "Coulomb friction of pad summits on the wafer", "Lai, PhD thesis MIT (2001): 0.40-0.49 in contact mode", 0.0, None, False),
        _P("pad_heat_transfer_coefficient", "pad", "h_s", "W/(m^2*K)", "W/(m^2*K)", 0.0, "Heat carried from the pad's surface to the slurry per unit track area and kelvin (the pad's heat balance of cmpsim polish); 0 = from the slurry flow, rho_w c_w Q / A_track", "0: cmpsim.physics.thermal.slurry_heat_transfer_coefficient (150 mL/min, docs/polisher.md); a calibration on a measured temperature sets it (docs/calibrate-die.md)", 0.0, None, False),
        # ---------------------------------------------------------------- numerics
        _P("model", "numerics", "-", "choice", "", "lep", "Model variant", "Paper: 'lep'; earlier elastic model; pure hydrodynamic", choices=("lep", "elastic", "hydrodynamic")),
        _P("grid", "numerics", "-", "grid", "", "default", "Polar grid: preset or rings x sectors", "docs/model.md ('Grid')"),
        _P("grid_grading", "numerics", "-", "choice", "", "edge", "Rings of the named grids: graded towards the wafer edge (a preset fixes the rim ring width: 0.9 / 0.3 / 0.15 mm), or equally wide ('uniform'; always for rings x sectors)", "docs/model.md ('Grid'); 'uniform' is the paper preset's (cmpsim 0.1) grid", choices=("edge", "uniform")),
        _P("flow_factor_floor", "numerics", "Phi_min", "", "", 0.05, "Smallest eigenvalue of the pressure flow-factor tensor passed to the solver", "docs/model.md ('Flow-factor validity')", 0.0, 1.0, True, False),
        _P("flow_factor_continuation", "numerics", "Phi_c", "", "", 0.4, "Eigenvalue of the pressure flow-factor tensor below which eq. 8-10 are continued by a C1 power law in the film, vanishing only at h = 0 (0: none, the floor alone, as the paper preset)", "docs/model.md ('Flow-factor validity'): the largest value that leaves the default model's and the presets' base cases on eq. 8 (smallest eigenvalue 0.45-0.48), above the 0.2-0.3 below which the layered pad's equilibrium folds", 0.0, 1.0, False, True),
        _P("tolerance", "numerics", "-", "", "", 1e-9, "Newton tolerance on the relative load and moment residuals", "-", 0.0, 1e-3, True, False),
        _P("max_iterations", "numerics", "-", "", "", 40, "Newton steps allowed", "-", 1.0, 1000.0, False, False),
    ]
}

_SECTIONS = ("wafer", "process", "slurry", "pad", "numerics")

#: Named presets: the inputs in which each differs from the defaults of :data:`PARAMETERS`
#: (values as a user would type them). ``paper`` is the paper's model exactly, as cmpsim
#: 0.1.0 implemented it (``tests/test_paper_preset.py`` pins its results); ``default`` is
#: the predictive model of docs/model.md ("Beyond the paper"); ``300mm`` a production head and
#: recipe on the predictive model (docs/model.md, 13f).
PRESETS: dict[str, dict[str, Any]] = {
    "default": {},
    "paper": {
        "removal_law": "paper",
        "slurry_model": "granular",
        "granular_density": 134.0,
        "slurry_viscosity": 5e-3,
        "cavitation": "none",
        "pad_compliance": "rigid",
        "grid_grading": "uniform",
        # the paper's flow factors with cmpsim 0.1's floor alone (its hydrodynamic variant lives below eq. 8's validity)
        "flow_factor_continuation": 0.0,
        # SI floats, exactly the defaults of cmpsim 0.1.0 ("15 um" would parse to 1.4999999999999999e-05 m)
        "pad_modulus": 100e6,
        "pad_hardness": 9.4e6,
        "asperity_radius": 50e-6,
        "pad_roughness": 15e-6,
        "reference_roughness": 15e-6,
    },
    # A production oxide polish of a 300 mm wafer (sources of every number: docs/model.md, 13f,
    # "The 300mm preset"). zone_pressures stay unset: applied_pressure fills every zone.
    "300mm": {
        "wafer_diameter": "300 mm",
        "wafer_thickness": "775 um",
        "edge_exclusion": "3 mm",
        "carrier": "membrane",
        "zone_radii": "50,100,130,145,150 mm",
        "retaining_ring_pressure": "3 psi",
        "pad_compliance": "layer",
        "applied_pressure": "3 psi",
        "rotation_speed": "93 rpm",
        "wafer_speed_ratio": 87.0 / 93.0,
        "centre_distance": "0.2 m",
        # the production pad is grooved (issue 32): the common concentric groove, 0.120 in pitch and 0.020 in
        # wide (0.030 in deep), read in the claims of an Applied Materials patent ("Polishing pad having a
        # grooved pattern for use in chemical mechanical polishing", claims 2, 4, 6, 7, 13; docs/_sources.md,
        # section 11). IC1000 is sold K-grooved (Pureon datasheet; McAllister et al. 2019); the K-groove's own
        # dimensions are not published, so these are the common groove, not a verified K-groove (model 13g).
        "pad_groove_pitch": "3.05 mm",
        "pad_groove_width": "0.51 mm",
    },
}


#: Largest particle diameter over pad roughness: the grain-flow and average-flow pictures need
#: many particles across the roughness layer that forms the film (docs/model.md, "Valid inputs").
MAX_PARTICLE_ROUGHNESS_RATIO = 0.1


def _check_consistency(c: "Config") -> None:
    """Refuse combinations of inputs that make the model meaningless, naming the parameters."""
    radius = 0.5 * c.wafer.wafer_diameter
    if c.wafer.edge_exclusion >= radius:
        raise ValueError(
            f"edge_exclusion = {c.wafer.edge_exclusion:g} m leaves no wafer (wafer_diameter = {c.wafer.wafer_diameter:g} m): "
            f"valid range [0, {radius:g}) m, i.e. below the wafer radius"
        )
    if c.pad.pad_compliance != "rigid" and c.numerics.model == "hydrodynamic":
        raise ValueError(
            f"pad_compliance = {c.pad.pad_compliance!r} needs a model with pad contact: model must be 'lep' or 'elastic' "
            "(got 'hydrodynamic'); use pad_compliance = 'rigid' for the pure hydrodynamic variant"
        )
    if c.pad.pad_compliance != "rigid" and c.pad.pad_poisson >= 0.5:
        raise ValueError(
            f"pad_poisson = {c.pad.pad_poisson:g} makes the compliant pad infinitely stiff (an incompressible bonded layer): "
            f"valid range [0, 0.5) with pad_compliance = {c.pad.pad_compliance!r}"
        )
    limit = MAX_PARTICLE_ROUGHNESS_RATIO * c.pad.pad_roughness
    if c.slurry.slurry_model == "granular" and c.slurry.particle_diameter >= limit:
        raise ValueError(
            f"particle_diameter = {c.slurry.particle_diameter:g} m is too large for pad_roughness = "
            f"{c.pad.pad_roughness:g} m with slurry_model = 'granular': valid range (0, {limit:g}) m, i.e. below "
            f"{MAX_PARTICLE_ROUGHNESS_RATIO:g} x pad_roughness (the grain-flow slurry averages over many grains across "
            "the roughness layer that forms the film; the Newtonian slurry takes particles up to 2 um)"
        )
    if c.slurry.slurry_model == "granular" and c.slurry.granular_density == 0 and c.slurry.solids_loading == 0:
        raise ValueError(
            "solids_loading = 0 leaves the granular slurry without grains (its pressure is that of the grains): valid range "
            "(0, 0.6) with slurry_model = 'granular' and granular_density = 0, or set granular_density > 0"
        )

def _check_chemistry(c: "Config") -> None:
    """Refuse film-chemistry constants that ``film_chemistry = 'none'`` would ignore, naming the input."""
    if c.process.film_chemistry != "none":
        return
    for film in FILMS:
        for name in chemistry_input_names(film):
            value = getattr(c.process, name)
            if value != PARAMETERS[name].default:
                raise ValueError(
                    f"{name} = {value:g} {PARAMETERS[name].unit or '(dimensionless)'} has no effect with film_chemistry = 'none': "
                    f"set film_chemistry = 'additive' (valid: 'none' with {name} = {PARAMETERS[name].default:g}, or 'additive')"
                )


def _check_grooves(c: "Config") -> None:
    """Refuse groove inputs without a land, or with the mass-conserving cavitation, naming the parameters."""
    pitch, width = c.pad.pad_groove_pitch, c.pad.pad_groove_width
    if pitch == 0 and width > 0:
        raise ValueError(f"pad_groove_width = {width:g} m needs pad_groove_pitch > 0 (got 0: an ungrooved pad); set both or neither")
    if pitch > 0 and width >= pitch:
        raise ValueError(f"pad_groove_width must be in [0, pad_groove_pitch) = [0, {pitch:g}) m (a land must remain); got {width:g} m")
    if pitch > 0 and c.slurry.slurry_model == "newtonian" and c.slurry.cavitation == "jfo":
        raise ValueError(
            "pad_groove_pitch > 0 (a grooved pad) cannot be combined with cavitation = 'jfo': the grooves' homogenised venting "
            "to ambient pressure is not part of the JFO mass balance in cmpsim (docs/model.md, 'Grooved pad'); "
            "use cavitation = 'gumbel' or 'none', or pad_groove_pitch = 0"
        )


def _check_carrier(c: "Config") -> None:
    """Refuse zone and ring inputs that the chosen carrier and pad cannot honour, naming the parameters."""
    p = c.process
    if c.process.carrier != "membrane" and (p.zone_radii or p.zone_pressures):
        name = "zone_pressures" if p.zone_pressures else "zone_radii"
        raise ValueError(f"{name} needs carrier = 'membrane' (got carrier = {p.carrier!r}): a rigid carrier presses with applied_pressure alone")
    if p.carrier == "membrane" and c.pad.pad_compliance == "rigid":
        raise ValueError(
            "carrier = 'membrane' needs a compliant pad: pad_compliance must be 'winkler' or 'layer' (got 'rigid'); "
            "on a rigid pad the thin wafer's bending over the slurry film has no converged solution in cmpsim (docs/limitations.md)"
        )
    radius = 0.5 * c.wafer.wafer_diameter
    radii = p.zone_radii
    if radii:
        if any(b <= a for a, b in zip(radii, radii[1:])):
            raise ValueError(f"zone_radii must increase from the centre outwards; got {', '.join(f'{r:g}' for r in radii)} m")
        if not math.isclose(radii[-1], radius, rel_tol=_MATCH_RTOL):
            raise ValueError(
                f"zone_radii: the last zone must end at the wafer rim, {radius:g} m (wafer_diameter / 2); got {radii[-1]:g} m. "
                f"Valid: increasing radii in (0, {radius:g}] m, the last = {radius:g} m"
            )
    n_zones = len(radii) or 1
    if p.zone_pressures and len(p.zone_pressures) != n_zones:
        raise ValueError(
            f"zone_pressures has {len(p.zone_pressures)} values but there are {n_zones} zones "
            f"({'zone_radii = ' + ', '.join(f'{r:g}' for r in radii) + ' m' if radii else 'zone_radii unset: one zone'}); give one pressure per zone"
        )
    if p.retaining_ring_pressure > 0 and c.pad.pad_compliance != "layer":
        raise ValueError(
            f"retaining_ring_pressure = {p.retaining_ring_pressure:g} Pa cannot act on the wafer with pad_compliance = "
            f"{c.pad.pad_compliance!r}: a local pad carries the ring's load where it presses, not under the wafer. "
            "Set retaining_ring_pressure = 0, or use pad_compliance = 'layer' (the laterally coupled pad)"
        )


def parameter(name: str) -> Param:
    """The registry entry of input ``name``; ``ValueError`` listing the known names if there is none."""
    if name not in PARAMETERS:
        hint = did_you_mean(name, PARAMETERS)
        raise ValueError(f"unknown parameter {name!r}" + (f"{hint} (cmpsim params lists the inputs)" if hint else f"; known: {', '.join(sorted(PARAMETERS))}"))
    return PARAMETERS[name]


def parse_value(name: str, value: Any) -> Any:
    """Convert one input to its SI value, checking unit dimension and range (:func:`cmpsim.inputs.units.parse`).

    ``value`` may be a string with units (``"4 psi"``), a pint Quantity, or a number
    (taken as SI). Raises ``ValueError`` naming the parameter and its valid range.
    """
    return units.parse(parameter(name), value)


#: The keys of a process file's [calibration] table (:mod:`cmpsim.calibration.processfile` writes them).
_CALIBRATION_KEYS = frozenset({"constants", "settings", "data", "chi2_before", "chi2_after", "dof", "rms_before", "rms_after",
                               "identifiability", "ci95", "stderr", "correlation", "pad", "die", "padlife"})


def _section_fields(section: str) -> list[str]:
    return [n for n, p in PARAMETERS.items() if p.section == section]


def _make_section(section: str, doc: str):
    names = _section_fields(section)
    cls = dataclasses.make_dataclass(
        section.capitalize(),
        [(n, Any, dataclasses.field(default=PARAMETERS[n].default)) for n in names],
        frozen=True,
    )
    cls.__doc__ = doc + "\n\nFields (SI): " + ", ".join(f"{n} [{PARAMETERS[n].unit or '-'}]" for n in names)
    cls.__module__ = __name__
    return cls


Wafer = _make_section("wafer", "Wafer geometry.")
Process = _make_section("process", "Machine settings: load, speeds, kinematics, removal constant.")
Slurry = _make_section("slurry", "Slurry as a Haff granular fluid.")
Pad = _make_section("pad", "Pad surface (Greenwood-Williamson summits), pad and wafer materials.")
Numerics = _make_section("numerics", "Model variant and numerical settings.")
_CLASSES = {"wafer": Wafer, "process": Process, "slurry": Slurry, "pad": Pad, "numerics": Numerics}


@dataclass(frozen=True)
class Config:
    """All inputs of one operating point, in SI, grouped as wafer, process, slurry, pad, numerics.

    Build with :meth:`default`, :meth:`from_toml` or :meth:`replace`; every value is checked
    on the way in. Flat attribute access works too: ``config.applied_pressure``.
    """

    wafer: Any = dataclasses.field(default_factory=Wafer)
    process: Any = dataclasses.field(default_factory=Process)
    slurry: Any = dataclasses.field(default_factory=Slurry)
    pad: Any = dataclasses.field(default_factory=Pad)
    numerics: Any = dataclasses.field(default_factory=Numerics)

    @classmethod
    def default(cls) -> "Config":
        """The default, predictive model at the paper's operating point (3-inch wafer, 5 um dome,
        4 psi, 60 rpm): Newtonian slurry, Gumbel cavitation, compliant pad stack, measured IC1000
        summits, shear-power removal (docs/model.md, section 13d). :meth:`paper` is the paper's model."""
        return cls()

    @classmethod
    def preset(cls, name: str) -> "Config":
        """A named preset of :data:`PRESETS`: ``"default"``, ``"paper"`` or ``"300mm"``."""
        if name not in PRESETS:
            raise ValueError(f"preset must be one of {', '.join(repr(p) for p in PRESETS)}; got {name!r}")
        return cls().replace(**PRESETS[name])

    @classmethod
    def paper(cls) -> "Config":
        """The paper's model exactly (``cmpsim run --preset paper``): the results of cmpsim 0.1.0."""
        return cls.preset("paper")

    def __getattr__(self, name: str):
        p = PARAMETERS.get(name)
        if p is None:
            raise AttributeError(name)
        return getattr(object.__getattribute__(self, p.section), name)

    def replace(self, **overrides) -> "Config":
        """A copy with some inputs changed (flat names; strings with units, Quantities or SI)."""
        groups: dict[str, dict[str, Any]] = {}
        parsed = _loading_overrides(self, {name: parse_value(name, value) for name, value in overrides.items()})
        for name, v in parsed.items():
            groups.setdefault(PARAMETERS[name].section, {})[name] = v
        new = Config(**{s: dataclasses.replace(getattr(self, s), **groups.get(s, {})) for s in _SECTIONS})
        _check_carrier(new)
        _check_grooves(new)
        _check_chemistry(new)
        if new.process.zone_pressures:
            new = _with_zone_load(new, overrides)
        _check_consistency(new)
        return new

    @property
    def zone_outer_radii(self) -> tuple[float, ...]:
        """Outer radius of each membrane zone, m: ``zone_radii``, or the wafer radius alone when unset."""
        return self.process.zone_radii or (0.5 * self.wafer.wafer_diameter,)

    @property
    def zone_pressure_values(self) -> tuple[float, ...]:
        """Membrane pressure of each zone, Pa: ``zone_pressures``, or ``applied_pressure`` in every zone when unset."""
        return self.process.zone_pressures or (self.process.applied_pressure,) * len(self.zone_outer_radii)

    def to_dict(self) -> dict[str, Any]:
        """Flat {name: SI value} of every input."""
        return {n: getattr(getattr(self, p.section), n) for n, p in PARAMETERS.items()}

    def key(self) -> tuple:
        """A hashable key of every input, ``((name, repr(SI value)), ...)`` sorted by name: equal for
        equal configurations (the key of a cached solve; tuples and None included)."""
        return tuple(sorted((k, repr(v)) for k, v in self.to_dict().items()))

    def to_sections(self) -> dict[str, dict[str, Any]]:
        """{section: {name: SI value}}, the layout of the TOML file."""
        return {s: {n: getattr(getattr(self, s), n) for n in _section_fields(s)} for s in _SECTIONS}

    def to_toml_text(self) -> str:
        """Every input as TOML text, by section, in SI (floats written exactly)."""
        import tomli_w

        return tomli_w.dumps(self.to_sections())

    def to_toml(self, path) -> None:
        """Write every input to a TOML file in SI (floats written exactly); atomic."""
        from ..io import atomic_write_text

        text = "# cmpsim configuration; every value in SI units (see `cmpsim params`)\n"
        atomic_write_text(Path(path), text + self.to_toml_text())

    @classmethod
    def from_mapping(cls, data: dict[str, Any], base: "Config | None" = None) -> "Config":
        """Build from a flat or sectioned mapping; values with units or SI numbers.

        A top-level ``preset = "paper"`` starts from that preset instead of ``base``.
        """
        flat: dict[str, Any] = {}
        data = dict(data)
        calibration = data.pop("calibration", None)  # a process file's record of its calibration: metadata, not inputs
        if calibration is not None and not isinstance(calibration, dict):
            raise ValueError(f"calibration must be the [calibration] table of a process file (cmpsim calibrate); got {calibration!r}")
        stray = sorted(set(calibration or {}) - _CALIBRATION_KEYS)
        if stray:  # e.g. a version key of a newer cmpsim's file, or a hand edit: nothing would read it
            raise ValueError(f"[calibration]: unknown key(s) {', '.join(stray)}; this cmpsim writes and reads {', '.join(sorted(_CALIBRATION_KEYS))}")
        if "preset" in data:
            base = cls.preset(str(data.pop("preset")))
        for key, value in data.items():
            if key in _SECTIONS and isinstance(value, dict):
                for k, v in value.items():
                    if k not in PARAMETERS:
                        hint = did_you_mean(k, PARAMETERS)
                        raise ValueError(f"unknown parameter {k!r} in [{key}]" + (hint or f"; known: {', '.join(_section_fields(key))}"))
                    if PARAMETERS[k].section != key:
                        raise ValueError(f"parameter {k!r} belongs in [{PARAMETERS[k].section}], not [{key}]")
                    if k in flat:  # set at the top level too: one of the two would be dropped without a word
                        raise ValueError(f"parameter {k!r} is set twice, at the top level and in [{key}]; keep one")
                    flat[k] = v
            elif isinstance(value, dict) and key not in PARAMETERS:  # a misspelt section: say so, not "unknown parameter"
                raise ValueError(f"unknown parameter {key!r}: [{key}] is not a section{did_you_mean(key, _SECTIONS)}; the sections are {', '.join(f'[{s}]' for s in _SECTIONS)}")
            else:
                if key in flat:
                    raise ValueError(f"parameter {key!r} is set twice, in [{PARAMETERS[key].section}] and at the top level; keep one")
                flat[key] = value
        return (base or cls.default()).replace(**flat)

    @classmethod
    def from_toml(cls, path, base: "Config | None" = None) -> "Config":
        """Read a TOML file (sections or flat keys; values with units or SI numbers).

        Inputs the file does not set come from ``base`` (default: the defaults), or from the
        file's own top-level ``preset = "..."``.
        """
        from ..io import read_text

        path = Path(path)
        try:
            data = tomllib.loads(read_text(path, "config file"))
        except tomllib.TOMLDecodeError as exc:
            raise ValueError(f"config file {str(path)!r} is not valid TOML: {exc}") from None
        if isinstance(data.get("step"), list) or isinstance(data.get("film"), list):
            raise ValueError(f"config file {str(path)!r} is a recipe ([[film]] and [[step]] tables: `cmpsim polish RECIPE`, "
                             "`--recipe RECIPE`), not a configuration of inputs")
        if isinstance(data.get("axes"), dict):
            raise ValueError(f"config file {str(path)!r} is a sweep specification ([axes]: `cmpsim sweep FILE`), not a configuration of inputs")
        try:
            return cls.from_mapping(data, base=base)
        except ValueError as exc:  # an unknown key or a bad value: say which file holds it
            raise ValueError(f"config file {str(path)!r}: {exc}") from None

    @property
    def solid_volume_fraction(self) -> float:
        """Solid volume fraction phi of the slurry, from solids_loading and the abrasive's density."""
        return float(volume_fraction(self.slurry.solids_loading, ABRASIVES[self.slurry.abrasive].density))

    @property
    def grain_bulk_density(self) -> float:
        """Bulk density of the grains of the granular slurry, kg/m^3: granular_density, or phi rho_a when it is 0."""
        rho = self.slurry.granular_density
        return rho if rho > 0 else self.solid_volume_fraction * ABRASIVES[self.slurry.abrasive].density

    @property
    def newtonian_viscosity(self) -> float:
        """Viscosity of the Newtonian slurry, Pa s: slurry_viscosity, or Krieger-Dougherty of the loading when it is 0."""
        eta = self.slurry.slurry_viscosity
        return eta if eta > 0 else float(krieger_dougherty(self.solid_volume_fraction, self.slurry.carrier_viscosity))

    @property
    def grid_shape(self) -> tuple[int, int]:
        """(rings, sectors) of the polar grid (:meth:`polar_grid`)."""
        g = self.polar_grid()
        return g.n_r, g.n_theta

    def polar_grid(self):
        """The :class:`cmpsim.numerics.grid.PolarGrid` of this configuration: a named grid graded towards the
        edge (:data:`GRID_EDGE`) unless ``grid_grading = "uniform"``; rings x sectors: equal rings."""
        from ..numerics.grid import PolarGrid, edge_graded_grid

        g, radius = self.numerics.grid, 0.5 * self.wafer.wafer_diameter
        if g in GRID_PRESETS:
            n_r, n_t = GRID_PRESETS[g]
            if self.numerics.grid_grading == "edge":
                return edge_graded_grid(radius, n_r, n_t, *GRID_EDGE[g])
            return PolarGrid(radius, n_r, n_t)
        nr, nt = g.split("x")
        return PolarGrid(radius, int(nr), int(nt))

    def describe(self) -> list[tuple[str, str, str, str]]:
        """Rows (name, value in display unit, display unit, source) for provenance and tables."""
        rows = []
        for n, p in PARAMETERS.items():
            v = getattr(self, n)
            rows.append((n, format_display(n, v), p.display, p.source))
        return rows


def to_display(name: str, value: Any) -> Any:
    """SI value of a parameter converted to its display unit (strings unchanged; :func:`cmpsim.inputs.units.to_display`)."""
    return units.to_display(parameter(name), value)


def format_display(name: str, value: Any) -> str:
    """SI value of a parameter as display text (:func:`cmpsim.inputs.units.format_display`)."""
    return units.format_display(parameter(name), value)


def parameter_table_markdown() -> str:
    """The parameter table of docs/model.md, generated from :data:`PARAMETERS`."""
    lines = [
        "| name | symbol | SI unit | default | shown as | valid range (SI) | source |",
        "|---|---|---|---|---|---|---|",
    ]
    for n, p in PARAMETERS.items():
        if p.items:  # list inputs have no default list: unset
            d = shown = "unset"
        else:
            d = p.default if isinstance(p.default, str) else f"{p.default:.6g}"
            shown = format_display(n, p.default) + (f" {p.display}" if p.display and p.display not in ("", p.unit) else "")
        unit = p.unit if p.unit not in ("choice", "grid", "") else "-"
        lines.append(f"| `{n}` | {p.symbol} | {unit} | {d} | {shown} | {p.range_text()} | {p.source} |")
    return "\n".join(lines) + "\n"
