"""The zone response of a membrane head: how each zone's pressure moves the removal profile.

A membrane head presses the wafer in concentric zones of pressure P_k (``zone_radii``,
``zone_pressures``). The *zone response* is the derivative of the rotation-averaged removal
profile RR(r_i) (:mod:`cmpsim.results.uniformity`) with respect to each zone pressure,

    J_ik = d RR_i / d P_k      (m/s per Pa; rings i x zones k),

measured by one-sided finite differences of solves warm-started from the equilibrium and the
wafer's bending at the given pressures. From it:

- the share of each zone's response that stays under the zone (:func:`inside_share`): 1 when
  a zone moves the rate only beneath itself, about the zone's area share when it moves the
  whole wafer;
- the local gain of each zone (:func:`local_gains`), the elasticity (P_k / RR_k) dRR_k/dP_k of
  the zone's own area-mean rate RR_k: a gain of 1 means +10 % of pressure gives +10 % of rate
  under the zone, as Preston's law would locally;
- the contrast gain of each zone (:func:`contrast_gains`), the elasticity of the ratio of the
  zone's mean rate to the mean rate of the rest of the wafer: what the zone does to the *shape*
  of the profile. A response common to the whole wafer (a zone's load that only shifts the
  wafer's level) cancels from it; a zone that moves only its own rate, like Preston's law, has
  contrast gain = local gain;
- the response width at each zone boundary (:func:`boundary_widths`): raise every zone inside
  the boundary R_b by the same pressure (a pressure step at R_b) and measure over which radial
  distance the rate change falls from 90 % to 10 % of its fall between the middles of the two
  zones on either side. An ideal head (a membrane on a local pad under a rigid-free wafer)
  gives a step, width 0 up to the grid's ring width; a bending wafer and a laterally coupled
  pad smear it over the bending length ell = (D/k)^(1/4) (docs/model.md, section 13f), D the
  wafer's bending stiffness and k the load stiffness -d(mean pressure)/d(h0) of the equilibrium
  (:func:`load_stiffness`): Hetenyi's step on a Winkler bed falls from 90 % to 10 % over 2.82 ell
  (:func:`cmpsim.testing.plates.hetenyi_step_width`).

The tuner (:mod:`cmpsim.head.tuning`) uses the same solver and the same finite differences.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from .. import models
from ..inputs.config import Config
from ..solver.model import build_problem, solve

__all__ = [
    "RESPONSE_STEP",
    "ZoneSolver",
    "ZoneResponse",
    "BoundaryWidth",
    "zone_response",
    "response_matrix",
    "ring_response",
    "profile_of",
    "inside_share",
    "local_gains",
    "contrast_gains",
    "load_stiffness",
    "boundary_widths",
]

#: Relative step of the finite-difference zone response.
RESPONSE_STEP = 0.02
#: Levels of the 10-90 % response width at a zone boundary (fractions of the fall).
WIDTH_LEVELS = (0.9, 0.1)


def profile_of(result) -> dict:
    """The removal profile of a solve: {"radius": ring centres (m), "rate": ring means (m/s)}."""
    return {"radius": np.asarray(result.profiles["radius"]), "rate": np.asarray(result.profiles["removal_rate_profile"])}


class ZoneSolver:
    """Solves of one membrane head at changing zone pressures, each warm-started from the adopted one, counted."""

    def __init__(self, config: Config):
        self.config, self.solves = config, 0
        self.start, self.bending = None, None

    def __call__(self, pressures, ring=None):
        """The solve at these zone pressures (Pa), warm-started from the adopted equilibrium and bending.

        ``ring``: the retaining ring's pressure (Pa) for this solve; None keeps the configuration's.
        """
        changes = {"zone_pressures": tuple(float(p) for p in pressures)}
        if ring is not None:
            changes["retaining_ring_pressure"] = float(ring)
        cfg = self.config.replace(**changes)
        problem = build_problem(cfg)
        problem.carrier.initial_bending = self.bending
        r = solve(cfg, start=self.start, relative=False, problem=problem)
        self.solves += 1
        return r

    def adopt(self, result) -> None:
        """Start the next solves from ``result``'s equilibrium and bending."""
        self.start, self.bending = result.solution.state.u, result.problem.carrier.bending[1]


