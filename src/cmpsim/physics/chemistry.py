"""Film chemistry that adds to the mechanical removal rate: the additive (Babu) form.

A pure vectorised kernel (SI units) of ``film_chemistry = "additive"``. Copper slurries remove
720-1500 nm/min on a Mirra (Tugbawa, PhD thesis, MIT 2002, Table 3.3) where the mechanical
(Preston-like) rate of the same pad and load is a few hundred nm/min: the slurry's chemistry
(oxidiser, complexing agent) removes material besides the abrasion, and chemical dissolution of
abraded copper accelerates the rate (Steigerwald et al. 1994). The empirical law of S. V. Babu's
group writes the blanket rate as the Preston term plus a speed term and a constant (read in a
transcription, docs/model.md section 13h)::

    RR = K P V + B V + R_c                                                       (13h.1)

cmpsim keeps its own mechanical rate RR_m (the removal law, :mod:`cmpsim.models.removal_laws`)
in place of K P V, scaled by a per-film factor k_F, and adds the two chemical terms locally::

    RR(x) = k_F RR_m(x) + B_F |du(x)| + R_c,F                                     (13h.2)

with |du| the local sliding speed (m/s), B_F the material removed per unit sliding distance by
the chemistry (dimensionless, m/m; shown in nm/m) and R_c,F a rate that does not need sliding
(m/s). k_F = 1, B_F = R_c,F = 0 give RR_m exactly. The rate is linear in (k_F, B_F, R_c,F):
:func:`additive_sensitivities` gives its exact derivatives, which the calibration uses.
"""

from __future__ import annotations

import numpy as np

__all__ = ["additive_rate", "additive_sensitivities", "input_names", "CHEMISTRY_SYMBOLS"]

#: The symbols of eq. 13h.2 in the order of :func:`input_names`.
CHEMISTRY_SYMBOLS = ("k_F", "B_F", "R_c,F")


def input_names(film: str) -> tuple[str, str, str]:
    """The inputs of film ``film``'s terms of eq. 13h.2: (k_F, B_F, R_c,F) as
    ``mechanical_factor_<film>``, ``chemistry_speed_<film>``, ``chemistry_rate_<film>``."""
    return f"mechanical_factor_{film}", f"chemistry_speed_{film}", f"chemistry_rate_{film}"


def additive_rate(mechanical, relative_speed, factor: float, speed_coefficient: float, chemical_rate: float):
    """The removal rate of eq. 13h.2, RR = k_F RR_m + B_F |du| + R_c,F, m/s.

    ``mechanical`` RR_m (m/s, array), ``relative_speed`` |du| (m/s, array), ``factor`` k_F
    (dimensionless, >= 0), ``speed_coefficient`` B_F (m removed per m slid, >= 0),
    ``chemical_rate`` R_c,F (m/s, >= 0).
    """
    m = np.asarray(mechanical, dtype=float)
    return factor * m + speed_coefficient * np.asarray(relative_speed, dtype=float) + chemical_rate


def additive_sensitivities(mechanical, relative_speed) -> tuple:
    """(dRR/dk_F, dRR/dB_F, dRR/dR_c,F) of eq. 13h.2: (RR_m in m/s, |du| in m/s, 1), arrays."""
    m = np.asarray(mechanical, dtype=float)
    return m, np.asarray(relative_speed, dtype=float) * np.ones_like(m), np.ones_like(m)
