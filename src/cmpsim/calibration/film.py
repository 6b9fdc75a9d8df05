"""The film chemistry's part of a measured removal: d(model value)/d(constant) at a solved point.

The removal rate of eq. 13h.2 (docs/model.md) is linear in the film's constants (k_F, B_F,
R_c,F), so a solved equilibrium gives their exact derivatives: the wafer-mean (or, at a
``radius``, rotation-averaged) mechanical rate, sliding speed and 1, times the polish ``time``
for a ``removal`` depth (minus it for a remaining ``thickness``). The leave-one-out comparison of
``cmpsim validate`` fits these constants by linear least squares on them
(:mod:`cmpsim.calibration.heldout`).
"""

from __future__ import annotations

import numpy as np

from .. import models
from ..results.uniformity import ring_mean
from ..solver.postprocess import removal_law_fields, stress_fields

__all__ = ["chemistry_sensitivities"]


def chemistry_sensitivities(result, film: str | None = None, where: dict | None = None, quantity: str = "removal_rate_mean") -> dict[str, float]:
    """{input: d(value)/d(input)} (SI) of a removal quantity of ``film`` (default the result's) at a solved point.

    ``result`` is a :class:`cmpsim.results.result.Result`; ``where`` the point's ``radius`` (m),
    ``time`` (s) and ``initial_thickness`` (m) as in :func:`cmpsim.validation.compare.model_value`.
    """
    where = where or {}
    cfg = result.config
    cfg = cfg.replace(film=film or cfg.film, film_chemistry="additive")
    problem, state = result.problem, result.solution.state
    stresses = stress_fields(cfg, problem, state, problem.lub.kinematics, problem.lub)
    fields = removal_law_fields(stresses, state, problem)
    law = models.removal_law(cfg)
    sens = law.sensitivities(**{n: fields[n]() for n in law.needs})
    grid = problem.grid
    out = {}
    for name, field in sens.items():
        if "radius" in where:
            value = float(np.interp(where["radius"], np.asarray(result.profiles["radius"], dtype=float), ring_mean(field)))
        else:
            value = float(grid.integrate(field) / (np.pi * grid.radius**2))
        if quantity == "removal":
            value *= where["time"]
        elif quantity == "thickness":
            value *= -where["time"]
        out[name] = value
    return out
