"""Measurements of test structures and of the pad's temperature: the CSV format and its reader.

The files use the format of ``cmpsim validate`` (``cmpsim/data/README.md``): a block of
``# key: value`` comment lines (``dataset``, ``kind``, ``citation``, ``provenance``,
``uncertainty``, ``note``, ...), a header row, one row per measured point. Two families of
quantities are read here (docs/calibrate-die.md):

**Test structures** (``quantity`` = ``dishing``, ``erosion`` or ``step_height``, lengths):

| column | required | meaning |
|---|---|---|
| ``process`` | yes | ``copper`` or ``oxide`` (the die model's film stack) |
| ``line_width`` | yes | width of the lines, with units (``0.25 um``) |
| ``line_space`` | no | space between the lines; empty: an isolated line in a field |
| ``structure_size`` | no | side of the square block of lines; empty: larger than the planarization length |
| ``time`` | no | polish time of the step from its start (``92 s``); empty: the structure's end point |
| ``blanket_rate`` | no | blanket removal rate of the step (``15.9 nm/s``); needed with ``time`` unless a configuration is given |
| ``applied_pressure`` | no | the step's pressure (the pad body's bulge into a gap grows with it); default the configuration's |
| any input of :data:`cmpsim.die.DIE_PARAMETERS` | no | the film thicknesses (``copper_thickness``, ``trench_depth``, ``barrier_thickness``, ``step_height``) and other die inputs of the point |

**The pad's temperature** (``quantity`` = ``pad_temperature_rise`` (K, rise of the pad surface
above its start) or ``friction_coefficient`` (1, frictional power over pressure times the
wafer-mean sliding speed)): ``time`` (s, required for a temperature), the operating conditions as
cmpsim parameter columns (``applied_pressure``, ``wafer_diameter``, ``centre_distance``,
``rotation_speed`` or ``sliding_speed``, ...) and ``slurry_flow_rate`` (``175 mL/min``).

Common columns: ``dataset``, ``quantity``, ``value``, ``unit``, ``uncertainty`` (one standard
uncertainty, in ``unit``), ``source``, ``label``, ``note``. A file that cannot be used is refused
with a :class:`MeasurementError` naming the file, the row (its line number) and the column.
"""

from __future__ import annotations

import csv
import math
from dataclasses import dataclass, field
from pathlib import Path

__all__ = ["MeasurementError", "StructureRecord", "ThermalRecord", "read_measurements", "read_polish_time", "STRUCTURE_QUANTITIES",
           "THERMAL_QUANTITIES", "shipped_measurement_paths"]

#: Test-structure quantities: name -> (SI unit, meaning).
STRUCTURE_QUANTITIES = {
    "dishing": ("m", "copper: depth of the line below the cleared field at the block's centre"),
    "erosion": ("m", "copper: field oxide lost below its original top at the block's centre"),
    "step_height": ("m", "oxide: step between the oxide over the lines and over the spaces at the block's centre"),
}
#: Pad quantities: name -> (SI unit, meaning).
THERMAL_QUANTITIES = {
    "pad_temperature_rise": ("K", "rise of the pad surface temperature above its value at the start of the step"),
    "friction_coefficient": ("", "frictional power per area over (applied pressure x wafer-mean sliding speed)"),
}
_COMMON = ("dataset", "quantity", "value", "unit", "uncertainty", "source", "label", "note", "comparison")
_STRUCTURE_COLUMNS = ("process", "line_width", "line_space", "structure_size", "time", "blanket_rate")
_THERMAL_EXTRA = {"time": "s", "slurry_flow_rate": "m^3/s", "sliding_speed": "m/s"}


class MeasurementError(ValueError):
    """A measurement file that cannot be used; the message names the file, the row (line) and the column."""


@dataclass(frozen=True, kw_only=True)
class _Provenance:
    """Where a record comes from: its data set, file line, source, label and file."""

    dataset: str = ""
    line: int = 0
    source: str = ""
    label: str = ""
    path: str = ""

    @property
    def where(self) -> str:
        return f"{self.path}:{self.line}" if self.path else f"row {self.line}"


@dataclass(frozen=True)
class StructureRecord(_Provenance):
    """One measured test structure (SI): the quantity, its value and standard uncertainty (m), the structure and the step."""

    quantity: str
    value: float
    uncertainty: float | None
    process: str
    line_width: float
    line_space: float | None = None  # None: an isolated line in a field
    structure_size: float | None = None  # None: larger than the planarization length
    time: float | None = None  # None: at the structure's end point
    blanket_rate: float | None = None  # m/s
    inputs: dict = field(default_factory=dict)  # die inputs of the point (SI), e.g. copper_thickness

    @property
    def density(self) -> float:
        """Line density of the block, w / (w + s); an isolated line: 0 (a field)."""
        return 0.0 if self.line_space is None else self.line_width / (self.line_width + self.line_space)


