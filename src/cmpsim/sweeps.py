"""Parameter sweeps: the outer product of setting axes, run on dask.distributed, resumable.

A sweep file (TOML, see docs/sweeps.md and ``cmpsim/data/example_sweep.toml``) holds

* ``[base]``: any ``cmpsim run`` setting (same names, values with units), flat or in the
  sections of a config file (``[base.process]``);
* ``[axes]``: one key per swept setting, a list (``applied_pressure = ["2psi", "4psi"]``) or a
  range (``rotation_speed = {start = "30rpm", stop = "90rpm", num = 7}``, optional
  ``scale = "log"``); the sweep is their outer product;
* ``[[points]]``: optional explicit extra points (tables of settings).

The result is one :class:`xarray.Dataset` with one dimension per swept setting (named as the
setting, SI coordinates, ``units`` in the attributes), every scalar of ``cmpsim run --json``
as a variable, plus ``status`` (``ok`` / ``failed`` / ``invalid`` / ``not_requested``),
``error`` and ``start`` (``warm`` / ``cold`` / ``cold-retry``) per point.

Execution
---------
Each point is one dask task. Points are grouped into *chains* along the last numeric axis
(at most ``chain_length`` points, a fixed split that does not depend on the number of workers)
and each task of a chain receives the converged records of the one or two previous points of
its chain as dask dependencies. The start of Newton is predicted from them (see
:func:`_predict_start`); if a predicted start fails, the point is solved again from the cold
start. The result of a point therefore depends only on the chain layout, never on how many
workers there are or on the order in which points finish.

Persistence and resume
----------------------
With an output path ``PATH`` every finished point is written atomically, by the client as it
arrives, to ``PATH.parts/<key>.json`` (key = hash of the sweep identity and the point's
settings); ``PATH.parts/manifest.json`` identifies the sweep. ``resume=True`` reloads those
records, feeds them to the chains as if they had just been computed (same warm starts) and
computes only the missing points, so the final dataset equals an uninterrupted run. The final
file is written to a temporary sibling and renamed; the state directory is removed once the
file is in place.
"""

from __future__ import annotations

import contextlib
import dataclasses
import hashlib
import itertools
import json
import logging
import math
import os
import shutil
import time
import tomllib
import uuid
from dataclasses import dataclass
from functools import cached_property, lru_cache
from pathlib import Path
from typing import Any, Callable, Iterable, Mapping

import numpy as np

from . import __version__
from .config import PARAMETERS, Config, _ureg, parse_value

__all__ = [
    "Axis",
    "SweepSpec",
    "SweepError",
    "sweep",
    "local_cluster",
    "summary_lines",
    "DEFAULT_MAX_POINTS",
    "DEFAULT_CHAIN_LENGTH",
    "STATUS_MEANINGS",
]

#: Largest number of points a sweep may have unless ``max_points`` says otherwise.
DEFAULT_MAX_POINTS = 10_000
#: Longest chain of warm-started points (one cold start per chain).
DEFAULT_CHAIN_LENGTH = 8
#: Version of the state-directory layout and of the chain/prediction scheme.
_STATE_FORMAT = 1

STATUS_MEANINGS = {
    "ok": "equilibrium found",
    "failed": "no equilibrium found (the error says why)",
    "invalid": "bad parameters at this point (the error names the parameter and its range)",
    "not_requested": "grid cell that is neither in the outer product of the axes nor an explicit point",
}
_SECTIONS = ("wafer", "process", "slurry", "pad", "numerics")
_INT_SCALARS = ("iterations", "factorizations")
_BOOL_SCALARS = ("converged",)


class SweepError(ValueError):
    """A bad sweep file or sweep option; raised before any point is computed."""


# ---------------------------------------------------------------------------- values


def _is_string_param(name: str) -> bool:
    p = PARAMETERS[name]
    return bool(p.choices) or p.unit == "grid"


def _si_value(name: str, value: Any, where: str) -> Any:
    """SI value of one swept value, checking the name, type and unit dimension but not the range.

    Out-of-range values are kept: the point is then recorded as ``invalid`` with the
    message of :func:`cmpsim.config.parse_value`, not dropped and not fatal.
    """
    if name not in PARAMETERS:
        raise SweepError(f"{where}: unknown setting {name!r} (see `cmpsim params` for the names)")
    p = PARAMETERS[name]
    if _is_string_param(name):
        if not isinstance(value, str):
            raise SweepError(f"{where}: {name} takes a string ({p.range_text()}); got {value!r}")
        try:
            return parse_value(name, value)
        except ValueError:
            return value.strip()  # recorded as an invalid point
    if isinstance(value, bool) or not isinstance(value, (int, float, str)):
        raise SweepError(f"{where}: {name} needs a number or a string with units of {p.unit or 'none'}; got {value!r}")
    if isinstance(value, str):
        try:
            q = _ureg().Quantity(value)
        except Exception as exc:  # pint raises several types
            raise SweepError(f"{where}: {name}: cannot read {value!r} as a quantity ({exc})") from None
        target = p.unit or "dimensionless"
        try:
            v = float(q.to(target).magnitude) if hasattr(q, "to") else float(q)
        except Exception:
            raise SweepError(
                f"{where}: {name}: {value!r} has the wrong unit dimension; expected units convertible to "
                f"{target!r} (e.g. {p.display or target})"
            ) from None
    else:
        v = float(value)
    if not math.isfinite(v):
        raise SweepError(f"{where}: {name} must be finite; got {value!r}")
    return v


