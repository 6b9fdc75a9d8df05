"""Constants of the removable films of a stack (copper, Ta/TaN barrier, oxide) for recipes and end points (issue 32).

Pure data and one optical kernel, SI units. Each number carries its source; "[T]" marks a value
read in a transcription (/work/shared/LITERATURE.md, "The polisher over time") and not checked in
the original: verify before relying on it. The mechanical constants of copper and oxide repeat
those of ``cmpsim.physics.materials.FILMS`` (same values, same sources; not imported, so that this module
stays free of cmpsim). An end point can be computed from the reflectance at 650 nm: the metals'
(opaque above ``opaque_thickness``) or, for the transparent oxide on silicon, the thin-film
reflectance :func:`film_reflectance` (Airy's formula at normal incidence).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

__all__ = ["FilmConstants", "FILM_CONSTANTS", "COPPER", "TANTALUM", "TANTALUM_NITRIDE", "OXIDE", "SILICON_INDEX_650",
           "film_reflectance", "interface_reflectance"]


@dataclass(frozen=True)
class FilmConstants:
    """One film: ``modulus`` E (Pa), ``poisson`` nu, ``hardness`` H (Pa), ``activation_energy`` E_a of the
    chemical step (J/mol; None where unsourced), ``reflectance_650`` of the opaque film at 650 nm
    (None for a transparent film), ``refractive_index_650`` n (transparent films; None for metals),
    ``opaque_thickness`` (m; a metal film thinner than this lets the layer below show, None for a
    transparent film), ``rate_vs_copper`` (removal rate over copper's in the stated slurry; None if
    unsourced), ``friction_coefficient`` (None: no sourced film-specific value), and ``sources``."""

    name: str
    modulus: float
    poisson: float
    hardness: float
    activation_energy: float | None
    reflectance_650: float | None
    refractive_index_650: float | None
    opaque_thickness: float | None
    rate_vs_copper: float | None
    friction_coefficient: float | None
    sources: str

    def __post_init__(self) -> None:
        if not (self.modulus > 0 and self.hardness > 0 and 0 <= self.poisson <= 0.5):
            raise ValueError(f"film {self.name!r}: modulus and hardness must be > 0, Poisson ratio in [0, 0.5]")
        if self.reflectance_650 is not None and not (0 <= self.reflectance_650 <= 1):
            raise ValueError(f"film {self.name!r}: reflectance must be in [0, 1]")

    @property
    def reduced_compliance(self) -> float:
        """(1 - nu^2) / E, 1/Pa: the film's share of 1/E* in a Hertz contact."""
        return (1.0 - self.poisson**2) / self.modulus


COPPER = FilmConstants(
    name="copper",
    # E = 128 GPa, nu = 0.34 (CRC Handbook); H = 1.5 GPa for sputtered/plated films (Nix, Metall.
    # Trans. A 20, 2217 (1989)): the values of cmpsim.physics.materials.FILMS["copper"].
    modulus=128e9, poisson=0.34, hardness=1.5e9,
    # Arrhenius fit of the blanket Cu rate against pad temperature, 151.7 kJ/mol (Shin et al.,
    # Materials 18, 4461 (2025), doi 10.3390/ma18194461) [T]: large for a chemical step; verify.
    activation_energy=151.7e3,
    # Reflectance at 650 nm, 0.943; metal films transparent below 30-40 nm (Tian et al.,
    # Micromachines 14, 2053 (2023)) [T]: 40 nm taken as opaque.
    reflectance_650=0.943, refractive_index_650=None, opaque_thickness=40e-9,
    rate_vs_copper=1.0, friction_coefficient=None,
    sources="cmpsim.physics.materials (E, nu, H); Shin et al. 2025 (E_a) [T]; Tian et al. 2023 (reflectance, opacity) [T]",
)

TANTALUM = FilmConstants(
    name="barrier",
    # Sputtered Ta film, nanoindentation: H = 15.6 GPa, E = 180 GPa (J. Nanomater. 2013, 154179) [T];
    # nu = 0.34 for bulk tantalum (CRC Handbook).
    modulus=180e9, poisson=0.34, hardness=15.6e9,
    # Ta blanket rate against pad temperature, 29.9 kJ/mol (Shin et al. 2025) [T].
    activation_energy=29.9e3,
    # Ta reflectance at 650 nm 0.460 (Tian et al. 2023) [T]; opaque above 40 nm as for the metals there.
    reflectance_650=0.460, refractive_index_650=None, opaque_thickness=40e-9,
    # Ta 215 vs Cu 45 nm/min at high pH, 6.3 psi (Li & Babu, Electrochem. Solid-State Lett. 4, G20
    # (2001)) [T]: 4.8 in that (barrier) slurry; a copper slurry's selectivity is the reverse.
    rate_vs_copper=215.0 / 45.0, friction_coefficient=None,
    sources="J. Nanomater. 2013, 154179 (H, E) [T]; CRC (nu); Shin et al. 2025 (E_a) [T]; Tian et al. 2023 (reflectance) [T]; Li & Babu 2001 (rate) [T]",
)

