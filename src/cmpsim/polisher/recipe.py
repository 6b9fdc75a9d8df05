"""The recipe file of ``cmpsim polish``: the film stack, the ordered steps and a target (issue 32).

A recipe is TOML::

    preset = "300mm"            # optional: a named preset (cmpsim.inputs.config.PRESETS)
    grid = "coarse"             # optional: any cmpsim input, for every step
    [[film]]                    # the film stack, top first
    material = "copper"         # a film of cmpsim.physics.films.FILM_CONSTANTS and of the removal law's table
    thickness = "1.2 um"
    [[step]]
    name = "bulk"
    time = "30 s"               # a timed step, or
    # until = "endpoint"        # an end-pointed step, stopped by the end-point signal,
    # max_time = "240 s"        # at the latest at max_time (required with until)
    # endpoint_fraction = 0.95  # share of the wafer area the top film must be cleared on (default 0.95)
    applied_pressure = "3 psi"  # any cmpsim input with units, for this step
    [target]
    remaining = "500 nm"        # optional: the remaining thickness aimed at (reported against)

and optionally the pad's life (docs/polisher.md, "Pad life in a recipe")::

    conditioning = "in_situ"    # "none" | "ex_situ" | "in_situ": the pad glazes through the steps
    [conditioner]               # optional: the diamond disk (cmpsim.physics.padlife.ConditionerDisk)
    down_force = "22.24 N"      # F_d, a force with units (default 22.24 N = 5 lbf)
    sweep_duty = 1.0            # share of the pad track the disk works per unit time, in [0, 1]

Parsed into frozen dataclasses (:class:`Recipe`, :class:`Film`, :class:`Step`, :class:`Target`),
SI inside. Every error is a :class:`RecipeError` (a ``ValueError``) that names the step or film
(its index, from 1, and name) and, where the TOML text gives it, the line.
"""

from __future__ import annotations

import math
import re
import tomllib
from dataclasses import dataclass, field, replace
from pathlib import Path

from ..inputs.config import PARAMETERS, PRESETS, Config
from ..inputs.param import did_you_mean
from ..inputs.units import to_si
from ..io import read_text
from ..physics.films import FILM_CONSTANTS
from ..physics.materials import FILMS
from ..physics.padlife import CONDITIONING, DEFAULT_DISK, ConditionerDisk

__all__ = ["RecipeError", "Film", "Step", "Target", "Recipe", "parse_recipe", "read_recipe", "load_recipe", "STEP_KEYS", "DEFAULT_ENDPOINT_FRACTION"]

#: Keys of a [[step]] table that are not cmpsim inputs.
STEP_KEYS = ("name", "time", "until", "max_time", "endpoint_fraction")
_TOP_KEYS = ("preset", "film", "step", "target", "conditioning", "conditioner")
#: Share of the wafer area on which the top film must be cleared at the end point, by default.
DEFAULT_ENDPOINT_FRACTION = 0.95
#: Materials a [[film]] may name: those the removal law knows (cmpsim.physics.materials.FILMS) that
#: have optical constants for the end point (cmpsim.physics.films.FILM_CONSTANTS).
MATERIALS = tuple(m for m in FILMS if m in FILM_CONSTANTS)


class RecipeError(ValueError):
    """A recipe that cannot run: the message names the step or film (index and name) and the line."""


@dataclass(frozen=True)
class Film:
    """One film of the stack: ``material`` (a name of :data:`MATERIALS`), ``thickness`` (m), its
    ``name`` in the outputs (the material; ``copper_2`` for a second copper film) and ``index`` (from 1, top first)."""

    material: str
    thickness: float
    name: str
    index: int


