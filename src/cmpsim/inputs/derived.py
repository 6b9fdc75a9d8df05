"""Inputs that another input sets: the solids loading and the older granular_density kept one
setting, and applied_pressure as the area-weighted mean of the zone pressures of a membrane head.

:meth:`cmpsim.inputs.config.Config.replace` calls these on every change; a contradiction (both inputs
given, disagreeing) raises ``ValueError`` naming both and what to set instead.
"""

from __future__ import annotations

import dataclasses
import math
from typing import Any

from ..physics.materials import ABRASIVES, mass_fraction

__all__ = ["MATCH_RTOL", "loading_overrides", "zone_mean_pressure", "with_zone_load"]


#: Relative tolerance of "the last zone radius is the wafer radius" and of "applied_pressure is
#: the zones' mean" (inputs typed in mm or psi carry round-off of ~1e-16 after conversion).
MATCH_RTOL = 1e-9


def loading_overrides(current, given: dict[str, Any]) -> dict[str, Any]:
    """Keep solids_loading and granular_density one setting (docs/model.md, 'Solids loading').

    ``granular_density`` > 0 (the older input) sets ``solids_loading`` (w from phi = rho /
    rho_a); ``solids_loading`` given alone returns ``granular_density`` to 0 (derived); both
    given and disagreeing by more than 1 % (more than rounding) is an error naming both.
    """
    out = dict(given)
    abrasive = ABRASIVES[out.get("abrasive", current.slurry.abrasive)]
    rho = out.get("granular_density", current.slurry.granular_density if "abrasive" in out else 0.0)
    if "granular_density" in out or ("abrasive" in out and rho > 0 and "solids_loading" not in out):
        if rho > 0:
            phi = rho / abrasive.density
            if phi >= 0.6:
                raise ValueError(
                    f"granular_density = {rho:g} kg/m^3 is a solid volume fraction of {phi:.3g} for abrasive = {abrasive.name!r} "
                    f"({abrasive.density:g} kg/m^3): valid range (0, {0.6 * abrasive.density:g}) kg/m^3"
                )
            implied = float(mass_fraction(phi, abrasive.density))
            if "solids_loading" in out and abs(out["solids_loading"] - implied) > 1e-2 * max(implied, 1e-12):
                raise ValueError(
                    f"granular_density = {rho:g} kg/m^3 and solids_loading = {out['solids_loading']:g} contradict each other: "
                    f"with abrasive = {abrasive.name!r} ({abrasive.density:g} kg/m^3) in water that density is a solids loading of "
                    f"{implied:.6g}. Set only solids_loading (granular_density = 0 derives the density from it); "
                    "granular_density is the older input, kept for old configurations"
                )
            out["solids_loading"] = implied
    elif "solids_loading" in out:
        out["granular_density"] = 0.0
    return out


def zone_mean_pressure(radii, pressures) -> float:
    """Area-weighted mean of zone pressures, Pa: sum P_k pi (R_k^2 - R_{k-1}^2) / (pi R_n^2), R_0 = 0 (radii in m)."""
    edges = (0.0,) + tuple(radii)
    areas = [b * b - a * a for a, b in zip(edges, edges[1:])]
    return math.fsum(pk * ak for pk, ak in zip(pressures, areas)) / (edges[-1] ** 2)


def with_zone_load(c, overrides: dict):
    """The :class:`cmpsim.inputs.config.Config` ``c`` with applied_pressure set to the zones' mean, Pa;
    refuses an input (``overrides``, as given to ``replace``) that sets both to different loads."""
    mean = zone_mean_pressure(c.zone_outer_radii, c.process.zone_pressures)
    given = c.process.applied_pressure
    if "applied_pressure" in overrides and not math.isclose(given, mean, rel_tol=MATCH_RTOL):
        where = "the same input sets zone_pressures" if "zone_pressures" in overrides else "zone_pressures are already set"
        raise ValueError(
            f"applied_pressure = {given:g} Pa conflicts with zone_pressures ({where}; their area-weighted mean is {mean:g} Pa): set one of them. "
            "With zone_pressures, applied_pressure is their mean; to go back to one pressure everywhere set zone_pressures = ''"
        )
    return dataclasses.replace(c, process=dataclasses.replace(c.process, applied_pressure=mean))
