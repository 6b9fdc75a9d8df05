"""The one registry of outputs: every scalar, field and profile, with its SI unit and meaning.

Each output is declared once in :data:`OUTPUTS` with

* its **name** (a contract: no unit in any name, US spelling),
* its **kind**: ``"value"`` (a result scalar), ``"diagnostic"`` (a solver scalar),
  ``"field"`` (a wafer map on the polar grid), ``"profile"`` (a 1-D function of the wafer
  radius) or ``"coordinate"``,
* its **SI unit**, written so that CF / UDUNITS-2 read it (``"m"``, ``"Pa"``, ``"m s-1"``,
  ``"rad"``, ``"1"`` for a ratio),
* a **long name** saying what it is (and, where it matters, what it includes),
* the **display unit** of tables and plots with the factor SI -> display,
* its **reduction**: how it is obtained from the solved fields (see :data:`REDUCTIONS`),
* its data type, and the name it had in cmpsim 0.1 (schema 1), if any.

The table of ``cmpsim run``, the JSON (schema 2) and its JSON Schema, the NetCDF, the sweep
dataset, the model quantities of ``validate`` and the plots are all generated from it; old
(0.1) names resolve through :func:`canonical_name`.
"""

from __future__ import annotations

import warnings
from dataclasses import dataclass

__all__ = [
    "Output",
    "OUTPUTS",
    "REDUCTIONS",
    "SCHEMA_VERSION",
    "SCHEMA1_KEYS",
    "LEGACY_NAMES",
    "canonical_name",
    "legacy_value",
    "scalar_names",
    "value_names",
    "diagnostic_names",
    "field_names",
    "profile_names",
    "to_display",
    "output_table_markdown",
    "json_schema",
    "json_schema_text",
    "scalar",
    "field",
    "profile",
]

#: Version of the JSON object of ``cmpsim run --json`` / ``Result.to_dict()``.
SCHEMA_VERSION = 2

#: The reductions of :attr:`Output.reduction`.
REDUCTIONS = {
    "field": "a wafer map: cell values of the polar finite-volume grid",
    "state": "an unknown of the force and moment equilibrium",
    "setup": "computed from the inputs before the solve",
    "center": "the field at the wafer centre (evaluated exactly)",
    "min": "minimum of the field over the cell centres and the wafer rim",
    "wafer_mean": "area mean of the field over the wafer (midpoint rule on the grid)",
    "sum": "sum of the listed outputs",
    "load_share": "integral of the pressure field over the wafer / applied load",
    "reference_ratio": "wafer-mean removal rate over that of the reference case",
    "ring_mean": "rotation average: mean of the field over the cell centres of one ring (circle r = r_i)",
    "profile_std_over_mean": "area-weighted standard deviation / mean of the profile inside radius <= wafer radius - edge_exclusion",
    "profile_range": "max - min of the profile inside radius <= wafer radius - edge_exclusion",
    "solver": "a diagnostic of the Newton solver",
}


