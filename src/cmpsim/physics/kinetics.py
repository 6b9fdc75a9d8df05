"""Chemical rate limit in series with the mechanical removal: the two-step form.

Pure vectorised kernels (SI units) of ``removal_kinetics = "two_step"``: the film is first
turned by the slurry chemistry into a removable surface layer (rate RR_c, thermally activated),
then removed by the abrasives (rate RR_m, :mod:`cmpsim.physics.abrasion`). In steady state the two
steps act in series, like the Langmuir–Hinshelwood two-step model of Sorooshian, Philipossian,
Borucki and co-workers (e.g. Borucki, Sorooshian, Philipossian, J. Electrochem. Soc. 2004-2006;
fitted to PETEOS/ceria by Mariscal et al., ECS J. Solid State Sci. Technol. 9, 044008 (2020)):

    RR = RR_c RR_m / (RR_c + RR_m),   RR_c = c_0 exp(-(E_a / R_g) (1/T - 1/T_0)),
    T = T_0 + beta mu p_c |du|        (flash heating by the friction power mu p_c |du|).

RR -> RR_m when the chemistry is fast (RR_c >> RR_m) and RR -> RR_c when the abrasives
are (mechanically limited vs chemically limited removal). ``docs/model.md``, "Two-step kinetics".
"""

from __future__ import annotations

import numpy as np

__all__ = ["GAS_CONSTANT", "flash_temperature", "chemical_rate", "series_rate"]

#: Molar gas constant R_g, J/(mol K) (CODATA 2018, exact).
GAS_CONSTANT = 8.314462618


def flash_temperature(base_temperature, friction_coefficient, contact_pressure, sliding_speed, heating_coefficient):
    """Surface temperature T = T_0 + beta mu p_c |du|, K.

    ``base_temperature`` T_0 in K, ``contact_pressure`` p_c in Pa, ``sliding_speed`` in m/s,
    ``heating_coefficient`` beta in K m^2/W (temperature rise per unit friction power per area).
    """
    return base_temperature + heating_coefficient * friction_coefficient * np.asarray(contact_pressure) * np.asarray(sliding_speed)


def chemical_rate(temperature, reference_rate, activation_energy, reference_temperature):
    """Arrhenius rate of the chemical step, RR_c = c_0 exp(-(E_a/R_g)(1/T - 1/T_0)), m/s.

    ``reference_rate`` c_0 (m/s) is the rate at ``reference_temperature`` T_0 (K);
    ``activation_energy`` E_a in J/mol.
    """
    t = np.asarray(temperature, dtype=float)
    return reference_rate * np.exp(-(activation_energy / GAS_CONSTANT) * (1.0 / t - 1.0 / reference_temperature))


def series_rate(chemical, mechanical):
    """Two steps in series, RR = RR_c RR_m / (RR_c + RR_m), m/s; 0 where both are 0 (nothing to remove)."""
    c = np.asarray(chemical, dtype=float)
    m = np.asarray(mechanical, dtype=float)
    total = c + m
    return np.where(total > 0, c * m / np.where(total > 0, total, 1.0), 0.0)
