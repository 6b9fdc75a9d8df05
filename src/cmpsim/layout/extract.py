"""Per-window pattern density, line width and line space of a layout's merged shapes.

Definitions (window of side W, A the area of the merged shapes inside it, L the length
of their boundary inside it, a boundary piece lying on the window's edge counting half):

* ``density = A / W**2``
* ``width   = 2 A / L``          (a line of width w and length l: 2 w l / 2 l = w)
* ``space   = 2 (W**2 - A) / L`` (the same for the complement, which has the same boundary)

so that ``width + space = 2 W**2 / L`` is the pitch and ``width / (width + space)`` the
density.  A window full of parallel lines of width w and pitch p, the window spanning a
whole number of pitches, gives exactly w and p - w wherever it sits on the array (a line
cut by the window's edge leaves its other part, and its other edge, in the neighbour).
A window without boundary (L = 0) is empty (width 0, space W) or full (width W, space 0).
"""

from __future__ import annotations

import math
import os
from dataclasses import dataclass

import numpy as np

from .engine import WindowGrid, window_rasters
from .layermaps import resolve_layers
from .reader import Layout, LayoutTooLarge, layer_indexes, layer_listing, layers_in, read_layout, top_cell

__all__ = ["LayoutWindows", "extract_windows", "extract_levels", "window_fields", "MAX_WINDOWS"]


@dataclass(frozen=True)
class LayoutWindows:
    """Fields on a regular grid of square windows (SI units).

    ``x`` (nx,) and ``y`` (ny,) are the window centres (m, layout coordinates);
    ``density`` (-), ``width`` (m), ``space`` (m) and ``boundary`` (m, L above) are
    (ny, nx) arrays indexed [row along y, column along x].  ``window`` is the side (m),
    ``origin`` the lower-left corner of window [0, 0] (m), ``bbox`` the top cell's
    bounding box (xmin, ymin, xmax, ymax) in m, ``layers`` the merged (layer, datatype)
    pairs, ``top`` the cell's name, ``dbu`` the database unit (m).
    """

    x: np.ndarray
    y: np.ndarray
    density: np.ndarray
    width: np.ndarray
    space: np.ndarray
    boundary: np.ndarray
    window: float
    origin: tuple[float, float]
    bbox: tuple[float, float, float, float]
    layers: tuple[tuple[int, int], ...]
    top: str
    dbu: float


def window_fields(area: np.ndarray, boundary: np.ndarray, window: float):
    """(density, width, space) from per-window area (m^2) and boundary length (m); window in m."""
    full = window * window
    density = area / full
    with np.errstate(divide="ignore", invalid="ignore"):
        width = np.where(boundary > 0, 2.0 * area / boundary, np.where(area > 0, window, 0.0))
        space = np.where(boundary > 0, 2.0 * (full - area) / boundary, np.where(area < full, window, 0.0))
    return density, width, np.maximum(space, 0.0)


def dbu_count(value: float, dbu: float, what: str) -> int:
    """``value`` (m) as a whole number of database units ``dbu`` (m); a ValueError naming ``what`` if it is not one (to 1e-6)."""
    n = value / dbu
    k = round(n)
    if abs(n - k) > 1e-6 * max(1.0, abs(n)):
        raise ValueError(f"{what} = {value:g} m is not a whole number of database units: it must be a multiple of the layout's "
                         f"database unit, {dbu:g} m")
    return int(k)


#: Windows of one die above which the grid is refused (each window holds a few dozen float64
#: fields through the die model): a 20 mm die at 20 um windows is 1e6.
MAX_WINDOWS = 25_000_000
#: Bytes one window costs at the peak of ``cmpsim die`` (measured: 11.1 GB for the 15.8 million
#: windows of a 20 mm chip at 5 um, 700 bytes each): a machine with less physical memory than
#: that for the grid refuses it below :data:`MAX_WINDOWS` (it would be killed or swap instead).
BYTES_PER_WINDOW = 800


def _physical_memory() -> int | None:
    """The machine's physical memory in bytes, None where the system does not tell."""
    try:
        return int(os.sysconf("SC_PHYS_PAGES")) * int(os.sysconf("SC_PAGE_SIZE"))
    except (ValueError, OSError, AttributeError):
        return None