@dataclass(frozen=True)
class Step:
    """One step: ``name``, ``index`` (from 1), ``inputs`` ((name, value) pairs as written, checked),
    ``until`` ("time" or "endpoint"), ``time`` (s; timed steps), ``max_time`` (s; end-pointed steps),
    ``endpoint_fraction`` (share of the wafer area) and ``line`` (of its ``[[step]]`` header)."""

    name: str
    index: int
    inputs: tuple
    until: str = "time"
    time: float | None = None
    max_time: float | None = None
    endpoint_fraction: float = DEFAULT_ENDPOINT_FRACTION
    line: int | None = None

    @property
    def limit(self) -> float:
        """The longest this step may run, s: its time, or its max_time."""
        return self.time if self.until == "time" else self.max_time

    @property
    def label(self) -> str:
        """``step 2 ('landing', line 17)``: how errors name the step."""
        return _label("step", self.index, self.name, self.line)


@dataclass(frozen=True)
class Target:
    """The recipe's target: ``remaining`` thickness of the top film left (m), or None."""

    remaining: float | None = None


@dataclass(frozen=True)
class Recipe:
    """A parsed recipe (SI): ``preset`` (or None), ``inputs`` for every step ((name, value) pairs),
    ``films`` (top first), ``steps`` (in order), ``target``, ``source`` (the file or "recipe") and the
    pad's life: ``conditioning`` (None: no wear) with its ``conditioner`` disk."""

    preset: str | None
    inputs: tuple
    films: tuple
    steps: tuple
    target: Target = field(default_factory=Target)
    source: str = "recipe"
    text: str = field(default="", repr=False, compare=False)
    #: The pad's life through the steps: "none" | "ex_situ" | "in_situ", or None (the pad does not wear).
    conditioning: str | None = None
    #: The conditioning disk of ``[conditioner]`` (None: the calibrated default disk).
    conditioner: ConditionerDisk | None = None

    def base_config(self, overrides: dict | None = None) -> Config:
        """The configuration every step starts from: the preset, the recipe's inputs, then ``overrides``."""
        cfg = Config.preset(self.preset) if self.preset else Config.default()
        cfg = cfg.replace(**dict(self.inputs))
        return cfg.replace(**_checked_overrides(overrides)) if overrides else cfg

    def step_config(self, step: Step, overrides: dict | None = None) -> Config:
        """The configuration of ``step``: the preset, the recipe's inputs, the overrides (``--set``),
        then the step's own inputs (a step's setting wins over ``--set``: ``--set`` applies to every
        step unless the step sets it)."""
        overrides = _checked_overrides(overrides)
        cfg = Config.preset(self.preset) if self.preset else Config.default()
        cfg = cfg.replace(**dict(self.inputs))
        own = dict(step.inputs)
        cfg = cfg.replace(**{k: v for k, v in overrides.items() if k not in own})
        try:
            return cfg.replace(**own)
        except ValueError as exc:
            raise RecipeError(f"{self.source}: {step.label}: {exc}") from None

    def with_step_time(self, k: int, t: float) -> "Recipe":
        """This recipe with step ``k`` (0-based) polished for ``t`` s (a lot's controlled or logged time)."""
        steps = list(self.steps)
        steps[k] = replace(steps[k], time=t)
        return replace(self, steps=tuple(steps))

    def with_step_zones(self, k: int, pressures) -> "Recipe":
        """This recipe with step ``k`` (0-based) polished at the zone ``pressures`` (Pa; its own pressure, if it
        sets one, replaced): a lot's zone feedback on its controlled step, the other steps keeping theirs."""
        steps = list(self.steps)
        own = tuple((n, v) for n, v in steps[k].inputs if n not in ("applied_pressure", "zone_pressures"))
        steps[k] = replace(steps[k], inputs=own + (("zone_pressures", tuple(float(p) for p in pressures)),))
        return replace(self, steps=tuple(steps))

    @property
    def film_names(self) -> tuple:
        """The films' names in the outputs, top first."""
        return tuple(f.name for f in self.films)


def _checked_overrides(overrides) -> dict:
    overrides = dict(overrides or {})
    for name in overrides:
        if name == "film":
            raise RecipeError("--set film=...: the film of each solve is the material exposed, set by the recipe's [[film]] tables")
        if name not in PARAMETERS:
            raise RecipeError(f"--set {name}=...: unknown input {name!r} (cmpsim params lists them)")
    return overrides