@dataclass(frozen=True)
class ThermalRecord(_Provenance):
    """One measured pad quantity (SI) at ``time`` (s) under ``conditions`` (cmpsim parameter -> text with units)."""

    quantity: str
    value: float
    uncertainty: float | None
    time: float | None
    conditions: dict = field(default_factory=dict)
    slurry_flow_rate: float | None = None  # m^3/s


def shipped_measurement_paths(kind: str = "die") -> list[Path]:
    """The measurement files shipped for calibration (``kind`` "die" or "thermal"), sorted by name."""
    from importlib import resources

    root = Path(str(resources.files("cmpsim") / "data" / "calibration"))
    prefix = {"die": "die_", "thermal": "pad_"}[kind]
    return sorted(p for p in root.iterdir() if p.name.startswith(prefix) and p.suffix == ".csv")


#: The unit a message suggests for a cell without one, by SI unit: lengths of structures in um, flows in mL/min.
_EXAMPLE_UNITS = {"m": "um", "m^3/s": "mL/min", "m/s": "nm/s", "Pa": "psi"}


def _quantity(text: str, unit: str, target: str, where: str, column: str) -> float:
    from ..inputs import units

    try:
        if unit is None:
            return float(units.to_si(text, target, column, example=_EXAMPLE_UNITS.get(target, target)))
        v = float(text)
        if not math.isfinite(v):
            raise ValueError("not finite")
        return units.convert(v, unit, target) if target else float(units.convert(v, unit, "dimensionless"))
    except ValueError as exc:
        raise MeasurementError(f"{where}: column {column!r}: {exc}") from None
    except Exception as exc:  # pint's own errors
        raise MeasurementError(f"{where}: column {column!r}: cannot read {text!r} as a quantity in units of {target or '1'} ({exc})") from None


#: Spellings of the degree Celsius and Fahrenheit in a temperature-rise column, lower case (pint reads
#: ``degC``, ``degF`` as points on a scale: 18 degF would become 265 K, not the rise of 10 K it is).
_CELSIUS = ("degc", "°c", "c", "celsius", "deg c", "delta_degc", "℃")
_FAHRENHEIT = ("degf", "°f", "f", "fahrenheit", "deg f", "delta_degf", "℉")


def _temperature_difference_unit(unit: str) -> str:
    """The unit of a temperature difference as pint must read it: Celsius -> K, Fahrenheit -> delta_degF; others unchanged."""
    u = unit.strip().lower()
    return "K" if u in _CELSIUS else "delta_degF" if u in _FAHRENHEIT else unit


def _length(rec, column, where, required=False, positive=True):
    text = rec.get(column, "")
    if not text:
        if required:
            raise MeasurementError(f"{where}: column {column!r} is empty; it is required (a length with units, e.g. '1 um')")
        return None
    v = _quantity(text, None, "m", where, column)
    if not math.isfinite(v) or (positive and v <= 0):
        why = " (a space of 0 would make the block one solid line; leave the cell empty for an isolated line in a field)" if column == "line_space" else ""
        raise MeasurementError(f"{where}: column {column!r} = {text!r} must be a length > 0{why}")
    return v


def read_polish_time(rec: dict, where: str) -> float | None:
    """The row's ``time`` (s; None where the cell is empty); MeasurementError naming the column unless it is > 0 s
    (structure, pad and lot rows alike)."""
    if not rec.get("time"):
        return None
    t = _quantity(rec["time"], None, "s", where, "time")
    if not (math.isfinite(t) and t > 0):
        raise MeasurementError(f"{where}: column 'time' = {rec['time']!r} must be > 0 s")
    return t


