"""Named metal layers of the three open PDKs, user layer maps, and "L/D" strings.

A name resolves to every (layer, datatype) pair that is the same physical film: the
drawn datatype and the fill (dummy) datatype, merged by the extraction.

Sources (GDS numbers as published by the PDKs):

* ``sky130``: SkyWater SKY130 GDS layer table (skywater-pdk documentation, "rules/layers",
  gds_layers.csv) and the open_pdks Magic GDS style (sky130.tech, ``calma`` lines):
  li1 67/20, met1 68/20 ... met5 72/20 drawn; fill li1fill 56/28, met1fill 36/28,
  met2fill 41/28, met3fill 34/28, met4fill 51/28, met5fill 59/28.
* ``gf180mcu``: GlobalFoundries GF180MCU design manual, layer table (gf180mcu-pdk
  documentation): Metal1 34/0, Metal2 36/0, Metal3 42/0, Metal4 46/0, Metal5 81/0,
  MetalTop 53/0; "Metal* Dummy Fill" on datatype 4 of the same layer.
* ``sg13g2``: IHP SG13G2 open PDK layer map (IHP-Open-PDK, libs.tech/klayout/tech
  sg13g2 layer properties; the same map as gdsfactory's ``ihp.tech.LAYER``): Metal1 8/0,
  Metal2 10/0, Metal3 30/0, Metal4 50/0, Metal5 67/0, TopMetal1 126/0, TopMetal2 134/0;
  ``filler`` datatype 22 of the same layer.

A user map is a TOML file of ``name = ["L/D", ...]`` lines, e.g. ``m1 = ["68/20", "36/28"]``.
"""

from __future__ import annotations

import os
import re
import tomllib
from pathlib import Path

__all__ = ["PDK_LAYER_MAPS", "load_layer_map", "resolve_layer", "resolve_layers", "parse_layer"]

Pair = tuple[int, int]

PDK_LAYER_MAPS: dict[str, dict[str, tuple[Pair, ...]]] = {
    "sky130": {
        "li1": ((67, 20), (56, 28)),
        "met1": ((68, 20), (36, 28)),
        "met2": ((69, 20), (41, 28)),
        "met3": ((70, 20), (34, 28)),
        "met4": ((71, 20), (51, 28)),
        "met5": ((72, 20), (59, 28)),
    },
    "gf180mcu": {
        "metal1": ((34, 0), (34, 4)),
        "metal2": ((36, 0), (36, 4)),
        "metal3": ((42, 0), (42, 4)),
        "metal4": ((46, 0), (46, 4)),
        "metal5": ((81, 0), (81, 4)),
        "metaltop": ((53, 0), (53, 4)),
    },
    "sg13g2": {
        "metal1": ((8, 0), (8, 22)),
        "metal2": ((10, 0), (10, 22)),
        "metal3": ((30, 0), (30, 22)),
        "metal4": ((50, 0), (50, 22)),
        "metal5": ((67, 0), (67, 22)),
        "topmetal1": ((126, 0), (126, 22)),
        "topmetal2": ((134, 0), (134, 22)),
    },
}

_PAIR = re.compile(r"^\s*(\d+)\s*/\s*(\d+)\s*$")


def parse_layer(text: str) -> Pair | None:
    """``"68/20"`` -> (68, 20); None if ``text`` is not of that form."""
    m = _PAIR.match(str(text))
    if not m:
        return None
    return int(m.group(1)), int(m.group(2))


def load_layer_map(path: str | os.PathLike) -> dict[str, tuple[Pair, ...]]:
    """Read a TOML layer map ``name = ["L/D", ...]`` (names are case-insensitive).

    Raises FileNotFoundError or ValueError (naming ``layer_map`` and the offending entry).
    """
    p = Path(path)
    if not p.is_file():
        raise FileNotFoundError(f"layer_map {str(p)!r} does not exist (expected a TOML file of name = [\"L/D\", ...])")
    try:
        data = tomllib.loads(p.read_text())
    except (tomllib.TOMLDecodeError, UnicodeDecodeError) as exc:
        raise ValueError(f"layer_map {str(p)!r} is not valid TOML ({exc}); expected name = [\"L/D\", ...]") from exc
    out: dict[str, tuple[Pair, ...]] = {}
    for name, value in data.items():
        items = [value] if isinstance(value, str) else value
        if not isinstance(items, list) or not items:
            raise ValueError(f"layer_map {p.name}: {name!r} must be a list of \"L/D\" strings, got {value!r}")
        pairs = []
        for item in items:
            pair = parse_layer(item) if isinstance(item, str) else None
            if pair is None:
                raise ValueError(f"layer_map {p.name}: {name!r} has {item!r}, expected \"L/D\" such as \"68/20\"")
            pairs.append(pair)
        out[name.lower()] = tuple(pairs)
    return out


def resolve_layer(spec, pdk: str | None = None, layer_map=None) -> tuple[Pair, ...]:
    """The (layer, datatype) pairs of one layer spec.

    ``spec`` is ``"L/D"``, a (layer, datatype) tuple, or a name looked up in ``layer_map``
    (a dict from :func:`load_layer_map` or a path to such a file) and then in the PDK
    map ``pdk`` (``"sky130"``, ``"gf180mcu"`` or ``"sg13g2"``).
    """
    if isinstance(spec, tuple) and len(spec) == 2:
        return ((int(spec[0]), int(spec[1])),)
    pair = parse_layer(spec)
    if pair is not None:
        return (pair,)
    if pdk is not None and pdk not in PDK_LAYER_MAPS:
        raise ValueError(f"pdk {pdk!r} is unknown; valid: {sorted(PDK_LAYER_MAPS)}")
    if isinstance(layer_map, (str, os.PathLike)):
        layer_map = load_layer_map(layer_map)
    name = str(spec).lower()
    if layer_map and name in layer_map:
        return tuple(layer_map[name])
    if pdk is not None and name in PDK_LAYER_MAPS[pdk]:
        return PDK_LAYER_MAPS[pdk][name]
    known = sorted(set(layer_map or {}) | set(PDK_LAYER_MAPS.get(pdk, {}) if pdk else set()))
    hint = f"names known here: {known}" if known else "give a pdk (sky130, gf180mcu, sg13g2) or a layer_map for names"
    raise ValueError(f"layer {spec!r} is neither \"L/D\" (e.g. \"68/20\") nor a known name; {hint}")


def resolve_layers(specs, pdk: str | None = None, layer_map=None) -> list[tuple[Pair, ...]]:
    """One tuple of pairs per spec (see :func:`resolve_layer`); a single spec may be given bare."""
    if isinstance(specs, (str, tuple)):
        specs = [specs]
    if isinstance(layer_map, (str, os.PathLike)):
        layer_map = load_layer_map(layer_map)
    out = [resolve_layer(s, pdk, layer_map) for s in specs]
    if not out:
        raise ValueError("layers is empty: give at least one \"L/D\" or layer name")
    return out
