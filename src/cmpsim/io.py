"""File output that never leaves a partial file behind: write to a temporary sibling, then rename."""

from __future__ import annotations

import contextlib
import csv
import io
import re
import os
import tempfile
from pathlib import Path

__all__ = ["atomic_write_text", "atomic_path", "read_text", "comments_and_rows", "tidy_csv", "delimiter_hint", "fields_hint", "repeated_columns"]


@contextlib.contextmanager
def atomic_path(path: Path, suffix: str = ""):
    """Yield a temporary path next to ``path``; on success rename it onto ``path`` atomically.

    On an exception the temporary file is removed and ``path`` is left untouched.
    """
    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    fd, tmp = tempfile.mkstemp(prefix=f".{path.name}.", suffix=suffix or ".tmp", dir=path.parent)
    os.close(fd)
    tmp_path = Path(tmp)
    # mkstemp creates the file 0600; give the result the permissions of an ordinary new file
    umask = os.umask(0)
    os.umask(umask)
    os.chmod(tmp_path, 0o666 & ~umask)
    try:
        yield tmp_path
        os.replace(tmp_path, path)
    except BaseException:
        with contextlib.suppress(FileNotFoundError):
            tmp_path.unlink()
        raise


def atomic_write_text(path: Path, text: str) -> None:
    """Write ``text`` to ``path`` atomically (UTF-8)."""
    with atomic_path(Path(path)) as tmp:
        tmp.write_text(text, encoding="utf-8")


def read_text(path: Path, what: str, error: type[Exception] = ValueError) -> str:
    """The UTF-8 text of an input file, or ``error`` saying which file (``what``) and why.

    A leading byte-order mark (spreadsheets write one when they save "CSV UTF-8") is dropped: kept,
    it would glue itself to the first column name or hide the first comment line.
    """
    path = Path(path)
    save = "(save it as UTF-8, e.g. a spreadsheet's 'CSV UTF-8')"
    try:
        data = path.read_bytes()
    except FileNotFoundError:
        raise error(f"{what} {str(path)!r} does not exist") from None
    except OSError as exc:
        raise error(f"cannot read {what} {str(path)!r}: {exc}") from None
    if data.startswith((b"\xff\xfe", b"\xfe\xff")) or b"\x00" in data[:4096]:  # a spreadsheet's "Unicode text": every other byte 0
        raise error(f"{what} {str(path)!r} is UTF-16 text, not UTF-8 {save}")
    try:
        return data.decode("utf-8-sig")
    except UnicodeDecodeError as exc:
        line = data[: exc.start].count(b"\n") + 1
        raise error(f"{what} {str(path)!r} is not UTF-8 text: line {line} has the byte {data[exc.start:exc.start + 1]!r} "
                    f"({exc.reason}; a Windows or Latin-1 export writes 'µ' and 'Å' so) {save}") from None


def comments_and_rows(text: str) -> tuple[dict[str, str], list[tuple[int, str]]]:
    """A data file's ``# key: value`` comment lines (keys lower case, a repeated key's values joined)
    and its other non-blank lines with their line numbers (1-based): the header first."""
    meta: dict[str, str] = {}
    body: list[tuple[int, str]] = []
    for i, line in enumerate(text.splitlines(), start=1):
        s = line.strip()
        if s.startswith("#"):
            content = s.lstrip("#").strip()
            if ":" in content:
                k, v = content.split(":", 1)
                k = k.strip().lower()
                if k and " " not in k:
                    meta[k] = (meta[k] + " " + v.strip()) if k in meta else v.strip()
            continue
        if s:
            body.append((i, line))
    return meta, body


#: Columns whose cells are names (of a quantity, a comparison, a process, a film), read in lower case.
NAME_COLUMNS = ("quantity", "comparison", "process", "film")
#: Columns that hold no quantity: a unit in their header (``wafer (#)``) is dropped, not given to their cells.
TEXT_COLUMNS = NAME_COLUMNS + ("dataset", "wafer", "source", "label", "note", "unit")
_HEADER_UNIT = re.compile(r"^\s*([A-Za-z_][A-Za-z0-9_]*)\s*(?:[\(\[]\s*(.*?)\s*[\)\]]|,\s*(.*?))\s*$")


