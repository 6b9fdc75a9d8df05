"""Measurement files of every scale at once: each row to the reader of its family, errors by row and column.

One file (or several) may hold rows of four families, told apart by the row:

* **film**: removal rates, depths and profiles, and the other quantities of ``cmpsim validate``
  (:func:`cmpsim.validation.data.load_datasets`);
* **structure**: ``dishing``, ``erosion``, ``step_height`` of test structures, and
* **pad**: ``pad_temperature_rise``, ``friction_coefficient`` (the pad's effective friction q/(P U))
  (:func:`cmpsim.calibration.measurements.read_measurements`);
* **lot**: a row with a ``wafer`` (:func:`cmpsim.calibration.lotdata.read_lot_rows`).

Each family's reader sees the file with the other families' rows blanked (so its line numbers are
the file's) and only the columns it knows; a column of another family filled in a row is refused
naming the row. Every message names the file, the line, the row (1 = the first data row) and the
column.
"""

from __future__ import annotations

import csv
import io
import re
from dataclasses import dataclass, field
from pathlib import Path

__all__ = ["Measurements", "read_all", "family_of"]


@dataclass
class Measurements:
    """The rows of some files by family: ``datasets`` (film, :class:`cmpsim.validation.data.Dataset`),
    ``structures`` (:class:`~cmpsim.calibration.measurements.StructureRecord`), ``pad`` (:class:`~cmpsim.calibration.measurements.ThermalRecord`), ``lots`` (:class:`~cmpsim.calibration.lotdata.LotRecord`)."""

    datasets: list = field(default_factory=list)
    structures: list = field(default_factory=list)
    pad: list = field(default_factory=list)
    lots: list = field(default_factory=list)
    paths: list = field(default_factory=list)

    def __len__(self) -> int:
        return sum(len(d.points) for d in self.datasets) + len(self.structures) + len(self.pad) + len(self.lots)


def family_of(quantity: str, wafer: str = "") -> str:
    """The family of a row: ``lot`` (it has a wafer), ``structure``, ``pad`` or ``film``."""
    from .measurements import STRUCTURE_QUANTITIES, THERMAL_QUANTITIES

    if wafer:
        return "lot"
    if quantity in STRUCTURE_QUANTITIES:
        return "structure"
    if quantity in THERMAL_QUANTITIES:
        return "pad"
    return "film"


def _accepts(fam: str, column: str) -> bool:
    from ..die.process import DIE_PARAMETERS
    from ..inputs.config import PARAMETERS
    from ..validation.data import EXTRA_CONDITIONS, META_COLUMNS, POINT_COLUMNS
    from .lotdata import LOT_COLUMNS
    from .measurements import _COMMON, _STRUCTURE_COLUMNS, _THERMAL_EXTRA

    if fam == "film":
        return column in META_COLUMNS or column in EXTRA_CONDITIONS or column in POINT_COLUMNS or (
            column in PARAMETERS and (PARAMETERS[column].section != "numerics" or column == "model"))
    if fam == "lot":
        return column in LOT_COLUMNS
    return column in _COMMON or column in _STRUCTURE_COLUMNS or column in DIE_PARAMETERS or column in _THERMAL_EXTRA or column in PARAMETERS


class MixedDataError(ValueError):
    """A measurement file that cannot be used: names the file, the line, the row and the column."""


def _with_row(message: str, rows: dict[int, int]) -> str:
    """``message`` of a family's reader with the row number of the whole file (``rows``: line -> row)."""
    m = re.search(r":(\d+): (row \d+(, |: ))?", message)
    if not m or int(m.group(1)) not in rows:
        return message
    sep = m.group(3) or ", "
    return message[: m.start()] + f":{m.group(1)}: row {rows[int(m.group(1))]}{sep}" + message[m.end():]