@dataclass(frozen=True)
class Output:
    """One output of cmpsim (see the module docstring)."""

    name: str
    kind: str  # value | diagnostic | field | profile | coordinate
    unit: str  # SI, CF/UDUNITS-2 syntax
    long_name: str
    display_unit: str  # unit of tables and plots ("-" for counts and flags)
    display_factor: float  # display value = SI value * display_factor
    reduction: str  # a key of REDUCTIONS
    of: tuple[str, ...] = ()  # the outputs it reduces
    dtype: str = "float"  # float | int | bool
    schema1: str | None = None  # name in cmpsim 0.1 (schema 1)
    optional: bool = False  # present only on request (removal_rate_relative, moment_roots_found)
    flag_meanings: tuple[str, ...] = ()  # bool outputs: meanings of 0 and 1 (CF flags)

    @property
    def netcdf_name(self) -> str:
        """Variable name in a single result's NetCDF.

        Equal to :attr:`name`, except for a scalar that is the wafer mean of the field of the
        same name (the contact area ratios): the map keeps the name and the scalar is stored
        as ``NAME_mean`` (with ``cell_methods = "area: mean"``), as the other wafer means are.
        """
        if self.kind in ("value", "diagnostic") and self.name in _FIELD_NAMES:
            return self.name + "_mean"
        return self.name

    @property
    def pint_unit(self) -> str:
        """The SI unit in pint's spelling (``"m/s"`` for ``"m s-1"``, ``"dimensionless"`` for ``"1"``)."""
        return {"m s-1": "m/s", "1": "dimensionless"}.get(self.unit, self.unit)

    @property
    def cf_attrs(self) -> dict:
        """CF attributes: ``long_name``, ``units`` (or ``flag_values``/``flag_meanings``), ``cell_methods``."""
        attrs: dict = {"long_name": self.long_name}
        if self.dtype == "bool":
            attrs["flag_values"] = [0, 1]
            attrs["flag_meanings"] = " ".join(self.flag_meanings)
        else:
            attrs["units"] = self.unit
        if self.reduction == "wafer_mean":
            attrs["cell_methods"] = "area: mean"
        if self.display_unit not in (self.unit, "", "-"):
            attrs["display_units"] = self.display_unit
        return attrs


