"""The zone feedback of a lot: zone pressures chosen to flatten the next wafer, only where the head's
zone response predicts they do (issue 38).

On a zoned membrane head the lot sets, before each wafer, the zone pressures P (Pa) from what it
knows: the shape of the removal-rate profile at the current pressures, learnt from the wafers
polished so far, the head's zone response J_ik = d rate(r_i) / d P_k (m/s/Pa,
:func:`cmpsim.head.zone_response.response_matrix`, computed once per lot at the starting pressures
P_0 on the fresh pad, mean rate m_J there) and the incoming profile measured before the wafer.
w_i are the rings' shares of the wafer area (sum 1), A_k the zones' areas.

- (Z1) The rate shape (the rate over its wafer mean, sum_i w_i h_i = 1) after a pressure change dP:
  s(dP) = (h + rho dP) / (1 + w . rho dP), rho = J / m(P), m(P) = m_J + w . J (P - P_0) the mean rate
  at the current pressures on the response's pad. A glazing pad multiplies every rate and every
  response alike (the rate factor of docs/polisher.md, eq. L4), so the shape and rho do not see it.
- (Z2) The next wafer's predicted final profile when the polish time removes the mean down to the
  target T (eq. C0): f(dP) = t_in - (mean(t_in) - T) s(dP); its non-uniformity
  NU(dP) = std_w(f) / mean_w(f) (mean_w(f) = T).
- (Z3) The step: the area-weighted least squares of Z2 linearised, s ~ h + rho' dP with
  rho' = rho - h (w . rho): min |e - (mean(t_in) - T) rho' dP|_w^2 + alpha |dP|^2, e = f(0) - T,
  alpha = ``regularisation`` x trace/zones (neighbouring zones' responses overlap: docs/model.md
  13f), within ``bounds``. With ``keep_load`` the step also keeps the load (sum_k A_k dP_k = 0, issue
  32's constraint); by default it does not: on the grooved 300mm preset the zones' common mode
  against the retaining ring is what shapes the 140-150 mm band, and the mean rate it moves is the
  polish time's to follow (Z6).
- (Z4) **Only a step predicted to lower the non-uniformity is taken**: NU(dP) of Z2 (the exact
  shape of Z1, not the linearisation) must be below NU(0) (the current pressures); otherwise the
  step is halved, up to ``halvings`` times, and refused if none lowers it: the pressures stay.
- (Z5) After the wafer, the shape learns the measured one (EWMA of weight lambda_z, the
  ``zone_weight``): h <- lambda_z u / mean_w(u) + (1 - lambda_z) s(dP), u the wafer's measured
  removal rate per ring (removed thickness over the polish time) and s(dP) the shape Z1
  predicted at the pressures the wafer ran at.
- (Z6) The pressures' factor on the mean rate, g(P) = m(P) / m_J (Z1): the rate estimator of
  :mod:`cmpsim.polisher.control` learns r_k / g(P_k) (the pad's rate at the starting pressures)
  and the next wafer's time uses its prediction times g(P_(k+1)).

Issue 32's feedback (until this module) removed the filtered shape of the last wafer's remaining
thickness with an integral step whatever it predicted; in a lot without conditioning it doubled
the non-uniformity (0.64 % -> 1.23 %, wafer mean, default grid): it chased each wafer's random
incoming tilt, which the next wafer does not have, and never asked whether a step helped. The
incoming profile is measured before the wafer (the feed-forward of C0 uses its mean), so Z2 takes
its shape too.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

__all__ = ["ZoneFeedback", "ZoneState", "ZonePlan", "area_weights", "predicted_final", "nonuniformity", "PSI", "BOUNDS"]

PSI = 6894.757293168361
#: Zone-pressure bounds, Pa (0.5-8 psi: issue 32's controller).
BOUNDS = (0.5 * PSI, 8.0 * PSI)


def area_weights(radius) -> np.ndarray:
    """Area weights of a profile's radii (trapezoidal rings r dr, summing to 1): the wafer-area mean."""
    r = np.asarray(radius, dtype=float)
    edges = np.concatenate(([r[0]], 0.5 * (r[1:] + r[:-1]), [r[-1]]))
    w = r * np.diff(edges) if r.size > 1 else np.ones(1)
    w = np.where(w > 0, w, 0.0) + (w.sum() == 0)
    return w / w.sum()


def nonuniformity(profile, weights) -> float:
    """std over mean of ``profile`` with the area ``weights`` (summing to 1), 1."""
    f = np.asarray(profile, dtype=float)
    mean = float(np.sum(weights * f))
    return float(np.sqrt(np.sum(weights * (f - mean) ** 2)) / mean) if mean != 0 else float("inf")


def predicted_final(incoming, target: float, shape, weights) -> np.ndarray:
    """Eq. Z2: the final profile (m) when the polish time takes the area mean of ``incoming`` (m) to ``target`` (m) with the rate ``shape``."""
    inc = np.asarray(incoming, dtype=float)
    return inc - (float(np.sum(weights * inc)) - target) * np.asarray(shape, dtype=float)


@dataclass(frozen=True)
class ZoneState:
    """What the feedback knows before a wafer: the zone ``pressures`` (Pa) and the rate ``shape`` at
    them (1 per ring, area mean 1)."""

    pressures: tuple
    shape: np.ndarray

    def to_dict(self) -> dict:
        return {"pressures": [float(p) for p in self.pressures], "shape": [float(x) for x in self.shape]}

    @classmethod
    def from_dict(cls, data: dict) -> "ZoneState":
        return cls(tuple(float(p) for p in data["pressures"]), np.asarray(data["shape"], dtype=float))