def response_matrix(run: ZoneSolver, pressures, rate, high: float = np.inf, step: float = RESPONSE_STEP, ring=None) -> np.ndarray:
    """J_ik = d RR_i / d P_k (m/s/Pa) by one-sided differences of ``run`` at ``pressures`` (Pa).

    ``rate`` is the profile (m/s) at ``pressures``; each zone is raised by ``step`` times its
    pressure, or lowered by it where raising would pass ``high``. ``ring``: the retaining ring's
    pressure (Pa) of every solve, None for the configuration's.
    """
    pressures = np.asarray(pressures, dtype=float)
    rate = np.asarray(rate, dtype=float)
    out = np.zeros((rate.size, pressures.size))
    for k in range(pressures.size):
        dp = step * pressures[k]
        trial = pressures.copy()
        trial[k] += dp if trial[k] + dp <= high else -dp
        out[:, k] = (profile_of(run(trial, ring=ring))["rate"] - rate) / (trial[k] - pressures[k])
    return out


def ring_response(run: ZoneSolver, pressures, ring: float, rate, high: float = np.inf, step: float = RESPONSE_STEP) -> np.ndarray:
    """d RR_i / d P_ring (m/s/Pa), the removal profile's response to the retaining ring's pressure.

    One-sided difference of ``run`` at the zone ``pressures`` (Pa) and ring pressure ``ring``
    (Pa, > 0), whose profile is ``rate`` (m/s): the ring is raised by ``step`` times its pressure,
    or lowered by it where raising would pass ``high``. The ring presses the pad beside the wafer
    (``retaining_ring_*``; a laterally coupled pad carries it to the wafer's edge), so its response
    lies in the edge band.
    """
    ring = float(ring)
    if not ring > 0:
        raise ValueError(f"the ring's response needs a ring pressure > 0 Pa; got {ring:g} Pa")
    rate = np.asarray(rate, dtype=float)
    dp = step * ring
    trial = ring + dp if ring + dp <= high else ring - dp
    return (profile_of(run(pressures, ring=trial))["rate"] - rate) / (trial - ring)


def _zone_masks(radius, zone_radii) -> list:
    edges = np.concatenate([[0.0], np.asarray(zone_radii, dtype=float)])
    r = np.asarray(radius, dtype=float)
    return [(r >= a) & (r < b) for a, b in zip(edges[:-1], edges[1:])]


def inside_share(response, radius, ring_faces, zone_radii) -> tuple:
    """Share of each zone's removal response that falls inside the zone itself (fraction per zone).

    The ring-area-weighted |J_ik| summed over the rings whose centre lies in zone k, over its
    sum over the wafer: 1 when a zone moves the rate only under itself, the zone's area share
    when its pressure moves the wafer as a whole. NaN for a zone with no response at all.
    """
    ring_area = np.diff(np.asarray(ring_faces, dtype=float) ** 2)
    weight = np.abs(np.asarray(response)) * ring_area[:, None]
    out = []
    for k, m in enumerate(_zone_masks(radius, zone_radii)):
        total = weight[:, k].sum()
        out.append(float(weight[m, k].sum() / total) if total > 0 else float("nan"))
    return tuple(out)


def local_gains(response, rate, ring_faces, radius, zone_radii, pressures) -> tuple:
    """Elasticity of each zone's own mean rate to its pressure, (P_k / RR_k) d RR_k / d P_k (dimensionless).

    RR_k is the ring-area-weighted mean of the profile over the rings whose centre lies in zone k.
    """
    ring_area = np.diff(np.asarray(ring_faces, dtype=float) ** 2)
    rate = np.asarray(rate, dtype=float)
    out = []
    for k, m in enumerate(_zone_masks(radius, zone_radii)):
        a = ring_area[m]
        mean_rate = float(np.sum(a * rate[m]) / a.sum())
        mean_response = float(np.sum(a * np.asarray(response)[m, k]) / a.sum())
        out.append(pressures[k] * mean_response / mean_rate)
    return tuple(out)


def contrast_gains(response, rate, ring_faces, radius, zone_radii, pressures) -> tuple:
    """Elasticity of each zone's mean rate relative to the rest of the wafer, P_k d ln(RR_k / RR_out,k) / d P_k (dimensionless).

    RR_k is the ring-area-weighted mean of the profile over the rings whose centre lies in zone k
    (as in :func:`local_gains`), RR_out,k the same mean over every other ring. A change common to
    the whole wafer (every ring's rate moved by the same fraction) cancels; a zone that moves
    only its own rate has contrast gain equal to its local gain. NaN for a zone that covers the
    whole wafer (nothing outside it).
    """
    ring_area = np.diff(np.asarray(ring_faces, dtype=float) ** 2)
    rate, J = np.asarray(rate, dtype=float), np.asarray(response, dtype=float)
    out = []
    for k, m in enumerate(_zone_masks(radius, zone_radii)):
        elasticity = []
        for part in (m, ~m):
            a = ring_area[part]
            if not a.sum() > 0:
                elasticity.append(float("nan"))
                continue
            elasticity.append(float(np.sum(a * J[part, k]) / np.sum(a * rate[part])))
        out.append(float(pressures[k] * (elasticity[0] - elasticity[1])))
    return tuple(out)