def _split(path: Path, text: str) -> dict[str, tuple[str, dict[int, int]]]:
    """{family: (the file's text for that family's reader, line -> row)}; MixedDataError on a row that fits no family."""
    lines = text.splitlines()
    body = [(i, ln) for i, ln in enumerate(lines, start=1) if ln.strip() and not ln.strip().startswith("#")]
    if not body:
        return {"film": (text, {})}
    header = [h.strip() for h in next(csv.reader([body[0][1]]))]
    if "quantity" not in header:
        return {"film": (text, {})}  # the reader names the missing column
    q_at = header.index("quantity")
    w_at = header.index("wafer") if "wafer" in header else None
    rows: dict[int, int] = {}
    fam_of_line: dict[int, str] = {}
    parsed: dict[int, list[str]] = {}
    for row_no, ((lineno, ln), row) in enumerate(zip(body[1:], csv.reader([t for _, t in body[1:]])), start=1):
        rows[lineno] = row_no
        if len(row) != len(header):
            from ..io import fields_hint

            raise MixedDataError(f"{path}:{lineno}: row {row_no}: {len(row)} fields but the header has {len(header)} (columns {', '.join(header)})"
                                 + fields_hint(row, header))
        parsed[lineno] = row
        fam_of_line[lineno] = family_of(row[q_at].strip(), row[w_at].strip() if w_at is not None else "")
    _lot_row_without_wafer(path, header, parsed, fam_of_line, rows)
    families = sorted(set(fam_of_line.values()))
    reader = {"film": "film", "structure": "measurement", "pad": "measurement", "lot": "lot"}
    groups = sorted({reader[f] for f in families})
    if not groups:  # no data row: said before the film reader refuses the columns of a structure or lot template
        raise MixedDataError(f"{path}:{body[0][0]}: the file has a header but no data rows (header: {', '.join(header)})")
    # a column of another family that no row fills (a template's structure columns, a wafer column without lots) is
    # dropped; a name no family knows is still refused by the reader
    empty = {k for k in range(len(header)) if not any(parsed[i][k].strip() for i in parsed)}
    unknown_empty = [k for k in sorted(empty) if not all(_accepts(f, header[k]) for f in families)
                     and any(_accepts(f, header[k]) for f in ("film", "structure", "pad", "lot"))]
    if len(groups) == 1 and not unknown_empty:
        return {groups[0]: (text, rows)}  # one reader: it sees the file as it is and names a column it does not know
    out = {}
    for g in groups:
        fams = [f for f in families if reader[f] == g]
        if len(groups) == 1:  # the reader still names a filled column it does not know
            keep = [k for k in range(len(header)) if k not in unknown_empty]
        else:
            keep = [k for k, c in enumerate(header) if all(_accepts(f, c) for f in fams)]
        new = []
        for i, ln in enumerate(lines, start=1):
            if i == body[0][0]:
                new.append(_csv_line([header[k] for k in keep]))
            elif i in parsed:
                if reader[fam_of_line[i]] != g:
                    new.append("")
                    continue
                row = parsed[i]
                for k, c in enumerate(header):
                    if k not in keep and row[k].strip():
                        q = row[q_at].strip()
                        raise MixedDataError(f"{path}:{i}: row {rows[i]}, column {c!r}: has no meaning for a {fam_of_line[i]} row "
                                             f"(quantity {q!r}{', wafer ' + row[w_at].strip() if w_at is not None and row[w_at].strip() else ''}); leave it empty")
                new.append(_csv_line([row[k] for k in keep]))
            else:
                new.append(ln)
        out[g] = ("\n".join(new) + "\n", rows)
    return out


def _lot_row_without_wafer(path, header, parsed, fam_of_line, rows) -> None:
    """MixedDataError naming the ``wafer`` of a row that lost its wafer number among a lot's rows: a ``thickness`` without
    ``initial_thickness`` or a ``removal`` without ``time`` cannot be a film row, whose refusal ("needs the time column")
    would not say that the wafer is missing."""
    if "lot" not in fam_of_line.values():
        return
    at = {c: header.index(c) for c in ("quantity", "time", "initial_thickness") if c in header}
    for line, row in parsed.items():
        q = row[at["quantity"]].strip()
        needs = {"thickness": "initial_thickness", "removal": "time"}.get(q)
        if fam_of_line[line] == "film" and needs and not (needs in at and row[at[needs]].strip()):
            raise MixedDataError(f"{path}:{line}: row {rows[line]}, column 'wafer': empty, but the file's other rows are a lot's wafers: "
                                 f"give this {q} its wafer (a {q} of a blanket film, without a wafer, needs the {needs} column)")


def _csv_line(values) -> str:
    buf = io.StringIO()
    csv.writer(buf, lineterminator="").writerow(values)
    return buf.getvalue()


def read_all(paths) -> Measurements:
    """Read measurement files of every family (film, structures, pad, lots); ValueError naming file, line, row and column."""
    from ..io import read_text, tidy_csv
    from ..validation.data import load_datasets
    from .lotdata import check_once, read_lot_rows
    from .measurements import StructureRecord, read_measurements

    out = Measurements()
    for p in [paths] if isinstance(paths, (str, Path)) else list(paths):
        path = Path(p)
        text = tidy_csv(read_text(path, "data file", MixedDataError), path)
        out.paths.append(str(path))
        for group, (sub, rows) in _split(path, text).items():
            try:
                if group == "film":
                    out.datasets += load_datasets(path, text=sub)
                elif group == "lot":
                    out.lots += read_lot_rows(path, sub)
                    check_once(out.lots)  # the files' lot rows are one lot: a wafer of an earlier file given again here
                else:
                    for r in read_measurements(path, text=sub):
                        (out.structures if isinstance(r, StructureRecord) else out.pad).append(r)
            except ValueError as exc:
                raise MixedDataError(_with_row(str(exc), rows)) from None
    names = [d.name for d in out.datasets]
    dup = sorted({n for n in names if names.count(n) > 1})
    if dup:
        where = {n: sorted({str(d.path) for d in out.datasets if d.name == n}) for n in dup}
        raise MixedDataError("data set names must be unique; repeated: " + "; ".join(f"{n!r} in {' and '.join(where[n])}" for n in dup)
                             + " (give each file its own '# dataset: NAME' line, or a dataset column)")
    return out
