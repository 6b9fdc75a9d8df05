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

import re
from functools import lru_cache
from typing import Any

from ..io import is_number

__all__ = ["placeholder_hint", "normalise_unit", "value_and_unit", "uncertainty_text", "read_value_cells", "registry", "parse", "parse_list", "to_display", "format_display", "to_si", "convert", "unit_text"]

#: Unit spellings found in data files that pint does not read as meant.
ALIASES = {"a/min": "angstrom/minute", "å/min": "angstrom/minute", "a/s": "angstrom/second", "å/s": "angstrom/second", "%": "percent", "-": "dimensionless", "1": "dimensionless", "": "dimensionless"}


#: Unit words of published CMP data, by their lower-case spelling, in pint's spelling. Read only when
#: pint cannot read a unit as written or reads it with the wrong dimension (:func:`normalise_unit`):
#: "A" and "Angstrom" (pint: ampere, unknown) are angstroms, "PSI", "RPM", "NM/MIN" upper-case,
#: "sec" and "hr" the second and the hour, "rev" and "r" a revolution.
UNIT_WORDS = {
    "a": "angstrom", "å": "angstrom", "ang": "angstrom", "angstrom": "angstrom", "angstroms": "angstrom",
    "ka": "kiloangstrom", "kå": "kiloangstrom",
    "nm": "nm", "um": "um", "µm": "um", "μm": "um", "mm": "mm", "cm": "cm", "m": "m", "micron": "micron", "microns": "micron",
    "in": "inch", "inch": "inch", "inches": "inch", "mil": "thou", "mils": "thou",
    "psi": "psi", "pa": "Pa", "kpa": "kPa", "mpa": "MPa", "hpa": "hPa", "bar": "bar", "mbar": "mbar",
    "rpm": "rpm", "rev": "revolution", "r": "revolution",
    "s": "second", "sec": "second", "secs": "second", "min": "minute", "mins": "minute", "h": "hour", "hr": "hour", "hrs": "hour",
    "ml": "mL", "l": "L", "k": "K",
}
#: Mass units that a pressure in kg/cm^2 or g/cm^2 means as a force (the weight of that mass).
_FORCE_WORDS = {"g": "gram_force", "gf": "gram_force", "kg": "kilogram_force", "kgf": "kilogram_force", "lb": "pound_force", "lbs": "pound_force"}
_WORD = re.compile(r"([A-Za-zµμÅå]+)(\^?-?[0-9]+)?")
_NUMBER = re.compile(r"^\s*([-+]?(?:[0-9]+\.?[0-9]*|\.[0-9]+)(?:[eE][-+]?[0-9]+)?)\s*(.*)$", re.S)


def normalise_unit(unit: str, pressure: bool = False) -> str:
    """A unit as written in a published table in pint's spelling, word by word (:data:`UNIT_WORDS`).

    ``"Angstrom/min"`` -> ``"angstrom/minute"``, ``"NM/MIN"`` -> ``"nm/minute"``, ``"A"`` -> ``"angstrom"``,
    ``"cm2"`` -> ``"cm^2"``, ``"nm min-1"`` -> ``"nm minute^-1"``; with ``pressure``, ``"g/cm2"`` ->
    ``"gram_force/cm^2"``. Words it does not know are kept. Used only after pint failed on the text as
    written, so a unit pint reads with the right dimension is never reinterpreted.
    """

    def word(m: re.Match) -> str:
        w = m.group(1)
        out = (_FORCE_WORDS.get(w.lower()) if pressure else None) or UNIT_WORDS.get(w.lower(), w)
        power = (m.group(2) or "").lstrip("^")
        return out + (f"^{power}" if power else "")

    return _WORD.sub(word, unit)