def tidy_csv(text: str, path="") -> str:
    """A data file's text as a spreadsheet's export of it is meant: the header's column names in lower case
    and without the empty names of trailing commas; a row's trailing empty fields beyond the header dropped;
    the cells of :data:`NAME_COLUMNS` in lower case (``Dishing``, ``Copper``); a unit in a column's header
    (``value (nm/min)``, ``applied_pressure [psi]``) written after each plain number of the column.

    Lines keep their numbers (a changed line is rewritten in place), so messages still name the file's
    lines; a row with a filled field beyond the header is left for the reader to refuse. A quoted field
    that runs past the end of its line (a line break inside a cell) raises ValueError naming ``path`` and
    the line: the readers number rows by lines.
    """
    if text.startswith("\ufeff"):  # a byte-order mark in text handed over already decoded (an upload, the API)
        text = text[1:]
    lines = text.splitlines()
    body = [i for i, ln in enumerate(lines) if ln.strip() and not ln.strip().startswith("#")]
    if not body:
        return text
    sep = re.fullmatch(r"\s*sep=(.?)\s*,*\s*", lines[body[0]], flags=re.I)
    if sep:  # Excel's "sep=;" line names the separator: a comma is this reader's, anything else is refused
        if sep.group(1) != ",":
            raise ValueError(f"{path}:{body[0] + 1}: the line {lines[body[0]].strip()!r} says the file is separated by "
                             f"{sep.group(1)!r}: cmpsim reads comma-separated files with a decimal point; export the sheet "
                             "as CSV with ',' as the separator")
        lines[body[0]] = ""
        return tidy_csv("\n".join(lines) + "\n", path)
    header = next(csv.reader([lines[body[0]]]))
    n = len(header)
    while n > 1 and not header[n - 1].strip():
        n -= 1
    names, header_units = [], {}
    for k, h in enumerate(header[:n]):  # "value (nm/min)", "applied_pressure [psi]": the unit of the column's plain numbers
        m = _HEADER_UNIT.match(h)
        names.append((m.group(1) if m else h.strip()).lower())
        if m and (m.group(2) or m.group(3)) and names[-1] not in TEXT_COLUMNS:
            header_units[k] = m.group(2) or m.group(3)
    if "" in names:  # an empty column of the sheet between two others: "unknown column ''" did not say which
        k = names.index("")
        raise ValueError(f"{path}:{body[0] + 1}: header, column {k + 1} ({f'after {names[k - 1]!r}' if k else 'the first'}) has no name: "
                         "delete the sheet's empty column, or name it (note, source, label)")
    _refuse_hidden_rows(lines, body[0], names, path)
    changed = False
    if names != [h.strip() for h in header]:
        lines[body[0]] = _csv_line(names)
        changed = True
    for i in body:
        try:
            row = next(csv.reader([lines[i]], strict=True), [])
        except csv.Error as exc:
            if "end of data" not in str(exc):  # another irregular quote ('"a"b'): read as before, leniently
                row = next(csv.reader([lines[i]]), [])
            else:
                raise ValueError(f"{path}:{i + 1}: a quoted field runs past the end of the line (a line break inside a cell); "
                                 "keep each row on one line") from None
        if i == body[0]:
            continue
        if not any(c.strip() for c in row):  # ",,,,": a spreadsheet's empty row
            lines[i] = ""
            changed = True
        else:
            keep = row[:n] if len(row) > n and not any(c.strip() for c in row[n:]) else row
            named = [c.lower() if k < len(names) and names[k] in NAME_COLUMNS
                     else f"{c.strip()} {header_units[k]}" if k in header_units and is_number(c) else c for k, c in enumerate(keep)]
            if named != row:
                lines[i] = _csv_line(named)
                changed = True
    return "\n".join(lines) + "\n" if changed else text


def _refuse_hidden_rows(lines: list[str], header_at: int, names: list[str], path) -> None:
    """ValueError naming the line of a ``#`` line after the header that has the header's fields (``#1,removal_rate,150,...``):
    a data row whose first cell begins with ``#`` (a label, a wafer ``#3``) that would be read as a comment and dropped."""
    if len(names) < 3:  # too few columns to tell a row from a comment with commas
        return
    row = 0
    for i in range(header_at + 1, len(lines)):
        s = lines[i].strip()
        if s and not s.startswith("#"):
            row += 1
        if not s.startswith("#"):
            continue
        cells = next(csv.reader([s]), [])
        while len(cells) > len(names) and not cells[-1].strip():
            cells.pop()
        if len(cells) == len(names) and sum(bool(c.strip()) for c in cells) >= 3:
            raise ValueError(f"{path}:{i + 1}: row {row + 1}, column {names[0]!r}: the line starts with '#' but has the header's "
                             f"{len(names)} fields: a data row whose first cell begins with '#' ({cells[0].strip()!r}) would be read as a "
                             f"comment and dropped; quote the cell (\"{cells[0].strip()}\"), drop the '#', or put another column first")


def is_number(text: str) -> bool:
    """Whether ``text`` reads as a float."""
    try:
        float(text)
    except ValueError:
        return False
    return True


def _csv_line(values) -> str:
    buf = io.StringIO()
    csv.writer(buf, lineterminator="").writerow(values)
    return buf.getvalue()


def repeated_columns(header: list[str]) -> list[str]:
    """The names a CSV ``header`` holds more than once, sorted ([] when none): a row's dict would keep the last."""
    return sorted({h for h in header if header.count(h) > 1})


def fields_hint(row: list[str], header: list[str]) -> str:
    """A hint for a row with more fields than its ``header`` where a comma split a number (``249,5`` unquoted: a decimal
    comma, or ``1,497``: a thousands separator), naming the column; "" otherwise."""
    if len(row) <= len(header):
        return ""
    for k, (a, b) in enumerate(zip(row[: len(header)], row[1:])):
        if re.search(r"[0-9]$", a.strip()) and re.match(r"[0-9]{1,3}(\s|$)", b.strip()):
            return (f" (column {header[k]!r}: '{a.strip()},{b.strip()}', a decimal comma or a thousands separator splitting a number? "
                    "write it with a decimal point and no separator)")
    return ""


def delimiter_hint(header_text: str) -> str:
    """A hint for a header that is not comma-separated (``quantity;value;unit``): "" when it is."""
    for sep, name in ((";", "semicolons"), ("\t", "tabs")):
        if header_text.count(sep) > header_text.count(","):  # "quantity;value;unit;note, free": a comma inside a name
            return (f" (the header is separated by {name}: cmpsim reads comma-separated files with a decimal point; "
                    "export the sheet as CSV with ',' as the separator)")
    return ""