_O = Output
_OUTPUT_LIST = [
    # ------------------------------------------------------------------ values (SI scalars)
    _O("film_thickness_center", "value", "m", "film thickness at the wafer centre", "um", 1e6, "center", ("film_thickness",), schema1="film_thickness_center_m"),
    _O("film_thickness_min", "value", "m", "minimum film thickness over the wafer", "um", 1e6, "min", ("film_thickness",), schema1="film_thickness_min_m"),
    _O("film_thickness_mean", "value", "m", "wafer-mean film thickness", "um", 1e6, "wafer_mean", ("film_thickness",)),
    _O("h0", "value", "m", "height of the rim-chord centre (pivot) above the pad mean plane", "um", 1e6, "state", schema1="h0_m"),
    _O("attack_angle", "value", "rad", "attack angle: tilt about y, > 0 converging along the sliding direction", "urad", 1e6, "state", schema1="attack_angle_rad"),
    _O("cross_tilt", "value", "rad", "cross tilt: tilt about x", "urad", 1e6, "state", schema1="cross_tilt_rad"),
    _O("fluid_load_fraction", "value", "1", "share of the applied load carried by the slurry", "%", 100.0, "load_share", ("slurry_pressure",), schema1="fluid_load_fraction"),
    _O("contact_load_fraction", "value", "1", "share of the applied load carried by the pad asperities", "%", 100.0, "load_share", ("contact_pressure",), schema1="contact_load_fraction"),
    _O("contact_area_ratio", "value", "1", "real contact area / wafer area (elastic + elastoplastic + plastic)", "%", 100.0, "sum",
       ("contact_area_ratio_elastic", "contact_area_ratio_elastoplastic", "contact_area_ratio_plastic")),
    _O("contact_area_ratio_elastic", "value", "1", "elastic real contact area / wafer area", "%", 100.0, "wafer_mean", ("contact_area_ratio_elastic",), schema1="contact_area_ratio_elastic"),
    _O("contact_area_ratio_elastoplastic", "value", "1", "elastoplastic real contact area / wafer area", "%", 100.0, "wafer_mean", ("contact_area_ratio_elastoplastic",), schema1="contact_area_ratio_elastoplastic"),
    _O("contact_area_ratio_plastic", "value", "1", "plastic real contact area / wafer area", "%", 100.0, "wafer_mean", ("contact_area_ratio_plastic",), schema1="contact_area_ratio_plastic"),
    _O("normal_stress_mean", "value", "Pa", "wafer-mean normal stress of the removal law: contact pressure plus the slurry pressure (granular: absolute, ambient p0 included)", "kPa", 1e-3, "wafer_mean", ("normal_stress",), schema1="mean_normal_stress_pa"),
    _O("shear_stress_mean", "value", "Pa", "wafer-mean shear stress magnitude tau on the wafer", "kPa", 1e-3, "wafer_mean", ("shear_stress",), schema1="mean_shear_stress_pa"),
    _O("removal_rate_mean", "value", "m s-1", "wafer-mean removal rate", "nm/min", 6e10, "wafer_mean", ("removal_rate",), schema1="removal_rate"),
    _O("removal_rate_relative", "value", "1", "wafer-mean removal rate / that of the reference case (LEP, 100 nm, sigma = reference_roughness: 15 um in the paper preset, 4 psi, 60 rpm)", "1", 1.0, "reference_ratio", ("removal_rate_mean",), schema1="removal_rate_relative", optional=True),
    _O("ambient_pressure", "value", "Pa", "slurry pressure at the wafer edge: granular p0 (0 gauge for a Newtonian slurry)", "kPa", 1e-3, "setup", schema1="ambient_pressure_pa"),
    _O("sliding_speed", "value", "m s-1", "relative sliding speed at the wafer centre", "m/s", 1.0, "setup", schema1="sliding_speed_m_s"),
    _O("within_wafer_nonuniformity", "value", "1", "within-wafer non-uniformity of the removal rate: 1-sigma / mean of removal_rate_profile, edge excluded", "%", 100.0, "profile_std_over_mean", ("removal_rate_profile",)),
    _O("removal_rate_range", "value", "m s-1", "max - min of removal_rate_profile, edge excluded", "nm/min", 6e10, "profile_range", ("removal_rate_profile",)),
    # ------------------------------------------------------------------ solver diagnostics
    _O("converged", "diagnostic", "1", "equilibrium converged (load and moment residuals below the tolerance)", "-", 1.0, "solver", dtype="bool", schema1="converged", flag_meanings=("not_converged", "converged")),
    _O("iterations", "diagnostic", "1", "Newton iterations", "-", 1.0, "solver", dtype="int", schema1="iterations"),
    _O("factorizations", "diagnostic", "1", "sparse LU factorizations (pressure solves)", "-", 1.0, "solver", dtype="int", schema1="factorizations"),
    _O("load_residual", "diagnostic", "1", "relative load residual", "1", 1.0, "solver", schema1="load_residual"),
    _O("moment_residual", "diagnostic", "1", "relative moment residual (max of the two axes)", "1", 1.0, "solver", schema1="moment_residual"),
    _O("flow_factor_floored_fraction", "diagnostic", "1", "share of the faces where the flow-factor tensor was regularised", "%", 100.0, "solver", schema1="flow_factor_floored_fraction"),
    _O("moment_roots_found", "diagnostic", "1", "moment roots found by the attack-angle scan (--check-roots)", "-", 1.0, "solver", dtype="int", schema1="moment_roots_found", optional=True),
    # ------------------------------------------------------------------ fields (wafer maps)
    _O("film_thickness", "field", "m", "film thickness h (eq. 30)", "um", 1e6, "field"),
    _O("slurry_pressure", "field", "Pa", "slurry (granular) gauge pressure on the wafer, (1 - A_r/A_n)(p - p0)", "kPa", 1e-3, "field"),
    _O("granular_pressure", "field", "Pa", "slurry pressure of the removal law's normal stress: absolute granular pressure p (eq. 5), or the compressive gauge pressure of a Newtonian slurry", "kPa", 1e-3, "field"),
    _O("contact_pressure", "field", "Pa", "pad asperity contact pressure (eq. 28)", "kPa", 1e-3, "field"),
    _O("total_pressure", "field", "Pa", "slurry gauge pressure plus contact pressure", "kPa", 1e-3, "field"),
    _O("contact_area_ratio_elastic", "field", "1", "local elastic real contact area fraction", "%", 100.0, "field"),
    _O("contact_area_ratio_elastoplastic", "field", "1", "local elastoplastic real contact area fraction", "%", 100.0, "field"),
    _O("contact_area_ratio_plastic", "field", "1", "local plastic real contact area fraction", "%", 100.0, "field"),
    _O("normal_stress", "field", "Pa", "normal stress sigma_n of the removal law, (1 - A_r/A_n) p + p_c (granular p absolute, including p0)", "kPa", 1e-3, "field"),
    _O("shear_stress", "field", "Pa", "shear stress magnitude tau on the wafer", "kPa", 1e-3, "field"),
    _O("removal_rate", "field", "m s-1", "local removal rate", "nm/min", 6e10, "field"),
    _O("pad_deflection", "field", "m", "bulk deflection w of the pad stack under the total pressure (0 on a rigid pad)", "um", 1e6, "field"),
    _O("wafer_bending", "field", "m", "bending w of the wafer away from the pad on a membrane carrier (0 on the rigid carrier; cmpsim.numerics.plate)", "um", 1e6, "field"),
    _O("fill_fraction", "field", "1", "fill fraction of the film (JFO cavitation of a Newtonian slurry; 1 = full film)", "%", 100.0, "field", optional=True),
    # ------------------------------------------------------------------ profiles (rotation averages)
    _O("radius", "coordinate", "m", "wafer radius of the ring centres, r_i = (i + 1/2) R_w / n_r", "mm", 1e3, "field"),
    _O("removal_rate_profile", "profile", "m s-1", "rotation-averaged removal rate: mean of the fixed-frame removal-rate map along the circle of radius r", "nm/min", 6e10, "ring_mean", ("removal_rate",)),
    _O("film_thickness_profile", "profile", "m", "rotation-averaged film thickness: mean of the film thickness along the circle of radius r", "um", 1e6, "ring_mean", ("film_thickness",)),
    _O("wafer_bending_profile", "profile", "m", "rotation-averaged bending of the wafer (membrane carrier; 0 on the rigid carrier)", "um", 1e6, "ring_mean", ("wafer_bending",)),
]
_FIELD_NAMES = frozenset(o.name for o in _OUTPUT_LIST if o.kind == "field")