def value_and_unit(value: str, unit: str) -> tuple[str, str]:
    """A data file's value cell and unit cell as (number text, unit text): ``"150 nm/min"`` with an empty unit
    cell (or the same unit) gives ``("150", "nm/min")``; a number is returned unchanged.

    Raises ``ValueError`` when the cell's unit and the unit column disagree (the value is not guessed).
    """
    if _DIGIT_SEPARATOR.search(value):  # Python's float() reads "1_497" as 1497: a separator, refused as a comma is
        raise ValueError(f"{value!r} is not a number (a thousands separator? write the number with a decimal point and no separator)")
    m = _NUMBER.match(value)
    if not m or not m.group(2).strip():
        return value, unit
    inside = m.group(2).strip()
    if uncertainty_text(inside) != inside:  # "150 ± 10 nm/min": not guessed which unit the 10 is in, nor read as a number
        raise ValueError(f"{value!r} holds an uncertainty: give the value here and its uncertainty in the uncertainty column")
    if not (inside[0].isalpha() or inside[0] in "%°µμÅ"):  # "1,500" or "1.5.2": not a number and a unit; the reader says it is no number
        if inside[0] == "," and inside[1:2].isdigit():  # "1,500", "1,5 nm"
            raise ValueError(f"{value!r} is not a number (a thousands separator or a decimal comma? write the number with a decimal "
                             "point and no separator)")
        return value, unit
    if unit.strip() and inside.replace(" ", "").lower() != unit.replace(" ", "").lower():
        raise ValueError(f"{value!r} carries the unit {inside!r} but the unit column says {unit!r}; give the unit in one place")
    return m.group(1), inside


def read_value_cells(rec: dict) -> None:
    """A data row's ``value``, ``unit`` and ``uncertainty`` cells read in place: a value written with its unit
    (``"512 nm"``, the unit cell empty or the same), an uncertainty with its plus-minus sign (``"±4 nm"``, in
    the value's unit). ValueError ``column 'NAME': why``."""
    try:
        rec["value"], rec["unit"] = value_and_unit(rec.get("value", ""), rec.get("unit", ""))
    except ValueError as exc:
        raise ValueError(f"column 'value': {exc}") from None
    if rec.get("uncertainty"):
        try:
            rec["uncertainty"] = value_and_unit(uncertainty_text(rec["uncertainty"]), rec["unit"] or "(none)")[0]
        except ValueError as exc:
            raise ValueError(f"column 'uncertainty': {exc}") from None


def uncertainty_text(text: str) -> str:
    """An uncertainty cell without the plus-minus sign papers print before it (``"±10"``, ``"+/- 10"``, ``"+-10"``)."""
    return re.sub(r"^\s*(±|\+/-|\+-)\s*", "", text)


def _is_pressure(target: str) -> bool:
    try:
        return registry().Quantity(1.0, target or "dimensionless").dimensionality == registry().Quantity(1.0, "Pa").dimensionality
    except Exception:  # noqa: BLE001 - a target pint does not know is not a pressure
        return False


def _normalised_quantity(text: str, target: str):
    """``text`` (a number and a unit) as a pint Quantity with its unit normalised, or None if it still cannot be read."""
    m = _NUMBER.match(text)
    if not m or not m.group(2).strip():
        return None
    try:
        q = registry().Quantity(float(m.group(1)), normalise_unit(m.group(2).strip(), _is_pressure(target)))
        q.to(target or "dimensionless")
    except Exception:  # noqa: BLE001 - still not a quantity of the target's dimension
        return None
    return q


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
    if isinstance(value, str):
        return _text_to_si(value, unit, name, example)
    return _quantity_to_si(value, unit, name, example)


@lru_cache(maxsize=4096)
def _text_to_si(value: str, unit: str, name: str, example: str | None) -> float:
    """:func:`to_si` of a text, remembered: a data file's column repeats a few texts over thousands of rows, and pint
    parses each in about 0.2 ms."""
    _refuse_misread(value, name)
    return _quantity_to_si(value, unit, name, example)


