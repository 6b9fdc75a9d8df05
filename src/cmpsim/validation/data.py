"""Data sets: the CSV format, the measurable quantities and their units, reading and checking files.

A data set is a CSV file (format in ``cmpsim/data/README.md``): a block of ``# key: value``
comment lines with its citation and provenance, then one row per measured point with the
quantity, value, unit, uncertainty, comparison mode, the operating conditions (columns named
exactly as cmpsim parameters, values with units, or ``sliding_speed``) and a source note.
"""

from __future__ import annotations

import csv
import math
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any, Callable

import numpy as np

from ..results import outputs
from ..inputs import units
from ..inputs.config import PARAMETERS, Config

__all__ = [
    "QUANTITIES",
    "QUANTITY_ALIASES",
    "MEASURABLE_OUTPUTS",
    "COMPARISONS",
    "DEPTH_QUANTITIES",
    "POINT_COLUMNS",
    "PROFILE_QUANTITIES",
    "quantity_unit",
    "DataError",
    "DataPoint",
    "Dataset",
    "load_dataset",
    "load_datasets",
    "shipped_dataset_paths",
    "point_config",
    "to_si",
    "from_si",
]

#: Comparison modes of a data set (see the module docstring).
COMPARISONS = ("absolute", "range", "order", "shape")
#: Half-width, in decades, of the ``order`` comparison.
ORDER_TOLERANCE_DECADES = 0.5
#: Columns that are not operating conditions.
META_COLUMNS = ("dataset", "quantity", "value", "unit", "uncertainty", "comparison", "source", "label", "note")
#: Extra condition columns (not cmpsim parameters) that are converted on reading.
EXTRA_CONDITIONS = {"sliding_speed": "m/s"}
#: Columns that place a point on the wafer or in time (SI unit): not operating conditions, so points
#: that differ only in them share one equilibrium. ``radius`` (or ``x`` and ``y``) reads the rotation-
#: averaged removal-rate profile there; ``time`` (polish time) and ``initial_thickness`` turn a rate into
#: a ``removal`` depth or a remaining ``thickness``.
POINT_COLUMNS = {"radius": "m", "x": "m", "y": "m", "time": "s", "initial_thickness": "m"}


def _film_max(result) -> float:
    g = result.grid
    rim = result.problem.film(result.solution.state.u, *g.rim())
    return float(max(result.polar["film_thickness"].max(), rim.max()))


def _friction(result) -> float:
    """Friction coefficient: mean shear stress on the wafer over the applied pressure.

    With ``removal_shear = "total"`` the model's mean shear stress already holds the slurry
    shear and the summit friction; with ``"slurry"`` the summit friction mu * p_c is added
    (magnitudes added: both act along the sliding direction to first order).
    """
    s = result.scalars
    p = result.config.applied_pressure
    mu = s["shear_stress_mean"] / p
    if getattr(result.config, "removal_shear", "total") != "total":
        mu += result.config.friction_coefficient * s["contact_load_fraction"]
    return float(mu)


#: The outputs of :mod:`cmpsim.results.outputs` that a data set may give (measurable results).
MEASURABLE_OUTPUTS = (
    "film_thickness_center",
    "film_thickness_mean",
    "film_thickness_min",
    "attack_angle",
    "fluid_load_fraction",
    "contact_load_fraction",
    "contact_area_ratio",
    "contact_area_ratio_elastic",
    "contact_area_ratio_elastoplastic",
    "contact_area_ratio_plastic",
    "normal_stress_mean",
    "shear_stress_mean",
    "removal_rate_mean",
    "within_wafer_nonuniformity",
    "removal_rate_range",
)
#: The 0.1 quantity names, still read: old name -> output name.
QUANTITY_ALIASES = {"film_thickness": "film_thickness_center", "removal_rate": "removal_rate_mean"}


def _from_registry(name: str) -> tuple[str, str, str, Callable[[Any], float]]:
    o = outputs.scalar(name)
    return (o.pint_unit, o.display_unit, o.long_name, lambda r: r.scalars[name])