def read_measurements(path, text: str | None = None) -> list:
    """Read a measurement file: a list of :class:`StructureRecord` and :class:`ThermalRecord` (SI).

    ``text``: the file's content when already read (``path`` then only names it in messages).

    Raises :class:`MeasurementError` naming the file, the row's line and the column of the
    first problem: a missing required column or value, an unknown quantity, process or column, a
    number that is not one, a unit of the wrong dimension, a value out of its valid range.
    """
    from ..die.process import DIE_PARAMETERS, PROCESSES
    from ..inputs.config import PARAMETERS, Config
    from ..validation.data import point_config
    from ..io import read_text

    path = Path(path)
    if text is None:
        text = read_text(path, "measurement file", MeasurementError)
    from ..io import comments_and_rows, delimiter_hint, fields_hint, repeated_columns, tidy_csv

    meta, body = comments_and_rows(tidy_csv(text, path))
    if not body:
        raise MeasurementError(f"{path}: no header row and no data rows (format: cmpsim/data/README.md, docs/calibrate-die.md)")
    hline, htext = body[0]
    header = [h.strip() for h in next(csv.reader([htext]))]
    where0 = f"{path}:{hline}"
    for required in ("quantity", "value"):  # the unit: a column, or after each value ("50 nm")
        if required not in header:
            raise MeasurementError(f"{where0}: required column {required!r} is missing (header: {', '.join(header)})" + delimiter_hint(htext))
    twice = repeated_columns(header)
    if twice:
        raise MeasurementError(f"{where0}: column {twice[0]!r}: a column name is repeated in the header ({', '.join(header)})")
    for col in header:
        if col in _COMMON or col in _STRUCTURE_COLUMNS or col in DIE_PARAMETERS or col in _THERMAL_EXTRA or col in PARAMETERS:
            continue
        from ..validation.data import _near

        raise MeasurementError(f"{where0}: unknown column {col!r}: use the columns of docs/calibrate-die.md, die inputs "
                               f"({', '.join(DIE_PARAMETERS)}) or cmpsim parameter names"
                               + _near(col, [*_COMMON, *_STRUCTURE_COLUMNS, *DIE_PARAMETERS, *_THERMAL_EXTRA, *PARAMETERS]))
    default_name = meta.get("dataset") or path.stem
    out = []
    for (lineno, _), row in zip(body[1:], csv.reader([t for _, t in body[1:]])):
        where = f"{path}:{lineno}"
        if len(row) != len(header):
            raise MeasurementError(f"{where}: {len(row)} fields but the header has {len(header)} (columns {', '.join(header)})"
                                   + fields_hint(row, header))
        rec = {h: c.strip() for h, c in zip(header, row)}
        rec.setdefault("unit", "")
        q = rec["quantity"]
        if q not in STRUCTURE_QUANTITIES and q not in THERMAL_QUANTITIES:
            raise MeasurementError(f"{where}: column 'quantity': unknown quantity {q!r}; known: "
                                   f"{', '.join(list(STRUCTURE_QUANTITIES) + list(THERMAL_QUANTITIES))}")
        from ..inputs.units import placeholder_hint, read_value_cells

        try:  # "50 nm", "±4 nm"
            read_value_cells(rec)
        except ValueError as exc:
            raise MeasurementError(f"{where}: {exc}") from None
        if "unit" not in header and not rec["unit"] and rec["value"] and q != "friction_coefficient":
            raise MeasurementError(f"{where0}: required column 'unit' is missing (header: {', '.join(header)}); give it, or the unit after "
                                   f"every value ('50 nm'): line {lineno} has none")
        if not rec["value"]:
            raise MeasurementError(f"{where}: column 'value' is empty")
        if not rec["unit"] and q != "friction_coefficient":
            raise MeasurementError(f"{where}: column 'unit' is empty (give the unit in the unit column or after the value: '50 nm')")
        target = (STRUCTURE_QUANTITIES.get(q) or THERMAL_QUANTITIES[q])[0]
        try:
            float(rec["value"])
        except ValueError:
            raise MeasurementError(f"{where}: column 'value': {rec['value']!r} is not a number{placeholder_hint(rec['value'])}") from None
        if q == "pad_temperature_rise":  # a difference of temperatures: a degree Celsius is a kelvin, a degree Fahrenheit 5/9 K
            unit = _temperature_difference_unit(rec["unit"])
        else:
            unit = rec["unit"] or "1"
        value = _quantity(rec["value"], unit, target, where, "value")
        unc = None
        if rec.get("uncertainty"):
            try:
                float(rec["uncertainty"])
            except ValueError:
                raise MeasurementError(f"{where}: column 'uncertainty': {rec['uncertainty']!r} is not a number"
                                       f"{placeholder_hint(rec['uncertainty'])}") from None
            unc = _quantity(rec["uncertainty"], unit, target, where, "uncertainty")
            if not unc > 0:
                raise MeasurementError(f"{where}: column 'uncertainty' must be > 0 (or empty); got {rec['uncertainty']!r}")
        name = rec.get("dataset") or default_name
        common = dict(dataset=name, line=lineno, source=rec.get("source", ""), label=rec.get("label", ""), path=str(path))
        if q in STRUCTURE_QUANTITIES:
            for col in header:
                if rec[col] and col in PARAMETERS and col not in DIE_PARAMETERS and col not in _COMMON and col != "applied_pressure":
                    raise MeasurementError(f"{where}: column {col!r}: a wafer-scale input has no meaning for a test structure "
                                           f"(give blanket_rate, or the die inputs {', '.join(DIE_PARAMETERS)})")
            process = rec.get("process", "")
            if process not in PROCESSES:
                raise MeasurementError(f"{where}: column 'process': {process!r} must be one of {', '.join(PROCESSES)}")
            if q in ("dishing", "erosion") and process != "copper":
                raise MeasurementError(f"{where}: column 'process': {q} is measured on copper structures; got {process!r}")
            if q == "step_height" and process != "oxide":
                raise MeasurementError(f"{where}: column 'process': step_height is the oxide process's quantity; got {process!r}")
            if value < 0:
                raise MeasurementError(f"{where}: column 'value': {q} must be >= 0; got {rec['value']}")
            w = _length(rec, "line_width", where, required=True)
            s = _length(rec, "line_space", where)
            size = _length(rec, "structure_size", where)
            if size is not None and size < w:
                raise MeasurementError(f"{where}: column 'structure_size': the block ({rec['structure_size']}) is narrower than one line ({rec['line_width']})")
            t = read_polish_time(rec, where)
            k = None
            if rec.get("blanket_rate"):
                k = _quantity(rec["blanket_rate"], None, "m/s", where, "blanket_rate")
                if not (math.isfinite(k) and k > 0):
                    raise MeasurementError(f"{where}: column 'blanket_rate' = {rec['blanket_rate']!r} must be > 0")
            inputs = {}
            for col in header:
                if col in DIE_PARAMETERS and rec[col]:
                    unit_si, _, (lo, hi), _, _ = DIE_PARAMETERS[col]
                    v = _quantity(rec[col], None, "" if unit_si == "1" else unit_si, where, col)
                    if not (lo <= v <= hi):
                        raise MeasurementError(f"{where}: column {col!r} = {rec[col]!r} is outside its valid range [{lo:g}, {hi:g}] {unit_si}")
                    inputs[col] = v
            if rec.get("applied_pressure"):  # the pressure of the step: the pad body's bulge into a gap grows with it
                pr = _quantity(rec["applied_pressure"], None, "Pa", where, "applied_pressure")
                if not pr > 0:
                    raise MeasurementError(f"{where}: column 'applied_pressure' must be > 0")
                inputs["applied_pressure"] = pr
            out.append(StructureRecord(q, value, unc, process, w, s, size, t, k, inputs, **common))
        else:
            for col in header:
                if rec[col] and (col in _STRUCTURE_COLUMNS[:4] or col in DIE_PARAMETERS) and col not in PARAMETERS:
                    raise MeasurementError(f"{where}: column {col!r} describes a test structure; it has no meaning for {q}")
            t = read_polish_time(rec, where)
            if t is None and q == "pad_temperature_rise":
                raise MeasurementError(f"{where}: column 'time' is empty; a temperature rise needs the polish time it was reached at")
            flow = None
            if rec.get("slurry_flow_rate"):
                flow = _quantity(rec["slurry_flow_rate"], None, "m^3/s", where, "slurry_flow_rate")
                if not flow > 0:
                    raise MeasurementError(f"{where}: column 'slurry_flow_rate' must be > 0")
            conditions = {c: rec[c] for c in header if rec[c] and (c in PARAMETERS or c == "sliding_speed") and c not in _COMMON and c != "time"}
            for c, v in conditions.items():
                try:
                    point_config(Config.default(), {c: v})
                except ValueError as exc:
                    raise MeasurementError(f"{where}: column {c!r}: {exc}") from None
            if q == "pad_temperature_rise" and not value > 0:
                raise MeasurementError(f"{where}: column 'value': a pad temperature rise must be > 0 K (friction only heats the pad; "
                                       f"the heat balance cannot fit a rise of {rec['value']} {rec['unit']})")
            if q == "friction_coefficient" and not 0 < value < 10:
                raise MeasurementError(f"{where}: column 'value': a friction coefficient must lie in (0, 10); got {rec['value']}")
            out.append(ThermalRecord(q, value, unc, t, conditions, flow, **common))
    if not out:
        raise MeasurementError(f"{path}: the file has a header but no data rows")
    return out
