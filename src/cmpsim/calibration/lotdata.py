"""Per-wafer results of a lot against ``wafer``: the rows of a measurement file that carry a ``wafer`` column.

A fab keeps the post-polish metrology of every wafer of a lot. In the CSV format of
``cmpsim validate`` (``cmpsim/data/README.md``) such a row has

| column | required | meaning |
|---|---|---|
| ``wafer`` | yes | the wafer's place in the lot, 1, 2, ... (an integer, at most :data:`MAX_LOT_WAFERS`): counted from the first wafer on the pad, not a wafer ID or a slot |
| ``quantity`` | yes | ``thickness`` (wafer-mean film left after the recipe) or ``removal`` (wafer-mean depth removed) |
| ``value``, ``unit`` | yes | a length with its unit (``nm``, ``angstrom``, ``um``) |
| ``uncertainty`` | no | one standard uncertainty, in ``unit`` |
| ``film`` | no | the film measured (default: the recipe's target film) |
| ``time`` | no | the polish time of the recipe's timed step on this wafer, as the tool logged it (with a unit: ``62 s``). Given on every wafer up to the last measured, the lot is replayed at these times (:func:`logged_times`) instead of being run by cmpsim's controller: a lot under the fab's own run-to-run control |
| ``zone_pressures`` | no | the head's zone pressures on this wafer as logged, one quoted cell (``"3.1, 3, 2.9, 3, 3.2 psi"``), with ``time``: replayed too (:func:`logged_zone_pressures`) |
| ``dataset``, ``source``, ``label``, ``note`` | no | as in every data file |

:func:`read_lot_rows` reads them (SI) and refuses a bad row naming its line and column;
``cmpsim validate LOT.csv --recipe RECIPE.toml`` compares them with ``cmpsim lot`` of that recipe.
The rows may come in any order (each is compared with the wafer it names); a wafer's quantity is
given once (:func:`check_once`: a second row of it, equal or not, is refused naming both).
"""

from __future__ import annotations

import csv
import math
from dataclasses import dataclass
from pathlib import Path

__all__ = ["LotRecord", "LOT_QUANTITIES", "LOT_COLUMNS", "MAX_LOT_WAFERS", "read_lot_rows", "check_once", "logged_times",
           "logged_zone_pressures"]

#: Per-wafer quantities of a lot: name -> meaning (both lengths, m).
LOT_QUANTITIES = {
    "thickness": "wafer-mean thickness of the film left after the recipe",
    "removal": "wafer-mean depth of film removed by the recipe",
}
#: The columns a lot row may fill.
LOT_COLUMNS = ("dataset", "quantity", "value", "unit", "uncertainty", "wafer", "film", "time", "zone_pressures", "source", "label", "note")
#: The last ``wafer`` a lot row may name. A lot is compared by running every wafer up to the last named,
#: each a full recipe solve, so a wafer ID or a slot number (2301) in the column would start hours of
#: solves. The bound is an assumption, not a measurement of this project: a pad is replaced after of
#: order 500-1500 wafers (fab practice as commonly quoted), so a place on one pad beyond 1000 is far
#: more likely an ID than a place; a pad that really lasts longer cannot be compared past it here.
MAX_LOT_WAFERS = 1000


class LotDataError(ValueError):
    """A lot row that cannot be used; the message names the file, the line and the column."""


@dataclass(frozen=True)
class LotRecord:
    """One measured wafer of a lot (SI): ``wafer`` (1-based), ``quantity``, ``value`` and ``uncertainty`` (m), ``film``."""

    wafer: int
    quantity: str
    value: float
    uncertainty: float | None
    film: str | None = None
    dataset: str = ""
    line: int = 0
    source: str = ""
    label: str = ""
    path: str = ""
    #: the polish time (s) of the recipe's timed step on this wafer, as logged (None: not given)
    time: float | None = None
    #: the head's zone pressures (Pa) on this wafer, as logged (None: not given)
    zone_pressures: tuple | None = None