def _quantity_to_si(value: Any, unit: str, name: str, example: str | None) -> float:
    """:func:`to_si` of a text or a pint Quantity."""
    try:
        q = registry().Quantity(value) if isinstance(value, str) else value
    except Exception as exc:  # pint raises several error types for bad strings
        fixed = _normalised_quantity(value, unit) if isinstance(value, str) else None
        if fixed is None:
            raise ValueError(f"{name}: cannot read {value!r} as a quantity ({exc}); expected units of {unit or 'none (dimensionless)'}") from None
        q = fixed
    if not hasattr(q, "to"):
        try:
            return float(q)
        except (TypeError, ValueError):
            raise ValueError(f"{name} must be a number with units of {unit or 'none'}; got {value!r}") from None
    target = unit or "dimensionless"
    try:
        out = float(q.to(target).magnitude)
    except Exception:
        fixed = _normalised_quantity(value, unit) if isinstance(value, str) else None
        if fixed is not None:
            _check_angle(fixed, target, name, value)
            return float(fixed.to(target).magnitude)
        if isinstance(value, str) and is_number(value.strip()):
            raise ValueError(f"{name}: {value!r} has no unit (the wrong dimension for units of {target!r}); write it with its unit "
                             f"(e.g. '{value.strip()} {example or target}')") from None
        raise ValueError(
            f"{name}: {value!r} has the wrong dimension; expected units convertible to {target!r} (e.g. {example or target})"
        ) from None
    _check_angle(q, target, name, value)
    return out


#: Typographic minus signs and dashes that ``float`` refuses and pint drops ("\u22123 psi" read as 3 psi).
_MINUS_SIGNS = "\u2212\u2013\u2014\u2012\ufe63\uff0d"
#: A digit separator between digits ("1_497"), which ``float`` and pint read as if absent.
_DIGIT_SEPARATOR = re.compile(r"[0-9]_[0-9]")

#: Cells that stand for "no value" in spreadsheets and papers (lower case): refused with :func:`placeholder_hint`.
PLACEHOLDERS = ("-", "--", "\u2013", "\u2014", "n/a", "na", "n.a.", "none", "null", "?", "nd", "n.d.")


def placeholder_hint(text: str) -> str:
    """" (... leave the cell empty ...)" for a cell that stands for no value (``-``, ``n/a``), " (... written '-')" for
    a number with a typographic minus (``\u22121.5``, which ``float`` refuses); "" for any other text."""
    if text.strip().lower() not in PLACEHOLDERS:
        return " (its minus sign is typographic: write '-')" if text.strip()[:1] in _MINUS_SIGNS and text.strip()[1:] else ""
    return (f" ({text.strip()!r} stands for no value: leave the cell empty where the column is optional and the value not known, "
            "or leave out the row)")


#: Characters besides letters, digits and spaces that a quantity's text may hold (operators, a unit's marks).
_QUANTITY_MARKS = ".+-*/^()%_\u00b0\u00b7\u00d7\u207b\u22c5,:\u00b1'"


_CLOCK = re.compile(r"^\s*\d+(:\d+){1,2}(\.\d*)?\s*$")


#: A unit word's power (``cm2``, ``m^3``, ``min-1``, ``s**-1``) or a leading ``1/``: the digits a unit may hold.
_UNIT_POWER = re.compile(r"(?<=[A-Za-zµμÅå°%)])(\^|\*\*)?-?[0-9]+|^1\s*/")


