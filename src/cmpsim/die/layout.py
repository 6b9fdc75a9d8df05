"""The layout of one die: a grid of local pattern density, its cell size, and line widths.

**CSV format** (``cmpsim die LAYOUT.csv``; :func:`read_layout`, :meth:`Layout.to_csv`)::

    # cmpsim die layout
    # name = my_die
    # cell_size = 50 um
    # [density]
    0.5,0.5,0.2, ...
    ...
    # [line_width um]
    1.0,1.0,0, ...
    ...

Lines starting with ``#`` are ``key = value`` metadata (``cell_size`` with units is required,
``name`` optional) or the header of a grid: ``# [density]`` (the local pattern density in
[0, 1]: the area fraction of the raised features, the metal lines) and, optionally,
``# [line_width UNIT]`` or ``# [pitch UNIT]`` (a unit such as ``um``; 0 where a cell has no
lines). The pitch of a line array is its line width over its density, so either grid gives the
other. Each grid has one row per line of cells; the **first row is the top of the die** (as a
mask is drawn) and every row has the same number of values. The die is nx x ny cells of
``cell_size``.

**Regions** (:meth:`Layout.regions`): the connected sets of cells with the same density and line
width: the blocks and line arrays of the layout, numbered from the bottom left. They belong to
block layouts; a die made from a real layout's windows (:meth:`Layout.from_windows`) has a
density, width and space of its own in every window and is reported per window instead.
"""

from __future__ import annotations

import io as _io
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

__all__ = ["Layout", "Region", "read_layout", "builtin_layout", "BUILTIN_LAYOUTS"]


@dataclass(frozen=True)
class Region:
    """One block or line array: its cells, density, line width (m, or None) and measurement site (the cell deepest inside it)."""

    index: int
    density: float
    line_width: float | None
    cells: np.ndarray = field(repr=False)  # boolean mask (ny, nx)
    site: tuple[int, int] = (0, 0)  # (iy, ix)

    @property
    def pitch(self) -> float | None:
        """Line pitch (m): line width over density (None without lines)."""
        if self.line_width is None or self.density <= 0:
            return None
        return self.line_width / self.density