def load_stiffness(result) -> float:
    """The load stiffness k = -d(mean pressure)/d(h0) (Pa/m) of a solved equilibrium on a compliant pad.

    The change of the wafer's mean face pressure when the whole wafer moves towards the pad, from
    the equilibrium's own linearisation (the pad model's ``sensitivity``: pad, asperity contact and
    slurry together); the foundation stiffness of the plate-on-foundation picture. Measured as the
    membrane carrier measures the stiffness that preconditions its bending
    (:meth:`cmpsim.models.carriers.MembraneCarrier.equilibrium`), but at ``result``'s bent
    equilibrium, not at the rigid-body start (300mm preset: 1.29e9 against 1.17e9 Pa/m).
    """
    problem, state = result.problem, result.solution.state
    _, dp_du = problem.pad_model.sensitivity(problem, state)
    grid = problem.grid
    return float(-grid.integrate(dp_du[..., 0]) / grid.integrate(np.ones_like(state.h)))


@dataclass(frozen=True)
class BoundaryWidth:
    """The response at one zone boundary (m; see :func:`boundary_widths`).

    ``boundary`` the boundary radius R_b; ``start`` and ``end`` the radii where the step response
    has fallen by 10 % and by 90 % of its fall; ``width`` = end - start (None where the step
    response does not fall across the boundary); ``centre`` the radius of the 50 % level;
    ``ring_width`` the width of the grid's ring at R_b (the resolution of the measurement).
    """

    boundary: float
    start: float | None
    centre: float | None
    end: float | None
    width: float | None
    ring_width: float

    def to_dict(self) -> dict:
        return {k: getattr(self, k) for k in ("boundary", "start", "centre", "end", "width", "ring_width")}


def _first_crossing(r, s, level) -> float | None:
    """First radius (linear interpolation) where s falls to ``level`` or below, going outwards."""
    below = np.nonzero(s <= level)[0]
    if below.size == 0:
        return None
    j = int(below[0])
    if j == 0:
        return float(r[0])
    return float(np.interp(level, [s[j], s[j - 1]], [r[j], r[j - 1]]))


def boundary_widths(response, radius, ring_faces, zone_radii, levels=WIDTH_LEVELS) -> list:
    """The 10-90 % width of the removal response to a pressure step at each inner zone boundary.

    For the boundary R_b between zones k and k + 1 the step response is
    S(r) = sum_{j <= k} J_j(r) (every zone inside R_b raised by the same pressure). Between the
    middles m_k and m_{k+1} of the two zones it falls from S(m_k) to S(m_{k+1}) (linear
    interpolation between ring centres); normalised, s = (S - S(m_{k+1})) / (S(m_k) - S(m_{k+1})),
    the width is the distance from where s first falls to 0.9 to where it first falls to 0.1.
    Returns one :class:`BoundaryWidth` per inner boundary (len(zone_radii) - 1); a boundary
    across which S does not fall (a zone that moves the rate outside more than inside) has
    width None.
    """
    r = np.asarray(radius, dtype=float)
    faces = np.asarray(ring_faces, dtype=float)
    J = np.asarray(response, dtype=float)
    edges = np.concatenate([[0.0], np.asarray(zone_radii, dtype=float)])
    middles = 0.5 * (edges[:-1] + edges[1:])
    hi, lo = levels
    out = []
    for k in range(len(zone_radii) - 1):
        rb = float(zone_radii[k])
        step = J[:, : k + 1].sum(axis=1)
        s_in, s_out = np.interp([middles[k], middles[k + 1]], r, step)
        ring = int(np.clip(np.searchsorted(faces, rb) - 1, 0, faces.size - 2))
        ring_width = float(faces[ring + 1] - faces[ring])
        fall = s_in - s_out
        if not fall > 0:
            out.append(BoundaryWidth(rb, None, None, None, None, ring_width))
            continue
        window = (r > middles[k]) & (r < middles[k + 1])
        rw = np.concatenate([[middles[k]], r[window], [middles[k + 1]]])
        sw = (np.concatenate([[s_in], step[window], [s_out]]) - s_out) / fall
        start, centre, end = (_first_crossing(rw, sw, level) for level in (hi, 0.5, lo))
        width = None if start is None or end is None else end - start
        out.append(BoundaryWidth(rb, start, centre, end, width, ring_width))
    return out