#: Measurable quantity -> (SI unit for pint, display unit for tables/plots, description, model
#: extractor): the measurable outputs of the registry (:mod:`cmpsim.results.outputs`), their 0.1 names
#: (``film_thickness`` = ``film_thickness_center``, ``removal_rate`` = ``removal_rate_mean``),
#: and two quantities derived here (largest film, friction coefficient).
QUANTITIES: dict[str, tuple[str, str, str, Callable[[Any], float]]] = {
    **{name: _from_registry(name) for name in MEASURABLE_OUTPUTS},
    **{old: _from_registry(new) for old, new in QUANTITY_ALIASES.items()},
    "film_thickness_max": ("m", "um", "largest film thickness over the wafer", _film_max),
    "friction_coefficient": ("dimensionless", "-", "wafer-mean shear stress (slurry + summit friction) / applied pressure", _friction),
}


#: Quantities of a blanket film polished for a ``time`` (wafer mean, or at a ``radius``): quantity ->
#: (SI unit for pint, display unit, description, the point columns it needs). The model value is the
#: removal rate there times the time (``removal``), or ``initial_thickness`` less it (``thickness``,
#: not below 0): the rate of the solved equilibrium held through the time (a blanket polish).
DEPTH_QUANTITIES: dict[str, tuple[str, str, str, tuple[str, ...]]] = {
    "removal": ("m", "nm", "depth of film removed in the polish time (blanket, at the solved rate)", ("time",)),
    "thickness": ("m", "nm", "film thickness left after the polish time (initial_thickness - rate x time, >= 0)", ("time", "initial_thickness")),
}
#: Quantities that may be negative (an angle, a stress by its sign); every other measured quantity is >= 0
#: (a rate, a depth, a thickness, a fraction, a ratio, a friction coefficient) and a negative value is refused.
SIGNED_QUANTITIES = ("attack_angle", "shear_stress_mean", "normal_stress_mean")
#: Quantities that may be given at a ``radius`` (or ``x``, ``y``): the removal rate and the depths.
PROFILE_QUANTITIES = ("removal_rate", "removal_rate_mean", "removal", "thickness")


def quantity_unit(quantity: str) -> str:
    """The SI (pint) unit of a measurable quantity."""
    return QUANTITIES[quantity][0] if quantity in QUANTITIES else DEPTH_QUANTITIES[quantity][0]


def known_quantities() -> tuple[str, ...]:
    """Every quantity a data file may give."""
    return tuple(QUANTITIES) + tuple(DEPTH_QUANTITIES)


class DataError(ValueError):
    """A data file that cannot be read; the message names the file, the row and column, and the problem."""


def to_si(value: float, unit: str, quantity: str) -> float:
    """``value`` in ``unit`` converted to the SI unit of ``quantity`` (ValueError if incompatible)."""
    target = quantity_unit(quantity)
    try:
        return units.convert(value, unit, target)
    except Exception as exc:
        raise ValueError(f"unit {unit!r} is not a unit of {quantity} (expected units convertible to {target!r}): {exc}") from None


def from_si(value: float, unit: str, quantity: str) -> float:
    """SI value of ``quantity`` expressed in ``unit``."""
    if value is None or not np.isfinite(value):
        return float("nan")
    return units.convert(value, quantity_unit(quantity), unit)


# --------------------------------------------------------------------------- data model
@dataclass
class DataPoint:
    """One measured (or, for a model-to-model data set, predicted) point."""

    dataset: str
    quantity: str
    value: float  # as written, in ``unit``
    unit: str
    uncertainty: float | None  # as written, in ``unit`` (None = not given)
    comparison: str
    conditions: dict[str, str]  # column -> value text (cmpsim parameter names or sliding_speed)
    source: str = ""
    line: int = 0
    label: str = ""
    #: where and when on the wafer, SI: ``radius`` (m, from x and y if given that way), ``time`` (s), ``initial_thickness`` (m)
    where: dict[str, float] = field(default_factory=dict)
    #: the data row (1 = the first row after the header)
    row: int = 0
    #: the file the point was read from ("" when built in code)
    path: str = ""

    @property
    def value_si(self) -> float:
        return to_si(self.value, self.unit, self.quantity)

    @property
    def uncertainty_si(self) -> float | None:
        if self.uncertainty is None:
            return None
        return to_si(self.uncertainty, self.unit, self.quantity) - to_si(0.0, self.unit, self.quantity)

    def conditions_text(self) -> str:
        text = ", ".join(f"{k}={v}" for k, v in self.conditions.items()) or "(base case)"
        extra = [f"{k}={_short(v, POINT_COLUMNS[k])}" for k, v in self.where.items()]
        return ", ".join([text] + extra) if extra else text

    @property
    def film(self) -> str | None:
        """The film of the point's ``film`` column (None: the configuration's)."""
        return self.conditions.get("film")


