"""Zone tuning, the inverse problem of the membrane head: zone pressures that flatten the removal profile.

The removal-rate profile RR(r) (rotation average, :mod:`cmpsim.uniformity`) of a membrane head
depends on its zone pressures P_k. :func:`tune_zones` finds, within bounds, the pressures that
minimise the area-weighted variance of the profile inside the edge exclusion, the square of the
within-wafer non-uniformity times the mean:

    minimise  sum_i a_i (RR_i(P) - m)^2     over P (and the level m),   P_lo <= P_k <= P_hi,

optionally keeping the mean pressure (the load) or the mean rate of the start. Each step is a
Gauss-Newton step on the zone response J_ik = d RR_i / d P_k, measured by finite differences of
warm-started solves (the equilibrium and the wafer's bending of the current pressures as the
start), solved as a bounded linear least-squares problem (:func:`scipy.optimize.lsq_linear`,
Branch & al.'s trust-region reflective method); the step is kept if the solved profile is
flatter, halved otherwise.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np
from scipy.optimize import lsq_linear

from . import models
from .config import Config
from .model import build_problem, solve
from .uniformity import ring_areas_inside, weighted_std_over_mean
from .units import to_si

__all__ = ["ZoneTuning", "tune_zones", "DEFAULT_BOUNDS", "KEEP"]

PSI = 6894.757293168361
#: Default bounds of the zone pressures, Pa (0.5-8 psi, issue 25).
DEFAULT_BOUNDS = (0.5 * PSI, 8.0 * PSI)
#: What a tuning may keep fixed besides flattening.
KEEP = (None, "pressure", "rate")
#: Relative step of the finite-difference zone response.
RESPONSE_STEP = 0.02


@dataclass
class ZoneTuning:
    """The result of :func:`tune_zones` (SI: Pa, m, m/s; non-uniformity as a fraction).

    ``zone_pressures`` the tuned pressures; ``within_wafer_nonuniformity`` and ``profile``
    (radius, rate) of the tuned solve, ``before`` the same of the start; ``response`` the last
    zone response d RR_i / d P_k (rings x zones, m/s/Pa); ``solves`` the operating points solved.
    """

    zone_radii: tuple
    zone_pressures: tuple
    within_wafer_nonuniformity: float
    profile: dict
    before: dict
    response: np.ndarray
    config: Config
    solves: int
    ring_faces: np.ndarray  # radii of the grid's ring faces, m
    history: list = field(default_factory=list)

    @property
    def response_inside(self) -> tuple:
        """Share of each zone's removal response that falls inside the zone itself (fraction per zone).

        The ring-area-weighted |d RR_i / d P_k| summed over the rings whose centre lies in zone k,
        over its sum over the wafer: 1 when a zone moves the rate only under itself, the zone's
        area share when its pressure moves the wafer as a whole.
        """
        r = np.asarray(self.profile["radius"])
        edges = np.concatenate([[0.0], self.zone_radii])
        ring_area = np.diff(np.asarray(self.ring_faces) ** 2)
        weight = np.abs(self.response) * ring_area[:, None]
        inside = [(r >= a) & (r < b) for a, b in zip(edges[:-1], edges[1:])]
        return tuple(float(weight[m, k].sum() / weight[:, k].sum()) if weight[:, k].sum() > 0 else float("nan") for k, m in enumerate(inside))

    def to_dict(self) -> dict:
        """The JSON object of ``cmpsim tune-zones --json`` (SI units)."""
        return {
            "zone_radii": list(self.zone_radii),
            "zone_pressures": list(self.zone_pressures),
            "within_wafer_nonuniformity": self.within_wafer_nonuniformity,
            "profile": {k: list(map(float, v)) for k, v in self.profile.items()},
            "before": {
                "zone_pressures": list(self.before["zone_pressures"]),
                "within_wafer_nonuniformity": self.before["within_wafer_nonuniformity"],
                "profile": {k: list(map(float, v)) for k, v in self.before["profile"].items()},
            },
            "zone_response_inside": list(self.response_inside),
            "units": {"zone_radii": "m", "zone_pressures": "Pa", "within_wafer_nonuniformity": "1", "radius": "m", "rate": "m/s", "zone_response_inside": "1"},
            "solves": self.solves,
        }


class _Solver:
    """Solves of one tuning: each from the last solved equilibrium and bending (warm starts), counted."""

    def __init__(self, config: Config):
        self.config, self.solves = config, 0
        self.start, self.bending = None, None

    def __call__(self, pressures):
        """The solve at these zone pressures (Pa), warm-started from the adopted one."""
        cfg = self.config.replace(zone_pressures=tuple(float(p) for p in pressures))
        problem = build_problem(cfg)
        problem.carrier.initial_bending = self.bending
        r = solve(cfg, start=self.start, relative=False, problem=problem)
        self.solves += 1
        return r

    def adopt(self, result) -> None:
        """Start the next solves from ``result``'s equilibrium and bending."""
        self.start, self.bending = result.solution.state.u, result.problem.carrier.bending[1]


def _weights(result) -> np.ndarray:
    """Area of each ring inside the edge exclusion, m^2 (the weights of the output's non-uniformity)."""
    return ring_areas_inside(result.grid.ring_faces, result.grid.radius - result.config.edge_exclusion)


