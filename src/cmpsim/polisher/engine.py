"""Time integration of a recipe: the film stack per radius and the pad's temperature through the steps (issue 32).

For each step (``docs/polisher.md``, "Recipes"):

1. **The wafer equilibrium** of the step's inputs (:func:`cmpsim.solve`; a cache solves each distinct
   configuration once). In cmpsim the film being polished enters only the removal law, not the
   equilibrium (pressure, contact, shear), so **one solve per step gives every film's rate**: the
   removal law is evaluated again on the solved fields with ``film`` set to each material of the
   stack (:func:`cmpsim.solver.postprocess.removal_law_fields`) and rotation-averaged per ring. A
   ring polishes the material on top there; a film that clears within a time step hands the rest
   of the step to the film below (:func:`cmpsim.polisher.stack.remove`).
2. **The pad's temperature**: the frictional power per unit wafer area q = <tau . (u_pad - u_wafer)>
   (the wafer mean of the solved shear field) heats the pad column of :func:`cmpsim.physics.thermal.polisher_column`
   (IC1000 stack on a platen held at the slurry temperature, the area-mean duty R/(4d) of the wafer
   track, slurry cooling of 150 mL/min). q does not depend on the temperature in this model, so
   the column is advanced exactly over each time step; the rate of the step is taken at the pad's
   temperature at mid-step (second order in the time step).
3. **The chemical step**: the pad's surface temperature is the input ``pad_temperature`` of the
   removal law, the base of the flash temperature of the two-step kinetics
   (``removal_kinetics = "two_step"``: RR_c = c_0 exp(-(E_a/R)(1/T - 1/T_0)), T = T_pad + beta mu p_c |du|,
   T_0 = ``slurry_temperature``). With the default ``removal_kinetics = "mechanical"`` the rate has no
   chemical step and does not depend on the temperature: the pad still warms (it is reported), but
   the removal does not follow it.
4. **The end point** (``until = "endpoint"``): after every time step (the tool's sampling, ``time_step``)
   the reflectance signal (:mod:`cmpsim.polisher.endpoint`) is compared with the level of the top
   film cleared; the step ends at the first sample within tolerance, at ``max_time`` at the latest.

5. **The pad's life** (``pad_life=``, :class:`cmpsim.polisher.pad.PadLife`): the summit caps wear
   (and in situ are renewed by the disk) at every time step; the rate of a time step is scaled by
   the glazed pad's rate factor at mid-step; with ``PadLife(worn_summits=True)`` the worn summit std
   enters each step's solve (:mod:`cmpsim.polisher.pad`). Without ``pad_life`` the pad does not wear.

A lot runs :func:`polish` wafer after wafer with :class:`PadState` carried in and out (``pad_state=``,
``PolishResult.pad_state``; :func:`idle` cools the pad between wafers); ``rate_factor`` scales every
removal rate besides (1 by default).
"""

from __future__ import annotations

import functools

import math
import time as _time
from dataclasses import dataclass, field

import numpy as np

from .. import models
from ..inputs.config import Config
from ..physics.thermal import PadThermalState, ThermalColumn, polisher_column
from ..results.uniformity import ring_mean
from ..solver.model import solve
from ..solver.postprocess import removal_law_fields, stress_fields
from ..physics.padlife import PadLifeState
from .endpoint import EndpointDetector, EndpointTrace, cleared_level, platen_torque, reflectance_signal
from .pad import PadLife, StepWear, worn_overrides
from .recipe import Recipe, RecipeError, Step, load_recipe
from .stack import FilmStack, remove

__all__ = ["PadState", "StepSolve", "StepResult", "PolishResult", "polish", "idle", "TIME_STEP", "SLURRY_FLOW_RATE", "PLATEN"]

#: Default time step, s: the end point's sampling (about one platen turn at 60-90 rpm is 0.7-1 s).
TIME_STEP = 1.0
#: Slurry flow of the pad's heat balance, m^3/s (150 mL/min, US 9,499,721 B2; thermal.polisher_column).
SLURRY_FLOW_RATE = 2.5e-6
#: The platen of the pad's heat balance: "sink" (held at the slurry temperature) or "adiabatic" (docs/polisher.md).
PLATEN = "sink"


