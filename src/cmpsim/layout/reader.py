"""Open GDSII (``.gds``, ``.gds.gz``) and OASIS (``.oas``) layouts with gdstk.

The format is recognised from the file's first bytes (GDSII's HEADER record, OASIS's
``%SEMI-OASIS`` magic, gzip's magic), not from its name.  The geometry is read in database
units (``unit`` = the file's precision), so every coordinate is an integer number of dbu;
:attr:`Layout.dbu` is that unit in metres.
"""

from __future__ import annotations

import gzip
import os
import shutil
import tempfile
from dataclasses import dataclass
from pathlib import Path

import gdstk

__all__ = ["Layout", "read_layout", "top_cell", "layers_in"]

_GDS_MAGIC = b"\x00\x06\x00\x02"
_OAS_MAGIC = b"%SEMI-OASIS\r\n"
_GZ_MAGIC = b"\x1f\x8b"


@dataclass(frozen=True)
class Layout:
    """A layout read by gdstk: its library (coordinates in dbu), the file and its format.

    ``dbu`` is the database unit in metres (1e-9 for a 1 nm grid); ``format`` is
    ``"gds"``, ``"gds.gz"`` or ``"oas"``.
    """

    library: gdstk.Library
    path: Path
    format: str
    dbu: float


def _sniff(head: bytes) -> str | None:
    if head.startswith(_GDS_MAGIC):
        return "gds"
    if head.startswith(_OAS_MAGIC):
        return "oas"
    if head.startswith(_GZ_MAGIC):
        return "gz"
    return None


def read_layout(path: str | os.PathLike) -> Layout:
    """Read a GDSII, gzipped GDSII or OASIS file.

    Raises FileNotFoundError if ``path`` does not exist and ValueError if it is not a
    GDSII/OASIS layout (the message names the parameter and the accepted formats).
    """
    p = Path(path)
    if not p.is_file():
        raise FileNotFoundError(f"layout path {str(p)!r} does not exist (expected a .gds, .gds.gz or .oas file)")
    with open(p, "rb") as fh:
        kind = _sniff(fh.read(16))
    what = "expected GDSII (.gds), gzipped GDSII (.gds.gz) or OASIS (.oas)"
    if kind is None:
        raise ValueError(f"layout path {str(p)!r} is not a layout file: {what}")
    try:
        if kind == "gz":
            with tempfile.TemporaryDirectory() as tmp:
                raw = Path(tmp) / "layout"
                with gzip.open(p, "rb") as src, open(raw, "wb") as dst:
                    shutil.copyfileobj(src, dst)
                with open(raw, "rb") as fh:
                    inner = _sniff(fh.read(16))
                if inner != "gds":
                    raise ValueError(f"layout path {str(p)!r} is gzip but not gzipped GDSII: {what}")
                lib = _read_gds(raw)
                fmt = "gds.gz"
        elif kind == "gds":
            lib, fmt = _read_gds(p), "gds"
        else:
            precision = gdstk.oas_precision(str(p))
            lib, fmt = gdstk.read_oas(str(p), unit=precision), "oas"
    except ValueError:
        raise
    except Exception as exc:  # gdstk raises OSError/RuntimeError on a broken stream
        raise ValueError(f"layout path {str(p)!r} could not be read as a layout ({exc}): {what}") from exc
    return Layout(library=lib, path=p, format=fmt, dbu=float(lib.unit))


def _read_gds(path: Path) -> gdstk.Library:
    _unit, precision = gdstk.gds_units(str(path))
    return gdstk.read_gds(str(path), unit=precision)


def top_cell(layout: Layout, top: str | None = None) -> gdstk.Cell:
    """The cell to extract: ``top`` by name, else the file's only top-level cell.

    Raises ValueError naming ``top`` and listing the valid names when ``top`` is unknown
    or when the file has several top-level cells and ``top`` was not given.
    """
    lib = layout.library
    cells = {c.name: c for c in lib.cells if isinstance(c, gdstk.Cell)}
    tops = sorted(c.name for c in lib.top_level() if isinstance(c, gdstk.Cell))
    if top is not None:
        if top not in cells:
            raise ValueError(f"top cell {top!r} is not in {layout.path.name}; "
                             f"its top-level cells are {tops} ({len(cells)} cells in all)")
        return cells[top]
    if not tops:
        raise ValueError(f"layout {layout.path.name} has no cells")
    if len(tops) > 1:
        raise ValueError(f"layout {layout.path.name} has {len(tops)} top-level cells {tops}: "
                         "choose one with top=NAME")
    return cells[tops[0]]


def layers_in(layout: Layout) -> set[tuple[int, int]]:
    """Every (layer, datatype) that carries a polygon or path anywhere in the file."""
    found: set[tuple[int, int]] = set()
    for cell in layout.library.cells:
        if not isinstance(cell, gdstk.Cell):
            continue
        found.update((p.layer, p.datatype) for p in cell.polygons)
        for path in cell.paths:
            found.update(zip(path.layers, path.datatypes))
    return found
