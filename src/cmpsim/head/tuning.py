"""Zone tuning, the inverse problem of the membrane head: zone pressures that flatten the removal profile.

The removal-rate profile RR(r) (rotation average, :mod:`cmpsim.results.uniformity`) of a membrane head
depends on its zone pressures P_k. :func:`tune_zones` finds, within bounds, the pressures that
minimise the area-weighted variance of the profile inside the edge exclusion, the square of the
within-wafer non-uniformity times the mean:

    minimise  sum_i a_i (RR_i(P) - m)^2     over P (and the level m),   P_lo <= P_k <= P_hi,

optionally keeping the zones' mean pressure (the load) or the mean rate of the start, and optionally
tuning the retaining ring's pressure with the zones (``ring=True``: the edge band is the ring's to
shape, not a zone's; the ring presses the pad beside the wafer). With the ring tuned the mean rate
(inside the edge exclusion) is kept by default: a fab tunes the profile at its rate, and flatness
alone lowers the load (on the grooved 300mm preset fourfold); ``keep="none"`` asks for that
explicitly. The kept rate is an equality of each linear step (one more least-squares row weighted
:data:`KEEP_WEIGHT`) and a solved trial that leaves it by more than :data:`RATE_TOLERANCE` is refused. Given an incoming
thickness profile t_in(r) and a polish time T, the flattened quantity is instead the remaining
thickness t_in(r) - RR(r) T (:func:`read_incoming` reads the profile from a CSV file). Each step is a
Gauss-Newton step on the zone response J_ik = d RR_i / d P_k, measured by finite differences of
warm-started solves (the equilibrium and the wafer's bending of the current pressures as the
start), solved as a bounded linear least-squares problem (:func:`scipy.optimize.lsq_linear`,
Branch & al.'s trust-region reflective method) inside a trust region, a box of half-width Delta
around the pressures: the step is kept if the solved profile is flatter; otherwise Delta is
halved and the step solved again. Delta starts at :data:`TRUST_START` of the largest start
pressure and follows the ratio of the achieved to the linearly predicted gain (Nocedal & Wright,
*Numerical Optimization*, 2006, algorithm 4.1): halved below 1/4, doubled above 3/4 for a step
that reached the box. The zone responses of a membrane head overlap (a zone's pressure moves the
rate far outside it), so the least-squares problem is ill-conditioned and an unbounded
Gauss-Newton step can ask for pressures the linearisation does not describe.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import csv
from pathlib import Path

import numpy as np
from scipy.optimize import lsq_linear

from .. import models
from ..inputs.config import Config
from ..operators.state import EquilibriumError
from ..results.uniformity import ring_areas_inside, weighted_std_over_mean
from ..inputs.units import to_si
from .zone_response import RESPONSE_STEP, ZoneSolver, boundary_widths, inside_share, profile_of, response_matrix, ring_response

__all__ = ["ZoneTuning", "tune_zones", "tune_zones_from_text", "read_incoming", "DEFAULT_BOUNDS", "DEFAULT_RING_BOUNDS", "KEEP", "LENGTH_UNITS", "RATE_TOLERANCE"]

PSI = 6894.757293168361
#: Default bounds of the zone pressures, Pa (0.5-8 psi, issue 25).
DEFAULT_BOUNDS = (0.5 * PSI, 8.0 * PSI)
#: Default bounds of the retaining ring's pressure when it is tuned (``ring=True``), Pa: 1.5-9 psi, the
#: range of a ring chamber's pressure in US 6,309,290 B1 [V-2] (docs/model.md 13f, the 300mm preset's table).
DEFAULT_RING_BOUNDS = (1.5 * PSI, 9.0 * PSI)
#: The first step's trust region, a fraction of the largest start pressure: no zone moves further.
TRUST_START = 0.25
#: Shrinks of the trust region in a step whose trial does not flatten the profile, before the tuning stops.
MAX_SHRINKS = 4
#: What a tuning may keep fixed besides flattening: nothing ("none": the load and the rate may fall),
#: the zones' mean pressure (the load) or the mean removal rate. ``keep=None`` is the default: "rate"
#: with the ring tuned (a fab tunes the profile at its rate), "none" without (issue 25's tuning).
KEEP = ("none", "pressure", "rate")
#: Weight of the kept-rate or kept-load row of the least-squares step against the profile's rows
#: (both relative): an equality constraint of the linearised step to about 1e-6 of the mean.
KEEP_WEIGHT = 1e3
#: The kept mean removal rate (``keep="rate"``) is held to this fraction of the start's: a Gauss-Newton
#: step keeps the linearised mean exactly, the solved one moves by the step's second-order change;
#: a trial step whose solved mean moves further is refused like one that does not flatten.
RATE_TOLERANCE = 1e-3
#: Units a column of an incoming-thickness CSV may name in its header (``radius_mm``), in m.
LENGTH_UNITS = {"m": 1.0, "mm": 1e-3, "um": 1e-6, "nm": 1e-9, "angstrom": 1e-10}


def read_incoming(path) -> tuple[np.ndarray, np.ndarray]:
    """An incoming thickness profile from a CSV file: (radius, thickness), both in m.

    The file has a header row naming two columns with their units, ``radius_<unit>`` and
    ``thickness_<unit>`` (any order; units from :data:`LENGTH_UNITS`, e.g. ``radius_mm,thickness_nm``),
    then one row of numbers per radius. Radii must be non-negative and strictly increasing, the
    thickness positive and finite. Raises ``ValueError`` naming the file, the row or column and
    what is wrong; ``OSError`` is turned into a ``ValueError`` too.
    """
    path = Path(path)
    try:
        with path.open(newline="") as fh:
            rows = [row for row in csv.reader(fh) if row and any(c.strip() for c in row)]
    except OSError as exc:
        raise ValueError(f"incoming: cannot read {path}: {exc}") from None
    if not rows:
        raise ValueError(f"incoming: {path} is empty; expected a header 'radius_mm,thickness_nm' and rows of numbers")
    header = [c.strip().lower() for c in rows[0]]
    columns = {}
    for j, name in enumerate(header):
        quantity, _, unit = name.partition("_")
        if quantity not in ("radius", "thickness"):
            raise ValueError(f"incoming: {path} header column {name!r} is not radius_<unit> or thickness_<unit> (e.g. 'radius_mm,thickness_nm')")
        if unit not in LENGTH_UNITS:
            raise ValueError(f"incoming: {path} column {name!r}: unit {unit!r} not known; use one of {', '.join(LENGTH_UNITS)}")
        if quantity in columns:
            raise ValueError(f"incoming: {path} names the {quantity} column twice")
        columns[quantity] = (j, LENGTH_UNITS[unit])
    if set(columns) != {"radius", "thickness"} or len(header) != 2:
        raise ValueError(f"incoming: {path} header must name exactly two columns, radius_<unit> and thickness_<unit>; got {rows[0]}")
    data = []
    for n, row in enumerate(rows[1:], start=2):
        if len(row) != 2:
            raise ValueError(f"incoming: {path} row {n} has {len(row)} values; expected 2")
        try:
            data.append([float(c) for c in row])
        except ValueError:
            raise ValueError(f"incoming: {path} row {n} is not two numbers: {row}") from None
    if len(data) < 2:
        raise ValueError(f"incoming: {path} has {len(data)} data rows; a profile needs at least 2")
    data = np.array(data)
    (jr, fr), (jt, ft) = columns["radius"], columns["thickness"]
    return _checked_incoming(data[:, jr] * fr, data[:, jt] * ft, str(path))


def _checked_incoming(radius, thickness, source: str = "incoming") -> tuple[np.ndarray, np.ndarray]:
    """(radius, thickness) as float arrays, m, after checking them (ValueError naming ``source``)."""
    r = np.asarray(radius, dtype=float)
    t = np.asarray(thickness, dtype=float)
    if r.ndim != 1 or r.shape != t.shape or r.size < 2:
        raise ValueError(f"incoming ({source}): radius and thickness must be 1-D arrays of the same length >= 2; got shapes {r.shape} and {t.shape}")
    if not (np.all(np.isfinite(r)) and np.all(np.isfinite(t))):
        raise ValueError(f"incoming ({source}): radius and thickness must be finite numbers")
    if r[0] < 0 or np.any(np.diff(r) <= 0):
        raise ValueError(f"incoming ({source}): radii must be >= 0 and strictly increasing")
    if np.any(t <= 0):
        i = int(np.argmin(t))
        raise ValueError(f"incoming ({source}): thickness must be positive; got {t[i]:g} m at radius {r[i]:g} m")
    return r, t


@dataclass
class ZoneTuning:
    """The result of :func:`tune_zones` (SI: Pa, m, m/s; non-uniformity as a fraction).

    ``zone_pressures`` the tuned pressures; ``within_wafer_nonuniformity`` and ``profile``
    (radius, rate) of the tuned solve, ``before`` the same of the start; ``response`` the last
    zone response d RR_i / d P_k (rings x zones, m/s/Pa); ``solves`` the operating points solved.
    With an incoming profile: ``polish_time`` (s), ``remaining_thickness`` (radius, thickness; m)
    and ``remaining_nonuniformity`` (fraction) of the tuned pressures, and the same in ``before``;
    ``within_wafer_nonuniformity`` stays that of the removal profile; ``history`` holds
    (pressures, objective) of each accepted step, the objective being the remaining thickness's
    non-uniformity then. With the ring tuned (``ring=True``): ``ring_pressure`` the tuned ring
    pressure (Pa; ``before["ring_pressure"]`` the start's) and ``ring_response`` the last response
    of the profile to it, d RR_i / d P_ring (m/s/Pa); both None otherwise, and ``config`` carries
    the tuned ring pressure. ``keep`` is what the tuning kept ("none", "pressure" or "rate");
    ``mean_rate`` the area mean of the tuned removal profile inside the edge exclusion (the mean the
    non-uniformity divides by, and the one ``keep="rate"`` keeps) and ``wafer_mean_rate`` its area
    mean over the whole wafer (m/s; ``before`` holds both of the start).
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
    polish_time: float | None = None
    remaining_thickness: dict | None = None
    remaining_nonuniformity: float | None = None
    ring_pressure: float | None = None
    ring_response: np.ndarray | None = None
    keep: str = "none"
    mean_rate: float | None = None  # area mean of the tuned profile inside the edge exclusion, m/s
    wafer_mean_rate: float | None = None  # area mean of the tuned profile over the whole wafer, m/s

    @property
    def response_inside(self) -> tuple:
        """Share of each zone's removal response that falls inside the zone itself (fraction per zone;
        :func:`cmpsim.head.zone_response.inside_share`): 1 when a zone moves the rate only under itself,
        the zone's area share when its pressure moves the wafer as a whole."""
        return inside_share(self.response, self.profile["radius"], self.ring_faces, self.zone_radii)

    @property
    def response_widths(self) -> list:
        """The 10-90 % response width at each inner zone boundary (:func:`cmpsim.head.zone_response.boundary_widths`)."""
        return boundary_widths(self.response, self.profile["radius"], self.ring_faces, self.zone_radii)

    def to_dict(self) -> dict:
        """The JSON object of ``cmpsim tune-zones --json`` (SI units)."""
        out = {
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
            "zone_response_width": [b.to_dict() for b in self.response_widths],
            "units": {"zone_radii": "m", "zone_pressures": "Pa", "within_wafer_nonuniformity": "1", "radius": "m", "rate": "m/s", "zone_response_inside": "1", "zone_response_width": "m", "mean_rate": "m/s", "wafer_mean_rate": "m/s"},
            "solves": self.solves,
            "keep": self.keep,
            "mean_rate": self.mean_rate,
            "wafer_mean_rate": self.wafer_mean_rate,
        }
        out["before"].update(mean_rate=self.before.get("mean_rate"), wafer_mean_rate=self.before.get("wafer_mean_rate"))
        if self.remaining_thickness is not None:
            out["polish_time"] = self.polish_time
            out["remaining_thickness"] = {k: list(map(float, v)) for k, v in self.remaining_thickness.items()}
            out["remaining_nonuniformity"] = self.remaining_nonuniformity
            out["before"]["remaining_thickness"] = {k: list(map(float, v)) for k, v in self.before["remaining_thickness"].items()}
            out["before"]["remaining_nonuniformity"] = self.before["remaining_nonuniformity"]
            out["units"].update(polish_time="s", thickness="m", remaining_nonuniformity="1")
        if self.ring_pressure is not None:
            out["ring_pressure"] = self.ring_pressure
            out["before"]["ring_pressure"] = self.before["ring_pressure"]
            out["units"]["ring_pressure"] = "Pa"
        return out


def _weights(result) -> np.ndarray:
    """Area of each ring inside the edge exclusion, m^2 (the weights of the output's non-uniformity)."""
    return ring_areas_inside(result.grid.ring_faces, result.grid.radius - result.config.edge_exclusion)


def _incoming_on_rings(incoming, result) -> np.ndarray:
    """The incoming thickness (m) interpolated linearly onto the profile radii of ``result``.

    The profile must cover the centre of every ring the non-uniformity weighs (inside the edge
    exclusion); otherwise ValueError naming the range needed and the range given.
    """
    r_in, t_in = incoming
    radius = profile_of(result)["radius"]
    used = radius[_weights(result) > 0]
    if r_in[0] > used[0] or r_in[-1] < used[-1]:
        raise ValueError(
            f"incoming: the profile covers radii {1e3 * r_in[0]:g}-{1e3 * r_in[-1]:g} mm; it must cover "
            f"{1e3 * used[0]:g}-{1e3 * used[-1]:g} mm (the centres of the rings inside the wafer radius minus the edge exclusion)"
        )
    return np.interp(radius, r_in, t_in)


def _remaining(result, thickness, polish_time) -> np.ndarray:
    """Remaining thickness t_in - RR polish_time on the profile radii, m."""
    return thickness - profile_of(result)["rate"] * polish_time


def _check_not_through(remaining, result, polish_time, which: str) -> None:
    """Refuse a polish that removes more than the incoming film anywhere inside the edge exclusion."""
    inside = _weights(result) > 0
    if np.any(remaining[inside] <= 0):
        i = int(np.argmin(np.where(inside, remaining, np.inf)))
        r = profile_of(result)["radius"][i]
        raise ValueError(
            f"polish_time = {polish_time:g} s removes more than the incoming thickness {which}: remaining "
            f"{remaining[i]:g} m at radius {1e3 * r:g} mm; shorten polish_time"
        )


def tune_zones(
    config: Config,
    bounds=DEFAULT_BOUNDS,
    keep: str | None = None,
    max_steps: int = 6,
    rtol: float = 1e-3,
    incoming=None,
    polish_time=None,
    ring: bool = False,
    ring_bounds=None,
) -> ZoneTuning:
    """Zone pressures of a membrane head that flatten its removal-rate profile, or the film left after polishing.

    Parameters
    ----------
    config : Config
        A membrane head (``carrier = "membrane"``); its ``zone_pressures`` (or ``applied_pressure`` in
        every zone) are the start.
    bounds : (low, high)
        Bounds of every zone pressure, Pa or text with units (default 0.5-8 psi).
    keep : None, "none", "pressure" or "rate"
        Also keep the zones' mean pressure (the load) or the mean removal rate of the start (the area
        mean inside the edge exclusion, the mean the non-uniformity divides by; held to
        :data:`RATE_TOLERANCE` of the start's), or nothing ("none": flatness alone, the load may fall
        and the rate with it). None, the default: "rate" with ``ring=True`` (a fab tunes the profile at
        its rate, and flatness alone lowers it), "none" without (the zone tuning of issue 25).
    max_steps : int
        Gauss-Newton steps at most (each costs one solve per zone and one of the step).
    rtol : float
        Stop when a step lowers the non-uniformity by less than this fraction of it.
    incoming : path, or (radius, thickness) arrays in m, optional
        An incoming film thickness profile (a CSV file read by :func:`read_incoming`). Then the
        pressures flatten the remaining thickness t_in(r) - RR(r) polish_time (t_in interpolated
        linearly onto the profile radii) instead of the rate; ``keep = "rate"`` keeps the mean rate.
    polish_time : float (s) or text with units
        The polish time; required with ``incoming``, refused without it.
    ring : bool
        Also tune the retaining ring's pressure (``retaining_ring_pressure``, its start; > 0, on the
        layered pad), within ``ring_bounds``: the ring shapes the edge band, which the zones cannot.
        Default False: the ring pressure stays the configuration's (the tuning of before).
    ring_bounds : (low, high), optional
        Bounds of the ring pressure, Pa or text with units (default :data:`DEFAULT_RING_BOUNDS`,
        1.5-9 psi); only with ``ring=True``.

    Returns
    -------
    ZoneTuning

    Raises
    ------
    ValueError
        Not a membrane head, or bad bounds (naming them); the start outside the bounds; ``ring``
        without a ring pressure to start from, or ``ring_bounds`` without ``ring``; a bad
        incoming profile (naming the file, row or column), one that does not cover the rings inside
        the edge exclusion, or a polish time that removes more than the incoming film anywhere
        inside the edge exclusion at the start or the tuned pressures.
    cmpsim.EquilibriumError
        A solve at the start failed.
    """
    if not models.carrier(config).has_zones:
        raise ValueError(f"tune_zones needs carrier = 'membrane' (zone pressures to tune); got carrier = {config.carrier!r}")
    if keep is None:
        keep = "rate" if ring else "none"
    if keep not in KEEP:
        raise ValueError(f"keep must be one of {KEEP} (or None: 'rate' with the ring tuned, 'none' without); got {keep!r}")
    lo, hi = (to_si(b, "Pa", "bounds", example="psi") for b in bounds)
    if not (0 < lo < hi):
        raise ValueError(f"bounds must be 0 < low < high (Pa); got ({lo:g}, {hi:g}) Pa")
    if ring_bounds is not None and not ring:
        raise ValueError("ring_bounds needs ring=True (the retaining ring's pressure tuned with the zones)")
    if ring:
        ring_lo, ring_hi = (to_si(b, "Pa", "ring_bounds", example="psi") for b in (DEFAULT_RING_BOUNDS if ring_bounds is None else ring_bounds))
        if not (0 < ring_lo < ring_hi):
            raise ValueError(f"ring_bounds must be 0 < low < high (Pa); got ({ring_lo:g}, {ring_hi:g}) Pa")
        ring_start = float(config.retaining_ring_pressure)
        if ring_start == 0.0:
            raise ValueError(
                "ring=True tunes the retaining ring's pressure but the configuration has none (retaining_ring_pressure = 0): "
                "set a start, e.g. retaining_ring_pressure = '3 psi' (on pad_compliance = 'layer')"
            )
        if not (ring_lo <= ring_start <= ring_hi):
            raise ValueError(f"the start's retaining_ring_pressure {ring_start:g} Pa lies outside the ring bounds [{ring_lo:g}, {ring_hi:g}] Pa")
    if (incoming is None) != (polish_time is None):
        raise ValueError("incoming and polish_time go together: give both (the incoming thickness profile and the polish time) or neither")
    if incoming is not None:
        if isinstance(incoming, (str, Path)):
            incoming = read_incoming(incoming)
        elif len(incoming) == 2:
            incoming = _checked_incoming(*incoming)
        else:
            raise ValueError(f"incoming must be a CSV path or a (radius, thickness) pair of arrays in m; got {len(incoming)} items")
        polish_time = to_si(polish_time, "s", "polish_time", example="min")
        if not (np.isfinite(polish_time) and polish_time > 0):
            raise ValueError(f"polish_time must be > 0 s; got {polish_time:g} s")
    radii = config.zone_outer_radii
    start = np.array(config.zone_pressure_values, dtype=float)
    if np.any(start < lo) or np.any(start > hi):
        raise ValueError(f"the start's zone pressures {', '.join(f'{p:g}' for p in start)} Pa lie outside the bounds [{lo:g}, {hi:g}] Pa")
    n = start.size  # the zones; with the ring tuned, the variables are the zone pressures and the ring's, Pa
    if ring:
        start_x = np.append(start, ring_start)
        x_lo, x_hi = np.append(np.full(n, lo), ring_lo), np.append(np.full(n, hi), ring_hi)
    else:
        start_x, x_lo, x_hi = start.copy(), np.full(n, lo), np.full(n, hi)
    run = ZoneSolver(config)

    def solve_at(x):
        return run(x[:n], ring=x[n] if ring else None)

    base = solve_at(start_x)
    run.adopt(base)
    weights = _weights(base)
    areas = np.diff(np.concatenate([[0.0], radii]) ** 2)  # zone areas / pi

    if incoming is None:
        scale = 1.0  # the flattened quantity q = RR, d q / d RR = 1
        offset = np.zeros(weights.size)
    else:  # q = t_in - RR T
        scale, offset = -polish_time, _incoming_on_rings(incoming, base)
        _check_not_through(_remaining(base, offset, polish_time), base, polish_time, "at the start's pressures")

    def quantity(result) -> np.ndarray:
        return offset + scale * profile_of(result)["rate"]

    target = float(np.sum(weights * quantity(base)) / weights.sum())  # the start's mean of q

    def mean_rate_of(result) -> float:  # area mean of the removal rate inside the edge exclusion, m/s
        return float(np.sum(weights * profile_of(result)["rate"]) / weights.sum())

    rate_target = mean_rate_of(base)

    def nonuniformity_of(values) -> float:
        return weighted_std_over_mean(values, weights)

    def nonuniformity(result) -> float:
        return nonuniformity_of(quantity(result))

    current, x = base, start_x.copy()
    wiwnu = nonuniformity(base)
    history = [(tuple(x[:n]), wiwnu)]
    response = np.zeros((weights.size, start_x.size))
    delta = TRUST_START * float(np.max(start_x))  # the trust region: no pressure moves by more than this in a step, Pa
    for _ in range(max_steps):
        rate = profile_of(current)["rate"]
        q = quantity(current)
        ring_now = x[n] if ring else None
        response = response_matrix(run, x[:n], rate, high=hi, step=RESPONSE_STEP, ring=ring_now)  # warm-started from the current solve
        if ring:
            response = np.hstack([response, ring_response(run, x[:n], ring_now, rate, high=ring_hi, step=RESPONSE_STEP)[:, None]])
        # least squares in (dP, m): sqrt(a_i) (q_i + s J dP - m) -> 0, relative to the mean of q
        w = np.sqrt(weights / weights.sum()) / abs(target)
        A = np.hstack([w[:, None] * (scale * response), -w[:, None]])
        b = -w * q
        lower = np.concatenate([x_lo - x, [-np.inf]])
        upper = np.concatenate([x_hi - x, [np.inf]])
        rows, rhs = [A], [b]
        if keep == "pressure":  # sum A_k dP_k = 0 over the zones (the ring's load is not the wafer's), weighted to dominate
            load_row = np.zeros(start_x.size + 1)
            load_row[:n] = areas / areas.sum()
            rows.append(KEEP_WEIGHT * load_row[None, :] / PSI)
            rhs.append([0.0])
        elif keep == "rate":
            # the level m is the start's mean of q (of the rate, or t_in - rate T), and the linearised
            # profile's own mean is held there too (an equality, weighted to dominate): fixing the
            # level alone only penalised the mean's drift as part of the variance about m
            lower[-1], upper[-1] = target - 1e-12 * abs(target), target + 1e-12 * abs(target)
            mean_row = np.zeros(start_x.size + 1)
            mean_row[:-1] = (weights / weights.sum()) @ (scale * response) / abs(target)
            rows.append(KEEP_WEIGHT * mean_row[None, :])
            rhs.append([KEEP_WEIGHT * (target - float(np.sum(weights * q) / weights.sum())) / abs(target)])
        A_all, b_all = np.vstack(rows), np.concatenate(rhs)
        accepted = False
        for _shrink in range(MAX_SHRINKS + 1):
            box_lo = np.concatenate([np.maximum(lower[:-1], -delta), lower[-1:]])
            box_hi = np.concatenate([np.minimum(upper[:-1], delta), upper[-1:]])
            step = lsq_linear(A_all, b_all, bounds=(box_lo, box_hi)).x[:-1]
            trial = np.clip(x + step, x_lo, x_hi)
            if np.max(np.abs(trial - x)) <= 1e-9 * float(np.max(x)):
                break  # the linear model asks for no change: a (bounded) least-squares minimum
            predicted = nonuniformity_of(q + scale * response @ (trial - x))
            try:
                result = solve_at(trial)
            except EquilibriumError:  # a step too far for the solver counts as one that does not flatten
                delta = 0.5 * np.max(np.abs(trial - x))
                continue
            value = nonuniformity(result)
            if keep == "rate" and abs(mean_rate_of(result) - rate_target) > RATE_TOLERANCE * abs(rate_target):
                value = np.inf  # the solved mean left the kept rate: a step too far for the linearisation
            if value < wiwnu:
                accepted = True
                break
            delta = 0.5 * np.max(np.abs(trial - x))
        if not accepted:
            break
        # the trust radius follows how well the linear model predicted the gain (Nocedal & Wright 2006, alg. 4.1)
        agreement = (wiwnu - value) / max(wiwnu - predicted, 1e-300)
        moved = np.max(np.abs(trial - x))
        if agreement < 0.25:
            delta = 0.5 * moved
        elif agreement > 0.75 and moved > 0.99 * delta:
            delta = 2.0 * delta
        gain = (wiwnu - value) / wiwnu
        current, x, wiwnu = result, trial, value
        run.adopt(result)
        history.append((tuple(x[:n]), wiwnu))
        if gain < rtol:
            break
    pressures = x[:n]
    tuned = {"zone_pressures": tuple(float(p) for p in pressures)}
    if ring:
        tuned["retaining_ring_pressure"] = float(x[n])
    final_cfg = config.replace(**tuned)
    before = {"zone_pressures": tuple(start), "within_wafer_nonuniformity": weighted_std_over_mean(profile_of(base)["rate"], weights), "profile": profile_of(base)}
    area = np.diff(np.asarray(base.grid.ring_faces, dtype=float) ** 2)  # ring areas / pi: the whole wafer's weights
    before.update(mean_rate=rate_target, wafer_mean_rate=float(np.sum(area * profile_of(base)["rate"]) / area.sum()))
    extra = dict(keep=keep, mean_rate=mean_rate_of(current), wafer_mean_rate=float(np.sum(area * profile_of(current)["rate"]) / area.sum()))
    if ring:
        before["ring_pressure"] = ring_start
        extra.update(ring_pressure=float(x[n]), ring_response=response[:, n])
    if incoming is not None:
        remaining = _remaining(current, offset, polish_time)
        _check_not_through(remaining, current, polish_time, "at the tuned pressures")
        radius = profile_of(current)["radius"]
        extra.update(polish_time=polish_time, remaining_thickness={"radius": radius, "thickness": remaining}, remaining_nonuniformity=wiwnu)
        before.update(remaining_thickness={"radius": radius, "thickness": _remaining(base, offset, polish_time)}, remaining_nonuniformity=history[0][1])
        wiwnu = weighted_std_over_mean(profile_of(current)["rate"], weights)
    return ZoneTuning(
        zone_radii=tuple(radii),
        zone_pressures=tuple(float(p) for p in pressures),
        within_wafer_nonuniformity=wiwnu,
        profile=profile_of(current),
        before=before,
        response=response[:, :n],
        config=final_cfg,
        solves=run.solves,
        ring_faces=np.asarray(base.grid.ring_faces, dtype=float),
        history=history,
        **extra,
    )



#: How the command line spells the options :func:`tune_zones_from_text` names in its messages.
CLI_NAMES = {"bounds": "--bounds", "ring": "--ring", "ring_bounds": "--ring-bounds"}


def tune_zones_from_text(config: Config, bounds: str = "0.5,8 psi", keep: str | None = None, ring: bool = False, ring_bounds: str | None = None, names=None, **options) -> ZoneTuning:
    """:func:`tune_zones` with its bounds as text, ``LOW,HIGH UNIT`` (e.g. ``"0.5,8 psi"``): the one call of
    ``cmpsim tune-zones`` and of ``POST /api/tune-zones``, so the two parse and check the same way.

    ``names`` maps ``"bounds"``, ``"ring"`` and ``"ring_bounds"`` to the caller's spelling of them in
    messages (:data:`CLI_NAMES` on the command line; the API's query names by default). ``options``
    go to :func:`tune_zones` as they are (``incoming``, ``polish_time``, ``max_steps``, ...).
    Raises ``ValueError`` for bounds that are not two pressures, ``ring_bounds`` without ``ring``,
    and whatever :func:`tune_zones` refuses.
    """
    from ..inputs.units import parse_list

    name = {"bounds": "bounds", "ring": "ring", "ring_bounds": "ring_bounds", **(names or {})}
    limits = parse_list(bounds, "Pa", name["bounds"], example="psi")
    if len(limits) != 2:
        raise ValueError(f"{name['bounds']} takes two pressures, LOW,HIGH with one unit (e.g. '0.5,8 psi'); got {bounds!r}")
    ring_limits = None
    if ring_bounds is not None:
        if not ring:
            raise ValueError(f"{name['ring_bounds']} needs {name['ring']} (the retaining ring's pressure tuned with the zones)")
        ring_limits = parse_list(ring_bounds, "Pa", name["ring_bounds"], example="psi")
        if len(ring_limits) != 2:
            raise ValueError(f"{name['ring_bounds']} takes two pressures, LOW,HIGH with one unit (e.g. '1.5,9 psi'); got {ring_bounds!r}")
    return tune_zones(config, bounds=limits, keep=keep, ring=ring, ring_bounds=ring_limits, **options)