def _short(value: float, unit: str) -> str:
    if unit == "m":
        return f"{value * 1e3:g} mm" if value >= 1e-3 or value == 0 else f"{value * 1e9:g} nm"  # a radius of 0 is the centre, in mm
    return f"{value:g} s"


@dataclass
class Dataset:
    """The points of one data set with the metadata of its file header."""

    name: str
    points: list[DataPoint]
    meta: dict[str, str] = field(default_factory=dict)
    path: Path | None = None

    @property
    def kind(self) -> str:
        """``measurement`` or ``model_prediction`` (a model-to-model comparison)."""
        return self.meta.get("kind", "measurement")

    @property
    def comparison(self) -> str:
        return self.points[0].comparison

    @property
    def quantity(self) -> str:
        return ", ".join(sorted({p.quantity for p in self.points}))

    @property
    def citation(self) -> str:
        return self.meta.get("citation", "")


def shipped_dataset_paths() -> list[Path]:
    """The CSV data sets shipped with the package, sorted by name."""
    from importlib import resources

    root = resources.files("cmpsim") / "data"
    return sorted(Path(str(p)) for p in root.iterdir() if str(p).endswith(".csv"))


def _parse_float(text: str, what: str, where: str) -> float:
    try:
        v = float(text)
    except ValueError:
        raise DataError(f"{where}: {what} {text!r} is not a number{units.placeholder_hint(text)}") from None
    if not math.isfinite(v):
        raise DataError(f"{where}: {what} {text!r} is not finite")
    return v