#: Every output. Scalars (values, diagnostics) and fields live in separate namespaces: the
#: wafer-mean contact area ratios share the names of their maps.
OUTPUTS: dict[tuple[str, str], Output] = {}
for _o in _OUTPUT_LIST:
    _key = ("scalar" if _o.kind in ("value", "diagnostic") else _o.kind, _o.name)
    assert _key not in OUTPUTS, _key
    assert _o.reduction in REDUCTIONS, _o
    OUTPUTS[_key] = _o
del _o, _key


def _names(*kinds: str) -> list[str]:
    return [o.name for o in _OUTPUT_LIST if o.kind in kinds]


def value_names() -> list[str]:
    """Names of the result scalars (``"values"`` of the JSON), in table order."""
    return _names("value")


def diagnostic_names() -> list[str]:
    """Names of the solver diagnostics (``"solver"`` of the JSON)."""
    return _names("diagnostic")


def scalar_names() -> list[str]:
    """Values then diagnostics."""
    return _names("value", "diagnostic")


def field_names() -> list[str]:
    """Names of the wafer maps."""
    return _names("field")


def profile_names() -> list[str]:
    """Names of the 1-D profiles on the ``radius`` coordinate."""
    return _names("profile")


def scalar(name: str) -> Output:
    """The registry entry of a scalar (value or diagnostic), by its current name."""
    return OUTPUTS[("scalar", name)]


def field(name: str) -> Output:
    """The registry entry of a field, by its current name."""
    return OUTPUTS[("field", name)]


def profile(name: str) -> Output:
    """The registry entry of a profile or of the ``radius`` coordinate."""
    return OUTPUTS.get(("profile", name)) or OUTPUTS[("coordinate", name)]


def to_display(out: Output, value):
    """An SI value in the output's display unit."""
    return value * out.display_factor