def _profile(result) -> dict:
    return {"radius": np.asarray(result.profiles["radius"]), "rate": np.asarray(result.profiles["removal_rate_profile"])}


def tune_zones(config: Config, bounds=DEFAULT_BOUNDS, keep: str | None = None, max_steps: int = 6, rtol: float = 1e-3) -> ZoneTuning:
    """Zone pressures of a membrane head that flatten its removal-rate profile.

    Parameters
    ----------
    config : Config
        A membrane head (``carrier = "membrane"``); its ``zone_pressures`` (or ``applied_pressure`` in
        every zone) are the start.
    bounds : (low, high)
        Bounds of every zone pressure, Pa or text with units (default 0.5-8 psi).
    keep : None, "pressure" or "rate"
        Also keep the mean pressure (the load) or the mean removal rate of the start.
    max_steps : int
        Gauss-Newton steps at most (each costs one solve per zone and one of the step).
    rtol : float
        Stop when a step lowers the non-uniformity by less than this fraction of it.

    Returns
    -------
    ZoneTuning

    Raises
    ------
    ValueError
        Not a membrane head, or bad bounds (naming them); the start outside the bounds.
    cmpsim.EquilibriumError
        A solve at the start failed.
    """
    if not models.carrier(config).has_zones:
        raise ValueError(f"tune_zones needs carrier = 'membrane' (zone pressures to tune); got carrier = {config.carrier!r}")
    if keep not in KEEP:
        raise ValueError(f"keep must be one of {KEEP}; got {keep!r}")
    lo, hi = (to_si(b, "Pa", "bounds", example="psi") for b in bounds)
    if not (0 < lo < hi):
        raise ValueError(f"bounds must be 0 < low < high (Pa); got ({lo:g}, {hi:g}) Pa")
    radii = config.zone_outer_radii
    start = np.array(config.zone_pressure_values, dtype=float)
    if np.any(start < lo) or np.any(start > hi):
        raise ValueError(f"the start's zone pressures {', '.join(f'{p:g}' for p in start)} Pa lie outside the bounds [{lo:g}, {hi:g}] Pa")
    run = _Solver(config)
    base = run(start)
    run.adopt(base)
    weights = _weights(base)
    areas = np.diff(np.concatenate([[0.0], radii]) ** 2)  # zone areas / pi
    target_rate = float(np.sum(weights * _profile(base)["rate"]) / weights.sum())

    def nonuniformity(result) -> float:
        return weighted_std_over_mean(_profile(result)["rate"], weights)

    current, pressures = base, start.copy()
    wiwnu = nonuniformity(base)
    history = [(tuple(pressures), wiwnu)]
    response = np.zeros((weights.size, start.size))
    for _ in range(max_steps):
        rate = _profile(current)["rate"]
        for k in range(start.size):  # the zone response, warm-started from the current solve
            dp = RESPONSE_STEP * pressures[k]
            trial = pressures.copy()
            trial[k] += dp if trial[k] + dp <= hi else -dp
            step_k = trial[k] - pressures[k]
            response[:, k] = (_profile(run(trial))["rate"] - rate) / step_k
        # least squares in (dP, m): sqrt(a_i) (rate_i + J dP - m) -> 0, relative to the mean rate
        w = np.sqrt(weights / weights.sum()) / target_rate
        A = np.hstack([w[:, None] * response, -w[:, None]])
        b = -w * rate
        lower = np.concatenate([lo - pressures, [-np.inf]])
        upper = np.concatenate([hi - pressures, [np.inf]])
        rows, rhs = [A], [b]
        if keep == "pressure":  # sum A_k dP_k = 0, weighted to dominate
            rows.append(1e3 * np.concatenate([areas / areas.sum(), [0.0]])[None, :] / PSI)
            rhs.append([0.0])
        elif keep == "rate":  # the level m is the start's mean rate
            lower[-1], upper[-1] = target_rate - 1e-12 * target_rate, target_rate + 1e-12 * target_rate
        sol = lsq_linear(np.vstack(rows), np.concatenate(rhs), bounds=(lower, upper))
        step = sol.x[:-1]
        accepted = False
        for _halving in range(4):
            trial = np.clip(pressures + step, lo, hi)
            result = run(trial)
            value = nonuniformity(result)
            if value < wiwnu:
                accepted = True
                break
            step = 0.5 * step
        if not accepted:
            break
        gain = (wiwnu - value) / wiwnu
        current, pressures, wiwnu = result, trial, value
        run.adopt(result)
        history.append((tuple(pressures), wiwnu))
        if gain < rtol:
            break
    final_cfg = config.replace(zone_pressures=tuple(float(p) for p in pressures))
    return ZoneTuning(
        zone_radii=tuple(radii),
        zone_pressures=tuple(float(p) for p in pressures),
        within_wafer_nonuniformity=wiwnu,
        profile=_profile(current),
        before={"zone_pressures": tuple(start), "within_wafer_nonuniformity": history[0][1], "profile": _profile(base)},
        response=response,
        config=final_cfg,
        solves=run.solves,
        ring_faces=np.asarray(base.grid.ring_faces, dtype=float),
        history=history,
    )