@dataclass(frozen=True)
class PadState:
    """The pad carried from step to step and wafer to wafer: ``thermal`` (the temperatures of the pad
    column, :class:`cmpsim.physics.thermal.PadThermalState`, K; None = at the slurry temperature),
    ``life`` (a pad-life state, :class:`cmpsim.physics.padlife.PadLifeState`; advanced by
    :func:`polish` with ``pad_life``, carried unchanged without it) and ``time`` (s the pad has polished or idled since it was new)."""

    thermal: PadThermalState | None = None
    life: object = None
    time: float = 0.0

    @property
    def surface_temperature(self) -> float | None:
        """The pad's surface temperature, K (None before any step)."""
        return None if self.thermal is None else float(self.thermal.surface)


class StepSolve:
    """One wafer equilibrium and what the recipe needs of it: every film's rate profile (m/s) at a
    pad temperature, the frictional power (W/m^2, wafer mean) and the platen torque (N m)."""

    def __init__(self, config: Config):
        self.config = config
        self.result = solve(config)
        r = self.result
        problem, state = r.problem, r.solution.state
        kin = problem.lub.kinematics
        stresses = stress_fields(config, problem, state, kin, problem.lub)
        fields = removal_law_fields(stresses, state, problem)
        self._fields = {}
        self._lazy = fields
        grid = problem.grid
        area = grid.area
        tx, ty = stresses["shear_stress"]
        dux, duy = stresses["relative_velocity"]
        self.frictional_power = float(np.sum((tx * dux + ty * duy) * area) / np.sum(area))
        upx, upy, _, _ = kin.velocities(problem.xc, problem.yc)
        self.torque = platen_torque((tx, ty), (upx, upy), area, kin.pad_speed)
        self.radius = np.asarray(r.profiles["radius"], dtype=float)
        self.ring_faces = np.asarray(grid.ring_faces, dtype=float)
        self.pad_speed = kin.pad_speed
        self._laws = {}
        self._fixed = {}

    def _field(self, name):
        if name not in self._fields:
            self._fields[name] = self._lazy[name]()
        return self._fields[name]

    def _law(self, material: str, temperature: float | None):
        key = (material, temperature)
        if key not in self._laws:
            cfg = self.config.replace(film=material) if temperature is None else self.config.replace(film=material, pad_temperature=temperature)
            self._laws = {k: v for k, v in self._laws.items() if k[1] is None}  # keep the temperature-free ones only
            self._laws[key] = models.removal_law(cfg)
        return self._laws[key]

    def depends_on_temperature(self, material: str) -> bool:
        """Whether the rate of ``material`` follows the pad's temperature (a chemical step in series)."""
        return getattr(self._law(material, None), "kinetics", None) is not None

    def rate_profile(self, material: str, temperature: float) -> np.ndarray:
        """The rotation-averaged removal rate of ``material`` on each ring, m/s, on a pad at ``temperature`` K."""
        if not self.depends_on_temperature(material):
            if material not in self._fixed:
                law = self._law(material, None)
                self._fixed[material] = ring_mean(law.rate(**{n: self._field(n) for n in law.needs}))
            return self._fixed[material]
        law = self._law(material, float(temperature))
        return ring_mean(law.rate(**{n: self._field(n) for n in law.needs}))