@dataclass(frozen=True)
class Layout:
    """Local pattern density over one die (rows along y from the bottom), cell size (m), optional line widths (m).

    ``space`` (m, optional) is the line space of every cell; without it the space of a line
    array, w (1 - rho) / rho, is used. ``origin`` (m) is the lower-left corner of cell [0, 0] in
    the layout's coordinates and ``bbox`` (xmin, ymin, xmax, ymax, m) the die's outline when it
    came from a real layout (:meth:`from_windows`; ``windowed`` is then True).
    """

    density: np.ndarray
    cell_size: float
    line_width: np.ndarray | None = None
    name: str = "layout"
    space: np.ndarray | None = None
    origin: tuple[float, float] = (0.0, 0.0)
    bbox: tuple[float, float, float, float] | None = None
    windowed: bool = False
    layers: tuple = ()

    def __post_init__(self) -> None:
        rho = np.asarray(self.density, dtype=float)
        if rho.ndim != 2 or min(rho.shape) < 1:
            raise ValueError(f"density must be a 2-D grid of cells; got shape {rho.shape}")
        if not np.all(np.isfinite(rho)) or rho.min() < 0 or rho.max() > 1:
            raise ValueError(f"density must lie in [0, 1] in every cell; got values from {np.nanmin(rho):g} to {np.nanmax(rho):g}")
        if not (np.isfinite(self.cell_size) and self.cell_size > 0):
            raise ValueError(f"cell_size must be > 0 m; got {self.cell_size!r}")
        object.__setattr__(self, "density", rho)
        if self.line_width is not None:
            w = np.asarray(self.line_width, dtype=float)
            if w.shape != rho.shape:
                raise ValueError(f"line_width grid has shape {w.shape}, density {rho.shape}: they must match")
            if not np.all(np.isfinite(w)) or w.min() < 0:
                raise ValueError("line_width must be >= 0 m in every cell (0: no lines)")
            object.__setattr__(self, "line_width", w)
        if self.space is not None:
            sp = np.asarray(self.space, dtype=float)
            if sp.shape != rho.shape:
                raise ValueError(f"space grid has shape {sp.shape}, density {rho.shape}: they must match")
            if not np.all(np.isfinite(sp)) or sp.min() < 0:
                raise ValueError("space must be >= 0 m in every cell")
            object.__setattr__(self, "space", sp)

    @classmethod
    def from_windows(cls, windows, name: str | None = None) -> "Layout":
        """The die of a real layout's windows (:class:`cmpsim.layout.LayoutWindows`): every window a cell with its own density, width and space."""
        # the last row and column of windows may reach past the die's outline: their fields are those of the part inside it
        # (on the wafer the rest of such a window is the next die, which its opposite edge stands for in the periodic model)
        W = float(windows.window)
        x0, y0, x1, y1 = windows.bbox
        fx = np.clip((np.minimum(windows.x + 0.5 * W, x1) - np.maximum(windows.x - 0.5 * W, x0)) / W, 0.0, 1.0)
        fy = np.clip((np.minimum(windows.y + 0.5 * W, y1) - np.maximum(windows.y - 0.5 * W, y0)) / W, 0.0, 1.0)
        inside = np.maximum(fy[:, None] * fx[None, :], 1e-300) * W * W
        area = np.asarray(windows.density, dtype=float) * W * W
        length = np.asarray(windows.boundary, dtype=float)
        rho = np.clip(area / inside, 0.0, 1.0)
        with np.errstate(divide="ignore", invalid="ignore"):
            space = np.where(length > 0, 2.0 * np.maximum(inside - area, 0.0) / length, np.where(rho < 1, np.sqrt(inside), 0.0))
        width = np.where(rho > 0, np.asarray(windows.width, dtype=float), 0.0)
        return cls(rho, W, width, name or windows.top, space,
                   tuple(float(v) for v in windows.origin), tuple(float(v) for v in windows.bbox), True, tuple(windows.layers))

    def with_fields(self, density=None, line_width=None, space=None) -> "Layout":
        """A copy with some per-cell fields replaced (e.g. a die with fill added)."""
        from dataclasses import replace

        return replace(self, **{k: v for k, v in (("density", density), ("line_width", line_width), ("space", space)) if v is not None})

    @property
    def shape(self) -> tuple[int, int]:
        """(ny, nx) cells."""
        return self.density.shape

    @property
    def size(self) -> tuple[float, float]:
        """Die size (width along x, height along y), m."""
        ny, nx = self.shape
        return nx * self.cell_size, ny * self.cell_size

    def coordinates(self) -> tuple[np.ndarray, np.ndarray]:
        """Cell-centre coordinates (x of the columns, y of the rows), m, from :attr:`origin` (the bottom-left corner; a real layout's coordinates)."""
        ny, nx = self.shape
        return self.origin[0] + (np.arange(nx) + 0.5) * self.cell_size, self.origin[1] + (np.arange(ny) + 0.5) * self.cell_size

    @property
    def extent(self) -> tuple[float, float, float, float]:
        """(xmin, ymin, xmax, ymax) of the die, m: the layout's bounding box, or the grid's."""
        if self.bbox is not None:
            return self.bbox
        wx, wy = self.size
        return self.origin[0], self.origin[1], self.origin[0] + wx, self.origin[1] + wy

    def widths(self) -> np.ndarray:
        """Line width of every cell (m); NaN where the layout gives none."""
        if self.line_width is None:
            return np.full(self.shape, np.nan)
        return np.where(self.line_width > 0, self.line_width, np.nan)

    def spaces(self) -> np.ndarray:
        """Line space of every cell (m): the given ``space``, else w (1 - rho) / rho; NaN where a cell has no lines or no space."""
        rho = self.density
        two = (rho > 0) & (rho < 1)
        if self.space is not None:
            return np.where(two & (self.space > 0), self.space, np.nan)
        with np.errstate(divide="ignore", invalid="ignore"):
            return np.where(two, self.widths() * (1.0 - rho) / rho, np.nan)

    def pitches(self) -> np.ndarray:
        """Line pitch of every cell (m): width + space; NaN without lines."""
        if self.space is not None:
            return np.where(self.density > 0, self.widths() + self.space, np.nan)
        with np.errstate(divide="ignore", invalid="ignore"):
            return np.where(self.density > 0, self.widths() / self.density, np.nan)

    def regions(self) -> list[Region]:
        """The blocks and line arrays: connected cells of equal (density, line width)."""
        from scipy import ndimage

        w = np.nan_to_num(self.widths(), nan=-1.0)
        keys = np.stack([self.density, w], axis=-1).reshape(-1, 2)
        uniq, inverse = np.unique(keys, axis=0, return_inverse=True)
        inverse = inverse.reshape(self.shape)
        out = []
        for k, (rho, width) in enumerate(uniq):
            labels, n = ndimage.label(inverse == k)
            for lab in range(1, n + 1):
                cells = labels == lab
                depth = ndimage.distance_transform_cdt(np.pad(cells, 1), metric="chessboard")[1:-1, 1:-1]
                iy, ix = np.unravel_index(int(np.argmax(depth)), depth.shape)
                out.append((iy, ix, float(rho), None if width < 0 else float(width), cells))
        out.sort(key=lambda r: (r[0], r[1]))
        return [Region(i, rho, width, cells, (iy, ix)) for i, (iy, ix, rho, width, cells) in enumerate(out)]

    def to_csv(self, path) -> Path:
        """Write the layout in the CSV format of this module (line widths in um), atomically."""
        from ..io import atomic_write_text

        buf = _io.StringIO()
        buf.write(f"# cmpsim die layout\n# name = {self.name}\n# cell_size = {self.cell_size * 1e6:.12g} um\n# [density]\n")
        np.savetxt(buf, self.density[::-1], delimiter=",", fmt="%.10g")
        if self.line_width is not None:
            buf.write("# [line_width um]\n")
            np.savetxt(buf, self.line_width[::-1] * 1e6, delimiter=",", fmt="%.10g")
        atomic_write_text(Path(path), buf.getvalue())
        return Path(path)