#: The 0.1 (schema 1) object of ``cmpsim run --json``, in its order: (0.1 name, current
#: name, factors): value(0.1) = value(current) * factor_1 * factor_2 ..., in that order (so
#: ``removal_rate_nm_per_min`` is bit for bit what 0.1 wrote).
SCHEMA1_KEYS: tuple[tuple[str, str, tuple[float, ...]], ...] = (
    ("film_thickness_center_m", "film_thickness_center", ()),
    ("film_thickness_min_m", "film_thickness_min", ()),
    ("h0_m", "h0", ()),
    ("attack_angle_rad", "attack_angle", ()),
    ("cross_tilt_rad", "cross_tilt", ()),
    ("fluid_load_fraction", "fluid_load_fraction", ()),
    ("contact_load_fraction", "contact_load_fraction", ()),
    ("contact_area_ratio_elastic", "contact_area_ratio_elastic", ()),
    ("contact_area_ratio_elastoplastic", "contact_area_ratio_elastoplastic", ()),
    ("contact_area_ratio_plastic", "contact_area_ratio_plastic", ()),
    ("mean_normal_stress_pa", "normal_stress_mean", ()),
    ("mean_shear_stress_pa", "shear_stress_mean", ()),
    ("removal_rate", "removal_rate_mean", ()),
    ("ambient_pressure_pa", "ambient_pressure", ()),
    ("sliding_speed_m_s", "sliding_speed", ()),
    ("load_residual", "load_residual", ()),
    ("moment_residual", "moment_residual", ()),
    ("flow_factor_floored_fraction", "flow_factor_floored_fraction", ()),
    ("iterations", "iterations", ()),
    ("factorizations", "factorizations", ()),
    ("converged", "converged", ()),
    ("removal_rate_nm_per_min", "removal_rate_mean", (1e9, 60.0)),
    ("removal_rate_relative", "removal_rate_relative", ()),
    ("moment_roots_found", "moment_roots_found", ()),
)

#: Old (0.1) names -> current names, for scalars and fields; values in SI except
#: ``removal_rate_nm_per_min`` (see :data:`SCHEMA1_KEYS`).
LEGACY_NAMES: dict[str, str] = {
    **{old: new for old, new, _ in SCHEMA1_KEYS if old != new},
    "area_ratio_elastic": "contact_area_ratio_elastic",
    "area_ratio_elastoplastic": "contact_area_ratio_elastoplastic",
    "area_ratio_plastic": "contact_area_ratio_plastic",
}
_LEGACY_FACTORS = {old: f for old, _, f in SCHEMA1_KEYS if f}


def legacy_value(value, factors: tuple[float, ...]):
    """A current SI value converted by the 0.1 factors (see :data:`SCHEMA1_KEYS`)."""
    for f in factors:
        value = value * f
    return value


def canonical_name(name: str, warn: bool = True) -> tuple[str, tuple[float, ...]]:
    """(current name, factors) of an output name, current or 0.1 (see :func:`legacy_value`).

    A 0.1 name gives a ``DeprecationWarning`` (unless ``warn`` is false).
    """
    if name in LEGACY_NAMES:
        new = LEGACY_NAMES[name]
        if warn:
            warnings.warn(f"output name {name!r} is deprecated (cmpsim 0.1); use {new!r}, in SI", DeprecationWarning, stacklevel=3)
        return new, _LEGACY_FACTORS.get(name, ())
    return name, ()


def output_table_markdown() -> str:
    """The output table of docs/model.md, generated from :data:`OUTPUTS`."""
    lines = [
        "| name | kind | SI unit | shown as | how it is obtained | meaning | 0.1 name |",
        "|---|---|---|---|---|---|---|",
    ]
    for o in _OUTPUT_LIST:
        reduction = REDUCTIONS[o.reduction] + (f" ({', '.join(f'`{n}`' for n in o.of)})" if o.of else "")
        unit = "flag" if o.dtype == "bool" else o.unit
        old = f"`{o.schema1}`" if o.schema1 and o.schema1 != o.name else ""
        if o.kind == "field" and o.name.startswith("contact_area_ratio_"):
            old = f"`{o.name.replace('contact_', '', 1)}`"
        lines.append(f"| `{o.name}` | {o.kind} | {unit} | {o.display_unit or '-'} | {reduction} | {o.long_name} | {old} |")
    return "\n".join(lines) + "\n"