TANTALUM_NITRIDE = FilmConstants(
    name="tantalum_nitride",
    # Epitaxial TaN: H = 30.8 GPa, E = 457 GPa (Appl. Phys. Lett. 75, 3808 (1999)) [T]: an upper
    # bound for sputtered barrier TaN; nu = 0.30 assumed (no source found).
    modulus=457e9, poisson=0.30, hardness=30.8e9,
    activation_energy=None, reflectance_650=None, refractive_index_650=None, opaque_thickness=None,
    rate_vs_copper=None, friction_coefficient=None,
    sources="Appl. Phys. Lett. 75, 3808 (1999) (H, E) [T]; nu assumed; no E_a, reflectance or rate found",
)

OXIDE = FilmConstants(
    name="oxide",
    # Thermal oxide as fused silica: E = 72 GPa, nu = 0.17, H about 9 GPa (Oliver & Pharr, J. Mater.
    # Res. 7, 1564 (1992)): the values of cmpsim.physics.materials.FILMS["oxide"].
    modulus=72e9, poisson=0.17, hardness=9e9,
    # SiO2 blanket rate against pad temperature, 8.75 kJ/mol (Shin et al. 2025) [T].
    activation_energy=8.75e3,
    # Transparent: fused silica n = 1.4565 at 650 nm (Malitson, J. Opt. Soc. Am. 55, 1205 (1965),
    # Sellmeier fit); its reflectance is that of the film on its substrate (film_reflectance).
    reflectance_650=None, refractive_index_650=1.4565, opaque_thickness=None,
    rate_vs_copper=None, friction_coefficient=None,
    sources="cmpsim.physics.materials (E, nu, H); Shin et al. 2025 (E_a) [T]; Malitson 1965 (n)",
)

#: Films by the name a recipe's [[film]] table uses ("barrier" is Ta; TaN by its own name).
FILM_CONSTANTS: dict[str, FilmConstants] = {f.name: f for f in (COPPER, TANTALUM, TANTALUM_NITRIDE, OXIDE)}

#: Crystalline silicon at 650 nm, n + i k = 3.85 + 0.016i (Green, Sol. Energy Mater. Sol. Cells 92,
#: 1305 (2008), tabulated at 300 K; rounded, read from memory of the table: verify). Bare silicon
#: then reflects ((n-1)^2 + k^2)/((n+1)^2 + k^2) = 0.345.
SILICON_INDEX_650 = complex(3.85, 0.016)


def interface_reflectance(n1, n2):
    """Normal-incidence intensity reflectance |(n1 - n2)/(n1 + n2)|^2 of the interface between media of
    (complex) refractive indices n1 and n2 (Fresnel), dimensionless."""
    n1 = np.asarray(n1, dtype=complex)
    n2 = np.asarray(n2, dtype=complex)
    return np.abs((n1 - n2) / (n1 + n2)) ** 2


def film_reflectance(thickness, film_index=OXIDE.refractive_index_650, substrate_index=SILICON_INDEX_650,
                     wavelength=650e-9, ambient_index=1.333):
    """Reflectance at normal incidence of a transparent film on a substrate, seen through the ambient
    (slurry water, n = 1.333 by default), dimensionless (Airy's formula; Born & Wolf, Principles of
    Optics, section 1.6.4):

        r = (r01 + r12 exp(2 i beta)) / (1 + r01 r12 exp(2 i beta)),  beta = 2 pi n1 t / lambda,
        r_ij = (n_i - n_j)/(n_i + n_j),  R = |r|^2.

    ``thickness`` t in m (array), ``wavelength`` lambda in m. t = 0 gives the bare substrate; R is
    periodic in t with period lambda / (2 n1). The end-point trace of an oxide film as it thins.
    """
    t = np.asarray(thickness, dtype=float)
    n0, n1, n2 = complex(ambient_index), complex(film_index), complex(substrate_index)
    r01 = (n0 - n1) / (n0 + n1)
    r12 = (n1 - n2) / (n1 + n2)
    phase = np.exp(2j * (2 * np.pi * n1 * t / wavelength))
    r = (r01 + r12 * phase) / (1 + r01 * r12 * phase)
    return np.abs(r) ** 2