def load_datasets(path, text: str | None = None) -> list[Dataset]:
    """Read a data file; one :class:`Dataset` per distinct value of its ``dataset`` column.

    ``text``: the file's content when already read (``path`` then only names it in messages).
    Raises :class:`DataError` (a ValueError) naming the file, line and problem: missing
    required column, unknown quantity, comparison or condition column, bad number or unit.
    """
    from ..io import comments_and_rows, delimiter_hint, fields_hint, read_text, repeated_columns, tidy_csv

    path = Path(path)
    if text is None:
        text = read_text(path, "data file", DataError)
    meta, body_lines = comments_and_rows(tidy_csv(text, path))
    if not body_lines:
        raise DataError(f"{path}: no header row and no data rows (see cmpsim/data/README.md for the format)")
    header_line, header_text = body_lines[0]
    header = [h.strip() for h in next(csv.reader([header_text]))]
    where0 = f"{path}:{header_line}"
    for required in ("quantity", "value"):  # the unit: a column, or after each value ("150 nm/min")
        if required not in header:
            raise DataError(f"{where0}: required column {required!r} is missing (header: {', '.join(header)})" + delimiter_hint(header_text))
    twice = repeated_columns(header)
    if twice:
        raise DataError(f"{where0}: header, column {twice[0]!r}: duplicate column names in the header ({', '.join(header)})")
    for col in header:
        if col in META_COLUMNS or col in EXTRA_CONDITIONS or col in POINT_COLUMNS:
            continue
        if col not in PARAMETERS:
            raise DataError(
                f"{where0}: header, column {col!r}: unknown column {col!r}: condition columns must be cmpsim parameter names "
                f"(see `cmpsim params`), {', '.join(EXTRA_CONDITIONS)}, or the position and time columns {', '.join(POINT_COLUMNS)}"
                + _near(col, [*META_COLUMNS, *EXTRA_CONDITIONS, *POINT_COLUMNS, *PARAMETERS])
            )
        if PARAMETERS[col].section == "numerics" and col != "model":
            raise DataError(f"{where0}: header, column {col!r}: column {col!r} is a numerical setting, not an operating condition")
    if ("x" in header) != ("y" in header):
        raise DataError(f"{where0}: header, column {'x' if 'x' in header else 'y'!r}: a position by x needs y too (or give radius)")
    if "radius" in header and "x" in header:
        raise DataError(f"{where0}: header, column 'radius': give radius or x and y, not both")
    default_name = meta.get("dataset") or path.stem
    default_comparison = (meta.get("comparison") or "absolute").split()[0].strip(" -:,").lower()
    datasets: dict[str, Dataset] = {}
    base = Config.default()
    checked: set = set()  # the cells and rows of conditions already checked (10,000 rows repeat a few settings)
    rows = csv.reader([t for _, t in body_lines[1:]])
    for row_no, ((lineno, _), row) in enumerate(zip(body_lines[1:], rows), start=1):
        where = f"{path}:{lineno}"

        def bad(column: str, message: str) -> DataError:
            return DataError(f"{path}:{lineno}: row {row_no}, column {column!r}: {message}")

        if len(row) != len(header):
            raise DataError(f"{where}: row {row_no}: {len(row)} fields but the header has {len(header)}" + fields_hint(row, header))
        rec = {h: c.strip() for h, c in zip(header, row)}
        rec.setdefault("unit", "")
        quantity = rec["quantity"]
        if quantity not in QUANTITIES and quantity not in DEPTH_QUANTITIES:
            near = _near(quantity.replace(" ", "_"), known_quantities()).lstrip("; ")
            raise bad("quantity", f"unknown quantity {quantity!r}" + (f" ({near})" if near else "") + f"; known: {', '.join(known_quantities())}")
        try:
            rec["value"], rec["unit"] = units.value_and_unit(rec["value"], rec["unit"])
        except ValueError as exc:
            raise bad("value", str(exc)) from None
        if "unit" not in header and not rec["unit"] and rec["value"]:
            raise DataError(f"{where0}: required column 'unit' is missing (header: {', '.join(header)}); give it, or the unit after every "
                            f"value ('150 nm/min'): line {lineno}, row {row_no} has none")
        if not rec["value"]:
            raise bad("value", "the value is empty (a measured number, in the unit column's unit)")
        if not rec["unit"] and quantity_unit(quantity) != "dimensionless":
            raise bad("unit", f"the unit is empty; a {quantity} needs a unit convertible to {quantity_unit(quantity)} "
                              f"(e.g. {DEPTH_QUANTITIES[quantity][1] if quantity in DEPTH_QUANTITIES else QUANTITIES[quantity][1]}), "
                              "in the unit column or after the value")
        try:
            value = _parse_float(rec["value"], "value", where)
        except DataError as exc:
            raise bad("value", str(exc).split(": ", 1)[1]) from None
        unit = rec["unit"]
        unc_text = rec.get("uncertainty", "")
        uncertainty = None
        if unc_text:
            uncertainty = _uncertainty(unc_text, unit, quantity, where, bad)
            if uncertainty <= 0:
                raise bad("uncertainty", f"uncertainty must be > 0 (or empty); got {unc_text!r}")
        comparison = rec.get("comparison") or default_comparison
        if comparison not in COMPARISONS:
            raise bad("comparison", f"unknown comparison {comparison!r}; known: {', '.join(COMPARISONS)}")
        if comparison == "range" and uncertainty is None:
            raise bad("uncertainty", "comparison 'range' needs the half-width of the range in the uncertainty column")
        if comparison in ("order", "shape") and value <= 0:
            raise bad("value", f"comparison {comparison!r} needs a positive value; got {value:g}")
        if value < 0 and quantity not in SIGNED_QUANTITIES:
            raise bad("value", f"a {quantity} is >= 0; got {rec['value']} {unit}")
        try:
            to_si(value, unit, quantity)
        except ValueError as exc:
            raise bad("unit", str(exc)) from None
        place = _point_place(rec, quantity, bad)
        if quantity == "thickness" and to_si(value, unit, quantity) > place["initial_thickness"] * (1 + 1e-12):
            raise bad("value", f"the thickness left ({rec['value']} {unit}) exceeds the initial_thickness ({rec['initial_thickness']}): "
                               "a polish only removes film")
        conditions = {}
        for col in header:
            if col in META_COLUMNS or col in POINT_COLUMNS or not rec[col]:
                continue
            conditions[col] = rec[col]
        for col, text in conditions.items():  # each column alone first: the error names it
            if (col, text) not in checked:
                try:
                    point_config(base, {col: text})
                except ValueError as exc:
                    raise bad(col, str(exc) + (film_hint(text) if col == "film" else "")) from None
                checked.add((col, text))
        if tuple(conditions.items()) not in checked:
            try:
                point_config(base, conditions)
            except ValueError as exc:
                raise bad(", ".join(conditions), str(exc)) from None
            checked.add(tuple(conditions.items()))
        name = rec.get("dataset") or default_name
        p = DataPoint(name, quantity, value, unit, uncertainty, comparison, conditions, rec.get("source", ""), lineno, rec.get("label", ""), place, row_no, str(path))
        ds = datasets.setdefault(name, Dataset(name, [], dict(meta), path))
        ds.points.append(p)
    if not datasets:
        raise DataError(f"{path}: the file has a header but no data rows")
    for ds in datasets.values():
        _one_unit(ds)
        modes = {p.comparison for p in ds.points}
        first = ds.points[0]
        if len(modes) > 1:
            other = next(p for p in ds.points if p.comparison != first.comparison)
            raise DataError(f"{path}:{other.line}: row {other.row}, column 'comparison': data set {ds.name!r} mixes comparison modes "
                            f"{sorted(modes)} ({first.comparison!r} in line {first.line}); use one per data set")
        if ds.comparison == "shape":
            if len({p.quantity for p in ds.points}) > 1:
                other = next(p for p in ds.points if p.quantity != first.quantity)
                raise DataError(f"{path}:{other.line}: row {other.row}, column 'quantity': shape data set {ds.name!r} must hold one quantity "
                                f"({first.quantity!r} in line {first.line})")
            if len(ds.points) < 2:
                raise DataError(f"{path}:{first.line}: row {first.row}, column 'comparison': shape data set {ds.name!r} needs at least 2 points "
                                "(a scale fitted to one point says nothing; use 'absolute')")
    return list(datasets.values())