def _pairs(layout: Layout, cell, layers, pdk, layer_map) -> set[tuple[int, int]]:
    """The (layer, datatype) pairs of the specs that the die has; ValueError naming a spec it lacks."""
    groups = resolve_layers(layers, pdk=pdk, layer_map=layer_map)
    in_file = layers_in(layout)
    present = layers_in(layout, cell)
    listing = layer_listing(in_file)
    pairs: set[tuple[int, int]] = set()
    for spec, group in zip([layers] if isinstance(layers, (str, tuple)) else layers, groups):
        have = [p for p in group if p in present]
        if not have:
            want = ", ".join(f"{l}/{d}" for l, d in group)
            if any(p in in_file for p in group):
                here = ", ".join(f"{l}/{d}" for l, d in sorted(present)) or f"none (no shapes under {cell.name!r})"
                raise ValueError(f"--layer {spec!r}: layers {want} have no shapes under top cell {cell.name!r} (an empty layer: they are drawn "
                                 f"only under other top cells of {layout.name}); the die's layers are: {here}")
            raise ValueError(f"--layer {spec!r} ({want}) is not in {layout.name}; its layers are: {listing}")
        pairs.update(have)
    return pairs


def _grid(layout: Layout, cell, window: float, origin) -> tuple[WindowGrid, tuple[int, int, int, int]]:
    dbu = layout.dbu
    if not (isinstance(window, (int, float)) and window > 0 and math.isfinite(window)):
        shown = f"{window:g}" if isinstance(window, (int, float)) else repr(window)
        raise ValueError(f"window = {shown} must be a positive length in metres (--window)")
    w = dbu_count(window, dbu, "--window")
    box = cell.bbox()
    if box.empty():
        raise ValueError(f"top cell {cell.name!r} is empty")
    bx0, by0, bx1, by1 = box.left, box.bottom, box.right, box.top
    if w > bx1 - bx0 or w > by1 - by0:
        raise ValueError(f"window = {window:g} m (--window) is larger than the die {cell.name!r} "
                         f"({(bx1 - bx0) * dbu:g} x {(by1 - by0) * dbu:g} m); choose a smaller window")
    if origin is None:
        ox, oy = bx0, by0
    else:
        ox, oy = dbu_count(origin[0], dbu, "origin x"), dbu_count(origin[1], dbu, "origin y")
    nx = max(int(math.ceil((bx1 - ox) / w)), 1)
    ny = max(int(math.ceil((by1 - oy) / w)), 1)
    memory = _physical_memory()
    limit = MAX_WINDOWS if not memory else max(1, min(MAX_WINDOWS, memory // BYTES_PER_WINDOW))
    if nx * ny > limit:
        held = "" if limit == MAX_WINDOWS else f" (its {memory / 2**30:.1f} GiB at about {BYTES_PER_WINDOW} bytes a window)"
        raise LayoutTooLarge(f"window = {window:g} m (--window) cuts the die {cell.name!r} ({(bx1 - bx0) * dbu * 1e3:g} x "
                             f"{(by1 - by0) * dbu * 1e3:g} mm) into {nx} x {ny} = {nx * ny:,} windows, more than the "
                             f"{limit:,} this machine's memory{held} is sized for: choose a larger --window "
                             f"(at least {math.sqrt((bx1 - bx0) * (by1 - by0) / limit) * dbu * 1e6:.3g} um) or a smaller region")
    return WindowGrid(int(ox), int(oy), int(w), nx, ny), (bx0, by0, bx1, by1)


def _windows(layout: Layout, cell, pairs, grid: WindowGrid, box, threads, big, progress, stats) -> LayoutWindows:
    dbu = layout.dbu
    lis = layer_indexes(layout, pairs)
    try:
        area, length = window_rasters(layout.db, cell, lis, grid, threads=threads, big=big, progress=progress, stats=stats)
    except MemoryError:
        raise LayoutTooLarge(f"the shapes of layers {sorted(pairs)} under {cell.name!r} do not fit in this machine's memory "
                             "when merged: choose a larger --window, a smaller region (--top a sub-cell), or more memory") from None
    except RuntimeError as exc:
        if "bad_alloc" in str(exc) or "memory" in str(exc).lower():
            raise LayoutTooLarge(f"the shapes of layers {sorted(pairs)} under {cell.name!r} do not fit in this machine's memory "
                                 f"when merged ({str(exc).strip()}): choose a smaller region (--top a sub-cell) or more memory") from None
        raise
    if not np.any(area > 0):
        want = ", ".join(f"{l}/{d}" for l, d in sorted(pairs))
        raise ValueError(f"layers {want} have no shapes in the windows of top cell {cell.name!r} (an empty layer)")
    w = grid.w
    full = float(w) * w
    # sums of pasted windows carry float noise (~1e-4 dbu^2 on 1e12); a real piece of a shape in a
    # window has at least ~1 dbu^2 of area and 1 dbu of outline: snap the noise of empty and full windows
    area = np.where(np.abs(area) < 1e-3, 0.0, np.where(np.abs(area - full) < 1e-3, full, area))
    length = np.where(np.abs(length) < 1e-3, 0.0, length)
    area_m = np.clip(area, 0.0, full) * dbu * dbu
    length_m = np.maximum(length, 0.0) * dbu
    window_m = w * dbu
    _, width, space = window_fields(area_m, length_m, window_m)
    density = np.clip(area, 0.0, full) / full  # in dbu^2: a full window is exactly 1
    bx0, by0, bx1, by1 = box
    return LayoutWindows(
        x=(grid.ox + (np.arange(grid.nx) + 0.5) * w) * dbu,
        y=(grid.oy + (np.arange(grid.ny) + 0.5) * w) * dbu,
        density=density, width=width, space=space, boundary=length_m,
        window=window_m, origin=(grid.ox * dbu, grid.oy * dbu),
        bbox=(bx0 * dbu, by0 * dbu, bx1 * dbu, by1 * dbu),
        layers=tuple(sorted(pairs)), top=cell.name, dbu=dbu,
    )


def _threads() -> int:
    return max(1, min(2, os.cpu_count() or 1))


def extract_windows(layout: Layout | str | os.PathLike, layers, window: float, *, top: str | None = None,
                    pdk: str | None = None, layer_map=None, origin: tuple[float, float] | None = None,
                    big: int | None = None, progress=None, stats: dict | None = None) -> LayoutWindows:
    """Density, line width and line space per window of the merged shapes of ``layers``.

    ``layout`` is a :class:`Layout` or a path (.gds, .gds.gz, .oas; read with KLayout);
    ``layers`` one or several specs (``"68/20"``, ``(68, 20)`` or a name resolved with
    ``pdk``/``layer_map``, see :mod:`.layermaps`), all merged; ``window`` the window side (m,
    a whole number of database units, at most the die's width and height); ``top`` the cell
    (required when the file has several top-level cells); ``origin`` the lower-left corner of
    the grid (m, default the top cell's bounding-box corner); ``big`` the size (in windows)
    from which a placed cell is merged once and pasted (:mod:`.hierarchy`; the result is the
    same, only the time differs); ``progress`` a callable told (stage, done, total);
    ``stats`` a dict that receives what the engine did.

    Raises ValueError (naming the parameter and the valid values) for a layer the file
    lacks, layers without shapes under the top cell, or a window larger than the die, and
    :class:`LayoutTooLarge` when the grid or the merge does not fit the machine.
    """
    if not isinstance(layout, Layout):
        layout = read_layout(layout)
    cell = top_cell(layout, top)
    pairs = _pairs(layout, cell, layers, pdk, layer_map)
    grid, box = _grid(layout, cell, window, origin)
    return _windows(layout, cell, pairs, grid, box, _threads(), big, progress, stats)


def extract_levels(layout: Layout | str | os.PathLike, levels, window: float, *, top: str | None = None,
                   pdk: str | None = None, layer_map=None, origin: tuple[float, float] | None = None,
                   big: int | None = None, progress=None, names=None) -> list[LayoutWindows]:
    """:func:`extract_windows` for several levels (each a layer spec or a list of them) on one
    read of the file, one window grid and one store of KLayout's hierarchy. Every level's
    layers are checked before any is extracted; a level whose layers are missing or empty is
    named in the message (``names``: the levels' names, e.g. a stack file's, else their numbers)."""
    if not isinstance(layout, Layout):
        layout = read_layout(layout)
    cell = top_cell(layout, top)
    levels = list(levels)
    names = [str(k + 1) for k in range(len(levels))] if names is None else [repr(str(n)) for n in names]
    all_pairs = []
    for name, spec in zip(names, levels):
        try:
            all_pairs.append(_pairs(layout, cell, spec, pdk, layer_map))
        except ValueError as exc:
            raise ValueError(f"level {name} of {len(levels)}: {exc}") from None
    grid, box = _grid(layout, cell, window, origin)
    out = []
    for k, pairs in enumerate(all_pairs):
        def told(stage, done, total, k=k):
            if progress:
                progress(f"level {k + 1}/{len(all_pairs)}: {stage}", done, total)
        out.append(_windows(layout, cell, pairs, grid, box, _threads(), big, told if progress else None, None))
    return out