@dataclass
class StepResult:
    """One step of a polished recipe (SI). The JSON keys of :meth:`to_dict` are a contract (issue 32):
    ``name``, ``duration`` (s), ``end`` ("time" or "endpoint"), ``removal_rate_mean`` (m/s, the removed
    volume over the wafer area and the duration), ``pad_temperature`` {``time`` (s from the recipe's
    start), ``value`` (K)}, ``thickness`` {``radius`` (m), film name: (m) after the step}; besides them
    the end-point ``signals`` trace, the ``endpoint`` outcome, the ``top_film`` and its ``cleared_fraction``
    (of the wafer area) after the step, ``frictional_power`` (W/m^2), ``platen_torque`` (N m),
    ``removed_volume`` (m^3), ``removal_rate_profile`` {radius, material: m/s at the step's start} and, with a
    pad life, ``glazing`` {``time`` (s from the recipe's start), ``rate_factor`` (1), ``summit_sigma`` (1,
    worn over fresh, at the step's start, as the step's solve takes it)}."""

    name: str
    duration: float
    end: str
    removal_rate_mean: float
    pad_temperature: dict
    thickness: dict
    signals: EndpointTrace
    top_film: str | None
    cleared_fraction: float
    frictional_power: float
    platen_torque: float
    removed_volume: float
    removal_rate_profile: dict
    endpoint: dict | None = None
    limit: float = 0.0
    glazing: dict | None = None
    #: ``polish(die=...)``: the die at each site after the step (:meth:`cmpsim.polisher.ride.Ride.step`), else None
    die: list | None = None
    #: material -> the blanket depth (m) each ring would lose in the step, integral of the rate over the step (the die's drive)
    blanket_removal: dict | None = field(default=None, repr=False)

    def to_dict(self) -> dict:
        return {
            "name": self.name,
            "duration": self.duration,
            "end": self.end,
            "removal_rate_mean": self.removal_rate_mean,
            "pad_temperature": {"time": list(self.pad_temperature["time"]), "value": list(self.pad_temperature["value"])},
            "thickness": self.thickness,
            "signals": self.signals.to_dict(),
            "endpoint": self.endpoint,
            "top_film": self.top_film,
            "cleared_fraction": self.cleared_fraction,
            "frictional_power": self.frictional_power,
            "platen_torque": self.platen_torque,
            "removed_volume": self.removed_volume,
            "removal_rate_profile": self.removal_rate_profile,
            "limit": self.limit,
            "glazing": self.glazing,
        } | ({"die": self.die} if self.die is not None else {})


UNITS = {
    "duration": "s", "removal_rate_mean": "m/s", "pad_temperature.time": "s (from the recipe's start)", "pad_temperature.value": "K",
    "thickness": "m", "radius": "m", "signals.time": "s (from the recipe's start)", "signals.reflectance": "1 (area mean at 650 nm)",
    "signals.torque": "N m", "signals.cleared_fraction": "1 (share of the wafer area)", "cleared_fraction": "1 (share of the wafer area)",
    "frictional_power": "W/m^2 (wafer mean)", "platen_torque": "N m", "removed_volume": "m^3", "removal_rate_profile": "m/s",
    "limit": "s (time, or max_time)", "endpoint.time": "s (from the step's start)", "target.remaining": "m", "wall_time": "s",
    "pad_state.surface_temperature": "K", "pad_state.time": "s", "films.thickness": "m",
    "glazing.time": "s (from the recipe's start)", "glazing.rate_factor": "1 (glazed pad / fresh pad)",
    "glazing.summit_sigma": "1 (worn / fresh summit-height std)",
}


@dataclass
class PolishResult:
    """A polished recipe: ``steps`` (:class:`StepResult`), the ``films`` (name, material, incoming
    thickness in m), the initial ``stack`` and the ``final`` one, the ``target`` (m or None), the
    ``pad_state`` after the last step (:class:`PadState`, for the next wafer), ``solves`` (wafer
    equilibria solved by this call) and ``wall_time`` (s)."""

    recipe: Recipe
    steps: list
    initial: FilmStack
    final: FilmStack
    pad_state: PadState
    solves: int
    wall_time: float
    time_step: float
    #: ``polish(die=...)``: the ride (:class:`cmpsim.polisher.ride.Ride`: its sites and the die at each after the last step)
    ride: object = None

    @property
    def target(self) -> dict | None:
        """The target of the recipe against the top film's area-mean thickness after the last step (m)."""
        rem = self.recipe.target.remaining
        if rem is None:
            return None
        mean = self.final.mean_thickness(0)
        return {"film": self.final.names[0], "remaining": rem, "final_mean": mean, "deviation": mean - rem}

    def to_dict(self) -> dict:
        """The JSON object of ``cmpsim polish --json`` (SI, units in ``units``)."""
        out = {
            "recipe": self.recipe.source,
            "films": [{"name": f.name, "material": f.material, "thickness": f.thickness} for f in self.recipe.films],
            "steps": [s.to_dict() for s in self.steps],
            "target": self.target,
            "pad_state": {"surface_temperature": self.pad_state.surface_temperature, "time": self.pad_state.time},
            "time_step": self.time_step,
            "solves": self.solves,
            "wall_time": self.wall_time,
            "units": dict(UNITS),
        }
        if self.ride is not None:  # the ride's keys and their units beside the recipe's
            ride = self.ride.to_dict()
            out["ride"] = ride["ride"]
            out["units"] |= ride["units"]
        return out

    def to_json(self) -> str:
        import json

        return json.dumps(self.to_dict())

    def summary_rows(self) -> list:
        """(step, end, duration s, mean rate nm/min, pad temperature rise K, top film, cleared %) per step."""
        rows = []
        for s in self.steps:
            v = s.pad_temperature["value"]
            rows.append((s.name, s.end, f"{s.duration:.1f}", f"{s.removal_rate_mean * 6e10:.1f}", f"{v[0]:.2f} -> {v[-1]:.2f}",
                         s.top_film or "-", f"{100 * s.cleared_fraction:.1f}"))
        return rows


