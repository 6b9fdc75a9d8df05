"""Run-to-run control of a lot: the EWMA controller of the fab (issue 32).

The exponentially weighted moving average (EWMA) controller of Sachs, Hu and Ingolfsson (IEEE
Trans. Semicond. Manuf. 8 (1995) 26), as used for CMP by Boning et al. (MRS 1999: thickness held
to +-10 nm of target with two products alternating): the controller keeps an estimate of the
process and updates it after each wafer with weight ``weight`` (lambda),

    rate_{k+1} = lambda * removed_k / time_k + (1 - lambda) * rate_k,                 (mean rate)

and sets the next wafer's polish time from the thickness measured before it (feed-forward):

    time_{k+1} = (incoming_mean_{k+1} - target) / rate_{k+1}.

The zone pressures follow the last wafer's post-polish profile (feedback): the shape of its
remaining thickness about its mean, e(r), filtered with the same kind of average,
e_f <- lambda_z e + (1 - lambda_z) e_f, is removed on the next wafer by the pressure change that
the zone response R = d rate(r) / d P_k (m/s/Pa, :func:`cmpsim.head.zone_response.response_matrix`)
says removes it in the polish time: R' t dP = e_f in the area-weighted least-squares sense (R'
the response about its wafer-area mean: the mean is the polish time's to set), with
a small Tikhonov term because neighbouring zones' responses overlap (the problem is ill
conditioned: docs/model.md 13f), keeping the load (sum_k A_k dP_k = 0: a uniform change of the
zones moves the mean rate, which is the polish time's to set, and barely the shape), and within
the zone-pressure bounds.

A single EWMA lags a drifting process (pad wear: Chen & Guo, IEEE TSM 14 (2001) 19 propose an
age-based double EWMA); the lag is visible in the lot's first wafers and is reported, not hidden.
Pure logic on numbers: the solves are the caller's (:mod:`cmpsim.polisher.lot`).
"""

from __future__ import annotations

from dataclasses import dataclass, replace

import numpy as np

__all__ = ["EWMAController", "ControllerState", "feed_forward_time", "update_rate", "zone_correction", "area_weights"]


@dataclass(frozen=True)
class EWMAController:
    """The controller's settings: ``target`` remaining thickness (m), EWMA weights of the rate and
    of the profile (0 < lambda <= 1), the zone-pressure bounds (Pa) and the relative Tikhonov weight."""

    target: float
    weight: float = 0.3
    zone_weight: float = 0.5
    bounds: tuple[float, float] = (0.5 * 6894.757293168361, 8.0 * 6894.757293168361)
    regularisation: float = 1e-3

    def __post_init__(self):
        if not (np.isfinite(self.target) and self.target >= 0):
            raise ValueError(f"target must be a remaining thickness >= 0 m; got {self.target!r}")
        for name in ("weight", "zone_weight"):
            value = getattr(self, name)
            if not 0 < value <= 1:
                raise ValueError(f"{name} (the EWMA weight) must be in (0, 1]; got {value!r}")
        lo, hi = self.bounds
        if not 0 <= lo < hi:
            raise ValueError(f"bounds must be 0 <= low < high (Pa); got {self.bounds!r}")


@dataclass(frozen=True)
class ControllerState:
    """What the controller knows before a wafer: the estimated mean removal rate (m/s), the zone
    pressures (Pa) and the filtered profile error (m, one value per radius; None before feedback)."""

    rate: float
    zone_pressures: tuple
    profile_error: np.ndarray | None = None


def feed_forward_time(state: ControllerState, incoming_mean: float, target: float) -> float:
    """Polish time (s) that removes incoming_mean - target (m) at the estimated rate (m/s)."""
    if not state.rate > 0:
        raise ValueError(f"the estimated removal rate must be > 0 m/s; got {state.rate!r}")
    return max(incoming_mean - target, 0.0) / state.rate


def update_rate(state: ControllerState, removed_mean: float, time: float, weight: float) -> ControllerState:
    """The EWMA update of the mean-rate estimate after a wafer that lost ``removed_mean`` (m) in ``time`` (s)."""
    if not time > 0:
        return state
    return replace(state, rate=weight * removed_mean / time + (1.0 - weight) * state.rate)


def area_weights(radius) -> np.ndarray:
    """Area weights of the profile's radii (trapezoidal rings r dr, summing to 1): the wafer-area mean."""
    r = np.asarray(radius, dtype=float)
    edges = np.concatenate(([r[0]], 0.5 * (r[1:] + r[:-1]), [r[-1]]))
    w = r * np.diff(edges) if r.size > 1 else np.ones(1)
    w = np.where(w > 0, w, 0.0) + (w.sum() == 0)
    return w / w.sum()


def zone_correction(
    controller: EWMAController,
    state: ControllerState,
    weights,
    final_thickness,
    response,
    polish_time: float,
    zone_areas=None,
) -> ControllerState:
    """The zone pressures for the next wafer from the last wafer's remaining thickness (m at each radius).

    ``weights`` are the radii's shares of the wafer area (e.g. the film stack's ring areas, or
    :func:`area_weights` of the radii); they need not sum to 1.

    ``response`` is d rate(r) / d P_k (m/s/Pa, radii x zones) at the current pressures; the shape
    of the remaining thickness about its area mean is filtered (EWMA) and removed in
    ``polish_time`` (s) by the bounded, regularised least-squares pressure change that keeps the
    load (``zone_areas``, m^2, the weights of the zones' pressures in the load; equal by default).
    """
    final = np.asarray(final_thickness, dtype=float)
    w = np.asarray(weights, dtype=float) / float(np.sum(weights))
    error = final - np.sum(w * final)
    filtered = error if state.profile_error is None else controller.zone_weight * error + (1.0 - controller.zone_weight) * state.profile_error
    shape = np.asarray(response, dtype=float)
    shape = shape - w @ shape  # what each zone does to the profile's shape (its mean is the time's job)
    a = shape * polish_time * np.sqrt(w)[:, None]
    b = filtered * np.sqrt(w)
    gram = a.T @ a
    n = gram.shape[0]
    alpha = controller.regularisation * np.trace(gram) / max(n, 1)
    # the load is kept: sum_k A_k dP_k = 0 (the zones' areas), so that the shape correction does not
    # drift along the common mode the shape barely sees (the mean rate is the polish time's)
    c = np.ones(n) if zone_areas is None else np.asarray(zone_areas, dtype=float)
    kkt = np.block([[gram + alpha * np.eye(n), c[:, None]], [c[None, :], np.zeros((1, 1))]])
    step = np.linalg.solve(kkt, np.concatenate([a.T @ b, [0.0]]))[:n]
    lo, hi = controller.bounds
    pressures = tuple(float(p) for p in np.clip(np.asarray(state.zone_pressures, dtype=float) + step, lo, hi))
    return replace(state, zone_pressures=pressures, profile_error=filtered)