def _label(kind: str, index: int, name: str | None, line: int | None) -> str:
    where = f"line {line}" if line else None
    inner = ", ".join(x for x in ((repr(name) if name else None), where) if x)
    return f"{kind} {index}" + (f" ({inner})" if inner else "")


_HEADER = re.compile(r"^\s*\[\[\s*(step|film)\s*\]\]")
_TABLE = re.compile(r"^\s*\[")


def _table_lines(text: str) -> dict:
    """{"step": [(header line, {key: line})], "film": [...]} from the TOML text (1-based lines)."""
    out = {"step": [], "film": []}
    current = None
    for n, line in enumerate(text.splitlines(), start=1):
        m = _HEADER.match(line)
        if m:
            current = {}
            out[m.group(1)].append((n, current))
            continue
        if _TABLE.match(line):
            current = None
            continue
        if current is not None:
            k = re.match(r"^\s*([A-Za-z0-9_\-]+)\s*=", line)
            if k:
                current.setdefault(k.group(1), n)
    return out


def _duration(value, what: str, allow_zero: bool = False) -> float:
    t = to_si(value, "s", what, example="s")
    if not math.isfinite(t) or t < 0 or (t == 0 and not allow_zero):
        raise ValueError(f"{what} must be a time > 0 (e.g. '60 s'); got {value!r}")
    return t