def _column(config: Config, cache: dict) -> ThermalColumn:
    hs = getattr(config, "pad_heat_transfer_coefficient", 0.0) or None  # 0: from the slurry flow
    key = (0.5 * config.wafer_diameter, config.centre_distance, config.slurry_temperature, hs)
    if key not in cache:
        cache[key] = _built_column(key)
    return cache[key]


@functools.lru_cache(maxsize=32)
def _built_column(key) -> ThermalColumn:
    """The thermal column of a (wafer radius, centre distance, slurry temperature, heat removal): built once
    (an eigen-decomposition, 0.1 s; the column is frozen), shared by every polish and idle of a lot."""
    return polisher_column(key[0], key[1], SLURRY_FLOW_RATE, platen=PLATEN, slurry_temperature=key[2], surface_coefficient=key[3])


def idle(pad_state: PadState, seconds: float, config: Config) -> PadState:
    """The pad after ``seconds`` without a wafer (no frictional power: it cools towards the slurry's
    temperature), for the column of ``config`` (wafer radius, centre distance, slurry temperature)."""
    column = _column(config, {})
    thermal = pad_state.thermal if pad_state.thermal is not None else column.initial_state()
    return PadState(column.advance(thermal, 0.0, float(seconds)), pad_state.life, pad_state.time + float(seconds))


