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

from .hierarchy import CellRasters
from .layermaps import resolve_layers
from .reader import Layout, layers_in, read_layout, top_cell

__all__ = ["LayoutWindows", "extract_windows", "window_fields"]


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
        raise ValueError(f"{what} = {value!r} m is not a whole number of database units ({dbu:g} m)")
    return int(k)


def extract_windows(layout: Layout | str | os.PathLike, layers, window: float, *, top: str | None = None,
                    pdk: str | None = None, layer_map=None, origin: tuple[float, float] | None = None,
                    flat_limit: int = 200_000) -> LayoutWindows:
    """Density, line width and line space per window of the merged shapes of ``layers``.

    ``layout`` is a :class:`Layout` or a path (.gds, .gds.gz, .oas); ``layers`` one or
    several specs (``"68/20"``, ``(68, 20)`` or a name resolved with ``pdk``/``layer_map``,
    see :mod:`.layermaps`), all merged; ``window`` the window side (m, a whole number of
    database units, at most the die's width and height); ``top`` the cell (required when
    the file has several top-level cells); ``origin`` the lower-left corner of the grid (m,
    default the top cell's bounding-box corner); ``flat_limit`` the number of flattened
    shapes up to which a cell with references is flattened instead of composed from its
    children (the result is the same; only the time differs).

    Raises ValueError (naming the parameter and the valid values) for a layer the file
    lacks, layers without shapes under the top cell, or a window larger than the die.
    """
    if not isinstance(layout, Layout):
        layout = read_layout(layout)
    cell = top_cell(layout, top)
    groups = resolve_layers(layers, pdk=pdk, layer_map=layer_map)
    present = layers_in(layout)
    listing = ", ".join(f"{l}/{d}" for l, d in sorted(present))
    pairs: set[tuple[int, int]] = set()
    for spec, group in zip([layers] if isinstance(layers, (str, tuple)) else layers, groups):
        have = [p for p in group if p in present]
        if not have:
            want = ", ".join(f"{l}/{d}" for l, d in group)
            raise ValueError(f"layer {spec!r} ({want}) is not in {layout.path.name}; its layers are: {listing}")
        pairs.update(have)
    dbu = layout.dbu
    if not (isinstance(window, (int, float)) and window > 0 and math.isfinite(window)):
        raise ValueError(f"window = {window!r} must be a positive length in metres")
    w = dbu_count(window, dbu, "window")
    box = cell.bounding_box()
    if box is None:
        raise ValueError(f"top cell {cell.name!r} is empty")
    (bx0, by0), (bx1, by1) = np.round(box[0]), np.round(box[1])
    if w > bx1 - bx0 or w > by1 - by0:
        raise ValueError(f"window = {window:g} m is larger than the die {cell.name!r} "
                         f"({(bx1 - bx0) * dbu:g} x {(by1 - by0) * dbu:g} m); choose a smaller window")
    if origin is None:
        ox, oy = int(bx0), int(by0)
    else:
        ox, oy = dbu_count(origin[0], dbu, "origin x"), dbu_count(origin[1], dbu, "origin y")
    nx = max(int(math.ceil((bx1 - ox) / w)), 1)
    ny = max(int(math.ceil((by1 - oy) / w)), 1)

    engine = CellRasters(layout.library, pairs, w, flat_limit=flat_limit)
    phase = (ox % w, oy % w)
    area_r, len_r, ix0, iy0 = engine.raster(cell.name, phase=phase)
    area = np.zeros((ny, nx))
    length = np.zeros((ny, nx))
    # window [0, 0] of the die is grid window ((ox - phase) / w, ...) of the raster
    kx, ky = (ox - phase[0]) // w - ix0, (oy - phase[1]) // w - iy0
    if area_r.size:
        rh, rw = area_r.shape
        sx0, sy0 = max(kx, 0), max(ky, 0)
        sx1, sy1 = min(kx + nx, rw), min(ky + ny, rh)
        if sx1 > sx0 and sy1 > sy0:
            area[sy0 - ky:sy1 - ky, sx0 - kx:sx1 - kx] = area_r[sy0:sy1, sx0:sx1]
            length[sy0 - ky:sy1 - ky, sx0 - kx:sx1 - kx] = len_r[sy0:sy1, sx0:sx1]
    if not np.any(area > 0):
        want = ", ".join(f"{l}/{d}" for l, d in sorted(pairs))
        raise ValueError(f"layers {want} have no shapes under top cell {cell.name!r} (an empty layer); "
                         f"the file's layers are: {listing}")
    area_m = np.clip(area, 0.0, float(w) * w) * dbu * dbu
    length_m = length * dbu
    window_m = w * dbu
    density, width, space = window_fields(area_m, length_m, window_m)
    return LayoutWindows(
        x=(ox + (np.arange(nx) + 0.5) * w) * dbu,
        y=(oy + (np.arange(ny) + 0.5) * w) * dbu,
        density=density, width=width, space=space, boundary=length_m,
        window=window_m, origin=(ox * dbu, oy * dbu),
        bbox=(bx0 * dbu, by0 * dbu, bx1 * dbu, by1 * dbu),
        layers=tuple(sorted(pairs)), top=cell.name, dbu=dbu,
    )
