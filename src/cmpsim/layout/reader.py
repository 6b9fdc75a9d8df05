"""Open a layout as KLayout does: GDSII and OASIS, plain or gzipped (``klayout.db``).

KLayout's reader is the field's own: it reads GDSII and OASIS (plain or gzipped), OASIS with CBLOCKs
and strict mode, arrays, every placement transformation (mirrored, rotated, magnified,
non-Manhattan), paths (turned into polygons where shapes are wanted), texts and properties
(never shapes), and the ``$$$CONTEXT_INFO$$$`` cell that KLayout and gdsfactory write for
PCells and library references (it is read as metadata, not as a cell).  The format is
recognised from the file's first bytes (GDSII's HEADER record, OASIS's ``%SEMI-OASIS``
magic, gzip's magic), not from its name.

Coordinates stay in database units (``dbu``, integers); :attr:`Layout.dbu` is that unit in
metres.  KLayout (``klayout`` on the package index) is GPL-3.0-or-later; cmpsim's own code
is MIT (README).
"""

from __future__ import annotations

import gzip
import os
from dataclasses import dataclass
from decimal import Decimal
from pathlib import Path

import klayout.db as kdb

from .blocks import COORD_LIMIT
from .twisted import untwist

__all__ = ["Layout", "read_layout", "top_cell", "check_extent", "layers_in", "layer_listing", "LayoutTooLarge"]

_GDS_MAGIC = b"\x00\x06\x00\x02"
_OAS_MAGIC = b"%SEMI-OASIS\r\n"
_GZ_MAGIC = b"\x1f\x8b"
_WHAT = "expected GDSII (.gds), gzipped GDSII (.gds.gz) or OASIS (.oas, .oas.gz)"


class LayoutTooLarge(ValueError):
    """A layout (or its window grid) that does not fit the machine: the message names the limit
    and what to do (a larger ``--window``, a smaller region, more memory)."""


@dataclass(frozen=True, eq=False)
class Layout:
    """A layout read by KLayout: the database (coordinates in dbu), the file and its format.

    ``db`` is the :class:`klayout.db.Layout`; ``dbu`` the database unit in metres (1e-9 for a
    1 nm grid); ``format`` is ``"gds"``, ``"gds.gz"``, ``"oas"`` or ``"oas.gz"``.
    """

    db: kdb.Layout
    path: Path
    format: str
    dbu: float

    @property
    def name(self) -> str:
        return self.path.name


def _sniff(head: bytes) -> str | None:
    if head.startswith(_GDS_MAGIC):
        return "gds"
    if head.startswith(_OAS_MAGIC):
        return "oas"
    if head.startswith(_GZ_MAGIC):
        return "gz"
    return None