def _grid(rows: list[str], what: str, path) -> np.ndarray:
    try:
        data = [[float(v) for v in r.split(",")] for r in rows]
    except ValueError as exc:
        raise ValueError(f"{path}: grid [{what}] holds a value that is not a number ({exc})") from None
    if not data:
        raise ValueError(f"{path}: grid [{what}] is empty")
    n = {len(r) for r in data}
    if len(n) != 1:
        raise ValueError(f"{path}: the rows of grid [{what}] have different lengths {sorted(n)}")
    return np.array(data)[::-1]  # first row = top of the die


def read_layout(path) -> Layout:
    """Read a layout CSV (format in the module docstring); ValueError naming what is wrong."""
    from ..inputs.units import to_si

    path = Path(path)
    if not path.is_file():
        raise ValueError(f"layout {str(path)!r} is neither a file nor a built-in die (cmpsim die --list)")
    meta: dict[str, str] = {}
    grids: dict[str, tuple[str, list[str]]] = {}
    current = None
    for raw in path.read_text(encoding="utf-8").splitlines():
        line = raw.strip()
        if not line:
            continue
        if line.startswith("#"):
            body = line.lstrip("#").strip()
            if body.startswith("[") and body.endswith("]"):
                parts = body[1:-1].split()
                name = parts[0].lower()
                if name not in ("density", "line_width", "pitch"):
                    raise ValueError(f"{path}: unknown grid [{name}]; valid grids: [density], [line_width UNIT], [pitch UNIT]")
                unit = parts[1] if len(parts) > 1 else ("" if name == "density" else None)
                if unit is None:
                    raise ValueError(f"{path}: grid [{name}] needs a unit, e.g. [{name} um]")
                grids[name] = (unit, [])
                current = name
            elif "=" in body:
                k, v = body.split("=", 1)
                meta[k.strip().lower()] = v.strip()
            continue
        if current is None:
            raise ValueError(f"{path}: values before the first grid header (# [density])")
        grids[current][1].append(line)
    if "density" not in grids:
        raise ValueError(f"{path}: no [density] grid")
    if "cell_size" not in meta:
        raise ValueError(f"{path}: no cell_size (a line '# cell_size = 50 um')")
    cell = to_si(meta["cell_size"], "m", "cell_size", "50 um")
    rho = _grid(grids["density"][1], "density", path)
    width = None
    if "line_width" in grids and "pitch" in grids:
        raise ValueError(f"{path}: give [line_width] or [pitch], not both")
    for key in ("line_width", "pitch"):
        if key in grids:
            unit, rows = grids[key]
            scale = to_si(f"1 {unit}", "m", key, "um")
            vals = _grid(rows, key, path) * scale
            if vals.shape != rho.shape:
                raise ValueError(f"{path}: grid [{key}] has {vals.shape[0]} x {vals.shape[1]} cells, [density] {rho.shape[0]} x {rho.shape[1]}")
            width = vals if key == "line_width" else vals * rho
    return Layout(rho, cell, width, meta.get("name", path.stem))


