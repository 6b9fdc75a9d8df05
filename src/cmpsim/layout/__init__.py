"""Layouts in: any layout KLayout opens, per-window density, line width and space of merged shapes.

The engine is KLayout's Python module (``klayout.db``, GPL-3.0-or-later; cmpsim's own code is
MIT): its reader, its deep (hierarchical) merge and its rasteriser, with large cells placed many
times merged once and pasted (:mod:`.hierarchy`, :mod:`.engine`). This package imports nothing
else of cmpsim, so that the die model can build on it. See docs/layouts.md.
"""

from .extract import MAX_WINDOWS, LayoutWindows, extract_levels, extract_windows, window_fields
from .layermaps import PDK_LAYER_MAPS, load_layer_map, parse_layer, resolve_layer, resolve_layers
from .reader import Layout, LayoutTooLarge, layers_in, read_layout, top_cell

__all__ = [
    "Layout", "LayoutTooLarge", "LayoutWindows", "MAX_WINDOWS", "PDK_LAYER_MAPS", "extract_levels", "extract_windows",
    "layers_in", "load_layer_map", "parse_layer", "read_layout", "resolve_layer", "resolve_layers", "top_cell",
    "window_fields",
]
