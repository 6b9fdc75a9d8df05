"""The pad's life inside a recipe: glazing and conditioning as they enter each step (issue 32).

:mod:`cmpsim.physics.padlife` holds the kernels (the worn volume W of the summit caps, eq. L2; the
worn pad's summit constants, L3; the glazed-area rate factor, L4). This module joins them to a
recipe's steps (``docs/polisher.md``, "Pad life in a recipe"):

- **Within a step** the pad wears (and, ``in_situ``, is renewed by the disk) at every time step of
  the recipe engine, at the step's applied pressure and the pad's speed under the wafer centre
  (Omega_p d); the removal rate of a time step is scaled by the rate factor at mid-step. The glazing
  of a wafer is thereby resolved in time: with in-situ conditioning the worn volume relaxes to its
  balance W* = k_w P U / r_c with the time constant 1/r_c (20 s at the calibrated disk), well inside
  a wafer, so a wafer's rate is not the rate of the pad it started on.
- **At a step's start**, with ``worn_summits = True`` (not the default), the worn pad's
  summit-height std enters the step's wafer solve: the contact model's ``pad_roughness`` becomes
  sigma_s (worn) and the summits keep their radius and density (wear flattens summits, it does not
  remove them: eq. L3), i.e. ``roughness_scaling = "fixed_summits"`` with the fresh pad's effective
  radius and density. The worn height density (a normal density below the front plus the atom of
  flattened summits) is then represented in the Greenwood-Williamson integrals and the flow
  factors by a Gaussian of the worn std: a poor representation of flat plateaus, and one the
  solver cannot balance below about 2 um on the 300mm preset (docs/polisher.md, "Pad life in a
  recipe", for the measured effect and why it is not the default).
"""

from __future__ import annotations

from dataclasses import dataclass, field, replace

import numpy as np

from ..inputs.config import Config
from ..solver.setup import summit_geometry
from ..physics.padlife import (
    CONDITIONING,
    DEFAULT_DISK,
    DEFAULT_PAD,
    ConditionerDisk,
    FreshPad,
    PadLifeState,
    SummitConstants,
    advance_pad_life,
    condition_ex_situ,
    summit_constants,
)

__all__ = ["PadLife", "StepWear", "fresh_pad", "worn_overrides", "sliding_speed", "wear_through", "wear_samples"]


def fresh_pad(config: Config) -> FreshPad:
    """The fresh pad of ``config``: its summit std (m), radius (m) and density (1/m^2) as the solver
    sets them up (:func:`cmpsim.solver.setup.summit_geometry`), its ``contact_cutoff``, and the
    calibrated wear coefficient k_w of :data:`cmpsim.physics.padlife.DEFAULT_PAD` (Jeong et al. 2024)."""
    sigma, radius, density = summit_geometry(config)
    return replace(DEFAULT_PAD, sigma=float(sigma), density=float(density), radius=float(radius), cutoff=float(config.contact_cutoff))


def sliding_speed(config: Config) -> float:
    """The pad's speed under the wafer centre, Omega_p d (m/s): the sliding speed of the pad's wear."""
    return float(config.rotation_speed * config.centre_distance)


def worn_overrides(config: Config, state: PadLifeState, pad: FreshPad | None = None) -> dict:
    """The inputs that put the worn pad of ``state`` into ``config``'s wafer solve (eq. L3): the worn
    summit std as ``pad_roughness`` (m), the fresh pad's summit radius and density kept
    (``roughness_scaling = "fixed_summits"``). Empty for a fresh pad (W = 0): the config is unchanged."""
    if float(np.max(np.asarray(state.worn_volume, dtype=float))) == 0.0:
        return {}
    p = pad if pad is not None else fresh_pad(config)
    ratio = float(np.asarray(summit_constants(state, p).sigma))
    return {
        "pad_roughness": p.sigma * ratio,
        "asperity_radius": p.radius,
        "asperity_density": p.density,
        "roughness_scaling": "fixed_summits",
    }


@dataclass(frozen=True)
class PadLife:
    """How the pad's life runs through a recipe: ``conditioning`` "none" | "ex_situ" | "in_situ"
    (the disk during polishing only in situ; between wafers a lot conditions ex situ), the
    conditioning ``disk`` and the ``pad`` (None: the calibrated disk, and the fresh pad of each
    step's config, :func:`fresh_pad`); ``worn_summits``: the worn summit std enters each step's
    wafer solve (:func:`worn_overrides`; off by default)."""

    conditioning: str = "in_situ"
    disk: ConditionerDisk | None = None
    pad: FreshPad | None = None
    worn_summits: bool = False
    #: the glazing and conditioning constants of a calibrated process file ({name: SI} of
    #: :data:`cmpsim.physics.padlife.GLAZING_CONSTANTS`; None or missing names: the calibrated defaults)
    constants: dict | None = field(default=None, compare=False)

    def __post_init__(self) -> None:
        if self.conditioning not in CONDITIONING:
            raise ValueError(f"conditioning must be one of {CONDITIONING}; got {self.conditioning!r}")
        from ..physics.padlife import check_constants

        check_constants(self.constants or {})

    def _disk(self) -> ConditionerDisk:
        d = self.disk if self.disk is not None else DEFAULT_DISK
        k = (self.constants or {}).get("conditioner_rate_constant")
        return d if k is None else replace(d, rate_constant=float(k))

    def _pad(self, config: Config) -> FreshPad:
        p = self.pad if self.pad is not None else fresh_pad(config)
        c = self.constants or {}
        if "pad_wear_coefficient" in c:
            p = replace(p, wear_coefficient=float(c["pad_wear_coefficient"]))
        if "critical_glazed_area" in c:
            p = replace(p, critical_glazed_area=float(c["critical_glazed_area"]))
        return p

    def idle(self, state: PadLifeState, seconds: float) -> PadLifeState:
        """The pad after ``seconds`` between wafers: conditioned by the disk ex situ (eq. L2 with P = 0),
        unchanged otherwise (in situ the disk works only while polishing)."""
        if self.conditioning != "ex_situ":
            return state
        return condition_ex_situ(state, seconds, self._disk())

    def at(self, config: Config) -> "StepWear":
        """The pad's wear in a step of ``config``: its applied pressure, the sliding speed, the disk and
        the fresh pad (the given one, or the step's config's), resolved once for the step's time steps."""
        return StepWear(float(config.applied_pressure), sliding_speed(config), self.conditioning, self._disk(), self._pad(config))