def json_schema() -> dict:
    """The JSON Schema (draft 2020-12) of the schema-2 object of ``cmpsim run --json``.

    Generated from this registry and :data:`cmpsim.inputs.config.PARAMETERS`; shipped as
    ``cmpsim/data/result.schema.json`` (regenerate with ``python -m cmpsim.results.outputs``).
    """
    from ..inputs.config import PARAMETERS

    def number(o: Output) -> dict:
        t = {"bool": "boolean", "int": "integer"}.get(o.dtype, "number")
        types = [t] if o.dtype in ("bool", "int") else ["number", "null"]
        unit = "" if o.dtype == "bool" else f" [{o.unit}]"
        return {"type": types if len(types) > 1 else types[0], "description": f"{o.long_name}{unit}"}

    def section(names: list[str]) -> dict:
        return {
            "type": "object",
            "properties": {n: number(scalar(n)) for n in names},
            "required": [n for n in names if not scalar(n).optional],
            "additionalProperties": False,
        }

    inputs = {}
    for n, p in PARAMETERS.items():
        if p.choices or p.unit == "grid":
            inputs[n] = {"type": "string", "description": p.description}
        elif p.items:
            inputs[n] = {"type": "array", "items": {"type": "number"}, "description": f"{p.description} [{p.unit}]"}
        else:
            unit = p.unit or "1"
            inputs[n] = {"type": "integer" if isinstance(p.default, int) else "number", "description": f"{p.description} [{unit}]"}
    profile_keys = {"radius": profile("radius")} | {profile(n).of[0]: profile(n) for n in profile_names()}
    units = {n: scalar(n).unit for n in scalar_names()} | {k: o.unit for k, o in profile_keys.items()}
    required_units = [n for n in scalar_names() if not scalar(n).optional] + list(profile_keys)
    return {
        "$schema": "https://json-schema.org/draft/2020-12/schema",
        "title": f"cmpsim result, schema {SCHEMA_VERSION}",
        "description": "The object printed by `cmpsim run --json` and returned by cmpsim.Result.to_dict(); every number in SI, its unit in 'units' (UDUNITS-2 syntax). NaN and infinity are written as null.",
        "type": "object",
        "properties": {
            "schema": {"const": SCHEMA_VERSION, "description": "version of this layout"},
            "cmpsim_version": {"type": "string"},
            "inputs": {"type": "object", "description": "every input, SI (see `cmpsim params`)", "properties": inputs, "required": list(inputs), "additionalProperties": False},
            "values": dict(section(value_names()), description="result scalars, SI"),
            "units": {
                "type": "object",
                "description": "unit of every value, solver diagnostic and profile",
                "properties": {k: {"const": u} for k, u in units.items()},
                "required": required_units,
                "additionalProperties": False,
            },
            "solver": dict(section(diagnostic_names()), description="solver diagnostics"),
            "profiles": {
                "type": "object",
                "description": "rotation-averaged profiles versus wafer radius, one value per ring of the grid",
                "properties": {
                    k: {"type": "array", "items": {"type": ["number", "null"]}, "description": f"{o.long_name} [{o.unit}]"} for k, o in profile_keys.items()
                },
                "required": list(profile_keys),
                "additionalProperties": False,
            },
        },
        "required": ["schema", "cmpsim_version", "inputs", "values", "units", "solver", "profiles"],
        "additionalProperties": False,
    }


def json_schema_text() -> str:
    """:func:`json_schema` as the text of ``cmpsim/data/result.schema.json``."""
    import json

    return json.dumps(json_schema(), indent=2) + "\n"


if __name__ == "__main__":  # pragma: no cover - regenerates the shipped JSON Schema
    from pathlib import Path

    path = Path(__file__).parents[1] / "data" / "result.schema.json"
    path.write_text(json_schema_text(), encoding="utf-8")
    print(f"wrote {path}")