def _same(a: Any, b: Any) -> bool:
    if isinstance(a, str) or isinstance(b, str):
        return a == b
    return a == b or math.isclose(a, b, rel_tol=1e-12, abs_tol=0.0)


def _find(values: Iterable[Any], v: Any) -> int | None:
    for i, w in enumerate(values):
        if _same(w, v):
            return i
    return None


# ---------------------------------------------------------------------------- spec


@dataclass(frozen=True)
class Axis:
    """One swept setting: its name and its values (SI floats, or strings for choices/grid)."""

    name: str
    values: tuple

    @property
    def numeric(self) -> bool:
        return not _is_string_param(self.name)


def _parse_axis(name: str, spec: Any, where: str) -> Axis:
    w = f"{where} [axes] {name}"
    if name not in PARAMETERS:
        raise SweepError(f"{where}: unknown setting {name!r} in [axes] (see `cmpsim params` for the names)")
    if isinstance(spec, list):
        if not spec:
            raise SweepError(f"{w}: the axis is empty; give at least one value")
        values = tuple(_si_value(name, v, w) for v in spec)
    elif isinstance(spec, dict):
        if _is_string_param(name):
            raise SweepError(f"{w}: a range needs a numeric setting; give a list of values for {name}")
        unknown = set(spec) - {"start", "stop", "num", "scale"}
        if unknown:
            raise SweepError(f"{w}: unknown key(s) {', '.join(sorted(unknown))} in the range; expected start, stop, num and optional scale")
        missing = [k for k in ("start", "stop", "num") if k not in spec]
        if missing:
            raise SweepError(f"{w}: the range needs {', '.join(missing)} (e.g. {{start = \"30rpm\", stop = \"90rpm\", num = 7}})")
        num = spec["num"]
        if isinstance(num, bool) or not isinstance(num, int):
            raise SweepError(f"{w}: num must be an integer; got {num!r}")
        if num < 1:
            raise SweepError(f"{w}: the axis is empty (num = {num}); num must be >= 1")
        start = _si_value(name, spec["start"], w + ".start")
        stop = _si_value(name, spec["stop"], w + ".stop")
        scale = spec.get("scale", "linear")
        if scale == "linear":
            arr = np.linspace(start, stop, num)
        elif scale == "log":
            if start <= 0 or stop <= 0:
                raise SweepError(f"{w}: a log range needs positive start and stop")
            arr = np.geomspace(start, stop, num)
        else:
            raise SweepError(f"{w}: scale must be 'linear' or 'log'; got {scale!r}")
        values = tuple(float(x) for x in arr)
    else:
        raise SweepError(f"{w}: expected a list of values or a range {{start, stop, num}}; got {spec!r}")
    for i, v in enumerate(values):
        if _find(values[:i], v) is not None:
            raise SweepError(f"{w}: the value {v!r} appears twice (after conversion to SI)")
    return Axis(name, values)