@dataclass(frozen=True)
class ZonePlan:
    """The zone step chosen for a wafer: the ``pressures`` (Pa) it runs at, the non-uniformity Z2
    predicts at the current pressures (``nu_before``) and at the chosen ones (``nu_after``, 1),
    and the ``decision``: "accepted", "halved N" (the step divided by 2^N) or "refused"."""

    pressures: tuple
    nu_before: float
    nu_after: float
    decision: str


@dataclass(frozen=True)
class ZoneFeedback:
    """The head's zone response and the feedback's settings (eqs. Z1-Z6).

    ``response`` J (rings x zones, m/s/Pa) at ``start_pressures`` P_0 (Pa), ``mean_rate`` m_J (m/s)
    of that solve, ``weights`` w (rings' area shares), ``zone_areas`` A_k (m^2), ``zone_weight``
    lambda_z in (0, 1], ``bounds`` (Pa), ``regularisation`` (relative Tikhonov weight), the
    number of ``halvings`` tried before a step is refused, and ``keep_load`` (sum_k A_k dP_k = 0)."""

    response: np.ndarray
    start_pressures: tuple
    mean_rate: float
    weights: np.ndarray
    zone_areas: np.ndarray
    zone_weight: float = 0.5
    bounds: tuple = BOUNDS
    regularisation: float = 1e-3
    halvings: int = 6
    keep_load: bool = False

    def __post_init__(self):
        if not 0 < self.zone_weight <= 1:
            raise ValueError(f"zone_weight (the EWMA weight of the profile) must be in (0, 1]; got {self.zone_weight!r}")
        lo, hi = self.bounds
        if not 0 <= lo < hi:
            raise ValueError(f"bounds must be 0 <= low < high (Pa); got {self.bounds!r}")
        if not self.mean_rate > 0:
            raise ValueError(f"mean_rate must be > 0 m/s; got {self.mean_rate!r}")

    def _rho(self, pressures) -> np.ndarray:
        return self.response / (self.mean_rate * self.pressure_factor(pressures))

    def pressure_factor(self, pressures) -> float:
        """Eq. Z6: g(P) = m(P)/m_J, the mean rate at ``pressures`` (Pa) over the response's, 1."""
        dp = np.asarray(pressures, dtype=float) - np.asarray(self.start_pressures, dtype=float)
        return 1.0 + float(self.weights @ self.response @ dp) / self.mean_rate

    def shape_after(self, state: ZoneState, step) -> np.ndarray:
        """Eq. Z1: the rate shape at ``state.pressures + step`` (Pa)."""
        change = self._rho(state.pressures) @ np.asarray(step, dtype=float)
        return (state.shape + change) / (1.0 + float(self.weights @ change))

    def predicted_nonuniformity(self, state: ZoneState, step, incoming, target: float) -> float:
        """Eq. Z2: the next wafer's predicted non-uniformity (1) after ``step`` (Pa) from ``state``."""
        return nonuniformity(predicted_final(incoming, target, self.shape_after(state, step), self.weights), self.weights)

    def plan(self, state: ZoneState, incoming, target: float) -> ZonePlan:
        """Eqs. Z3 and Z4: the pressures for a wafer of measured ``incoming`` profile (m per ring) polished to ``target`` (m)."""
        w = self.weights
        inc = np.asarray(incoming, dtype=float)
        depth = float(w @ inc) - target
        p = np.asarray(state.pressures, dtype=float)
        zero = np.zeros_like(p)
        before = self.predicted_nonuniformity(state, zero, inc, target)
        if depth <= 0:
            return ZonePlan(tuple(float(x) for x in p), before, before, "refused")
        rho = self._rho(p)
        shape_rho = rho - np.outer(state.shape, w @ rho)  # what each zone does to the shape
        error = predicted_final(inc, target, state.shape, w) - target
        sw = np.sqrt(w)[:, None]
        a = depth * shape_rho * sw
        b = error * sw[:, 0]
        gram = a.T @ a
        n = gram.shape[0]
        alpha = self.regularisation * np.trace(gram) / max(n, 1)
        if self.keep_load:
            c = np.asarray(self.zone_areas, dtype=float)
            kkt = np.block([[gram + alpha * np.eye(n), c[:, None]], [c[None, :], np.zeros((1, 1))]])
            step = np.linalg.solve(kkt, np.concatenate([a.T @ b, [0.0]]))[:n]
        else:
            step = np.linalg.solve(gram + alpha * np.eye(n), a.T @ b)
        lo, hi = self.bounds
        for k in range(self.halvings + 1):
            trial = np.clip(p + step / 2**k, lo, hi) - p
            after = self.predicted_nonuniformity(state, trial, inc, target)
            if after < before:
                return ZonePlan(tuple(float(x) for x in p + trial), before, after, "accepted" if k == 0 else f"halved {k}")
        return ZonePlan(tuple(float(x) for x in p), before, before, "refused")

    def learn(self, state: ZoneState, pressures, measured_rate) -> ZoneState:
        """Eq. Z5: the state after a wafer run at ``pressures`` (Pa) whose measured removal rate per ring was ``measured_rate`` (m/s)."""
        u = np.asarray(measured_rate, dtype=float)
        predicted = self.shape_after(state, np.asarray(pressures, dtype=float) - np.asarray(state.pressures, dtype=float))
        mean = float(self.weights @ u)
        shape = predicted if not mean > 0 else self.zone_weight * u / mean + (1.0 - self.zone_weight) * predicted
        return ZoneState(tuple(float(x) for x in pressures), shape)
