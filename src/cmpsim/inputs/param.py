"""One input of the parameter registry (:data:`cmpsim.inputs.config.PARAMETERS`): where it lives,
its SI and display units, default, valid range and source, and the check of a value.

A value reaches :meth:`Param.check` in SI (:mod:`cmpsim.inputs.units` converts text with units);
a value out of range raises ``ValueError`` naming the input and its valid range.
"""

from __future__ import annotations

import dataclasses
import math
from dataclasses import dataclass
from typing import Any

from . import units
from ..numerics.grid import GRID_PRESETS

__all__ = ["Param", "did_you_mean"]


def did_you_mean(name: str, names) -> str:
    """"; did you mean X?" naming the entries of ``names`` close to a misspelt ``name`` ("" when none is close)."""
    import difflib

    near = difflib.get_close_matches(str(name), [str(n) for n in names], n=3)
    return f"; did you mean {', '.join(near)}?" if near else ""


@dataclass(frozen=True)
class Param:
    """One input: where it lives, its unit, default, valid range and source."""

    name: str
    section: str
    symbol: str
    unit: str  # SI unit (pint syntax); "" dimensionless; "choice" / "grid" for strings
    display: str  # unit used in tables and the CLI
    default: Any
    description: str
    source: str
    low: float | None = None  # None = unbounded
    high: float | None = None
    low_open: bool = True
    high_open: bool = True
    choices: tuple[str, ...] = ()
    items: bool = False  # a list input: comma-separated numbers and one unit; stored as a tuple of SI floats
    #: Typical magnitude (SI) of a value a calibration may find: the scale of its fit variable when it
    #: starts at 0, and the span of its default bounds (None: from the start value).
    typical: float | None = None
    #: The outputs are linear in this input (film chemistry): a calibration fits it linearly, never in log.
    linear: bool = False

    def range_text(self) -> str:
        """Human-readable valid range, in SI."""
        if self.items:
            return "a list of numbers, each in " + dataclasses.replace(self, items=False).range_text()
        if self.choices:
            return "one of " + ", ".join(repr(c) for c in self.choices)
        if self.unit == "grid":
            return "'coarse', 'default', 'fine' or 'NRxNT' (rings x sectors, NR >= 3, NT even >= 8)"
        lo = "-inf" if self.low is None else f"{self.low:g}"
        hi = "inf" if self.high is None else f"{self.high:g}"
        lb = "(" if (self.low is None or self.low_open) else "["
        hb = ")" if (self.high is None or self.high_open) else "]"
        unit = f" {self.unit}" if self.unit else ""
        return f"{lb}{lo}, {hi}{hb}{unit}"

    def check(self, value: Any) -> Any:
        """``value`` if valid (an SI number, or the text of a choice or grid); ``ValueError`` naming the range if not."""
        if self.choices:
            text = str(value).strip()
            if text not in self.choices:
                raise ValueError(f"{self.name} must be {self.range_text()}; got {value!r}")
            return text
        if self.unit == "grid":
            return _parse_grid(value, self.range_text())
        if self.items:  # each value in the range of one item
            item = dataclasses.replace(self, items=False)
            return tuple(_check_range(item, v) for v in value)
        return _check_range(self, value)

    def display_range_text(self) -> str:
        """Human-readable valid range, in the display unit (``cmpsim params``)."""
        if self.items:
            return "a list of numbers, each in " + dataclasses.replace(self, items=False).display_range_text()
        if self.choices or self.unit == "grid" or not self.display or self.display == self.unit:
            return self.range_text()
        lo = "-inf" if self.low is None else f"{units.to_display(self, self.low):.6g}"
        hi = "inf" if self.high is None else f"{units.to_display(self, self.high):.6g}"
        lb = "(" if (self.low is None or self.low_open) else "["
        hb = ")" if (self.high is None or self.high_open) else "]"
        return f"{lb}{lo}, {hi}{hb} {self.display}"


def _check_range(p: Param, v: float) -> float:
    """``v`` as a float in the range of ``p`` (an int for max_iterations); ``ValueError`` naming the range if not."""
    if isinstance(v, bool) or not isinstance(v, (int, float)) or math.isnan(v) or math.isinf(v):
        raise ValueError(f"{p.name} must be a finite number; valid range {p.range_text()}; got {v!r}")
    if p.low is not None and (v < p.low or (p.low_open and v == p.low)):
        raise ValueError(f"{p.name} = {v:g} {p.unit} is out of range: valid range {p.range_text()}")
    if p.high is not None and (v > p.high or (p.high_open and v == p.high)):
        raise ValueError(f"{p.name} = {v:g} {p.unit} is out of range: valid range {p.range_text()}")
    if p.name == "max_iterations":
        if int(v) != v:
            raise ValueError(f"max_iterations must be an integer; valid range {p.range_text()}")
        return int(v)
    return float(v)


def _parse_grid(value: Any, range_text: str) -> str:
    """A grid input as stored: a named grid of :data:`cmpsim.numerics.grid.GRID_PRESETS` or ``'NRxNT'``; ``range_text`` is the grid input's valid range."""
    s = str(value).strip().lower().replace(" ", "")
    if s in GRID_PRESETS:
        return s
    parts = s.split("x")
    ok = len(parts) == 2 and all(q.isdigit() for q in parts)
    if ok:
        nr, nt = int(parts[0]), int(parts[1])
        ok = nr >= 3 and nt >= 8 and nt % 2 == 0
    if not ok:
        raise ValueError(f"grid must be {range_text}; got {value!r}")
    return f"{nr}x{nt}"
