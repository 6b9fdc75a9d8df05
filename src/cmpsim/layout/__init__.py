"""Layouts in: GDSII/OASIS read with gdstk, per-window density, line width and space.

This package imports nothing else of cmpsim (only numpy and gdstk), so that the die model
can build on it.  See docs/layouts.md.
"""

from .extract import LayoutWindows, extract_windows, window_fields
from .layermaps import PDK_LAYER_MAPS, load_layer_map, parse_layer, resolve_layer, resolve_layers
from .reader import Layout, layers_in, read_layout, top_cell

__all__ = [
    "Layout", "LayoutWindows", "PDK_LAYER_MAPS", "extract_windows", "layers_in", "load_layer_map",
    "parse_layer", "read_layout", "resolve_layer", "resolve_layers", "top_cell", "window_fields",
]