def polish(recipe, *, overrides: dict | None = None, pad_state: PadState | None = None, time_step: float = TIME_STEP,
           rate_factor: float = 1.0, incoming=None, pad_life: PadLife | None = None, die=None, cache: dict | None = None) -> PolishResult:
    """Polish a recipe through time (``cmpsim polish``).

    Parameters
    ----------
    recipe : Recipe, path or TOML text
        The recipe (:mod:`cmpsim.polisher.recipe`).
    overrides : dict, optional
        Inputs for every step unless the step sets them (``--set NAME=VALUE``), e.g. ``{"grid": "coarse"}``.
    pad_state : PadState, optional
        The pad at the start (a lot carries it from wafer to wafer); default a new pad at the slurry temperature.
    time_step : float
        Time step, s (the end point's sampling); each step's last time step is shortened to end on its time.
    rate_factor : float
        Scales every removal rate (e.g. a glazed pad's factor); 1 by default.
    incoming : (radius, thickness of each film) optional
        Incoming thickness per film, m, on given radii (m): ``(radius, [t_film1, t_film2, ...])``,
        interpolated onto the rings; default the recipe's uniform films.
    pad_life : PadLife, optional
        The pad wears and is conditioned through the steps (``pad_state.life`` carries it in and out);
        default: the recipe's ``conditioning`` and ``[conditioner]``, and no wear if it has none.
    die : cmpsim.polisher.ride.RidingDie or a layout, optional
        A layout riding along (docs/polisher.md, "A layout riding along"): the die model at a few
        wafer sites, each step polishing it at its site's blanket rate for the step's duration;
        every step's ``die`` and ``PolishResult.ride`` (the die at each site after the last step).
    cache : dict, optional
        The step solves of an earlier call (a lot passes one dict from wafer to wafer): a step whose
        configuration was solved there is not solved again. Afterwards it holds this call's solves only.

    Returns
    -------
    PolishResult

    Raises
    ------
    RecipeError
        A bad recipe or override (naming the step, the film and the line); an end point on a stack
        with no film left below the top film, or one the signal cannot see.
    cmpsim.EquilibriumError
        A step's wafer equilibrium failed.
    """
    t0 = _time.perf_counter()
    recipe = load_recipe(recipe)
    if not (math.isfinite(time_step) and time_step > 0):
        raise ValueError(f"time_step must be > 0 s; got {time_step!r}")
    if not (math.isfinite(rate_factor) and rate_factor >= 0):
        raise ValueError(f"rate_factor must be >= 0; got {rate_factor!r}")
    configs = [recipe.step_config(s, overrides) for s in recipe.steps]  # every step checked before any solve
    if pad_life is None and recipe.conditioning is not None:  # the recipe's own pad life (conditioning = ...)
        pad_life = PadLife(recipe.conditioning, recipe.conditioner)
    if die is not None and not hasattr(die, "prepare"):  # a layout alone: a CSV, a built-in die, a Layout
        from .ride import RidingDie

        die = RidingDie(die)
    ride = die.prepare(recipe, configs) if die is not None else None  # the layout read and the sites checked before any solve
    solves: dict = cache if cache is not None else {}
    used, solved = set(), 0
    columns: dict = {}
    pad = pad_state or PadState()
    stack = None
    initial = None
    clock = 0.0
    results = []
    for step, step_cfg in zip(recipe.steps, configs):
        life, wear, cfg = None, None, step_cfg
        if pad_life is not None:  # the worn summits may enter the step's solve (the fresh pad is the step's own)
            life = pad.life if isinstance(pad.life, PadLifeState) else PadLifeState()
            wear = pad_life.at(step_cfg)
            worn = worn_overrides(step_cfg, life, wear.pad) if pad_life.worn_summits else {}
            cfg = step_cfg.replace(**worn) if worn else step_cfg
        key = cfg.key()
        if key not in solves:
            solves[key] = StepSolve(cfg)
            solved += 1
        used.add(key)
        sol = solves[key]
        if stack is None:
            stack = _initial_stack(recipe, sol, incoming)
            initial = stack
        elif not np.array_equal(sol.radius, stack.radius):  # the stack holds the first step's rings
            raise RecipeError(f"{recipe.source}: {step.label}: its grid or wafer differs from the first step's; every step must polish the same wafer on the same grid")
        column = _column(cfg, columns)
        thermal = pad.thermal if pad.thermal is not None else column.initial_state()
        if thermal.temperature.shape[-1] != column.size:
            raise RecipeError(f"{recipe.source}: {step.label}: the pad state carried in does not fit this pad's thermal column")
        result, stack, thermal, clock, life = _run_step(recipe, step, sol, column, stack, thermal, clock, time_step, rate_factor,
                                                        wear, life, ride.materials if ride is not None else ())
        if ride is not None:
            result.die = ride.step(step_cfg, sol.radius, result)
        pad = PadState(thermal, life if pad_life is not None else pad.life, pad.time + result.duration)
        results.append(result)
    for key in [k for k in solves if k not in used]:  # a cache carries the last call's solves, no more
        del solves[key]
    return PolishResult(recipe, results, initial, stack, pad, solved, _time.perf_counter() - t0, float(time_step), ride)


def _initial_stack(recipe: Recipe, sol: StepSolve, incoming) -> FilmStack:
    stack = FilmStack.uniform(recipe.films, sol.radius, sol.ring_faces)
    if incoming is None:
        return stack
    r_in, t_in = incoming
    r_in = np.asarray(r_in, dtype=float)
    t_in = [np.asarray(t, dtype=float) for t in t_in]
    if len(t_in) != len(recipe.films):
        raise ValueError(f"incoming: {len(t_in)} thickness profiles for {len(recipe.films)} films")
    if r_in[0] > sol.radius[0] or r_in[-1] < sol.radius[-1]:
        raise ValueError(f"incoming: the radii {r_in[0]:g}-{r_in[-1]:g} m must cover the rings {sol.radius[0]:g}-{sol.radius[-1]:g} m")
    t = np.array([np.interp(sol.radius, r_in, ti) for ti in t_in])
    if np.any(t < 0) or not np.all(np.isfinite(t)):
        raise ValueError("incoming: thicknesses must be finite and >= 0")
    return FilmStack(stack.names, stack.materials, stack.radius, stack.areas, t)