#: Names of films in papers and fab logs (lower case) -> the film of cmpsim they would be; only named in a refusal, never
#: read as it: which removal law a fab's oxide (thermal, TEOS, HDP) or barrier (Ta, TaN, Ti, TiN) follows is the user's choice.
FILM_WORDS = {"cu": "copper", "sio2": "oxide", "teos": "oxide", "peteos": "oxide", "pe-teos": "oxide", "hdp": "oxide", "ild": "oxide",
              "thermal oxide": "oxide", "w": "tungsten", "ta": "barrier", "tan": "barrier", "ti": "barrier", "tin": "barrier"}


def film_hint(text: str) -> str:
    """" (for 'Cu' write copper ...)" for a film named as papers name it ("" for other names)."""
    film = FILM_WORDS.get(" ".join(text.lower().split()))
    return f" (for {text.strip()!r} write {film!r}, if its removal law is cmpsim's {film})" if film else ""


def _near(name: str, names) -> str:
    """"; did you mean X?" for the names close to a misspelt ``name`` ("" when none is close)."""
    from ..inputs.param import did_you_mean

    return did_you_mean(name, names)


def _one_unit(ds: Dataset) -> None:
    """Points of one quantity written in several units (``nm/min`` and ``A/min``) re-expressed, in place, in the
    first point's unit: a data set's RMS error, its shape scale and the mean it is compared with need one unit."""
    if len({p.quantity for p in ds.points}) != 1 or len({p.unit for p in ds.points}) == 1:
        return
    unit, q = ds.points[0].unit, ds.points[0].quantity
    for p in ds.points[1:]:
        if p.unit != unit:
            p.value = from_si(to_si(p.value, p.unit, q), unit, q)
            if p.uncertainty is not None:
                p.uncertainty = from_si(p.uncertainty_si + to_si(0.0, unit, q), unit, q)
            p.unit = unit