@dataclass(frozen=True)
class SweepSpec:
    """A validated sweep: base configuration, axes and explicit points (all values in SI).

    Build with :meth:`from_toml` or :meth:`from_mapping`; every problem of the file
    (unknown key, wrong unit dimension, empty axis, ...) raises :class:`SweepError` there.
    """

    base: Config
    axes: tuple[Axis, ...] = ()
    points: tuple[tuple[tuple[str, Any], ...], ...] = ()
    source: str = dataclasses.field(default="", compare=False)  # the sweep file as given (TOML)

    # ------------------------------------------------------------------ construction
    @classmethod
    def from_toml(cls, path) -> "SweepSpec":
        """Read and validate a sweep file."""
        from .io import read_text

        path = Path(path)
        text = read_text(path, "sweep file", SweepError)
        try:
            data = tomllib.loads(text)
        except tomllib.TOMLDecodeError as exc:
            raise SweepError(f"sweep file {str(path)!r} is not valid TOML: {exc}") from None
        return cls.from_mapping(data, source=text, where=f"sweep file {path.name}")

    @classmethod
    def from_mapping(cls, data: Mapping[str, Any], source: str | None = None, where: str = "sweep") -> "SweepSpec":
        """Validate a mapping with the layout of a sweep file (``base``, ``axes``, ``points``)."""
        if not isinstance(data, Mapping):
            raise SweepError(f"{where}: expected a table with [base], [axes] and [[points]]; got {type(data).__name__}")
        unknown = set(data) - {"base", "axes", "points"}
        if unknown:
            raise SweepError(f"{where}: unknown key(s) {', '.join(sorted(map(repr, unknown)))} at top level; expected [base], [axes], [[points]]")
        base_data = data.get("base", {})
        if not isinstance(base_data, Mapping):
            raise SweepError(f"{where}: [base] must be a table of settings")
        for k, v in base_data.items():
            if k in _SECTIONS and isinstance(v, Mapping):
                for kk in v:
                    if kk not in PARAMETERS:
                        raise SweepError(f"{where}: unknown setting {kk!r} in [base.{k}] (see `cmpsim params`)")
            elif k not in PARAMETERS:
                raise SweepError(f"{where}: unknown setting {k!r} in [base] (see `cmpsim params` for the names)")
        try:
            base = Config.from_mapping(dict(base_data))
        except ValueError as exc:
            raise SweepError(f"{where}: [base]: {exc}") from None
        axes_data = data.get("axes", {})
        if not isinstance(axes_data, Mapping):
            raise SweepError(f"{where}: [axes] must be a table (setting = list or range)")
        axes = tuple(_parse_axis(name, spec, where) for name, spec in axes_data.items())
        points_data = data.get("points", [])
        if not isinstance(points_data, list) or not all(isinstance(p, Mapping) for p in points_data):
            raise SweepError(f"{where}: points must be an array of tables ([[points]])")
        points = []
        for i, p in enumerate(points_data):
            w = f"{where} [[points]] #{i + 1}"
            if not p:
                raise SweepError(f"{w}: the point sets nothing")
            points.append(tuple((k, _si_value(k, v, w)) for k, v in p.items()))
        if not axes and not points:
            raise SweepError(f"{where}: the sweep has no points; give an [axes] table or [[points]]")
        if source is None:
            try:
                import tomli_w

                source = tomli_w.dumps(_plain(data))
            except Exception:
                source = json.dumps(_plain(data), default=str)
        return cls(base=base, axes=axes, points=tuple(points), source=source)

    # ------------------------------------------------------------------ layout
    @cached_property
    def dims(self) -> tuple[str, ...]:
        """Dimension names: the axes in file order, then settings set only by [[points]]."""
        names = [a.name for a in self.axes]
        for p in self.points:
            for k, _ in p:
                if k not in names:
                    names.append(k)
        return tuple(names)

    @cached_property
    def coords(self) -> dict[str, tuple]:
        """{dimension: values} (SI): the axis values, then new values of the explicit points."""
        out: dict[str, list] = {a.name: list(a.values) for a in self.axes}
        base = self.base.to_dict()
        for name in self.dims:
            vals = out.setdefault(name, [])
            if name not in {a.name for a in self.axes} and self.axes:
                vals.append(base[name])  # the outer product sits at the base value
            for p in self.points:
                v = dict(p).get(name, base[name])
                if _find(vals, v) is None:
                    vals.append(v)
        return {k: tuple(v) for k, v in out.items()}

    @property
    def shape(self) -> tuple[int, ...]:
        return tuple(len(self.coords[d]) for d in self.dims)

    @property
    def product_size(self) -> int:
        return math.prod(len(a.values) for a in self.axes) if self.axes else 0

    def _point_index(self, p) -> tuple[int, ...]:
        base = self.base.to_dict()
        d = dict(p)
        return tuple(_find(self.coords[n], d.get(n, base[n])) for n in self.dims)

    def _in_product(self, idx: tuple[int, ...]) -> bool:
        if not self.axes:
            return False
        n_ax = len(self.axes)
        if any(i >= len(a.values) for i, a in zip(idx[:n_ax], self.axes)):
            return False
        return all(i == 0 for i in idx[n_ax:])  # the base value is the first coordinate there

    @cached_property
    def _extra(self) -> tuple[tuple[int, ...], ...]:
        seen: list[tuple[int, ...]] = []
        for p in self.points:
            idx = self._point_index(p)
            if not self._in_product(idx) and idx not in seen:
                seen.append(idx)
        return tuple(seen)

    @property
    def n_points(self) -> int:
        """Number of distinct points (outer product plus explicit points not already in it)."""
        return self.product_size + len(self._extra)

    def requested(self) -> list[tuple[int, ...]]:
        """Index tuples of every point, outer product first (C order), then explicit points."""
        n_extra_dims = len(self.dims) - len(self.axes)
        out = []
        if self.axes:
            for combo in itertools.product(*(range(len(a.values)) for a in self.axes)):
                out.append(combo + (0,) * n_extra_dims)
        out.extend(self._extra)
        return out

    def settings(self, index: tuple[int, ...]) -> dict[str, Any]:
        """{setting: SI value} of the point at ``index``."""
        return {n: self.coords[n][i] for n, i in zip(self.dims, index)}

    @cached_property
    def chain_dim(self) -> str | None:
        """The dimension along which points warm-start each other: the last numeric axis.

        (Dimensions made only by [[points]] come after the axes and are used only when no
        axis is numeric.)
        """
        axis_names = [a.name for a in self.axes]
        order = list(reversed(axis_names)) + [d for d in reversed(self.dims) if d not in axis_names]
        for name in order:
            if not _is_string_param(name) and len(self.coords[name]) > 1:
                return name
        return None

    def invalid_values(self) -> list[str]:
        """Messages for coordinate values outside their valid range (their points will be ``invalid``)."""
        msgs = []
        for name in self.dims:
            for v in self.coords[name]:
                try:
                    parse_value(name, v)
                except ValueError as exc:
                    msgs.append(str(exc))
        return msgs

    def to_toml(self) -> str:
        """The sweep file as given (TOML)."""
        return self.source

    def check_size(self, max_points: int = DEFAULT_MAX_POINTS) -> None:
        """Raise :class:`SweepError` if the sweep has more than ``max_points`` points."""
        if max_points < 1:
            raise SweepError(f"max_points must be >= 1; got {max_points}")
        n = self.n_points
        if n > max_points:
            sizes = " x ".join(f"{a.name} ({len(a.values)})" for a in self.axes)
            extra = f" + {len(self._extra)} explicit points" if self._extra else ""
            raise SweepError(
                f"the sweep has {n} points ({sizes}{extra}), more than the maximum of {max_points}; "
                "shrink the axes or raise the limit (--max-points / max_points=)"
            )
        cells = math.prod(self.shape)
        if cells > 10 * max_points:
            raise SweepError(
                f"the explicit [[points]] spread the dataset over {cells} grid cells ({' x '.join(map(str, self.shape))}), "
                f"more than 10 x max_points = {10 * max_points}; put them in a separate sweep"
            )