@dataclass(frozen=True)
class StepWear:
    """The pad's wear in one step (:meth:`PadLife.at`): nominal ``pressure`` P (Pa), ``sliding_speed``
    U (m/s), the ``conditioning`` mode, the ``disk`` and the fresh ``pad``."""

    pressure: float
    sliding_speed: float
    conditioning: str
    disk: ConditionerDisk
    pad: FreshPad

    def advance(self, state: PadLifeState, dt: float) -> PadLifeState:
        """The pad after ``dt`` s of polishing in the step (eq. L2, exact)."""
        return advance_pad_life(state, self.pressure, self.sliding_speed, dt, self.conditioning, self.disk, self.pad)

    def summits(self, state: PadLifeState) -> SummitConstants:
        """The worn pad's summit constants relative to the fresh pad's and its rate factor (eqs. L3, L4)."""
        return summit_constants(state, self.pad)

    def factor(self, state: PadLifeState) -> float:
        """The glazed pad's rate factor RR/RR_fresh (eq. L4), dimensionless."""
        return float(np.asarray(self.summits(state).rate_factor))


def mean_factor(pad_life: PadLife, steps, life: PadLifeState, time_step: float) -> float:
    """The glazed pad's rate factor (eq. L4) averaged over a wafer's polish time, 1: the trapezoid over
    the factors at the time steps' ends, as the recipe engine records them (``StepResult.glazing``),
    for ``steps`` [(config, duration s), ...] polished from the pad-life state ``life`` (the lot's
    controller asks it of a wafer before polishing it: its pad-age clock, docs/polisher.md)."""
    return wear_through(pad_life, steps, life, time_step)[0]


def wear_through(pad_life: PadLife, steps, life: PadLifeState, time_step: float) -> tuple[float, PadLifeState]:
    """(:func:`mean_factor` of ``steps`` [(config, duration s), ...], the pad-life state after them): a
    wafer's steps as the recipe engine runs them (time steps of ``time_step`` s, the last one shorter),
    from ``life``. The lot's controller follows its own model of the pad with it (docs/polisher.md, C5)."""
    times, factors = [], []
    for clock, wear, life in wear_samples(pad_life, steps, life, time_step):
        times.append(clock)
        factors.append(wear.factor(life))
    return time_mean(times, factors), life


def wear_samples(pad_life: PadLife, steps, life: PadLifeState, time_step: float):
    """The pad-life states a wafer's ``steps`` [(config, duration s), ...] pass through, as the recipe
    engine samples them: (time from the wafer's start s, the step's :class:`StepWear`, the state) at
    each step's start and at the end of each of its time steps (``time_step`` s, the last one shorter).
    The last state yielded is the pad after the wafer (``life`` itself for a wafer of no steps)."""
    clock = 0.0
    for config, duration in steps:
        wear = pad_life.at(config)
        yield clock, wear, life
        elapsed = 0.0
        while elapsed < duration * (1 - 1e-12):
            dt = min(time_step, duration - elapsed)
            life = wear.advance(life, dt)
            elapsed += dt
            clock += dt
            yield clock, wear, life


def time_mean(times, values) -> float:
    """The trapezoid mean of ``values`` over ``times`` (s), as the lot records a wafer's rate factor; the
    first value for a wafer of no time."""
    t, f = np.asarray(times, dtype=float), np.asarray(values, dtype=float)
    span = t[-1] - t[0]
    return float(np.trapezoid(f, t) / span) if span > 0 else float(f[0])


class GlazingClock:
    """:func:`mean_factor` of a one-step wafer as a function of its polish time t (s), for a lot's
    controller that looks for the t whose pad age it predicts the rate of: the pad-life states at the
    whole time steps are computed once, lazily, so that each t costs one partial step."""

    def __init__(self, pad_life: PadLife, config: Config, life: PadLifeState, time_step: float):
        self.wear, self.time_step = pad_life.at(config), float(time_step)
        self.states = [life]
        self.factors = [self.wear.factor(life)]
        self.integral = [0.0]  # trapezoid of the factor from 0 to k time steps, s

    def __call__(self, t: float) -> float:
        """The time-mean rate factor (1) over a wafer of ``t`` s (the engine's time steps: whole ones, then the rest)."""
        if not t > 0:
            return self.factors[0]
        whole = int(t / self.time_step * (1 + 1e-12))
        while len(self.states) <= whole:
            state = self.wear.advance(self.states[-1], self.time_step)
            factor = self.wear.factor(state)
            self.integral.append(self.integral[-1] + 0.5 * self.time_step * (self.factors[-1] + factor))
            self.states.append(state)
            self.factors.append(factor)
        rest = t - whole * self.time_step
        total = self.integral[whole]
        if rest > 1e-12 * t:
            end = self.wear.factor(self.wear.advance(self.states[whole], rest))
            total += 0.5 * rest * (self.factors[whole] + end)
        return total / t
