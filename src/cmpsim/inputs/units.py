"""Units: the one place where a value with units becomes an SI float, and an SI float a display value.

Inputs may be strings with units (``"4 psi"``, ``"60rpm"``, ``"100nm"``), pint Quantities, or
plain numbers, which are taken as SI. Everything past this module carries SI floats.

* :func:`parse`: an input described by an entry of the parameter registry
  (:data:`cmpsim.inputs.config.PARAMETERS`) to its SI value, checking the unit dimension and the
  valid range (``Config`` uses it for every value it accepts, through
  ``cmpsim.inputs.config.parse_value``, which looks the name up and passes the entry in).
* :func:`to_display`: an SI value of a parameter in its display unit (tables, the CLI).

The dependency runs one way: ``cmpsim.inputs.config`` imports this module, never the reverse; the
functions that take a parameter are handed its registry entry.
* :func:`to_si` and :func:`convert`: any quantity given its unit (values of data files,
  sliding speeds, sweep axes before their range is checked, the paper's psi and rpm grids).

There is one pint registry (:func:`registry`), created on first use: ``import cmpsim`` does
not import pint.
"""

from __future__ import annotations

from functools import lru_cache
from typing import Any

__all__ = ["registry", "parse", "parse_list", "to_display", "format_display", "to_si", "convert", "unit_text"]

#: Unit spellings found in data files that pint does not read as meant.
ALIASES = {"a/min": "angstrom/minute", "å/min": "angstrom/minute", "a/s": "angstrom/second", "å/s": "angstrom/second", "%": "percent", "-": "dimensionless", "1": "dimensionless", "": "dimensionless"}


@lru_cache(maxsize=1)
def registry():
    """The pint ``UnitRegistry`` of cmpsim (one per process)."""
    import pint

    return pint.UnitRegistry()


def unit_text(text: str) -> str:
    """A unit as written in a data file, in pint's spelling (``"%"`` -> ``"percent"``)."""
    t = text.strip()
    return ALIASES.get(t.lower(), t)


def to_si(value: Any, unit: str, name: str = "value", example: str | None = None) -> float:
    """``value`` as a float in ``unit`` (an SI unit, pint syntax; ``""`` for dimensionless).

    ``value`` is a string with units, a pint Quantity, or a number (taken as already in
    ``unit``). Raises ``ValueError`` naming ``name`` when the text is not a quantity or has
    the wrong dimension (``example``: a unit to suggest, default ``unit``). No range check.
    """
    if isinstance(value, bool):
        raise ValueError(f"{name} must be a number with units of {unit or 'none'}; got {value!r}")
    if isinstance(value, (int, float)):
        return float(value)
    try:
        q = registry().Quantity(value) if isinstance(value, str) else value
    except Exception as exc:  # pint raises several error types for bad strings
        raise ValueError(f"{name}: cannot read {value!r} as a quantity ({exc}); expected units of {unit or 'none (dimensionless)'}") from None
    if not hasattr(q, "to"):
        try:
            return float(q)
        except (TypeError, ValueError):
            raise ValueError(f"{name} must be a number with units of {unit or 'none'}; got {value!r}") from None
    target = unit or "dimensionless"
    try:
        return float(q.to(target).magnitude)
    except Exception:
        raise ValueError(
            f"{name}: {value!r} has the wrong dimension; expected units convertible to {target!r} (e.g. {example or target})"
        ) from None


def convert(value: float, unit: str, to: str) -> float:
    """``value`` given in ``unit`` expressed in ``to`` (both pint syntax or data-file spellings)."""
    return float(registry().Quantity(float(value), unit_text(unit)).to(unit_text(to)).magnitude)


def _entry(param):
    if isinstance(param, str):
        raise TypeError(
            f"cmpsim.inputs.units takes a parameter entry (cmpsim.inputs.config.PARAMETERS[{param!r}]), not its name; "
            "by name use cmpsim.inputs.config.parse_value, to_display or format_display"
        )
    return param


def parse(param, value: Any) -> Any:
    """The SI value of the input described by ``param``, checking the unit dimension and the valid range.

    ``param`` is an entry of the parameter registry (a :class:`cmpsim.inputs.param.Param`: its
    ``name``, SI ``unit``, ``display`` unit, ``choices`` and ``check``); the registry lives
    with the ``Config`` and passes its entries in, so this module never imports it.
    ``value`` may be a string with units (``"4 psi"``), a pint Quantity, or a number (taken
    as SI, not re-parsed). Choices and the grid are strings, checked against their options.
    Raises ``ValueError`` naming the parameter and its valid range.
    """
    p = _entry(param)
    if getattr(p, "items", False):
        return p.check(parse_list(value, p.unit, p.name, example=p.display))
    if p.choices or p.unit == "grid" or (isinstance(value, (int, float)) and not isinstance(value, bool)):
        return p.check(value)
    return p.check(to_si(value, p.unit, p.name, example=p.display))


def parse_list(value: Any, unit: str, name: str = "value", example: str | None = None) -> tuple[float, ...]:
    """A list input as a tuple of floats in ``unit`` (SI); no range check.

    ``value`` is a string of comma-separated numbers and one unit after the last
    (``"3, 3, 3.5, 4, 2 psi"``; an item may carry its own unit: ``"50 mm, 0.1 m"``), an empty
    string for no items, or a sequence of numbers (taken as SI) or strings with units.
    Raises ``ValueError`` naming ``name`` when an item is not a quantity of the right dimension.
    """
    if isinstance(value, str):
        text = value.strip()
        if not text:
            return ()
        pieces = [q.strip() for q in text.split(",")]
        if any(not q for q in pieces):
            raise ValueError(f"{name}: {value!r} has an empty item; expected comma-separated numbers and one unit, e.g. '3, 3.5, 4 {example or unit}'")
        last = pieces[-1]
        number = last.split()[0] if last.split() else last
        trailing = last[len(number):].strip() if _is_number(number) else ""
        items = [q + (" " + trailing if trailing and _is_number(q) else "") for q in pieces[:-1]] + [last]
        return tuple(to_si(q if not _is_number(q) else float(q), unit, name, example) for q in items)
    if isinstance(value, (list, tuple)):
        return tuple(to_si(v, unit, name, example) for v in value)
    raise ValueError(f"{name} must be a list: comma-separated numbers and one unit (e.g. '3, 3.5, 4 {example or unit}'); got {value!r}")


def _is_number(text: str) -> bool:
    try:
        float(text)
    except ValueError:
        return False
    return True


def to_display(param, value: Any) -> Any:
    """SI value of the input described by ``param`` (a registry entry) in its display unit (strings unchanged)."""
    p = _entry(param)
    if isinstance(value, str) or not p.display or p.display == p.unit:
        return value
    if isinstance(value, (list, tuple)):
        return tuple(float(registry().Quantity(v, p.unit).to(p.display).magnitude) for v in value)
    return registry().Quantity(value, p.unit).to(p.display).magnitude


def format_display(param, value: Any) -> str:
    """SI value of the input described by ``param`` (a registry entry) as display text (6 significant digits)."""
    v = to_display(param, value)
    if isinstance(v, tuple):  # a list input: "3, 3.5, 4" ("" when unset)
        return ", ".join(f"{x:.6g}" for x in v)
    return v if isinstance(v, str) else f"{v:.6g}"