def _plain(obj):
    if isinstance(obj, Mapping):
        return {str(k): _plain(v) for k, v in obj.items()}
    if isinstance(obj, (list, tuple)):
        return [_plain(v) for v in obj]
    return obj


# ---------------------------------------------------------------------------- plan


@dataclass(frozen=True)
class _PlanPoint:
    index: tuple[int, ...]
    key: str
    settings: dict
    x: float | None  # coordinate along the chain dimension


def _canonical(obj) -> str:
    return json.dumps(obj, sort_keys=True, separators=(",", ":"), allow_nan=True)


def _identity(spec: SweepSpec, warm_start: bool, chain_length: int) -> str:
    """Hash of everything that determines the results: base, grid of points, chain layout, version."""
    ident = {
        "format": _STATE_FORMAT,
        "version": __version__,
        "base": spec.base.to_dict(),
        "dims": [[d, list(spec.coords[d])] for d in spec.dims],
        "points": [list(i) for i in spec.requested()],
        "warm_start": bool(warm_start),
        "chain_length": int(chain_length),
    }
    return hashlib.sha256(_canonical(ident).encode()).hexdigest()


def _plan(spec: SweepSpec, identity: str, warm_start: bool, chain_length: int) -> list[list[_PlanPoint]]:
    """Chains of points (each solved in order, warm-starting from its predecessors)."""
    base = spec.base.to_dict()
    chain_dim = spec.chain_dim if warm_start else None
    ci = spec.dims.index(chain_dim) if chain_dim else None

    def make(idx):
        s = spec.settings(idx)
        full = dict(base, **s)
        key = hashlib.sha256((identity + _canonical(full)).encode()).hexdigest()[:24]
        return _PlanPoint(idx, key, s, None if ci is None else float(s[chain_dim]))

    points = [make(i) for i in spec.requested()]
    if ci is None:
        return [[p] for p in points]
    groups: dict[tuple, list[_PlanPoint]] = {}
    for p in points:
        groups.setdefault(p.index[:ci] + p.index[ci + 1 :], []).append(p)
    chains = []
    for g in groups.values():
        g.sort(key=lambda p: p.x)
        n_seg = math.ceil(len(g) / chain_length)
        for part in np.array_split(np.arange(len(g)), n_seg):
            chains.append([g[i] for i in part])
    return chains


# ---------------------------------------------------------------------------- one point (runs on workers)


@lru_cache(maxsize=8)
def _base_config(base_json: str) -> Config:
    return Config.from_mapping(json.loads(base_json))


def _ok(rec) -> bool:
    return isinstance(rec, dict) and rec.get("status") == "ok" and rec.get("u") is not None


def _predict_start(cfg: Config, problem, x: float | None, prev, prev2):
    """Newton start predicted from the converged previous points of the chain (or None).

    For the contact models the cold start (the h0 at which the pad contact alone carries the
    load) already costs no pressure solve and is good; the prediction keeps it and adds the
    neighbours' converged offset from *their* cold start, extrapolated linearly along the
    chain (secant). For the hydrodynamic model the offset is the position itself. This choice
    was measured (docs/sweeps.md, 'Warm start'): it never cost more Newton iterations than the
    cold start on the axes tried, while a plain copy of the neighbour's position sometimes
    did (e.g. along pad_roughness or pad_modulus).
    Returns (start, cold_base) where cold_base is this point's cold start (stored for the next).
    """
    cold = None
    if cfg.model != "hydrodynamic":
        try:
            cold = problem.contact_only_start()
        except Exception:
            return None, None  # the cold solve will say why
    if not _ok(prev):
        return None, cold
    zero = np.zeros(3)

    def offset(rec):
        c = rec.get("cold_base")
        if cfg.model != "hydrodynamic" and c is None:
            return None
        return np.asarray(rec["u"], dtype=float) - (np.asarray(c, dtype=float) if c is not None else zero)

    d1 = offset(prev)
    if d1 is None:
        return None, cold
    d = d1
    if _ok(prev2) and x is not None and prev.get("x") is not None and prev2.get("x") is not None:
        d2 = offset(prev2)
        dx = prev["x"] - prev2["x"]
        if d2 is not None and dx != 0:
            d = d1 + (x - prev["x"]) / dx * (d1 - d2)
    start = d + (cold if cold is not None else zero)
    if not np.all(np.isfinite(start)):
        return None, cold
    return start, cold


