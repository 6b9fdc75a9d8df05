"""Dummy-fill rules: the numbers of each open PDK, and the rules and fill layer of ``cmpsim die --fill``.

:class:`FillRules` holds the geometry of square fill (m); :data:`FILL_RULES` the defaults of
each open PDK per layer; :func:`fill_rules` a PDK's rules with overrides; :func:`resolve_fill`
the rules and the fill's (layer, datatype) from the die command's values (``--pdk``,
``--layer``, ``--fill-layer``, ``--fill-size`` ...), its errors naming those options.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, replace

from .layermaps import PDK_LAYER_MAPS, parse_layer, resolve_layer

__all__ = ["FillRules", "FILL_RULES", "fill_rules", "resolve_fill"]


@dataclass(frozen=True)
class FillRules:
    """The geometry rules of square dummy fill (all lengths in m).

    ``size`` the side of a fill square; ``spacing`` the least distance between two fill
    squares; ``keepout`` the least distance from a fill square to a drawn shape of the
    layer; ``edge`` the least distance from a fill square to the die's edge (the top
    cell's bounding box); ``source`` where the numbers come from.
    """

    size: float
    spacing: float
    keepout: float
    edge: float = 0.0
    source: str = "user"

    def __post_init__(self) -> None:
        for name in ("size", "spacing", "keepout", "edge"):
            v = getattr(self, name)
            if not (isinstance(v, (int, float)) and math.isfinite(v) and v >= 0):
                raise ValueError(f"fill rule {name} = {v!r} must be a length >= 0 m")
        if self.size <= 0:
            raise ValueError(f"fill rule size = {self.size!r} must be > 0 m")
        if self.spacing <= 0:
            raise ValueError(f"fill rule spacing = {self.spacing!r} must be > 0 m (squares must not touch)")

    @property
    def pitch(self) -> float:
        """size + spacing (m): the lattice step."""
        return self.size + self.spacing

    def replace(self, **values) -> "FillRules":
        """A copy with some rules changed (m); the source becomes "... with overrides"."""
        values = {k: v for k, v in values.items() if v is not None}
        if not values:
            return self
        src = self.source if "overrides" in self.source else f"{self.source}, with overrides"
        return replace(self, **values, source=src)


# The default rules per open PDK (m). Sources:
# * gf180mcu: OpenROAD-flow-scripts, flow/platforms/gf180/fill.json (the density_fill rules
#   of the GF180MCU platform): Metal1-5 non-OPC fill 2 um minimum side (widths 12/6/3/2 um by
#   2 um), "space_to_fill" 1.0 um, "space_to_non_fill" 2.0 um, "space_to_outline" 5 um.
# * sg13g2: OpenROAD-flow-scripts, flow/platforms/ihp-sg13g2/fill.json: Metal1-4 fill squares
#   2.00/1.00/0.58/0.3(0.4) um, space_to_fill 0.3 um, space_to_non_fill 3 um; Metal5,
#   TopMetal1-2 3 um squares, space_to_fill 1.6 um, space_to_non_fill 3 um; space_to_outline 70 um.
#   The largest square is used (fewest shapes).
# * sky130: ASSUMED, not read from the PDK here: the open_pdks fill generator (magic "cif
#   ostyle wafflefill" in sky130A.tech, sky130/custom/scripts/generate_fill.py) makes square
#   met1-met5 fill; its sizes were not read. 2 um squares, 1 um apart, 3 um from drawn metal
#   are chosen to be legal under SKY130's metal width/space rules (met1 min width 0.14 um,
#   space 0.14 um, periphery rules m1.1/m1.2) with margin. Override them for a tape-out.
_UM = 1e-6
_GF = FillRules(2.0 * _UM, 1.0 * _UM, 2.0 * _UM, 5.0 * _UM, "gf180mcu: OpenROAD-flow-scripts platforms/gf180/fill.json")
_SG = FillRules(2.0 * _UM, 0.3 * _UM, 3.0 * _UM, 70.0 * _UM, "sg13g2: OpenROAD-flow-scripts platforms/ihp-sg13g2/fill.json")
_SG_TOP = FillRules(3.0 * _UM, 1.6 * _UM, 3.0 * _UM, 70.0 * _UM, "sg13g2: OpenROAD-flow-scripts platforms/ihp-sg13g2/fill.json")
_SKY = FillRules(2.0 * _UM, 1.0 * _UM, 3.0 * _UM, 0.0, "sky130: assumed (PDK fill sizes not read; see layout/fillrules.py)")

#: pdk -> layer name -> FillRules (layer names as in :data:`cmpsim.layout.PDK_LAYER_MAPS`).
FILL_RULES: dict[str, dict[str, FillRules]] = {
    "sky130": {name: _SKY for name in ("li1", "met1", "met2", "met3", "met4", "met5")},
    "gf180mcu": {name: _GF for name in ("metal1", "metal2", "metal3", "metal4", "metal5", "metaltop")},
    "sg13g2": {**{f"metal{i}": _SG for i in range(1, 5)}, "metal5": _SG_TOP, "topmetal1": _SG_TOP, "topmetal2": _SG_TOP},
}


def fill_rules(pdk: str | None = None, layer: str | None = None, **overrides) -> FillRules:
    """The fill rules of ``pdk`` for ``layer`` (a name; default its first metal), overrides applied.

    Without a PDK every rule must be given (``size``, ``spacing``, ``keepout``; ``edge``
    defaults to 0). Raises ValueError naming the parameter and the valid values.
    """
    if pdk is None:
        missing = [k for k in ("size", "spacing", "keepout") if overrides.get(k) is None]
        if missing:
            raise ValueError(f"fill rules without a pdk need {', '.join(missing)} (or pdk = one of {sorted(FILL_RULES)})")
        return FillRules(**{k: v for k, v in overrides.items() if v is not None})
    if pdk not in FILL_RULES:
        raise ValueError(f"pdk {pdk!r} has no fill rules; valid: {sorted(FILL_RULES)}")
    table = FILL_RULES[pdk]
    name = next(iter(table)) if layer is None else str(layer).lower()
    if name not in table:
        raise ValueError(f"layer {layer!r} has no fill rules in {pdk}; valid: {sorted(table)}")
    return table[name].replace(**overrides)


def _pdk_names(layers, pdk, layer_map) -> list[str]:
    """The PDK layer names of the ``--layer`` values (by name, or by their drawn pair)."""
    names: list[str] = []
    if not pdk:
        return names
    table = PDK_LAYER_MAPS[pdk]
    for spec in layers:
        key = str(spec).lower()
        if key in table and parse_layer(spec) is None:
            name = key
        else:
            pairs = resolve_layer(spec, pdk, layer_map)
            name = next((n for n, mp in table.items() if mp[0] in pairs), None)
        if name is not None and name not in names:
            names.append(name)
    return names


def resolve_fill(layers, pdk: str | None = None, layer_map=None, fill_layer: str | None = None, *,
                 size: float | None = None, spacing: float | None = None, keepout: float | None = None,
                 edge: float | None = None) -> tuple[FillRules, tuple[int, int]]:
    """The fill rules and the fill's (layer, datatype) of ``cmpsim die --fill`` (lengths in m).

    Where ``pdk`` names the one ``--layer`` (by name, or its drawn pair), the fill layer defaults to
    that PDK's fill datatype of the layer and the rules to the PDK's, each overridable; otherwise
    ``fill_layer`` ("L/D") and ``size``, ``spacing``, ``keepout`` are required (``edge`` defaults to
    0). Raises ValueError naming the die command's option (``--fill-layer``, ``--fill-size`` ...)
    and the valid values; a keep-out of 0 is refused (fill touching a drawn shape would merge with it).
    """
    layers = [layers] if isinstance(layers, (str, tuple)) else list(layers)
    names = _pdk_names(layers, pdk, layer_map)
    one = names[0] if len(names) == 1 and len(layers) == 1 else None
    where = (f"--pdk {pdk} names the --layer {one}" if one else
             f"--pdk does not name one fill layer for --layer {', '.join(map(str, layers))}" if pdk else "without --pdk")
    if fill_layer is None:
        if one is None:
            raise ValueError(f"--fill needs --fill-layer L/D (the fill's layer/datatype, e.g. 36/28): {where}")
        pair = PDK_LAYER_MAPS[pdk][one][1]
    else:
        pair = parse_layer(fill_layer)
        if pair is None:
            raise ValueError(f"--fill-layer {fill_layer!r} must be L/D, a layer/datatype such as 36/28")
    values = {"size": size, "spacing": spacing, "keepout": keepout, "edge": edge}
    from_pdk = one is not None and one in FILL_RULES.get(pdk, {})
    if not from_pdk:
        missing = [f"--fill-{k}" for k in ("size", "spacing", "keepout") if values[k] is None]
        if missing:
            raise ValueError(f"--fill needs the fill rules {', '.join(missing)} (e.g. --fill-size 2um --fill-spacing 1um "
                             f"--fill-keepout 3um): {where}")
    try:
        rules = fill_rules(pdk, one, **values) if from_pdk else fill_rules(None, **values)
    except ValueError as exc:
        raise ValueError(str(exc).replace("fill rule ", "--fill-")) from None
    if not rules.keepout > 0:
        raise ValueError(f"--fill-keepout must be a length > 0 (fill touching a drawn shape would merge with it); got {rules.keepout!r} m")
    return rules, tuple(pair)