def read_layout(path: str | os.PathLike) -> Layout:
    """Read a GDSII or OASIS file, plain or gzipped, with KLayout.

    Raises FileNotFoundError if ``path`` does not exist, ValueError if it is not a
    GDSII/OASIS layout or cannot be read (the message names the file and the accepted
    formats), and :class:`LayoutTooLarge` if the machine runs out of memory reading it.
    """
    p = Path(path)
    if p.is_dir():
        raise ValueError(f"layout path {str(p)!r} is a directory: give the layout file in it ({_WHAT})")
    if not p.is_file():
        raise FileNotFoundError(f"layout path {str(p)!r} does not exist (expected a .gds, .gds.gz, .oas or .oas.gz file)")
    try:
        with open(p, "rb") as fh:
            kind = _sniff(fh.read(16))
    except OSError as exc:  # no permission to read it, a device, ...
        raise ValueError(f"layout path {str(p)!r} cannot be opened ({exc.strerror or exc}): check that it is a readable file") from None
    if kind is None:
        raise ValueError(f"layout path {str(p)!r} is not a layout file: {_WHAT}")
    fmt = kind
    if kind == "gz":
        try:
            with gzip.open(p, "rb") as fh:
                inner = _sniff(fh.read(16))
        except OSError as exc:
            raise ValueError(f"layout path {str(p)!r} is a broken gzip stream ({exc}): {_WHAT}") from None
        if inner is None:
            raise ValueError(f"layout path {str(p)!r} is gzip but neither gzipped GDSII nor gzipped OASIS: {_WHAT}")
        fmt = f"{inner}.gz"
    db = kdb.Layout()
    options = kdb.LoadLayoutOptions()
    options.text_enabled = False  # texts are never shapes
    options.properties_enabled = False
    try:
        db.read(str(p), options)
    except MemoryError:
        raise LayoutTooLarge(f"layout path {str(p)!r} does not fit in this machine's memory; "
                             "cut the region of interest out of it (klayout -> Save As with a clip) or use a larger machine") from None
    except RuntimeError as exc:
        msg = str(exc)
        if "bad_alloc" in msg or "memory" in msg.lower():
            raise LayoutTooLarge(f"layout path {str(p)!r} does not fit in this machine's memory ({msg.strip()}); "
                                 "cut the region of interest out of it or use a larger machine") from None
        if "topological_sort" in msg:  # KLayout's words for a cell that places itself, directly or through others
            raise ValueError(f"layout path {str(p)!r} has a recursive cell hierarchy (a cell placed inside itself, directly or through "
                             f"other cells), which no layout tool can flatten; KLayout: {msg.strip()}") from None
        raise ValueError(f"layout path {str(p)!r} could not be read as a layout ({msg.strip()}): {_WHAT}") from None
    untwist(db)  # bow-ties: KLayout's deep merge would lose them, its flat merge keeps them
    # KLayout keeps the unit in micrometres (0.001): shifted as a decimal, 1e-9 m stays exactly 1e-9 (and a unit
    # below 0.1 nm, whose repr is "1e-05", shifts as well: pasting "e-6" to it made "1e-05e-6", not a number)
    return Layout(db=db, path=p, format=fmt, dbu=float(Decimal(repr(db.dbu)).scaleb(-6)))


#: Cell names listed in a message at most (a library of unused cells has hundreds of top cells).
_LISTED = 10


def _count(n: int, noun: str) -> str:
    """``n`` and the noun, plural unless ``n`` is 1."""
    return f"{n} {noun}{'' if n == 1 else 's'}"


def _names(names: list[str]) -> str:
    """Up to :data:`_LISTED` names, then how many more."""
    shown = ", ".join(repr(n) for n in names[:_LISTED])
    return f"[{shown}{f', ... and {len(names) - _LISTED} more' if len(names) > _LISTED else ''}]"


def top_cell(layout: Layout, top: str | None = None) -> kdb.Cell:
    """The die: the cell named ``top``, else the file's only top-level cell.

    Raises ValueError naming ``--top`` (``top=`` in Python) and listing the valid names when
    ``top`` is unknown or when the file has several top-level cells and ``top`` was not given.
    KLayout's ``$$$CONTEXT_INFO$$$`` cell is metadata, never a top cell.
    """
    db = layout.db
    tops = sorted(c.name for c in db.top_cells())
    if top is not None:
        cell = db.cell(str(top))
        if cell is None:
            raise ValueError(f"--top {top!r}: no such cell in {layout.name}; its top-level cells are {_names(tops)} "
                             f"({_count(sum(1 for _ in db.each_cell()), 'cell')} in all)")
        if cell.is_ghost_cell():
            raise ValueError(f"--top {top!r}: {layout.name} places this cell but does not define it (a ghost cell, without "
                             f"shapes); its top-level cells are {_names(tops)}")
    elif not tops:
        raise ValueError(f"layout {layout.name} has no cells")
    elif len(tops) > 1:
        raise ValueError(f"layout {layout.name} has {len(tops)} top-level cells {_names(tops)}: "
                         "choose the die with --top NAME (top=NAME in Python)")
    else:
        cell = db.cell(tops[0])
    check_extent(layout, cell)
    return cell