def _run_point(task: dict, prev=None, prev2=None) -> dict:
    """Solve one point; never raises (failures are returned as records)."""
    from .equilibrium import EquilibriumError
    from .model import build_problem, solve

    t0 = time.perf_counter()
    rec = {
        "key": task["key"],
        "index": list(task["index"]),
        "settings": task["settings"],
        "x": task["x"],
        "status": "ok",
        "error": "",
        "start": "",
        "scalars": {},
        "u": None,
        "cold_base": None,
    }
    try:
        cfg = _base_config(task["base"]).replace(**task["settings"])
        problem = build_problem(cfg)
    except ValueError as exc:
        rec.update(status="invalid", error=str(exc))
        rec["elapsed_s"] = time.perf_counter() - t0
        return rec
    except Exception as exc:  # a bug, not the user's input: keep the sweep going, say what
        rec.update(status="invalid", error=f"{type(exc).__name__}: {exc}")
        rec["elapsed_s"] = time.perf_counter() - t0
        return rec
    start = None
    if task["warm_start"]:
        start, cold = _predict_start(cfg, problem, task["x"], prev, prev2)
        rec["cold_base"] = None if cold is None else [float(v) for v in cold]

    def message(exc):
        if isinstance(exc, EquilibriumError):
            return f"no equilibrium: {exc}"
        if isinstance(exc, ValueError):
            return str(exc)
        return f"{type(exc).__name__}: {exc}"

    result = None
    try:
        result = solve(cfg, start=start)
        rec["start"] = "cold" if start is None else "warm"
    except Exception as exc:
        if start is None:
            rec.update(status="failed", error=message(exc), start="cold")
        else:
            try:
                result = solve(cfg)
                rec["start"] = "cold-retry"
            except Exception as exc2:
                rec.update(status="failed", error=message(exc2), start="cold-retry")
    if result is not None:
        rec["scalars"] = dict(result.scalars)
        rec["u"] = [float(v) for v in result.solution.state.u]
    rec["elapsed_s"] = time.perf_counter() - t0
    return rec


# ---------------------------------------------------------------------------- state directory


class _State:
    """``PATH.parts/``: manifest.json plus one JSON per finished point, each written atomically."""

    def __init__(self, out: Path):
        self.dir = Path(str(out) + ".parts")
        self.manifest = self.dir / "manifest.json"

    def part_files(self) -> list[Path]:
        if not self.dir.is_dir():
            return []
        return [p for p in self.dir.glob("*.json") if p.name != "manifest.json" and not p.name.startswith(".")]

    def exists(self) -> bool:
        return self.manifest.exists() or bool(self.part_files())

    def clean_temporaries(self) -> None:
        if self.dir.is_dir():
            for p in self.dir.glob(".*"):
                if p.is_file():
                    p.unlink(missing_ok=True)

    def read_manifest(self) -> dict | None:
        try:
            return json.loads(self.manifest.read_text(encoding="utf-8"))
        except (OSError, ValueError):
            return None

    def begin(self, identity: str, spec: SweepSpec, n: int, options: dict) -> None:
        from .io import atomic_write_text

        self.dir.mkdir(parents=True, exist_ok=True)
        text = json.dumps(
            {"identity": identity, "cmpsim_version": __version__, "points": n, "options": options, "sweep_toml": spec.source},
            indent=1,
        )
        atomic_write_text(self.manifest, text + "\n")

    def load(self, keys: set[str]) -> dict[str, dict]:
        done = {}
        for p in self.part_files():
            try:
                rec = json.loads(p.read_text(encoding="utf-8"))
            except (OSError, ValueError):
                continue  # cannot happen with atomic writes; recomputed if it does
            if isinstance(rec, dict) and rec.get("key") in keys and p.stem == rec["key"]:
                done[rec["key"]] = rec
        return done

    def save(self, rec: dict) -> None:
        from .io import atomic_write_text

        atomic_write_text(self.dir / f"{rec['key']}.json", json.dumps(rec))

    def remove(self) -> None:
        shutil.rmtree(self.dir, ignore_errors=True)


# ---------------------------------------------------------------------------- progress


class _Progress:
    def __init__(self, enabled: bool, total: int, done: int, failed: int):
        self.enabled = enabled
        self.total, self.done, self.failed = total, done, failed
        self._p = None
        if enabled:
            from rich.console import Console
            from rich.progress import BarColumn, Progress, TextColumn, TimeElapsedColumn, TimeRemainingColumn

            self._p = Progress(
                TextColumn("sweep"),
                BarColumn(),
                TextColumn("{task.fields[done]} done, {task.fields[failed]} failed, {task.fields[left]} remaining"),
                TimeElapsedColumn(),
                TextColumn("ETA"),
                TimeRemainingColumn(),
                console=Console(stderr=True),
            )
            self._task = self._p.add_task("sweep", total=total, completed=done, **self._fields())

    def _fields(self):
        return {"done": self.done, "failed": self.failed, "left": self.total - self.done}

    def __enter__(self):
        if self._p is not None:
            self._p.start()
        return self

    def __exit__(self, *exc):
        if self._p is not None:
            self._p.stop()

    def advance(self, rec: dict) -> None:
        self.done += 1
        if rec["status"] != "ok":
            self.failed += 1
        if self._p is not None:
            self._p.update(self._task, advance=1, **self._fields())


# ---------------------------------------------------------------------------- dataset


def _scalar_keys(records: Iterable[dict]) -> list[str]:
    from .result import SCALARS

    keys = list(SCALARS)
    extra = sorted({k for r in records for k in r.get("scalars", {}) if k not in SCALARS})
    return keys + extra


def _coord_attrs(name: str) -> dict:
    p = PARAMETERS[name]
    attrs = {"long_name": p.description}
    if not _is_string_param(name):
        attrs["units"] = p.unit or "1"
        if p.display and p.display != p.unit:
            attrs["display_units"] = p.display
    return attrs