# ------------------------------------------------------------------------------ built-in dies
def _blocks(values, block: float, cell: float) -> np.ndarray:
    """Grid of cells from a table of block values (first row = top), blocks of side ``block`` (m)."""
    n = int(round(block / cell))
    if n < 1 or abs(n * cell - block) > 1e-9 * block:
        raise ValueError(f"cell_size = {cell:g} m must divide the block size {block:g} m")
    arr = np.asarray(values, dtype=float)[::-1]
    return np.kron(arr, np.ones((n, n)))


def _density_mask(cell: float) -> Layout:
    # 5 x 5 blocks of 4 mm, densities 10-90 % in a pattern that puts dense next to sparse; lines
    # at a 250 um pitch (width = density x pitch), like the density mask of Stine et al. 1998
    d = [[0.1, 0.5, 0.9, 0.3, 0.7], [0.7, 0.2, 0.6, 0.8, 0.4], [0.3, 0.8, 0.5, 0.1, 0.9], [0.9, 0.4, 0.2, 0.6, 0.3], [0.5, 0.6, 0.8, 0.4, 0.1]]
    rho = _blocks(d, 4e-3, cell)
    return Layout(rho, cell, rho * 250e-6, "density")


def _line_mask(cell: float) -> Layout:
    # 5 x 5 blocks of 4 mm: line widths 0.25-100 um at 50 % density (rows 1-2), densities 10-90 %
    # at 2 um lines (row 3) and at 50 um lines (row 4), open field (row 5): a copper
    # characterisation die after Park et al. (VMIC 1998) and Tugbawa (MIT PhD 2002)
    w = [[0.25, 0.5, 1.0, 2.0, 5.0], [10.0, 25.0, 50.0, 100.0, 0.0], [2.0] * 5, [50.0] * 5, [0.0] * 5]
    d = [[0.5] * 5, [0.5, 0.5, 0.5, 0.5, 0.0], [0.1, 0.3, 0.5, 0.7, 0.9], [0.1, 0.3, 0.5, 0.7, 0.9], [0.0] * 5]
    return Layout(_blocks(d, 4e-3, cell), cell, _blocks(w, 4e-3, cell) * 1e-6, "lines")


def _step(cell: float) -> Layout:
    # a density step 20 % | 80 % over a 10 mm die, lines at 100 um pitch
    rho = _blocks([[0.2, 0.8]], 5e-3, cell)
    rho = np.repeat(rho[:1], int(round(10e-3 / cell)), axis=0)
    return Layout(rho, cell, rho * 100e-6, "step")


def _uniform(cell: float) -> Layout:
    rho = _blocks([[0.5]], 2e-3, cell)
    return Layout(rho, cell, rho * 100e-6, "uniform")


#: The built-in test dies: name -> (description, builder(cell_size)).
BUILTIN_LAYOUTS = {
    "density": ("20 x 20 mm, 5 x 5 blocks of 4 mm with densities 10-90 %, lines at 250 um pitch (oxide ILD density mask)", _density_mask),
    "lines": ("20 x 20 mm, 4 mm blocks: line widths 0.25-100 um at 50 %, densities 10-90 % at 2 and 50 um lines, open field (copper mask)", _line_mask),
    "step": ("10 x 10 mm, a density step 20 % | 80 %, lines at 100 um pitch", _step),
    "uniform": ("2 x 2 mm, uniform 50 % density, lines at 100 um pitch", _uniform),
}


def builtin_layout(name: str, cell_size: float = 50e-6) -> Layout:
    """A built-in test die by name (:data:`BUILTIN_LAYOUTS`) at ``cell_size`` (m; must divide its blocks)."""
    if name not in BUILTIN_LAYOUTS:
        raise ValueError(f"no built-in die {name!r}; valid names: {', '.join(BUILTIN_LAYOUTS)}")
    return BUILTIN_LAYOUTS[name][1](cell_size)
