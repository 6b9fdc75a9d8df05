"""Abrasive and film property tables, slurry composition and the suspension viscosity law.

Pure data and kernels (SI units): the abrasives (``silica``, ``ceria``, ``alumina``) with their
density, Young's modulus, Poisson ratio and hardness; the films (``oxide``, ``copper``,
``tungsten``, ``barrier``) with their modulus, Poisson ratio and hardness; the conversion of a solids
loading (mass fraction) into a solid volume fraction and a bulk grain density; and the
Krieger–Dougherty viscosity of a hard-sphere suspension. Every number carries its source
(``docs/model.md``, "Abrasive removal"); the least certain ones say so.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

__all__ = [
    "Material",
    "ABRASIVES",
    "FILMS",
    "LIQUID_DENSITY",
    "volume_fraction",
    "mass_fraction",
    "bulk_density",
    "krieger_dougherty",
    "INTRINSIC_VISCOSITY",
    "MAX_PACKING_FRACTION",
]

#: Density of the carrier liquid (water), kg/m^3 (CRC Handbook: 997 kg/m^3 at 25 C; 1000 is
#: the value cmpsim has always used to turn wt% into a volume fraction).
LIQUID_DENSITY = 1000.0

#: Intrinsic viscosity of hard spheres, [eta] = 5/2 (Einstein 1906).
INTRINSIC_VISCOSITY = 2.5
#: Maximum packing fraction of the Krieger–Dougherty law at high shear rate: 0.71 for hard-sphere
#: silica dispersions (de Kruif, van Iersel, Vrij & Russel, J. Chem. Phys. 83, 4717 (1985); 0.63
#: at low shear). CMP slurry films are sheared at 1e4-1e6 1/s, hence the high-shear value.
MAX_PACKING_FRACTION = 0.71


@dataclass(frozen=True)
class Material:
    """Elastic and plastic constants of one abrasive or film (SI) and where they come from.

    ``density`` (kg/m^3; abrasives only, 0 for films), ``modulus`` E (Pa), ``poisson`` nu,
    ``hardness`` H (Pa), ``source`` (text).
    """

    name: str
    density: float
    modulus: float
    poisson: float
    hardness: float
    source: str

    @property
    def reduced_compliance(self) -> float:
        """(1 - nu^2) / E, 1/Pa: this body's share of 1/E' in the Hertz contact."""
        return (1.0 - self.poisson**2) / self.modulus


#: The abrasives of ``abrasive``: (name, density kg/m^3, modulus Pa, Poisson ratio, hardness Pa, source).
ABRASIVES: dict[str, Material] = {r[0]: Material(*r) for r in (
    ('silica', 2200.0, 72000000000.0, 0.17, 9000000000.0, "Amorphous (fused) silica: rho 2200 kg/m^3 (the value cmpsim's wt% conversions used before); E = 72 GPa, nu = 0.17, H about 9 GPa (the nanoindentation reference material of Oliver & Pharr, J. Mater. Res. 7, 1564 (1992)). Colloidal (Stoeber) silica is more porous and softer: an upper bound"),
    ('ceria', 7215.0, 210000000000.0, 0.3, 6000000000.0, 'CeO2: rho 7215 kg/m^3 (CRC Handbook of Chemistry and Physics); E = 210 GPa (+-5 %) for dense ceramics (Korobko et al., Scripta Mater. 66, 155 (2012)); nu = 0.30 (assumed, typical oxide ceramic); H = 6 GPa: order of magnitude only (Mohs 6; no primary nanoindentation value was found): the least certain number of this table'),
    ('alumina', 3980.0, 416000000000.0, 0.231, 15000000000.0, 'alpha-Al2O3: rho 3980 kg/m^3, E = 416 GPa, nu = 0.231, Vickers hardness about 15 GPa (Munro, J. Am. Ceram. Soc. 80, 1919 (1997), evaluated properties of sintered alpha-alumina)'),
)}

#: The films of ``film`` (no density: 0).
FILMS: dict[str, Material] = {r[0]: Material(*r) for r in (
    ('oxide', 0.0, 72000000000.0, 0.17, 9000000000.0, 'Silicon dioxide (thermal oxide as fused silica: Oliver & Pharr, J. Mater. Res. 7, 1564 (1992), E = 72 GPa, nu = 0.17, H about 9 GPa); PECVD TEOS films are somewhat softer (6-8 GPa)'),
    ('copper', 0.0, 128000000000.0, 0.34, 1500000000.0, 'Polycrystalline copper: E = 128 GPa, nu = 0.34 (CRC Handbook); H = 1.5 GPa, the middle of the 1-2 GPa that nanoindentation gives for sputtered and electroplated films (film hardness exceeds the bulk 0.4-0.9 GPa; Nix, Metall. Trans. A 20, 2217 (1989))'),
    ('tungsten', 0.0, 411000000000.0, 0.28, 6000000000.0, 'Tungsten: E = 411 GPa, nu = 0.28 (CRC Handbook); H = 6 GPa for CVD films (bulk Vickers 3.4-4.5 GPa; thin films harder): order of magnitude, second-hand'),
    ('barrier', 0.0, 180000000000.0, 0.34, 15600000000.0, 'Tantalum barrier film (Ta; the barrier of cmpsim.physics.films): E = 180 GPa, H = 15.6 GPa by nanoindentation of a sputtered Ta film (J. Nanomater. 2013, 154179, read in a transcription: verify), nu = 0.34 of bulk tantalum (CRC Handbook). TaN is harder (epitaxial 457 GPa / 30.8 GPa, Appl. Phys. Lett. 75, 3808 (1999)): cmpsim.physics.films.TANTALUM_NITRIDE'),
)}


def volume_fraction(mass_fraction, particle_density, liquid_density=LIQUID_DENSITY):
    """Solid volume fraction phi of a slurry of solids loading w (mass fraction), dimensionless.

    phi = (w / rho_a) / (w / rho_a + (1 - w) / rho_l).
    """
    w = np.asarray(mass_fraction, dtype=float)
    a = w / particle_density
    return a / (a + (1.0 - w) / liquid_density)


def mass_fraction(phi, particle_density, liquid_density=LIQUID_DENSITY):
    """Solids loading w (mass fraction) of a slurry of solid volume fraction phi, the inverse of :func:`volume_fraction`."""
    phi = np.asarray(phi, dtype=float)
    m = phi * particle_density
    return m / (m + (1.0 - phi) * liquid_density)


def bulk_density(mass_fraction_, particle_density, liquid_density=LIQUID_DENSITY):
    """Bulk density of the grains rho = phi rho_a (the Haff grain flow's density), kg/m^3."""
    return volume_fraction(mass_fraction_, particle_density, liquid_density) * particle_density


def krieger_dougherty(phi, carrier_viscosity, intrinsic=INTRINSIC_VISCOSITY, max_packing=MAX_PACKING_FRACTION):
    """Viscosity of a hard-sphere suspension, eta = eta_c (1 - phi/phi_m)^(-[eta] phi_m), Pa s.

    Krieger & Dougherty, Trans. Soc. Rheol. 3, 137 (1959). It reduces to Einstein's
    eta_c (1 + [eta] phi) for phi -> 0 and diverges at the maximum packing fraction phi_m.
    ``phi`` must lie in [0, phi_m).
    """
    phi = np.asarray(phi, dtype=float)
    if np.any((phi < 0) | (phi >= max_packing)):
        raise ValueError(f"solid volume fraction must be in [0, {max_packing:g}) for the Krieger-Dougherty law; got {phi!r}")
    return carrier_viscosity * (1.0 - phi / max_packing) ** (-intrinsic * max_packing)