def check_extent(layout: Layout, cell: kdb.Cell) -> None:
    """A ValueError if a placement under ``cell`` puts shapes past KLayout's 32-bit coordinates.

    GDSII and OASIS allow it (a placement at 1.5e9 dbu of a cell 1.5e9 dbu wide), but KLayout keeps
    every cell's box and every merged shape in 32-bit integers (dbu): a magnified placement there
    comes out at -2**31 and a translated one wraps round, so the die's box, and the shapes, would
    be silently wrong (or KLayout's merge fails an internal check). Cells are visited children
    first, so a child's box from KLayout is right when its placements are looked at. A placement
    whose box from KLayout lies within +-2**30 dbu, of a child within +-2**29 dbu, cannot have
    wrapped (a wrapped coordinate lands beyond 2**30, a saturated one on -2**31); any other one,
    and every array, is placed again in floating point and the first past [-2**31, 2**31 - 1] is
    named. One pass over the placements (arrays once): 0.2 s for 179,000.
    """
    db = layout.db
    under = set(cell.called_cells())
    under.add(cell.cell_index())
    safe = kdb.Box(-2**30, -2**30, 2**30, 2**30)
    boxes: dict[int, tuple[kdb.DBox, bool]] = {}
    for ci in db.each_cell_bottom_up():
        if ci not in under:
            continue
        for inst in db.cell(ci).each_inst():
            child = inst.cell_index
            got = boxes.get(child)
            if got is None:
                b = db.cell(child).bbox()
                got = boxes[child] = (kdb.DBox(b), b.empty() or b.inside(kdb.Box(-2**29, -2**29, 2**29, 2**29)))
            box, small = got
            if box.empty() or (small and not inst.is_regular_array() and inst.bbox().inside(safe)):
                continue
            placed = box.transformed(kdb.DCplxTrans(inst.cplx_trans))
            if inst.is_regular_array():
                a = kdb.DVector(inst.a) * (max(inst.na, 1) - 1)
                b = kdb.DVector(inst.b) * (max(inst.nb, 1) - 1)
                placed = placed + placed.moved(a) + placed.moved(b) + placed.moved(a + b)
            if min(placed.left, placed.bottom) < -COORD_LIMIT or max(placed.right, placed.top) > COORD_LIMIT - 1:
                reach = max(-placed.left, -placed.bottom, placed.right, placed.top)
                d = inst.trans.disp
                array = f", an array of {inst.na} x {inst.nb} stepped by ({inst.a}) and ({inst.b})" if inst.is_regular_array() else ""
                raise ValueError(
                    f"layout {layout.name}: the placement of cell {db.cell(child).name!r} in {db.cell(ci).name!r} at ({d.x}, {d.y}) dbu "
                    f"(transformation {inst.cplx_trans}{array}) puts shapes {reach:,.0f} dbu from the origin ({reach * layout.dbu * 1e3:.6g} mm), past "
                    f"KLayout's 32-bit coordinates (+-2**31 dbu = +-{COORD_LIMIT * layout.dbu * 1e3:.4g} mm at a database unit of "
                    f"{layout.dbu:g} m), where its boxes and merges overflow; choose a cell below it with --top, or fix the "
                    "placement (its offset, magnification or array pitch) in the layout")


def layers_in(layout: Layout, cell: kdb.Cell | None = None) -> set[tuple[int, int]]:
    """Every (layer, datatype) that carries a shape under ``cell`` (default: any top cell)."""
    db = layout.db
    cells = [cell] if cell is not None else list(db.top_cells())
    found: set[tuple[int, int]] = set()
    for li in db.layer_indexes():
        info = db.get_info(li)
        if any(not c.bbox(li).empty() for c in cells):
            found.add((int(info.layer), int(info.datatype)))
    return found


def layer_listing(pairs) -> str:
    """The (layer, datatype) ``pairs`` of a file's shapes (:func:`layers_in`) as "L/D, L/D, ...", or why there are none."""
    return ", ".join(f"{l}/{d}" for l, d in sorted(pairs)) or "none (the file holds no shapes: empty cells or texts only)"


def layer_indexes(layout: Layout, pairs) -> list[int]:
    """KLayout's layer indexes of the (layer, datatype) pairs the file has (others skipped)."""
    out = []
    for l, d in sorted(set(pairs)):
        li = layout.db.find_layer(int(l), int(d))
        if li is not None:
            out.append(li)
    return out