def _run_step(recipe: Recipe, step: Step, sol: StepSolve, column: ThermalColumn, stack: FilmStack, thermal: PadThermalState,
              clock: float, time_step: float, rate_factor: float, wear: StepWear | None = None, life: PadLifeState | None = None,
              track=()):
    """Polish one step; ``wear``: the pad wears through it from ``life`` (:meth:`cmpsim.polisher.pad.PadLife.at`);
    ``track``: materials whose blanket depth per ring (the integral of their rate) the step records."""
    n_films = len(stack.names)
    tops = stack.top()
    k0 = int(tops.min())  # the step's top film: the highest film left anywhere
    detector = None
    if step.until == "endpoint":
        if k0 >= n_films - 1:
            left = "no film" if k0 >= n_films else f"only the last film ({stack.names[k0]!r})"
            raise RecipeError(
                f"{recipe.source}: {step.label}: until = \"endpoint\" clears the top film onto the film below it, but the stack has "
                f"{left} left at this step: there is nothing to clear onto"
            )
        try:
            detector = EndpointDetector(reflectance_signal(stack), cleared_level(stack, k0), step.endpoint_fraction)
        except ValueError as exc:
            raise RecipeError(f"{recipe.source}: {step.label}: {exc}") from None
    q = sol.frictional_power
    start_temperature = float(thermal.surface)
    glazing = None
    start_factor = rate_factor
    if wear is not None:
        summits = wear.summits(life)
        glazed = float(np.asarray(summits.rate_factor))
        start_factor = rate_factor * glazed
        glazing = {"time": [clock], "rate_factor": [glazed], "summit_sigma": float(np.asarray(summits.sigma))}
    profile = {"radius": [float(x) for x in sol.radius]}
    for m in dict.fromkeys(stack.materials):
        profile[m] = [float(x) for x in start_factor * sol.rate_profile(m, start_temperature)]
    times, temps = [clock], [start_temperature]
    signals = EndpointTrace()
    top_name = stack.names[k0] if k0 < n_films else None

    def cleared(s):
        return s.cleared_fraction(k0) if k0 < n_films else 1.0

    signals.append(clock, reflectance_signal(stack), sol.torque, cleared(stack))
    elapsed, volume, end, detected_at = 0.0, 0.0, "time", None
    depth = {m: np.zeros(len(sol.radius)) for m in track}
    limit = step.limit
    while elapsed < limit * (1 - 1e-12):
        dt = min(time_step, limit - elapsed)
        mid = float(column.advance(thermal, q, 0.5 * dt).surface)
        thermal = column.advance(thermal, q, dt)
        factor = rate_factor
        if wear is not None:  # the glazing of the time step at mid-step (second order in dt)
            factor = rate_factor * wear.factor(wear.advance(life, 0.5 * dt))
            life = wear.advance(life, dt)
            glazing["time"].append(clock + dt)
            glazing["rate_factor"].append(wear.factor(life))
        rates = np.array([sol.rate_profile(m, mid) for m in stack.materials]) * factor
        for m in track:  # the same rate the stack is polished with
            depth[m] += (rates[stack.materials.index(m)] if m in stack.materials else factor * sol.rate_profile(m, mid)) * dt
        stack, removal = remove(stack, rates, dt)
        volume += removal.volume(stack.areas)
        elapsed += dt
        clock += dt
        times.append(clock)
        temps.append(float(thermal.surface))
        signal = reflectance_signal(stack)
        signals.append(clock, signal, sol.torque, cleared(stack))
        if detector is not None and detector.reached(signal):
            end, detected_at = "endpoint", elapsed
            break
    endpoint = None
    if detector is not None:
        endpoint = {
            "detected": end == "endpoint", "time": detected_at, "fraction": step.endpoint_fraction, "film": top_name,
            "signal": "reflectance", "level_start": detector.start, "level_cleared": detector.target, "tolerance": detector.tolerance,
            "cleared_fraction": cleared(stack), "max_time": step.max_time,
        }
    duration = elapsed
    result = StepResult(
        name=step.name, duration=duration, end=end,
        removal_rate_mean=volume / (stack.wafer_area * duration) if duration > 0 else 0.0,
        pad_temperature={"time": times, "value": temps}, thickness=stack.to_dict(), signals=signals, top_film=top_name,
        cleared_fraction=cleared(stack), frictional_power=q, platen_torque=sol.torque, removed_volume=volume,
        removal_rate_profile=profile, endpoint=endpoint, limit=limit, glazing=glazing, blanket_removal=depth if track else None,
    )
    return result, stack, thermal, clock, life