def _build_dataset(spec: SweepSpec, chains, records: dict[str, dict], identity: str, warm_start: bool, chain_length: int):
    import xarray as xr

    from .result import SCALARS

    shape = spec.shape
    dims = spec.dims
    recs = list(records.values())
    keys = _scalar_keys(recs)
    arrays: dict[str, np.ndarray] = {}
    for k in keys:
        if k in _INT_SCALARS:
            arrays[k] = np.full(shape, -1, dtype=np.int32)
        elif k in _BOOL_SCALARS:
            arrays[k] = np.zeros(shape, dtype=bool)
        else:
            arrays[k] = np.full(shape, np.nan, dtype=float)
    status = np.full(shape, "not_requested", dtype=object)
    error = np.full(shape, "", dtype=object)
    start = np.full(shape, "", dtype=object)
    counts = {"ok": 0, "failed": 0, "invalid": 0}
    for chain in chains:
        for p in chain:
            rec = records[p.key]
            idx = tuple(p.index)
            status[idx] = rec["status"]
            error[idx] = rec["error"]
            start[idx] = rec.get("start", "")
            counts[rec["status"]] = counts.get(rec["status"], 0) + 1
            for k, v in rec.get("scalars", {}).items():
                if v is None:
                    continue
                arrays[k][idx] = v
    data_vars = {}
    for k in keys:
        attrs = {}
        if k in SCALARS:
            unit, _, _, desc = SCALARS[k]
            attrs = {"units": unit, "long_name": desc}
        if k in _INT_SCALARS:
            attrs["comment"] = "-1 where status is not 'ok'"
        data_vars[k] = (dims, arrays[k], attrs)
    data_vars["status"] = (dims, status, {"long_name": "outcome of the point", "flag_meanings": "; ".join(f"{k}: {v}" for k, v in STATUS_MEANINGS.items())})
    data_vars["error"] = (dims, error, {"long_name": "error message ('' when ok)"})
    data_vars["start"] = (
        dims,
        start,
        {"long_name": "Newton start: warm (predicted from converged chain neighbours), cold, or cold-retry (the warm start failed)"},
    )
    coords = {}
    for d in dims:
        vals = spec.coords[d]
        arr = np.array(vals, dtype=object) if _is_string_param(d) else np.array(vals, dtype=float)
        coords[d] = (d, arr, _coord_attrs(d))
    ds = xr.Dataset(data_vars, coords=coords)
    ds.attrs.update(
        {
            "title": "cmpsim parameter sweep",
            "cmpsim_version": __version__,
            "config_toml": spec.base.to_toml_text(),
            "sweep_toml": spec.source,
            "sweep_id": identity,
            "points_requested": int(spec.n_points),
            "points_ok": int(counts.get("ok", 0)),
            "points_failed": int(counts.get("failed", 0)),
            "points_invalid": int(counts.get("invalid", 0)),
            "warm_start": int(bool(warm_start)),
            "chain_dimension": (spec.chain_dim or "") if warm_start else "",
            "chain_length": int(chain_length),
            "status_meanings": "; ".join(f"{k}: {v}" for k, v in STATUS_MEANINGS.items()),
        }
    )
    return ds


def _write(ds, out: Path) -> None:
    """Write the dataset atomically: NetCDF (scipy engine), or zarr for a ``.zarr`` path."""
    from .io import atomic_path

    if out.suffix == ".zarr":
        import tempfile

        out.parent.mkdir(parents=True, exist_ok=True)
        tmp = Path(tempfile.mkdtemp(prefix=f".{out.name}.", dir=out.parent))
        try:
            # Zarr format 2 with consolidated metadata: readable by zarr 2 and 3 alike
            ds.to_zarr(tmp / "store.zarr", mode="w", zarr_format=2)
            old = None
            if out.exists():
                old = out.parent / f".{out.name}.old-{uuid.uuid4().hex[:8]}"
                os.replace(out, old)
            os.replace(tmp / "store.zarr", out)
            if old is not None:
                shutil.rmtree(old, ignore_errors=True)
        finally:
            shutil.rmtree(tmp, ignore_errors=True)
        return
    with atomic_path(out, suffix=".nc") as tmp:
        ds.to_netcdf(tmp, engine="scipy")


def _check_out(out: Path) -> None:
    if out.suffix == ".zarr":
        try:
            import zarr  # noqa: F401
        except ImportError:
            raise SweepError(
                f"writing {str(out)!r} needs the zarr package, which is not installed; "
                "install it (pip install zarr) or give a NetCDF path (.nc)"
            ) from None


# ---------------------------------------------------------------------------- runners


def _payload(p: _PlanPoint, base_json: str, warm_start: bool) -> dict:
    return {"key": p.key, "index": list(p.index), "settings": p.settings, "x": p.x, "base": base_json, "warm_start": warm_start}


def _run_serial(chains, done, base_json, warm_start, on_result):
    for chain in chains:
        prev = prev2 = None
        for p in chain:
            rec = done.get(p.key)
            if rec is None:
                rec = _run_point(_payload(p, base_json, warm_start), prev, prev2)
                on_result(p, rec, True)
            prev2, prev = prev, rec


def _local_workers(requested: int | None, chains, done) -> int:
    busy = sum(1 for c in chains if any(p.key not in done for p in c))
    if requested is not None:
        return max(1, requested)
    try:
        cores = len(os.sched_getaffinity(0))
    except AttributeError:  # pragma: no cover - macOS / Windows
        cores = os.cpu_count() or 1
    return max(1, min(cores, busy))


