"""Run-to-run control of a lot: the estimators of the removal rate, picked by name (issues 32, 38).

The lot sets each wafer's polish time from the thickness measured before the wafer and the rate
an estimator predicts for it (feed-forward, eq. C0); after the wafer the estimator learns the
rate the wafer had (``removed / time``). The estimators are a small family behind one protocol,
:class:`RateEstimator` (``predict(age)``, ``update(rate, age)``, ``to_dict()``), picked by name in one
place, :data:`ESTIMATORS` / :func:`make_estimator`:

``"single_ewma"`` (:class:`SingleEWMA`): the EWMA controller of Sachs, Hu and Ingolfsson (IEEE
Trans. Semicond. Manuf. 8 (1995) 26) as used for CMP by Boning et al. (MRS 1999), here on the
process gain (the rate), the lot's controller of issue 32::

    a_k = lambda_1 r_k + (1 - lambda_1) a_(k-1),       predicted rate  a_k            (C1)

A single EWMA lags a drifting process: for r_k = r_0 + delta k its prediction settles at
r_(k+1) - delta / lambda_1 (the pad glazes and the estimate chases it; Chen & Guo 2001).

``"ewma"`` (:class:`DoubleEWMA`, the default of ``cmpsim lot --control ewma``): the double EWMA, a
level a and a drift D per unit of pad age A (the predictor-corrector controller, PCC, of Butler &
Stefani, IEEE Trans. Semicond. Manuf. 7 (1994) 193, estimates the same two; Chen & Guo, IEEE Trans.
Semicond. Manuf. 14 (2001) 19, take the drift per unit of pad age for CMP). The level is carried
forward by the drift (Holt's form), which makes it exact at any age spacing::

    a_k = lambda_1 r_k + (1 - lambda_1) (a_(k-1) + D_(k-1) dA_k)                       (C2)
    D_k = lambda_2 (a_k - a_(k-1)) / dA_k + (1 - lambda_2) D_(k-1)      (dA_k != 0)   (C3)
    predicted rate of a wafer of age A:  a_k + D_k (A - A_k)                            (C4)

On a drift linear in the age, r = r_0 + delta A, a_k = r_k and D_k = delta is a fixed point of
C2-C3 whatever the spacing dA_k, so the prediction has no steady-state offset
(tests/test_lot_control.py checks it on a synthetic process, with unit and random age steps).
The age is the wafer's on a ``clock`` (:data:`CLOCKS`): "glazing", the pad-life model's rate
factor averaged over the wafer (docs/polisher.md, eq. L4), or "wafer", its index (the PCC's per
run). The first drift (C5, ``drift_prior``): "model", on the glazing clock, D_0 = a_0 / A_0 (the
rate proportional to the glazing factor, what the pad-life model says), or "none", D_0 = 0.

Weights: lambda_1 = 0.3, the lot's single-EWMA weight since issue 32 (the common textbook value,
chosen before any lot ran); lambda_2 = 0.3, the same constant for the drift as for the level, as
Brown's one-constant double exponential smoothing does. The values Butler & Stefani and Chen &
Guo used were not read here (only the papers' abstracts and the equations' later statements);
both weights are options (``cmpsim lot --weight, --drift-weight``).

Feed-forward (Boning et al. 1999): the next wafer's time removes the measured incoming mean down to
the target at the predicted rate,

    t_(k+1) = (incoming_mean_(k+1) - target) / predicted rate.                            (C0)

Pure logic on numbers: the solves are the caller's (:mod:`cmpsim.polisher.lot`); the zone feedback
is :mod:`cmpsim.polisher.zones`.
"""

from __future__ import annotations

import math
from dataclasses import asdict, dataclass, replace
from typing import Protocol, runtime_checkable

__all__ = ["RateEstimator", "SingleEWMA", "DoubleEWMA", "ESTIMATORS", "CONTROL", "make_estimator", "estimator_from_dict",
           "feed_forward_time", "WEIGHT", "DRIFT_WEIGHT", "CLOCKS", "DRIFT_PRIORS"]

#: lambda_1 of eqs. C1/C2: the lot's EWMA weight since issue 32 (Sachs et al. 1995; Boning et al. 1999; chosen before any lot ran).
WEIGHT = 0.3
#: lambda_2 of eq. C3: the level's constant (one constant for level and drift, as Brown's double smoothing).
DRIFT_WEIGHT = 0.3
#: The pad-age clocks of the double EWMA: "glazing" (the pad-life model's rate factor over the wafer, eq. L4) or "wafer" (its index).
CLOCKS = ("glazing", "wafer")
#: The first drift of the double EWMA (eq. C5): "model" (the rate proportional to the pad-life model's glazing factor) or "none" (0).
DRIFT_PRIORS = ("model", "none")
#: Two ages closer than this (relative) are one: the drift is not updated across them.
AGE_RESOLUTION = 1e-9


def _check_weight(name: str, value: float) -> None:
    if not (isinstance(value, (int, float)) and math.isfinite(value) and 0.0 < value <= 1.0):
        raise ValueError(f"{name} (an EWMA weight) must be in (0, 1]; got {value!r}")


def _check_rate(rate: float, what: str) -> None:
    if not (isinstance(rate, (int, float)) and math.isfinite(rate) and rate > 0.0):
        raise ValueError(f"{what} must be a removal rate > 0 m/s; got {rate!r}")


@runtime_checkable
class RateEstimator(Protocol):
    """What the lot asks of a rate estimator: the rate it predicts for the next wafer (m/s), a new
    estimator after a wafer whose measured mean rate was ``rate`` (m/s), and its state as a dict of
    floats (the checkpoint of an interrupted lot, :mod:`cmpsim.polisher.checkpoint`)."""

    name: str
    clock: str

    def predict(self, age: float) -> float: ...

    def update(self, rate: float, age: float) -> "RateEstimator": ...

    def to_dict(self) -> dict: ...