def _refuse_misread(text: str, name: str) -> None:
    """ValueError for a quantity pint would read other than as written: with a comma (``"3,5 psi"``, ``"1,500 nm"``:
    pint drops it and reads 35 psi, 1500 nm; a decimal comma or a thousands separator is not guessed), with a second
    number (``"93/87 rpm"``, a platen and a head speed, read as 1.07 rpm; ``"34 500 Pa"`` read as 34 x 500 Pa;
    ``"2 3 psi"``), a time written as a clock (``"1:30"``: minutes and seconds, or hours and minutes?), and a cell
    that stands for no value (``"-"``), and a character pint's tokenizer drops without a word (a typographic minus or
    dash: ``"\u22123 psi"`` read as 3 psi; a bound or an approximation: ``"<5 psi"``, ``"~5 psi"`` read as 5 psi)."""
    dropped = next((c for c in text if not (c.isalnum() or c.isspace() or c in _QUANTITY_MARKS)), None)
    if dropped is not None and text.strip().lower() not in PLACEHOLDERS:
        why = ("a minus sign is written '-'" if dropped in _MINUS_SIGNS else
               "a bound or an approximate value is not a value: write the number itself" if dropped in "<>~\u2248\u2264\u2265\u2272\u2273" else
               "write one number and its unit")
        raise ValueError(f"{name}: {text!r} holds the character {dropped!r} (U+{ord(dropped):04X}), which the unit parser would drop "
                         f"without a word ('\u22123 psi' would read as 3 psi, '<5 psi' as 5 psi); {why}")
    if not text.strip():  # `--set applied_pressure=` or `x = ""`: pint says "cannot be an empty string"
        raise ValueError(f"{name} is empty; give a value with its unit")
    if "," in text or _DIGIT_SEPARATOR.search(text):
        raise ValueError(f"{name}: {text!r} has a {'comma' if ',' in text else 'digit separator'}: a decimal comma ('3,5') or a thousands separator ('1,500') is not read "
                         "(it would be dropped: '3,5 psi' read as 35 psi); write the number with a decimal point and no separator "
                         "('3.5 psi', '1500 nm')")
    if placeholder_hint(text):  # pint's message for "-" is "()"
        raise ValueError(f"{name}: {text!r} is not a quantity{placeholder_hint(text)}")
    if _CLOCK.match(text):  # "1:30": pint reads a ratio of 1 and 30
        raise ValueError(f"{name}: {text!r} is written as a clock (minutes:seconds? hours:minutes?), which is not guessed; "
                         "write one number with its unit ('90 s', '1.5 min')")
    m = _NUMBER.match(text)
    if m and any(c in "0123456789" for c in _UNIT_POWER.sub("", m.group(2))):  # pint multiplies or divides the numbers
        raise ValueError(f"{name}: {text!r} holds more than one number (two settings such as a platen and a head speed, a range, "
                         "a thousands separator written as a space?), which pint would multiply or divide; write one number and its unit")


#: Words of pint's angle units: a rotation speed must name one (``rpm``, ``rad/s``, ``deg/s``, ``rev/min``).
_ANGLE_WORDS = ("radian", "revolution", "degree", "turn", "cycle", "arcminute", "arcsecond", "gradian")


def _check_angle(q, target: str, name: str, value) -> None:
    """Refuse a rotation speed given as a bare frequency (``60 1/min``, ``1 Hz``): pint's radian is
    dimensionless, so it would be read as radians per time, 2 pi times slower than the revolutions it usually means."""
    if not (target.startswith("rad/") and hasattr(q, "units")):  # an angular velocity only (an angle may be a plain number)
        return
    if not any(w in str(q.units) for w in _ANGLE_WORDS):
        raise ValueError(f"{name}: {value!r} is a frequency without an angle (revolutions or radians per time?); "
                         "write rpm (revolutions per minute), rev/s or rad/s")


def convert(value: float, unit: str, to: str) -> float:
    """``value`` given in ``unit`` expressed in ``to`` (both pint syntax or data-file spellings).

    A ``unit`` pint cannot read, or reads with a dimension other than ``to``'s, is read once more
    word by word (:func:`normalise_unit`: ``"Angstrom/min"``, ``"NM/MIN"``, ``"A"`` for a length);
    if that fails too, pint's error on the unit as written is raised.
    """
    source, target = unit_text(unit), unit_text(to)
    try:
        return float(registry().Quantity(float(value), source).to(target).magnitude)
    except Exception:
        # either side may be a data file's spelling: the unit of a value, or the unit to report it in
        for tgt in (target, normalise_unit(target, _is_pressure(source))):
            for src in (source, normalise_unit(source, _is_pressure(tgt))):
                try:
                    return float(registry().Quantity(float(value), src).to(tgt).magnitude)
                except Exception:  # noqa: BLE001 - the next spelling; pint's error on the units as written if none reads
                    continue
        raise


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
        trailing = last[len(number):].strip() if is_number(number) else ""
        items = [q + (" " + trailing if trailing and is_number(q) else "") for q in pieces[:-1]] + [last]
        return tuple(to_si(q if not is_number(q) else float(q), unit, name, example) for q in items)
    if isinstance(value, (list, tuple)):
        return tuple(to_si(v, unit, name, example) for v in value)
    raise ValueError(f"{name} must be a list: comma-separated numbers and one unit (e.g. '3, 3.5, 4 {example or unit}'); got {value!r}")



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