def _run_dask(chains, done, base_json, warm_start, on_result, client):
    from distributed import as_completed

    tag = uuid.uuid4().hex[:10]
    futures = {}
    for chain in chains:
        prev = prev2 = None
        for p in chain:
            rec = done.get(p.key)
            if rec is None:
                flat = "-".join(map(str, p.index))
                fut = client.submit(
                    _run_point, _payload(p, base_json, warm_start), prev, prev2, key=f"cmpsim-point-{tag}-{flat}", retries=0
                )
                futures[fut] = p
                rec = fut
            prev2, prev = prev, rec
    try:
        for fut in as_completed(list(futures)):
            p = futures[fut]
            if fut.status == "finished":
                on_result(p, fut.result(), True)
            else:  # the worker died or the graph broke: report the point, do not persist it
                try:
                    exc = fut.exception()
                except Exception as e:  # pragma: no cover
                    exc = e
                rec = {
                    "key": p.key, "index": list(p.index), "settings": p.settings, "x": p.x, "status": "failed",
                    "error": f"not computed: the dask task failed ({type(exc).__name__}: {exc}); run again with --resume",
                    "start": "", "scalars": {}, "u": None, "cold_base": None,
                }
                on_result(p, rec, False)
    finally:
        pending = [f for f in futures if f.status == "pending"]
        if pending:
            client.cancel(pending)
        futures.clear()


# ---------------------------------------------------------------------------- API


def _as_spec(spec_or_path) -> SweepSpec:
    if isinstance(spec_or_path, SweepSpec):
        return spec_or_path
    if isinstance(spec_or_path, Mapping):
        return SweepSpec.from_mapping(spec_or_path)
    if isinstance(spec_or_path, (str, os.PathLike)):
        return SweepSpec.from_toml(spec_or_path)
    raise SweepError(f"sweep: expected a SweepSpec, a mapping or the path of a sweep file; got {type(spec_or_path).__name__}")


def sweep(
    spec_or_path,
    out=None,
    workers: int | None = None,
    scheduler=None,
    resume: bool = False,
    progress: bool = True,
    warm_start: bool = True,
    max_points: int = DEFAULT_MAX_POINTS,
    chain_length: int = DEFAULT_CHAIN_LENGTH,
    log: Callable[[str], None] | None = None,
):
    """Run a parameter sweep; returns an :class:`xarray.Dataset` (see the module docstring).

    Parameters
    ----------
    spec_or_path : SweepSpec, mapping or path
        The sweep (a sweep file, or its content as a mapping).
    out : path, optional
        Write the dataset there (NetCDF; zarr for a ``.zarr`` path) and keep the state of
        finished points in ``out + ".parts/"`` while running. Without it nothing is written
        and the sweep cannot be resumed.
    workers : int, optional
        Size of the local ``dask.distributed.LocalCluster`` (one single-threaded worker
        process each); default: the machine's cores (at most one per chain). ``0`` runs the
        points one after the other in this process, without dask.
    scheduler : str or distributed.Client, optional
        Address of an existing Dask scheduler (``tcp://host:8786``) or a connected Client;
        the points then run on that cluster (its workers need cmpsim installed).
    resume : bool
        Reuse the points saved in ``out + ".parts/"`` by an interrupted run of the same sweep.
    progress : bool
        Show a progress bar (rich) and messages on stderr.
    warm_start : bool
        Start Newton from a prediction made from converged neighbours (default) or always cold.
    max_points : int
        Refuse sweeps with more points than this (before any work).
    chain_length : int
        Longest run of points solved in sequence with warm starts (one cold start per run);
        a fixed layout, so results do not depend on the number of workers.
    log : callable, optional
        Receives the messages (resume status, interruption); default: stderr when
        ``progress`` is on, otherwise silent.

    Raises
    ------
    SweepError
        Bad sweep file or options, too many points, zarr missing, saved state of another
        sweep: always before any point is computed.
    """
    spec = _as_spec(spec_or_path)
    spec.check_size(max_points)
    if chain_length < 1:
        raise SweepError(f"chain_length must be >= 1; got {chain_length}")
    if workers is not None and workers < 0:
        raise SweepError(f"workers must be >= 0; got {workers}")
    if workers is not None and scheduler is not None:
        raise SweepError("give either workers (a local cluster) or scheduler (an existing cluster), not both")
    if log is None:
        if progress:
            import sys

            def log(msg):
                print(msg, file=sys.stderr, flush=True)
        else:

            def log(msg):
                pass

    identity = _identity(spec, warm_start, chain_length)
    chains = _plan(spec, identity, warm_start, chain_length)
    plan_points = [p for c in chains for p in c]
    n = len(plan_points)
    keys = {p.key for p in plan_points}
    state = None
    done: dict[str, dict] = {}
    if out is not None:
        out = Path(out)
        _check_out(out)
        state = _State(out)
        options = {"warm_start": bool(warm_start), "chain_length": int(chain_length)}
        if resume:
            if state.exists():
                man = state.read_manifest()
                if man is not None and man.get("identity") != identity:
                    raise SweepError(
                        f"the saved state in {state.dir} belongs to a different sweep (the sweep file, the cmpsim version "
                        "or the warm-start settings changed); delete that directory or choose another --out"
                    )
                done = state.load(keys)
                log(f"resumed: {len(done)} of {n} points already done")
            else:
                log(f"resume: no saved state in {state.dir}; starting from zero (0 of {n} points done)")
        elif state.part_files():
            raise SweepError(
                f"{state.dir} holds {len(state.part_files())} saved points of an interrupted sweep; "
                "run with --resume (resume=True) to finish it, or delete that directory to start over"
            )
        state.clean_temporaries()
        state.begin(identity, spec, n, options)
    elif resume:
        raise SweepError("resume needs an output path (out=...): the saved state lives next to it")

    records: dict[str, dict] = dict(done)
    base_json = json.dumps(spec.base.to_sections())
    n_failed = sum(1 for r in done.values() if r["status"] != "ok")
    all_persisted = True
    n_saved = len(done)
    bar = _Progress(progress, n, len(done), n_failed)

    def on_result(p, rec, persist):
        nonlocal all_persisted, n_saved
        if persist and state is not None:
            state.save(rec)
            n_saved += 1
        elif not persist:
            all_persisted = False
        records[p.key] = rec
        bar.advance(rec)

    missing = n - len(done)
    try:
        with bar:
            if missing == 0:
                pass
            elif scheduler is None and workers == 0:
                _run_serial(chains, done, base_json, warm_start, on_result)
            else:
                _with_client(scheduler, workers, chains, done, lambda c: _run_dask(chains, done, base_json, warm_start, on_result, c))
    except KeyboardInterrupt:
        if state is not None:
            log(f"interrupted: {n_saved} of {n} points saved in {state.dir}; run again with --resume to finish")
        raise
    ds = _build_dataset(spec, chains, records, identity, warm_start, chain_length)
    if out is not None:
        _write(ds, out)
        if all_persisted:
            state.remove()
        else:
            log(f"some points were not computed (dask task failures); {state.dir} is kept: run again with --resume")
    return ds