@dataclass
class ZoneResponse:
    """The zone response of a membrane head at its zone pressures (SI: m, Pa, m/s).

    ``response`` J_ik = d RR_i / d P_k (rings x zones, m/s/Pa) at ``zone_pressures``; ``profile``
    the removal profile there (radius, rate); ``ring_faces`` the grid's ring faces; ``solves``
    the equilibria solved (one per zone plus the base); ``load_stiffness`` k (Pa/m,
    :func:`load_stiffness`) and ``bending_stiffness`` D (N m) of the wafer at the base
    equilibrium, None where not measured.
    """

    zone_radii: tuple
    zone_pressures: tuple
    profile: dict
    ring_faces: np.ndarray
    response: np.ndarray
    step: float
    solves: int
    load_stiffness: float | None = None
    bending_stiffness: float | None = None

    @property
    def inside(self) -> tuple:
        """:func:`inside_share` of each zone (fraction)."""
        return inside_share(self.response, self.profile["radius"], self.ring_faces, self.zone_radii)

    @property
    def gains(self) -> tuple:
        """:func:`local_gains` of each zone (dimensionless)."""
        return local_gains(self.response, self.profile["rate"], self.ring_faces, self.profile["radius"], self.zone_radii, self.zone_pressures)

    @property
    def contrast(self) -> tuple:
        """:func:`contrast_gains` of each zone (dimensionless)."""
        return contrast_gains(self.response, self.profile["rate"], self.ring_faces, self.profile["radius"], self.zone_radii, self.zone_pressures)

    @property
    def bending_length(self) -> float | None:
        """The wafer's bending length ell = (D / k)^(1/4) on the equilibrium's load stiffness, m (None if not measured)."""
        if self.load_stiffness is None or self.bending_stiffness is None or not self.load_stiffness > 0:
            return None
        return float((self.bending_stiffness / self.load_stiffness) ** 0.25)

    @property
    def boundaries(self) -> list:
        """:func:`boundary_widths` at each inner zone boundary."""
        return boundary_widths(self.response, self.profile["radius"], self.ring_faces, self.zone_radii)

    def to_dict(self) -> dict:
        """A JSON object (SI units)."""
        return {
            "zone_radii": list(self.zone_radii),
            "zone_pressures": list(self.zone_pressures),
            "profile": {k: list(map(float, v)) for k, v in self.profile.items()},
            "response": [list(map(float, row)) for row in self.response],
            "zone_response_inside": list(self.inside),
            "zone_response_gain": list(self.gains),
            "zone_response_width": [b.to_dict() for b in self.boundaries],
            "zone_response_contrast": [None if np.isnan(c) else c for c in self.contrast],  # None: nothing outside the zone
            "load_stiffness": self.load_stiffness,
            "bending_length": self.bending_length,
            "units": {"zone_radii": "m", "zone_pressures": "Pa", "radius": "m", "rate": "m/s", "response": "m/s/Pa",
                      "zone_response_inside": "1", "zone_response_gain": "1", "zone_response_width": "m",
                      "zone_response_contrast": "1", "load_stiffness": "Pa/m", "bending_length": "m"},
            "solves": self.solves,
        }


def zone_response(config: Config, step: float = RESPONSE_STEP) -> ZoneResponse:
    """The zone response of the membrane head of ``config`` at its zone pressures.

    Parameters
    ----------
    config : Config
        A membrane head (``carrier = "membrane"``); its ``zone_pressures`` (or
        ``applied_pressure`` in every zone) are where the response is measured.
    step : float
        Relative pressure step of the finite differences (default 2 %), in (0, 0.5].

    Returns
    -------
    ZoneResponse
        One solve at the pressures and one per zone, warm-started from it; the load stiffness of
        the first (its linearisation, after the zones' solves).

    Raises
    ------
    ValueError
        Not a membrane head, or a step outside (0, 0.5].
    cmpsim.EquilibriumError
        A solve failed.
    """
    if not models.carrier(config).has_zones:
        raise ValueError(f"zone_response needs carrier = 'membrane' (zone pressures to vary); got carrier = {config.carrier!r}")
    if not (0.0 < step <= 0.5):
        raise ValueError(f"step must be a relative pressure step in (0, 0.5]; got {step!r}")
    pressures = np.array(config.zone_pressure_values, dtype=float)
    run = ZoneSolver(config)
    base = run(pressures)
    run.adopt(base)
    profile = profile_of(base)
    J = response_matrix(run, pressures, profile["rate"], step=step)
    return ZoneResponse(
        zone_radii=tuple(config.zone_outer_radii),
        zone_pressures=tuple(float(p) for p in pressures),
        profile=profile,
        ring_faces=np.asarray(base.grid.ring_faces, dtype=float),
        response=J,
        step=step,
        solves=run.solves,
        load_stiffness=load_stiffness(base),
        bending_stiffness=float(base.problem.carrier.plate.bending_stiffness),
    )