def _length(rec: dict, column: str, unit: str, where: str) -> float:
    """The SI length of ``rec[column]`` in ``unit``; LotDataError naming the column (or the unit)."""
    from ..inputs import units

    text = rec.get(column, "")
    try:
        v = float(text)
    except ValueError:
        raise LotDataError(f"{where}: column {column!r}: {text!r} is not a number{units.placeholder_hint(text)}") from None
    try:
        si = float(units.convert(v, unit, "m"))
    except Exception as exc:  # noqa: BLE001 - pint's errors: a unit that is not a length
        raise LotDataError(f"{where}: column 'unit': {unit!r} is not a length ({exc})") from None
    if not math.isfinite(si):
        raise LotDataError(f"{where}: column {column!r}: {text!r} is not finite")
    return si


def _whole(text: str) -> int:
    """``text`` as an integer if it is a whole number written with a decimal point ("3.0"); ValueError otherwise."""
    v = float(text)
    if not (math.isfinite(v) and v == int(v)):
        raise ValueError(text)
    return int(v)


def read_lot_rows(path, text: str) -> list[LotRecord]:
    """The lot rows of ``text`` (the CSV content of the file ``path``; its comment lines give the ``dataset``), SI."""
    path = Path(path)
    from ..io import comments_and_rows, repeated_columns, tidy_csv

    meta, body = comments_and_rows(tidy_csv(text, path))
    if not body:
        raise LotDataError(f"{path}: no header row and no data rows")
    header = [h.strip() for h in next(csv.reader([body[0][1]]))]
    repeated = repeated_columns(header)
    if repeated:  # the row's dict would keep the last of them silently
        raise LotDataError(f"{path}:{body[0][0]}: column {repeated[0]!r}: a column name is repeated in the header ({', '.join(header)})")
    for col in header:
        if col not in LOT_COLUMNS:
            raise LotDataError(f"{path}:{body[0][0]}: column {col!r} has no meaning for a lot row; lot rows take {', '.join(LOT_COLUMNS)}")
    out = []
    for (lineno, _), row in zip(body[1:], csv.reader([t for _, t in body[1:]])):
        where = f"{path}:{lineno}"
        rec = {h: c.strip() for h, c in zip(header, row)}
        q = rec.get("quantity", "")
        if q not in LOT_QUANTITIES:
            raise LotDataError(f"{where}: column 'quantity': a lot row (with a wafer) takes {', '.join(LOT_QUANTITIES)}; got {q!r}")
        w = rec.get("wafer", "")
        try:  # "3", or "3.0" as a spreadsheet writes a whole number
            wafer = int(w) if w.strip().lstrip("+-").isdigit() else _whole(w)
        except ValueError:
            raise LotDataError(f"{where}: column 'wafer': {w!r} is not a wafer number (an integer >= 1)") from None
        if wafer < 1:
            raise LotDataError(f"{where}: column 'wafer': {w!r} must be >= 1 (the first wafer of the lot is 1)")
        if wafer > MAX_LOT_WAFERS:
            raise LotDataError(f"{where}: column 'wafer': {w!r} is outside 1 to {MAX_LOT_WAFERS}: 'wafer' is the wafer's place in the lot "
                               "counted from the first wafer on the pad (1, 2, ...), not a wafer ID or a slot number; every wafer up "
                               "to the last named is polished (a full recipe solve each)")
        from ..inputs.units import read_value_cells

        try:  # "512 nm", "±4 nm"
            read_value_cells(rec)
        except ValueError as exc:
            raise LotDataError(f"{where}: {exc}") from None
        unit = rec.get("unit", "")
        if not unit:
            raise LotDataError(f"{where}: column 'unit' is empty; a lot row is a length (nm, angstrom, um)")

        value = _length(rec, "value", unit, where)
        if value < 0:
            raise LotDataError(f"{where}: column 'value': a {q} must be >= 0; got {rec['value']}")
        unc = None
        if rec.get("uncertainty"):
            unc = _length(rec, "uncertainty", unit, where)
            if not unc > 0:
                raise LotDataError(f"{where}: column 'uncertainty' must be > 0 (or empty); got {rec['uncertainty']!r}")
        film = rec.get("film") or None
        if film is not None:
            from ..inputs.config import PARAMETERS
            from ..validation.data import film_hint

            if film not in PARAMETERS["film"].choices:  # "cu" was kept, and refused against the recipe's "copper" only with --recipe
                raise LotDataError(f"{where}: column 'film': {rec['film']!r} is not a film of cmpsim; one of "
                                   f"{', '.join(PARAMETERS['film'].choices)}{film_hint(film)}")
        from .measurements import MeasurementError, read_polish_time

        try:
            t = read_polish_time(rec, where)
        except MeasurementError as exc:
            raise LotDataError(str(exc)) from None
        zp = None
        if rec.get("zone_pressures"):
            from ..inputs.units import parse_list

            try:
                zp = tuple(float(v) for v in parse_list(rec["zone_pressures"], "Pa", "column 'zone_pressures'", "3, 3, 3.5 psi"))
            except ValueError as exc:
                raise LotDataError(f"{where}: {exc}") from None
            if not all(math.isfinite(v) and v > 0 for v in zp):
                raise LotDataError(f"{where}: column 'zone_pressures' = {rec['zone_pressures']!r}: every pressure must be > 0")
        out.append(LotRecord(wafer, q, value, unc, film, rec.get("dataset") or meta.get("dataset") or path.stem,
                             lineno, rec.get("source", ""), rec.get("label", ""), str(path), t, zp))
    check_once(out)
    return out