def local_cluster(n_workers: int):
    """The ``distributed.LocalCluster`` a sweep uses: ``n_workers`` single-threaded processes.

    Two departures from the Dask defaults, both for the worker processes only:

    * they ignore SIGINT, so that a Ctrl-C in the terminal (sent to the whole process group)
      reaches only the calling process, which saves its state and closes the cluster cleanly
      instead of the workers dying with tracebacks;
    * they keep glibc's default malloc trimming. Dask sets ``MALLOC_TRIM_THRESHOLD_=65536``
      for its workers, which also switches off glibc's dynamic mmap threshold: every large
      numpy temporary of the solver is then mapped and unmapped again, and a point took
      20-30 % longer in a worker than in the calling process (measured on the fine grid).
      A value set by the user (environment or Dask configuration) is respected.
    """
    import dask
    from distributed import LocalCluster

    cfg = {}
    key = "distributed.nanny.pre-spawn-environ"
    if "MALLOC_TRIM_THRESHOLD_" not in os.environ and str((dask.config.get(key, {}) or {}).get("MALLOC_TRIM_THRESHOLD_")) == "65536":
        cfg[key + ".MALLOC_TRIM_THRESHOLD_"] = None
    with dask.config.set(cfg), _sigint_ignored():
        return LocalCluster(
            n_workers=n_workers,
            threads_per_worker=1,
            processes=True,
            dashboard_address=None,
            silence_logs=logging.ERROR,
        )


@contextlib.contextmanager
def _sigint_ignored():
    """Ignore SIGINT while worker processes are spawned (they keep ignoring it)."""
    import signal
    import threading

    if threading.current_thread() is not threading.main_thread():
        yield
        return
    old = signal.signal(signal.SIGINT, signal.SIG_IGN)
    try:
        yield
    finally:
        signal.signal(signal.SIGINT, old)


def _with_client(scheduler, workers, chains, done, fn):
    from distributed import Client

    if scheduler is not None and not isinstance(scheduler, str):
        return fn(scheduler)  # a connected Client: used as is, not closed
    if scheduler is not None:
        try:
            client = Client(scheduler, timeout="20s")
        except Exception as exc:
            raise SweepError(f"cannot connect to the Dask scheduler at {scheduler!r}: {exc}") from None
        try:
            return fn(client)
        finally:
            client.close()
    cluster = local_cluster(_local_workers(workers, chains, done))
    try:
        client = Client(cluster)
        try:
            return fn(client)
        finally:
            client.close()
    finally:
        cluster.close()


# ---------------------------------------------------------------------------- reporting


def summary_lines(ds) -> list[str]:
    """Human summary of a sweep dataset: outcome counts and what the warm start saved."""
    status = ds["status"].values.ravel()
    n = int(ds.attrs.get("points_requested", np.count_nonzero(status != "not_requested")))
    lines = [
        f"{n} points: {np.count_nonzero(status == 'ok')} ok, {np.count_nonzero(status == 'failed')} failed, "
        f"{np.count_nonzero(status == 'invalid')} invalid"
    ]
    start = ds["start"].values.ravel()
    ok = status == "ok"
    warm = ok & (start == "warm")
    cold = ok & (start == "cold")
    if warm.any() and cold.any():
        it = ds["iterations"].values.ravel()
        fa = ds["factorizations"].values.ravel()
        lines.append(
            f"warm start: {np.count_nonzero(warm)} points started from converged neighbours: "
            f"{it[warm].mean():.2f} Newton iterations and {fa[warm].mean():.2f} pressure solves per point, "
            f"against {it[cold].mean():.2f} and {fa[cold].mean():.2f} for the {np.count_nonzero(cold)} cold-started "
            f"points (~{100 * (1 - fa[warm].mean() / fa[cold].mean()):.0f}% fewer pressure solves; an estimate over "
            "different points, --no-warm-start gives the exact cold cost)"
        )
    retry = np.count_nonzero(start == "cold-retry")
    if retry:
        lines.append(f"{retry} warm starts failed and were solved again from the cold start")
    return lines