def parse_recipe(text: str, source: str = "recipe") -> Recipe:
    """Parse a recipe's TOML ``text`` (``source`` names it in errors). Raises :class:`RecipeError`."""
    try:
        data = tomllib.loads(text)
    except tomllib.TOMLDecodeError as exc:
        raise RecipeError(f"{source}: not valid TOML: {exc}") from None
    lines = _table_lines(text)
    top_lines = {}
    for n, line in enumerate(text.splitlines(), start=1):
        if _TABLE.match(line):
            break
        k = re.match(r"^\s*([A-Za-z0-9_\-]+)\s*=", line)
        if k:
            top_lines.setdefault(k.group(1), n)

    def at(name):
        return f" (line {top_lines[name]})" if name in top_lines else ""

    preset = data.pop("preset", None)
    if preset is not None and preset not in PRESETS:
        raise RecipeError(f"{source}: preset{at('preset')} must be one of {', '.join(map(repr, PRESETS))}; got {preset!r}")
    films_raw = data.pop("film", None)
    steps_raw = data.pop("step", None)
    target_raw = data.pop("target", None)
    conditioning, conditioner = _pad_life(data.pop("conditioning", None), data.pop("conditioner", None), source, at)
    if isinstance(films_raw, str):
        raise RecipeError(f"{source}: film = {films_raw!r}{at('film')}: the films are [[film]] tables (material, thickness), top first; the film of each solve follows the material exposed")
    inputs = []
    for name, value in data.items():
        if isinstance(value, dict):
            raise RecipeError(f"{source}: unknown table [{name}]{did_you_mean(name, _TOP_KEYS)}; a recipe has [[film]], [[step]], [target] and [conditioner] tables")
        if name not in PARAMETERS:
            where_else = " (it goes in a [[step]] table)" if name in STEP_KEYS else did_you_mean(name, list(PARAMETERS) + list(_TOP_KEYS))
            raise RecipeError(f"{source}: unknown input {name!r}{at(name)}{where_else} (cmpsim params lists the inputs)")
        inputs.append((name, value))
    try:
        base = Config.preset(preset) if preset else Config.default()
        base = base.replace(**dict(inputs))
    except ValueError as exc:
        raise RecipeError(f"{source}: {exc}") from None

    # ---- films
    if not films_raw:
        raise RecipeError(f"{source}: no [[film]] table: give the film stack, top first ([[film]] with material and thickness)")
    films, seen = [], {}
    for i, (raw, (line, keys)) in enumerate(zip(films_raw, lines["film"] + [(None, {})] * len(films_raw)), start=1):
        material = raw.get("material")
        label = _label("film", i, material, line)
        unknown = set(raw) - {"material", "thickness"}
        if unknown:
            k = sorted(unknown)[0]
            raise RecipeError(f"{source}: {label}: unknown key {k!r}" + (f" (line {keys[k]})" if k in keys else "") + "; a film has material and thickness")
        if material not in MATERIALS:
            raise RecipeError(f"{source}: {label}: unknown film material {material!r}; one of {', '.join(map(repr, MATERIALS))}")
        if "thickness" not in raw:
            raise RecipeError(f"{source}: {label}: thickness missing (e.g. thickness = \"500 nm\")")
        try:
            thickness = to_si(raw["thickness"], "m", "thickness", example="nm")
            if not (math.isfinite(thickness) and thickness > 0):
                raise ValueError(f"thickness must be > 0; got {raw['thickness']!r}")
        except ValueError as exc:
            raise RecipeError(f"{source}: {label}" + (f", line {keys['thickness']}" if "thickness" in keys else "") + f": {exc}") from None
        seen[material] = seen.get(material, 0) + 1
        name = material if seen[material] == 1 else f"{material}_{seen[material]}"
        films.append(Film(material, float(thickness), name, i))

    # ---- steps
    if not steps_raw:
        raise RecipeError(f"{source}: no [[step]] table: a recipe needs at least one step (name, time = \"60 s\" or until = \"endpoint\" with max_time)")
    steps = []
    endpoints = 0
    named = {}
    for i, (raw, (line, keys)) in enumerate(zip(steps_raw, lines["step"] + [(None, {})] * len(steps_raw)), start=1):
        name = str(raw.get("name", f"step {i}"))
        label = _label("step", i, name, line)
        if name in named:  # the outputs (thickness.csv's columns, polish.json) name the steps: two alike would be one
            raise RecipeError(f"{source}: {label}: the name {name!r} is already step {named[name]}'s; give every step its own name")
        named[name] = i

        def where(key, keys=keys):
            return f" (line {keys[key]})" if key in keys else ""

        own = []
        for key, value in raw.items():
            if key in STEP_KEYS:
                continue
            if key == "film":
                raise RecipeError(f"{source}: {label}: film{where('film')} is set by the stack: the film of each solve is the material exposed ([[film]] tables)")
            if key not in PARAMETERS:
                hint = did_you_mean(key, list(PARAMETERS) + list(STEP_KEYS))
                raise RecipeError(f"{source}: {label}: unknown input {key!r}{where(key)}{hint} (cmpsim params lists the inputs)")
            own.append((key, value))
        try:
            base.replace(**dict(own))
        except ValueError as exc:
            raise RecipeError(f"{source}: {label}: {exc}") from None
        until = raw.get("until", "time")
        if until not in ("time", "endpoint"):
            raise RecipeError(f"{source}: {label}: until{where('until')} must be \"endpoint\" (or leave it out and give time); got {until!r}")
        try:
            fraction = float(raw.get("endpoint_fraction", DEFAULT_ENDPOINT_FRACTION))
        except (TypeError, ValueError):
            raise RecipeError(f"{source}: {label}: endpoint_fraction{where('endpoint_fraction')} must be a number in (0, 1]; got {raw.get('endpoint_fraction')!r}") from None
        if not (0 < fraction <= 1):
            raise RecipeError(f"{source}: {label}: endpoint_fraction{where('endpoint_fraction')} must be in (0, 1]; got {fraction!r}")
        time = max_time = None
        try:
            if until == "time":
                if "time" not in raw:
                    raise RecipeError(f"{source}: {label}: give time = \"60 s\" or until = \"endpoint\" with max_time")
                if "max_time" in raw:
                    raise RecipeError(f"{source}: {label}: max_time{where('max_time')} goes with until = \"endpoint\"; a timed step has time only")
                key = "time"
                time = _duration(raw["time"], "time")
            else:
                if "time" in raw:
                    raise RecipeError(f"{source}: {label}: time{where('time')} and until = \"endpoint\" exclude each other; an end-pointed step stops at max_time at the latest")
                if "max_time" not in raw:
                    raise RecipeError(f"{source}: {label}: until = \"endpoint\"{where('until')} needs max_time (e.g. max_time = \"240 s\"), the time the step may run at most")
                key = "max_time"
                max_time = _duration(raw["max_time"], "max_time")
        except RecipeError:
            raise
        except ValueError as exc:
            raise RecipeError(f"{source}: {label}{where(key).replace(' (', ', ').replace(')', '')}: {exc}") from None
        if until == "endpoint":
            endpoints += 1
            if endpoints >= len(films):
                raise RecipeError(
                    f"{source}: {label}: an end point clears the top film onto the film below it; the stack has "
                    f"{len(films)} film(s), so end-pointed step number {endpoints} would have no film left to clear onto "
                    f"(films: {', '.join(f.name for f in films)})"
                )
        steps.append(Step(name, i, tuple(own), until, time, max_time, fraction, line))

    # ---- target
    target = Target()
    if target_raw is not None:
        if not isinstance(target_raw, dict) or set(target_raw) - {"remaining"} or not target_raw:
            raise RecipeError(f"{source}: [target] takes remaining (e.g. remaining = \"500 nm\"); got {target_raw!r}")
        if "remaining" in target_raw:
            try:
                rem = to_si(target_raw["remaining"], "m", "remaining", example="nm")
            except ValueError as exc:
                raise RecipeError(f"{source}: [target]: {exc}") from None
            if not (math.isfinite(rem) and 0 <= rem < films[0].thickness):
                raise RecipeError(f"{source}: [target]: remaining must be in [0, {films[0].thickness:g}) m (below the top film's thickness); got {rem:g} m")
            target = Target(float(rem))
    return Recipe(preset, tuple(inputs), tuple(films), tuple(steps), target, source, text, conditioning, conditioner)