@dataclass(frozen=True)
class SingleEWMA:
    """The single EWMA of the rate (eq. C1): ``level`` a (m/s), ``weight`` lambda_1."""

    level: float
    weight: float = WEIGHT
    name: str = "single_ewma"

    def __post_init__(self):
        _check_weight("weight", self.weight)
        _check_rate(self.level, "the first rate estimate")

    clock: str = "wafer"

    def predict(self, age: float = 0.0) -> float:
        """The next wafer's rate, m/s: the level (eq. C1), whatever its age."""
        return self.level

    def update(self, rate: float, age: float = 0.0) -> "SingleEWMA":
        """Eq. C1 after a wafer of measured mean rate ``rate`` (m/s); the age is not used."""
        return replace(self, level=self.weight * rate + (1.0 - self.weight) * self.level)

    def to_dict(self) -> dict:
        return asdict(self)


@dataclass(frozen=True)
class DoubleEWMA:
    """The double EWMA (predictor-corrector) of the rate on a pad-age clock (eqs. C2-C4): ``level`` a
    (m/s) at the age ``age`` of the last wafer, ``drift`` D (m/s per unit of age), weights ``weight``
    lambda_1 and ``drift_weight`` lambda_2, and the ``clock`` that gives a wafer its age
    (:data:`CLOCKS`: "glazing", the pad-life model's rate factor over the wafer; "wafer", its index)."""

    level: float
    drift: float = 0.0
    weight: float = WEIGHT
    drift_weight: float = DRIFT_WEIGHT
    clock: str = "glazing"
    age: float = 0.0
    name: str = "ewma"

    def __post_init__(self):
        _check_weight("weight", self.weight)
        _check_weight("drift_weight", self.drift_weight)
        if not math.isfinite(self.level):
            raise ValueError(f"level must be a finite rate (m/s); got {self.level!r}")
        if self.clock not in CLOCKS:
            raise ValueError(f"clock must be one of {CLOCKS}; got {self.clock!r}")
        for name in ("drift", "age"):
            if not math.isfinite(getattr(self, name)):
                raise ValueError(f"{name} must be finite; got {getattr(self, name)!r}")

    def predict(self, age: float) -> float:
        """The rate (m/s) of a wafer of pad ``age`` (eq. C4): the level carried forward by the drift."""
        return self.level + self.drift * (age - self.age)

    def update(self, rate: float, age: float) -> "DoubleEWMA":
        """Eqs. C2 and C3 after a wafer of measured mean rate ``rate`` (m/s) and pad ``age``; a wafer
        of the same age as the last (a pad in its in-situ balance) updates the level only."""
        step = age - self.age
        level = self.weight * rate + (1.0 - self.weight) * (self.level + self.drift * step)
        drift = self.drift
        if abs(step) > AGE_RESOLUTION * max(abs(age), 1.0):
            drift = self.drift_weight * (level - self.level) / step + (1.0 - self.drift_weight) * self.drift
        return replace(self, level=level, drift=drift, age=float(age))

    def to_dict(self) -> dict:
        return asdict(self)


#: The run-to-run estimators by name (``cmpsim lot --control``); "none" runs the recipe as written.
ESTIMATORS = {"ewma": DoubleEWMA, "single_ewma": SingleEWMA}
#: The names ``--control`` takes.
CONTROL = ("none", *ESTIMATORS)


def make_estimator(name: str, rate: float, weight: float = WEIGHT, drift_weight: float = DRIFT_WEIGHT, clock: str = "glazing",
                   age: float = 0.0, drift_prior: str = "model") -> RateEstimator:
    """The estimator called ``name`` (:data:`ESTIMATORS`), seeded with the first ``rate`` (m/s) at pad
    ``age`` on its ``clock`` (the double EWMA's) and the first drift of ``drift_prior`` (eq. C5:
    "model", on the glazing clock, the rate proportional to the glazing factor, D_0 = a_0 / age; "none",
    D_0 = 0; on the wafer clock the drift starts at 0 either way)."""
    if name not in ESTIMATORS:
        raise ValueError(f"control must be one of {CONTROL}; got {name!r}")
    _check_weight("drift_weight", drift_weight)
    if clock not in CLOCKS:
        raise ValueError(f"clock must be one of {CLOCKS}; got {clock!r}")
    if drift_prior not in DRIFT_PRIORS:
        raise ValueError(f"drift_prior must be one of {DRIFT_PRIORS}; got {drift_prior!r}")
    _check_rate(rate, "the first rate estimate")
    if ESTIMATORS[name] is DoubleEWMA:
        drift = float(rate) / float(age) if (drift_prior == "model" and clock == "glazing" and age > 0) else 0.0
        return DoubleEWMA(level=float(rate), drift=drift, weight=weight, drift_weight=drift_weight, clock=clock, age=float(age))
    return SingleEWMA(level=float(rate), weight=weight)


def estimator_from_dict(data: dict) -> RateEstimator:
    """An estimator from its :meth:`to_dict` (a checkpoint)."""
    data = dict(data)
    name = data.get("name")
    if name not in ESTIMATORS:
        raise ValueError(f"the checkpoint's estimator {name!r} is not one of {tuple(ESTIMATORS)}")
    return ESTIMATORS[name](**data)


def feed_forward_time(rate: float, incoming_mean: float, target: float) -> float:
    """Polish time (s) that removes ``incoming_mean - target`` (m) at ``rate`` (m/s; eq. C0); 0 if already below the target."""
    _check_rate(rate, "the predicted removal rate")
    return max(incoming_mean - target, 0.0) / rate