def _uncertainty(text: str, unit: str, quantity: str, where: str, bad) -> float:
    """The uncertainty cell in the row's ``unit``: a number, or a number with a unit of the quantity (``"10 nm/min"``)."""
    try:
        number, own = units.value_and_unit(units.uncertainty_text(text), "")
    except ValueError as exc:  # "1,5": a decimal comma or a thousands separator
        raise bad("uncertainty", str(exc)) from None
    try:
        u = _parse_float(number, "uncertainty", where)
    except DataError as exc:
        raise bad("uncertainty", str(exc).split(": ", 1)[1]) from None
    if own and own.replace(" ", "").lower() != unit.replace(" ", "").lower():
        if own.strip() in ("%", "percent"):  # 5 % of a fraction given in 1, or 5 % of the value? not guessed
            raise bad("uncertainty", f"{text!r}: a relative uncertainty in % is not read; give it in {unit or 'the unit of the value'}")
        try:
            u = to_si(u, own, quantity) - to_si(0.0, own, quantity)
            u = from_si(u, unit, quantity) - from_si(0.0, unit, quantity)
        except Exception:  # noqa: BLE001 - a relative (5 %) or foreign unit
            raise bad("uncertainty", f"{text!r} is not an uncertainty in units of {quantity} (give it in {unit}, e.g. '10'; "
                                     "a relative uncertainty in % is not read)") from None
    return u


def _point_place(rec: dict, quantity: str, bad) -> dict[str, float]:
    """The position and time columns of a row, SI (``x``, ``y`` become ``radius``); ``bad(column, message)`` makes the error."""
    place: dict[str, float] = {}
    for col, unit in POINT_COLUMNS.items():
        text = rec.get(col, "")
        if not text:
            continue
        try:
            v = units.to_si(text, unit, col, example="mm" if unit == "m" else "s")
        except ValueError as exc:
            raise bad(col, str(exc)) from None
        if not math.isfinite(v) or (col not in ("x", "y") and v < 0) or (col == "time" and v == 0):
            raise bad(col, f"{col} must be {'> 0' if col == 'time' else '>= 0'} ({unit}); got {text!r}")
        place[col] = float(v)
    if ("x" in place) != ("y" in place):
        raise bad("y" if "x" in place else "x", "a position by x needs y too (or give radius)")
    if "x" in place:
        place["radius"] = math.hypot(place.pop("x"), place.pop("y"))
    if "radius" in place and quantity not in PROFILE_QUANTITIES:
        raise bad("radius", f"a position on the wafer applies to {', '.join(PROFILE_QUANTITIES)}; {quantity!r} is a wafer value")
    for col in DEPTH_QUANTITIES.get(quantity, ("", "", "", ()))[3]:
        if col not in place:
            raise bad(col, f"quantity {quantity!r} needs the {col} column ({POINT_COLUMNS[col]}; e.g. {'60 s' if col == 'time' else '1.2 um'})")
    extra = [c for c in ("time", "initial_thickness") if c in place and c not in DEPTH_QUANTITIES.get(quantity, ("", "", "", ()))[3]]
    if extra:
        raise bad(extra[0], f"{extra[0]} applies to the quantities {', '.join(DEPTH_QUANTITIES)}; not to {quantity!r}")
    return place


def load_dataset(path) -> Dataset:
    """Read a data file holding one data set (see :func:`load_datasets` for several)."""
    sets = load_datasets(path)
    if len(sets) != 1:
        raise DataError(f"{path}: holds {len(sets)} data sets ({', '.join(d.name for d in sets)}); use load_datasets()")
    return sets[0]


def _as_datasets(data) -> list[Dataset]:
    if data is None:
        data = shipped_dataset_paths()
    if isinstance(data, (Dataset, str, Path)):
        data = [data]
    out: list[Dataset] = []
    for item in data:
        out.extend([item] if isinstance(item, Dataset) else load_datasets(item))
    names = [d.name for d in out]
    dup = {n for n in names if names.count(n) > 1}
    if dup:
        raise DataError(f"data set names must be unique; repeated: {', '.join(sorted(dup))}")
    return out


def point_config(base: Config, conditions: dict[str, str]) -> Config:
    """The Config of one data point: ``base`` with the point's conditions.

    ``sliding_speed`` becomes ``rotation_speed = sliding_speed / centre_distance`` (the
    centre distance of the point, or of ``base``).
    """
    cond = dict(conditions)
    sliding = cond.pop("sliding_speed", None)
    cfg = base.replace(**cond) if cond else base
    if sliding is not None:
        if "rotation_speed" in cond:
            raise ValueError("give either sliding_speed or rotation_speed, not both")
        u = units.to_si(sliding, "m/s", "sliding_speed", example="m/s")
        if not (u > 0 and math.isfinite(u)):
            raise ValueError(f"sliding_speed must be > 0 m/s; got {sliding!r}")
        cfg = cfg.replace(rotation_speed=u / cfg.centre_distance)
    return cfg
