"""The sweep file: its validation into a :class:`SweepSpec` (axes and points in SI) and its layout.

Every problem of a sweep file (unknown setting, wrong unit dimension, empty axis, ...) raises
:class:`SweepError` here, before any point is computed.
"""

from __future__ import annotations

import dataclasses
import itertools
import json
import math
import tomllib
from dataclasses import dataclass
from functools import cached_property
from pathlib import Path
from typing import Any, Iterable, Mapping

import numpy as np

from ..inputs import units
from ..inputs.config import PARAMETERS, Config, parse_value
from ..inputs.param import did_you_mean

__all__ = ["Axis", "SweepSpec", "SweepError", "DEFAULT_MAX_POINTS"]

#: Largest number of points a sweep may have unless ``max_points`` says otherwise.
DEFAULT_MAX_POINTS = 10_000
#: Largest ``num`` of one range: more values than any sweep runs (each is 8 bytes before the size check).
_MAX_RANGE_NUM = 10_000_000
_SECTIONS = ("wafer", "process", "slurry", "pad", "numerics")


class SweepError(ValueError):
    """A bad sweep file or sweep option; raised before any point is computed."""


def _unknown(name: str) -> str:
    """The hint after "unknown setting NAME": close names, and where the names are listed."""
    return f"{did_you_mean(name, PARAMETERS)} (see `cmpsim params` for the names)"


def _is_string_param(name: str) -> bool:
    p = PARAMETERS[name]
    return bool(p.choices) or p.unit == "grid"


def _si_value(name: str, value: Any, where: str) -> Any:
    """SI value of one swept value, checking the name, type and unit dimension but not the range.

    Out-of-range values are kept: the point is then recorded as ``invalid`` with the
    message of :func:`cmpsim.inputs.config.parse_value`, not dropped and not fatal.
    """
    if name not in PARAMETERS:
        raise SweepError(f"{where}: unknown setting {name!r}{_unknown(name)}")
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
    try:
        v = units.to_si(value, p.unit, name, example=p.display)
    except ValueError as exc:
        raise SweepError(f"{where}: {exc}") from None
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
        raise SweepError(f"{where}: unknown setting {name!r} in [axes]{_unknown(name)}")
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
        if num > _MAX_RANGE_NUM:
            raise SweepError(f"{w}: num = {num} is more values than a sweep runs (at most {DEFAULT_MAX_POINTS} points by default, "
                             f"--max-points / max_points=); num must be <= {_MAX_RANGE_NUM}")
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
    _refuse_repeats(values, w, isinstance(spec, dict))
    return Axis(name, values)


def _refuse_repeats(values: tuple, w: str, is_range: bool) -> None:
    """SweepError if a value of an axis appears twice (equal to 1e-12 relative, as :func:`_same`);
    sorted neighbours are compared, so a range of a million values is checked in a second, not hours."""
    keyed = sorted(values, key=lambda v: (isinstance(v, str), v if isinstance(v, str) else float(v)))
    for a, b in zip(keyed, keyed[1:]):
        if isinstance(a, str) == isinstance(b, str) and _same(a, b):
            hint = " (a range whose start equals its stop gives one value: use num = 1)" if is_range else ""
            raise SweepError(f"{w}: the value {b!r} appears twice (after conversion to SI){hint}")


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
        from ..io import read_text

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
            if k == "preset":  # `preset = "paper"`: the base starts from that preset (Config.from_mapping)
                if not isinstance(v, str):
                    raise SweepError(f"{where}: [base] preset must be a preset name (a string); got {v!r}")
            elif k in _SECTIONS and isinstance(v, Mapping):
                for kk in v:
                    if kk not in PARAMETERS:
                        raise SweepError(f"{where}: unknown setting {kk!r} in [base.{k}]{_unknown(kk)}")
            elif k not in PARAMETERS:
                near = did_you_mean(k, _SECTIONS) if isinstance(v, Mapping) else ""
                raise SweepError(f"{where}: unknown setting {k!r} in [base]{near or _unknown(k)}")
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