def check_once(records) -> None:
    """LotDataError naming both rows where two records give the same wafer's same quantity.

    The rows of one call are one lot (several files' rows too: :func:`cmpsim.calibration.mixed.read_all`).
    A second row would count twice in a fit, or, with another value, make it fit their mean
    silently; two lots in one file (both from wafer 1) read as one lot would be the same mistake."""
    first: dict[tuple, LotRecord] = {}
    for r in records:
        key = (r.wafer, r.quantity)  # a lot measures the recipe's top film only: a film named or not, the same quantity
        if key not in first:
            first[key] = r
            continue
        o = first[key]
        there = f"line {o.line}" if o.path == r.path else f"{o.path}:{o.line}"
        what = f"wafer {r.wafer}'s {r.quantity}"
        if r.value == o.value:
            why = f"{what} is given twice (also in {there}, the same value): it would count twice in a fit; give it once"
        else:
            why = (f"{what} is {r.value * 1e9:.6g} nm here and {o.value * 1e9:.6g} nm in {there}: a wafer's {r.quantity} is given once "
                   "(repeated measurements: their mean, with its uncertainty; two lots: one at a time, each counted from its pad's "
                   "first wafer)")
        if r.film != o.film:
            why += f" (films {o.film or 'not given'} and {r.film or 'not given'}: a lot measures the recipe's top film only)"
        raise LotDataError(f"{r.path}:{r.line}: column 'wafer': {why}")


def logged_times(records) -> list[float] | None:
    """The polish times (s) of wafers 1..N (N the last measured) that lot ``records`` logged, to replay the lot
    at them; None if no record gives a time. LotDataError naming the wafers without one, or a wafer
    whose rows give two different times."""
    return _per_wafer(records, "time", "polish times")


def logged_zone_pressures(records) -> list[tuple] | None:
    """The zone pressures (Pa) of wafers 1..N that lot ``records`` logged (as :func:`logged_times`); None if none."""
    return _per_wafer(records, "zone_pressures", "zone pressures")


def _per_wafer(records, attr: str, what: str) -> list | None:
    """The logged ``attr`` of wafers 1..N (N the last measured), None if no record gives one; LotDataError naming
    the wafers without one, or a wafer whose rows give two."""
    given = [r for r in records if getattr(r, attr) is not None]
    if not given:
        return None
    n = max(r.wafer for r in records)
    seen: dict[int, object] = {}
    for r in given:
        v = getattr(r, attr)
        if r.wafer in seen and seen[r.wafer] != v:
            raise LotDataError(f"{r.path}:{r.line}: column {attr!r}: wafer {r.wafer} has {_shown(seen[r.wafer])} in another row, "
                               f"{_shown(v)} here")
        seen[r.wafer] = v
    missing = [w for w in range(1, n + 1) if w not in seen]
    if missing:
        shown = ", ".join(map(str, missing[:10])) + (f" and {len(missing) - 10} more" if len(missing) > 10 else "")
        raise LotDataError(f"{given[0].path}: column {attr!r}: a lot is replayed at its logged {what}, which every wafer up to "
                           f"the last measured ({n}) needs; wafers {shown} have none (give it on every wafer, or on none: then "
                           "the lot is run by cmpsim's controller)")
    return [seen[w] for w in range(1, n + 1)]


def _shown(v) -> str:
    return f"{v:g} s" if isinstance(v, float) else ", ".join(f"{p:g}" for p in v) + " Pa"