def _pad_life(conditioning, conditioner, source: str, at):
    """The recipe's ``conditioning`` and ``[conditioner]`` table, checked: (mode or None, disk or None)."""
    if conditioning is not None and conditioning not in CONDITIONING:
        raise RecipeError(f"{source}: conditioning{at('conditioning')} must be one of {', '.join(map(repr, CONDITIONING))}; got {conditioning!r}")
    if conditioner is None:
        return conditioning, None
    if not isinstance(conditioner, dict):
        raise RecipeError(f"{source}: conditioner{at('conditioner')} is a table: [conditioner] with down_force (e.g. \"22.24 N\") and sweep_duty (0-1)")
    if conditioning is None:
        raise RecipeError(f"{source}: [conditioner] needs conditioning = \"none\" | \"ex_situ\" | \"in_situ\" at the top of the recipe")
    unknown = set(conditioner) - {"down_force", "sweep_duty"}
    if unknown:
        raise RecipeError(f"{source}: [conditioner]: unknown key {sorted(unknown)[0]!r}; the disk has down_force and sweep_duty")
    try:
        force = to_si(conditioner.get("down_force", DEFAULT_DISK.down_force), "N", "down_force", example="N")
        duty = float(conditioner.get("sweep_duty", DEFAULT_DISK.sweep_duty))
        disk = ConditionerDisk(float(force), duty, DEFAULT_DISK.rate_constant)
    except (TypeError, ValueError) as exc:
        raise RecipeError(f"{source}: [conditioner]: {exc}") from None
    return conditioning, disk


def read_recipe(path) -> Recipe:
    """Read and parse a recipe file (:class:`RecipeError` naming the file)."""
    path = Path(path)
    return parse_recipe(read_text(path, "recipe", RecipeError), str(path))


def load_recipe(recipe) -> Recipe:
    """A :class:`Recipe` from a Recipe, a path to a TOML file, or TOML text (a string with a newline)."""
    if isinstance(recipe, Recipe):
        return recipe
    if isinstance(recipe, str) and "\n" in recipe:
        return parse_recipe(recipe)
    if isinstance(recipe, (str, Path)):
        return read_recipe(recipe)
    raise TypeError(f"recipe must be a Recipe, a path or TOML text; got {type(recipe).__name__}")
