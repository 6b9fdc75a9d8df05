"""Face the data: run the model at measured operating points and report model vs measurement.

A data set is a CSV file (format in ``cmpsim/data/README.md``): a block of ``# key: value``
comment lines with its citation and provenance, then one row per measured point with the
quantity, value, unit, uncertainty, comparison mode, the operating conditions (columns named
exactly as cmpsim parameters, values with units, or ``sliding_speed``) and a source note.

Comparison modes
----------------
``absolute``
    model against measurement; a point agrees when ``|model - value| <= 2 uncertainty``
    (no verdict without an uncertainty).
``range``
    the measurement is a range ``value +- uncertainty``; a point agrees when the model lies
    inside it.
``order``
    order-of-magnitude check; a point agrees when ``|log10(model / value)| <= 0.5``.
``shape``
    only the shape is compared: the model values are multiplied by the one scale that fits
    the data set best (least squares). The leave-one-out error of that prediction is reported
    beside the leave-one-out error of predicting the data set's mean (and of a Preston
    law ``s P U``): the data set "passes" when the model beats the mean.

``validate()`` with no argument runs every data set shipped in ``cmpsim/data``.
"""

from __future__ import annotations

import csv
import io
import math
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any, Callable, Iterable, Sequence

import numpy as np

from .config import PARAMETERS, Config

__all__ = [
    "QUANTITIES",
    "COMPARISONS",
    "DataPoint",
    "Dataset",
    "PointResult",
    "DatasetSummary",
    "ValidationReport",
    "load_dataset",
    "load_datasets",
    "shipped_dataset_paths",
    "point_config",
    "model_value",
    "validate",
    "fit_scale",
]

#: Comparison modes of a data set (see the module docstring).
COMPARISONS = ("absolute", "range", "order", "shape")
#: Half-width, in decades, of the ``order`` comparison.
ORDER_TOLERANCE_DECADES = 0.5
#: Columns that are not operating conditions.
META_COLUMNS = ("dataset", "quantity", "value", "unit", "uncertainty", "comparison", "source", "label", "note")
#: Extra condition columns (not cmpsim parameters) that are converted on reading.
EXTRA_CONDITIONS = {"sliding_speed": "m/s"}


def _film_mean(result) -> float:
    g = result.grid
    return float(g.integrate(result.polar["film_thickness"]) / (np.pi * g.radius**2))


def _film_max(result) -> float:
    g = result.grid
    t = np.linspace(0.0, 2.0 * np.pi, 4 * g.n_theta, endpoint=False)
    rim = result.problem.film(result.solution.state.u, g.radius * np.cos(t), g.radius * np.sin(t))
    return float(max(result.polar["film_thickness"].max(), rim.max()))


def _contact_total(result) -> float:
    s = result.scalars
    return s["contact_area_ratio_elastic"] + s["contact_area_ratio_elastoplastic"] + s["contact_area_ratio_plastic"]


def _friction(result) -> float:
    """Friction coefficient: mean shear stress on the wafer over the applied pressure.

    With ``removal_shear = "total"`` the model's mean shear stress already holds the slurry
    shear and the summit friction; with ``"slurry"`` the summit friction mu * p_c is added
    (magnitudes added: both act along the sliding direction to first order).
    """
    s = result.scalars
    p = result.config.applied_pressure
    mu = s["mean_shear_stress_pa"] / p
    if getattr(result.config, "removal_shear", "total") != "total":
        mu += result.config.friction_coefficient * s["contact_load_fraction"]
    return float(mu)


#: Measurable quantity -> (SI unit for pint, display unit for tables/plots, description, model extractor).
QUANTITIES: dict[str, tuple[str, str, str, Callable[[Any], float]]] = {
    "film_thickness": ("m", "um", "slurry film thickness at the wafer centre", lambda r: r.scalars["film_thickness_center_m"]),
    "film_thickness_mean": ("m", "um", "slurry film thickness averaged over the wafer", _film_mean),
    "film_thickness_min": ("m", "um", "smallest slurry film thickness over the wafer", lambda r: r.scalars["film_thickness_min_m"]),
    "film_thickness_max": ("m", "um", "largest slurry film thickness over the wafer", _film_max),
    "fluid_load_fraction": ("dimensionless", "%", "share of the applied load carried by the slurry", lambda r: r.scalars["fluid_load_fraction"]),
    "contact_area_ratio": ("dimensionless", "%", "real contact area / wafer area (elastic + elastoplastic + plastic)", _contact_total),
    "contact_area_ratio_elastic": ("dimensionless", "%", "elastic real contact area / wafer area", lambda r: r.scalars["contact_area_ratio_elastic"]),
    "contact_area_ratio_elastoplastic": ("dimensionless", "%", "elastoplastic real contact area / wafer area", lambda r: r.scalars["contact_area_ratio_elastoplastic"]),
    "friction_coefficient": ("dimensionless", "-", "wafer-mean shear stress (slurry + summit friction) / applied pressure", lambda r: _friction(r)),
    "removal_rate": ("m/s", "nm/min", "wafer-mean removal rate K sigma_n tau", lambda r: r.scalars["removal_rate"]),
}

_UNIT_ALIASES = {"a/min": "angstrom/minute", "å/min": "angstrom/minute", "%": "percent", "-": "dimensionless", "1": "dimensionless", "": "dimensionless"}


class DataError(ValueError):
    """A data file that cannot be read; the message names the file, line and problem."""


def _ureg():
    from .config import _ureg as ureg

    return ureg()


def _unit(text: str) -> str:
    t = text.strip()
    return _UNIT_ALIASES.get(t.lower(), t)


def to_si(value: float, unit: str, quantity: str) -> float:
    """``value`` in ``unit`` converted to the SI unit of ``quantity`` (ValueError if incompatible)."""
    target = QUANTITIES[quantity][0]
    ureg = _ureg()
    try:
        q = ureg.Quantity(float(value), _unit(unit))
        return float(q.to(target).magnitude)
    except Exception as exc:
        raise ValueError(f"unit {unit!r} is not a unit of {quantity} (expected units convertible to {target!r}): {exc}") from None


def from_si(value: float, unit: str, quantity: str) -> float:
    """SI value of ``quantity`` expressed in ``unit``."""
    if value is None or not np.isfinite(value):
        return float("nan")
    target = QUANTITIES[quantity][0]
    return float(_ureg().Quantity(float(value), target).to(_unit(unit)).magnitude)


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

    @property
    def value_si(self) -> float:
        return to_si(self.value, self.unit, self.quantity)

    @property
    def uncertainty_si(self) -> float | None:
        if self.uncertainty is None:
            return None
        return to_si(self.uncertainty, self.unit, self.quantity) - to_si(0.0, self.unit, self.quantity)

    def conditions_text(self) -> str:
        return ", ".join(f"{k}={v}" for k, v in self.conditions.items()) or "(base case)"


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
        raise DataError(f"{where}: {what} {text!r} is not a number") from None
    if not math.isfinite(v):
        raise DataError(f"{where}: {what} {text!r} is not finite")
    return v


def load_datasets(path) -> list[Dataset]:
    """Read a data file; one :class:`Dataset` per distinct value of its ``dataset`` column.

    Raises :class:`DataError` (a ValueError) naming the file, line and problem: missing
    required column, unknown quantity, comparison or condition column, bad number or unit.
    """
    from .io import read_text

    path = Path(path)
    text = read_text(path, "data file", DataError)
    meta: dict[str, str] = {}
    body_lines: list[tuple[int, str]] = []
    for i, line in enumerate(text.splitlines(), start=1):
        s = line.strip()
        if s.startswith("#"):
            content = s.lstrip("#").strip()
            if ":" in content:
                key, value = content.split(":", 1)
                key = key.strip().lower()
                if key and " " not in key:
                    meta[key] = (meta[key] + " " + value.strip()) if key in meta else value.strip()
            continue
        if s:
            body_lines.append((i, line))
    if not body_lines:
        raise DataError(f"{path}: no header row and no data rows (see cmpsim/data/README.md for the format)")
    header_line, header_text = body_lines[0]
    header = [h.strip() for h in next(csv.reader([header_text]))]
    where0 = f"{path}:{header_line}"
    for required in ("quantity", "value", "unit"):
        if required not in header:
            raise DataError(f"{where0}: required column {required!r} is missing (header: {', '.join(header)})")
    if len(set(header)) != len(header):
        raise DataError(f"{where0}: duplicate column names in the header")
    for col in header:
        if col in META_COLUMNS or col in EXTRA_CONDITIONS:
            continue
        if col not in PARAMETERS:
            raise DataError(
                f"{where0}: unknown column {col!r}: condition columns must be cmpsim parameter names "
                f"(see `cmpsim params`) or {', '.join(EXTRA_CONDITIONS)}"
            )
        if PARAMETERS[col].section == "numerics" and col != "model":
            raise DataError(f"{where0}: column {col!r} is a numerical setting, not an operating condition")
    default_name = meta.get("dataset") or path.stem
    default_comparison = (meta.get("comparison") or "absolute").split()[0].strip(" -:,")
    datasets: dict[str, Dataset] = {}
    rows = csv.reader([t for _, t in body_lines[1:]])
    for (lineno, _), row in zip(body_lines[1:], rows):
        where = f"{path}:{lineno}"
        if len(row) != len(header):
            raise DataError(f"{where}: {len(row)} fields but the header has {len(header)}")
        rec = {h: c.strip() for h, c in zip(header, row)}
        quantity = rec["quantity"]
        if quantity not in QUANTITIES:
            raise DataError(f"{where}: unknown quantity {quantity!r}; known: {', '.join(QUANTITIES)}")
        value = _parse_float(rec["value"], "value", where)
        unit = rec["unit"]
        unc_text = rec.get("uncertainty", "")
        uncertainty = None
        if unc_text:
            uncertainty = _parse_float(unc_text, "uncertainty", where)
            if uncertainty <= 0:
                raise DataError(f"{where}: uncertainty must be > 0 (or empty); got {unc_text!r}")
        comparison = rec.get("comparison") or default_comparison
        if comparison not in COMPARISONS:
            raise DataError(f"{where}: unknown comparison {comparison!r}; known: {', '.join(COMPARISONS)}")
        if comparison == "range" and uncertainty is None:
            raise DataError(f"{where}: comparison 'range' needs the half-width of the range in the uncertainty column")
        if comparison in ("order", "shape") and value <= 0:
            raise DataError(f"{where}: comparison {comparison!r} needs a positive value; got {value:g}")
        try:
            to_si(value, unit, quantity)
        except ValueError as exc:
            raise DataError(f"{where}: {exc}") from None
        conditions = {}
        for col in header:
            if col in META_COLUMNS or not rec[col]:
                continue
            conditions[col] = rec[col]
        try:
            point_config(Config.default(), conditions)
        except ValueError as exc:
            raise DataError(f"{where}: {exc}") from None
        name = rec.get("dataset") or default_name
        p = DataPoint(name, quantity, value, unit, uncertainty, comparison, conditions, rec.get("source", ""), lineno, rec.get("label", ""))
        ds = datasets.setdefault(name, Dataset(name, [], dict(meta), path))
        ds.points.append(p)
    if not datasets:
        raise DataError(f"{path}: the file has a header but no data rows")
    for ds in datasets.values():
        modes = {p.comparison for p in ds.points}
        if len(modes) > 1:
            raise DataError(f"{path}: data set {ds.name!r} mixes comparison modes {sorted(modes)}; use one per data set")
        if ds.comparison == "shape":
            if len({p.quantity for p in ds.points}) > 1:
                raise DataError(f"{path}: shape data set {ds.name!r} must hold one quantity")
            if len(ds.points) < 2:
                raise DataError(f"{path}: shape data set {ds.name!r} needs at least 2 points")
    return list(datasets.values())


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


# --------------------------------------------------------------------------- running the model
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
        ureg = _ureg()
        try:
            u = float(ureg.Quantity(sliding).to("m/s").magnitude) if isinstance(sliding, str) else float(sliding)
        except Exception:
            raise ValueError(f"sliding_speed: cannot read {sliding!r} as a speed (e.g. '0.75 m/s')") from None
        if not (u > 0 and math.isfinite(u)):
            raise ValueError(f"sliding_speed must be > 0 m/s; got {sliding!r}")
        cfg = cfg.replace(rotation_speed=u / cfg.centre_distance)
    return cfg


def solve_point(config: Config, start=None, relative: bool = False):
    """Solve with an optional warm start, retrying cold if the warm start fails.

    Returns ``(result, None)`` or ``(None, message)`` when no equilibrium is found.
    """
    from .equilibrium import EquilibriumError
    from .model import solve

    tries = [start, None] if start is not None else [None]
    msg = ""
    for s in tries:
        try:
            return solve(config, start=s, relative=relative), None
        except (EquilibriumError, ValueError, FloatingPointError, np.linalg.LinAlgError) as exc:
            msg = f"{type(exc).__name__}: {exc}"
    return None, msg


def model_value(result, quantity: str) -> float:
    """The model's value of a measurable quantity, SI."""
    return float(QUANTITIES[quantity][3](result))


def fit_scale(model: np.ndarray, data: np.ndarray, weights: np.ndarray | None = None) -> float:
    """The scale s minimising sum w (s m - y)^2."""
    w = np.ones_like(data) if weights is None else weights
    den = float(np.sum(w * model * model))
    return float(np.sum(w * model * data) / den) if den > 0 else float("nan")


def _loo(predictors: np.ndarray | None, data: np.ndarray, weights: np.ndarray) -> np.ndarray:
    """Leave-one-out errors: scale fit of ``predictors`` (None: weighted mean) on the others."""
    n = len(data)
    err = np.full(n, np.nan)
    for i in range(n):
        keep = np.arange(n) != i
        if predictors is None:
            pred = float(np.sum(weights[keep] * data[keep]) / np.sum(weights[keep]))
        else:
            s = fit_scale(predictors[keep], data[keep], weights[keep])
            pred = s * predictors[i]
        err[i] = pred - data[i]
    return err


def _rms(x) -> float:
    x = np.asarray(x, dtype=float)
    x = x[np.isfinite(x)]
    return float(np.sqrt(np.mean(x * x))) if x.size else float("nan")


@dataclass
class PointResult:
    """Model vs data at one point (values in the point's own unit)."""

    dataset: str
    kind: str
    quantity: str
    comparison: str
    conditions: str
    unit: str
    measured: float
    uncertainty: float | None
    model_raw: float  # model value in the point's unit (before any shape scale)
    model: float  # compared value (after the shape scale)
    error: float  # model - measured
    relative_error: float
    agrees: bool | None  # None: no verdict for this point
    floored_fraction: float
    fluid_load_fraction: float
    status: str  # "ok" or the reason no equilibrium was found
    source: str = ""

    def as_row(self) -> dict[str, Any]:
        return {
            "dataset": self.dataset,
            "kind": self.kind,
            "quantity": self.quantity,
            "comparison": self.comparison,
            "conditions": self.conditions,
            "unit": self.unit,
            "measured": self.measured,
            "uncertainty": "" if self.uncertainty is None else self.uncertainty,
            "model_raw": self.model_raw,
            "model": self.model,
            "error": self.error,
            "relative_error": self.relative_error,
            "agrees": "" if self.agrees is None else ("yes" if self.agrees else "no"),
            "flow_factor_floored_fraction": self.floored_fraction,
            "model_fluid_load_fraction": self.fluid_load_fraction,
            "status": self.status,
            "source": self.source,
        }


@dataclass
class DatasetSummary:
    """Errors of one data set."""

    name: str
    kind: str
    quantity: str
    comparison: str
    unit: str
    n: int
    n_solved: int
    rms_error: float  # in ``unit``
    rms_relative_error: float
    scale: float | None  # shape: fitted scale (model unit -> data unit, dimensionless)
    loo_rms_model: float | None
    loo_rms_mean: float | None
    loo_rms_preston: float | None
    verdict: str  # "pass", "fail" or "n/a"
    reason: str
    citation: str = ""
    path: str = ""

    @property
    def passed(self) -> bool:
        return self.verdict == "pass"

    @property
    def failed(self) -> bool:
        return self.verdict == "fail"


@dataclass
class ValidationReport:
    """Per-point rows and per-data-set errors of a validation run."""

    points: list[PointResult]
    datasets: list[DatasetSummary]
    config: Config
    equilibria: int = 0
    elapsed_s: float = 0.0

    def dataset(self, name: str) -> DatasetSummary:
        for d in self.datasets:
            if d.name == name:
                return d
        raise KeyError(name)

    def points_of(self, name: str) -> list[PointResult]:
        return [p for p in self.points if p.dataset == name]

    # ----------------------------------------------------------------- text output
    def point_rows(self) -> list[list[str]]:
        rows = []
        for p in self.points:
            unc = "" if p.uncertainty is None else f"+-{p.uncertainty:.4g}"
            rows.append(
                [
                    p.dataset,
                    p.quantity,
                    p.conditions,
                    f"{p.measured:.4g} {unc}".strip(),
                    f"{p.model:.4g}" if np.isfinite(p.model) else "no equilibrium",
                    f"{p.error:+.4g}" if np.isfinite(p.error) else "-",
                    f"{100 * p.relative_error:+.1f} %" if np.isfinite(p.relative_error) else "-",
                    p.unit,
                    "" if p.agrees is None else ("yes" if p.agrees else "no"),
                ]
            )
        return rows

    def dataset_rows(self) -> list[list[str]]:
        def f(x, fmt=".4g"):
            return "-" if x is None or not np.isfinite(x) else format(x, fmt)

        rows = []
        for d in self.datasets:
            rows.append(
                [
                    d.name,
                    "model-to-model" if d.kind == "model_prediction" else "measurement",
                    d.comparison,
                    f"{d.n_solved}/{d.n}",
                    f"{f(d.rms_error)} {d.unit}",
                    f"{f(100 * d.rms_relative_error, '.1f')} %",
                    f(d.loo_rms_model),
                    f(d.loo_rms_mean),
                    f(d.loo_rms_preston),
                    d.verdict,
                    d.reason,
                ]
            )
        return rows

    POINT_HEADER = ["dataset", "quantity", "conditions", "measured", "model", "error", "rel. error", "unit", "agrees"]
    DATASET_HEADER = ["dataset", "kind", "comparison", "solved", "RMS error", "RMS rel. error", "LOO RMS model", "LOO RMS mean", "LOO RMS Preston", "verdict", "why"]

    def table(self) -> str:
        """Plain-text tables: points, then data sets."""
        return _text_table(self.POINT_HEADER, self.point_rows()) + "\n\n" + _text_table(self.DATASET_HEADER, self.dataset_rows())

    def to_markdown(self) -> str:
        lines = ["| " + " | ".join(self.DATASET_HEADER) + " |", "|" + "---|" * len(self.DATASET_HEADER)]
        lines += ["| " + " | ".join(c.replace("|", "/") for c in r) + " |" for r in self.dataset_rows()]
        lines += ["", "| " + " | ".join(self.POINT_HEADER) + " |", "|" + "---|" * len(self.POINT_HEADER)]
        lines += ["| " + " | ".join(c.replace("|", "/") for c in r) + " |" for r in self.point_rows()]
        return "\n".join(lines) + "\n"

    def to_csv(self, path) -> Path:
        """Per-point table as CSV (atomic)."""
        from .io import atomic_write_text

        buf = io.StringIO()
        rows = [p.as_row() for p in self.points]
        w = csv.DictWriter(buf, fieldnames=list(rows[0]) if rows else ["dataset"])
        w.writeheader()
        for r in rows:
            w.writerow({k: (f"{v:.8g}" if isinstance(v, float) else v) for k, v in r.items()})
        atomic_write_text(Path(path), buf.getvalue())
        return Path(path)

    def summary_csv(self, path) -> Path:
        from .io import atomic_write_text

        buf = io.StringIO()
        w = csv.writer(buf)
        w.writerow(["dataset", "kind", "quantity", "comparison", "unit", "n", "n_solved", "rms_error", "rms_relative_error", "scale", "loo_rms_model", "loo_rms_mean", "loo_rms_preston", "verdict", "reason"])
        for d in self.datasets:
            w.writerow([d.name, d.kind, d.quantity, d.comparison, d.unit, d.n, d.n_solved, _g(d.rms_error), _g(d.rms_relative_error), _g(d.scale), _g(d.loo_rms_model), _g(d.loo_rms_mean), _g(d.loo_rms_preston), d.verdict, d.reason])
        atomic_write_text(Path(path), buf.getvalue())
        return Path(path)

    # ----------------------------------------------------------------- plot
    def parity_plot(self, path=None):
        """Parity plot (model vs measured), one panel per quantity; returns the Figure."""
        import matplotlib

        if path is not None:
            matplotlib.use("Agg", force=False)
        import matplotlib.pyplot as plt

        def family(q: str) -> str:
            return "film_thickness" if q.startswith("film_thickness") else ("contact_area_ratio" if q.startswith("contact_area_ratio") else q)

        families: list[str] = []
        for p in self.points:
            if family(p.quantity) not in families:
                families.append(family(p.quantity))
        quantities = families
        n = max(len(families), 1)
        ncol = min(n, 3)
        nrow = math.ceil(n / ncol)
        fig, axes = plt.subplots(nrow, ncol, figsize=(5.0 * ncol, 4.6 * nrow), squeeze=False, layout="constrained")
        markers = "osD^vP*Xh<>"
        ds_names = [d.name for d in self.datasets]
        titles = {"film_thickness": "slurry film thickness", "contact_area_ratio": "real contact area / wafer area"}
        for ax, fam in zip(axes.flat, families):
            disp = QUANTITIES[fam][1] if fam in QUANTITIES else QUANTITIES[fam + "_mean"][1]
            lo, hi = np.inf, -np.inf
            k = 0
            for d in self.datasets:
                for q in dict.fromkeys(p.quantity for p in self.points_of(d.name)):
                    if family(q) != fam:
                        continue
                    pts = [p for p in self.points_of(d.name) if p.quantity == q and np.isfinite(p.model)]
                    if not pts:
                        continue
                    meas = np.array([from_si(to_si(p.measured, p.unit, q), disp, q) for p in pts])
                    mod = np.array([from_si(to_si(p.model, p.unit, q), disp, q) for p in pts])
                    err = np.array([from_si(to_si(p.uncertainty, p.unit, q) - to_si(0.0, p.unit, q), disp, q) if p.uncertainty else 0.0 for p in pts])
                    label = d.name + (f" [{q[len(fam) + 1:]}]" if q != fam else "")
                    label += " (peer model, not a measurement)" if d.kind == "model_prediction" else ""
                    label += " (shape: scale fitted)" if d.comparison == "shape" else ""
                    label += " (range)" if d.comparison == "range" else ""
                    mk = markers[(ds_names.index(d.name) + k) % len(markers)]
                    k += 1
                    face = "none" if d.kind == "model_prediction" else None
                    ax.errorbar(meas, mod, xerr=err if err.any() else None, fmt=mk, mfc=face, label=label, capsize=3)
                    lo = min(lo, meas.min(), mod.min(), (meas - err).min())
                    hi = max(hi, meas.max(), mod.max(), (meas + err).max())
            if np.isfinite(lo):
                log = fam == "contact_area_ratio" and lo > 0
                pad = 0.1 * (hi - lo) if hi > lo else 0.1 * abs(hi) + 1e-12
                a, b = (lo / 2, hi * 2) if log else (min(0.0, lo - pad) if lo >= 0 else lo - pad, hi + pad)
                ax.plot([a, b], [a, b], "k--", lw=0.8, label="model = data")
                if log:
                    ax.set_xscale("log")
                    ax.set_yscale("log")
            name = fam.replace("_", " ")
            ax.set_xlabel(f"data: {name} ({disp})")
            ax.set_ylabel(f"model: {name} ({disp})")
            ax.set_title(titles.get(fam, QUANTITIES[fam][2] if fam in QUANTITIES else name), fontsize=9)
            ax.legend(fontsize=7)
        for ax in list(axes.flat)[len(quantities):]:
            ax.set_visible(False)
        fig.suptitle(f"cmpsim validation: model vs data (grid {self.config.numerics.grid}, model {self.config.model})")
        if path is not None:
            from .io import atomic_path

            with atomic_path(Path(path), suffix=".png") as tmp:
                fig.savefig(tmp, dpi=110, format="png")
            plt.close(fig)
        return fig


def _g(x) -> str:
    return "" if x is None or (isinstance(x, float) and not np.isfinite(x)) else f"{x:.6g}"


def _text_table(header: Sequence[str], rows: Iterable[Sequence[str]]) -> str:
    rows = [list(map(str, r)) for r in rows]
    widths = [max([len(h)] + [len(r[i]) for r in rows]) for i, h in enumerate(header)]
    line = "  ".join(h.ljust(w) for h, w in zip(header, widths))
    out = [line, "-" * len(line)]
    out += ["  ".join(c.ljust(w) for c, w in zip(r, widths)) for r in rows]
    return "\n".join(out)


# --------------------------------------------------------------------------- the comparison
def evaluate_dataset(ds: Dataset, values_si: Sequence[float], results: Sequence[Any], statuses: Sequence[str]) -> tuple[list[PointResult], DatasetSummary]:
    """Compare the model values (SI, NaN = no equilibrium) with the data set; rows + summary."""
    pts = ds.points
    unit = pts[0].unit
    q = pts[0].quantity
    measured = np.array([p.value for p in pts])
    raw = np.array([from_si(v, p.unit, p.quantity) for v, p in zip(values_si, pts)])
    unc = [p.uncertainty for p in pts]
    ok = np.isfinite(raw)
    scale = None
    compared = raw.copy()
    loo_model = loo_mean = loo_preston = None
    if ds.comparison == "shape":
        w = np.array([1.0 / u**2 if u else 1.0 for u in unc]) if all(unc) else np.ones(len(pts))
        if ok.sum() >= 2:
            scale = fit_scale(raw[ok], measured[ok], w[ok])
            compared = scale * raw
            loo_model = _rms(_loo(raw[ok], measured[ok], w[ok]))
            loo_mean = _rms(_loo(None, measured[ok], w[ok]))
            pu = np.array([r.config.applied_pressure * r.scalars["sliding_speed_m_s"] if r is not None else np.nan for r in results])
            loo_preston = _rms(_loo(pu[ok], measured[ok], w[ok]))
    err = compared - measured
    rel = err / np.where(measured != 0, np.abs(measured), np.nan)
    agrees: list[bool | None] = []
    for i, p in enumerate(pts):
        if not ok[i]:
            agrees.append(False if ds.kind != "model_prediction" else None)
        elif ds.kind == "model_prediction":
            agrees.append(None)
        elif p.comparison == "absolute":
            agrees.append(None if p.uncertainty is None else bool(abs(err[i]) <= 2.0 * p.uncertainty))
        elif p.comparison == "range":
            agrees.append(bool(abs(err[i]) <= p.uncertainty))
        elif p.comparison == "order":
            agrees.append(bool(raw[i] > 0 and abs(math.log10(raw[i] / p.value)) <= ORDER_TOLERANCE_DECADES))
        else:
            agrees.append(None)
    rows = []
    for i, p in enumerate(pts):
        r = results[i]
        rows.append(
            PointResult(
                ds.name,
                ds.kind,
                p.quantity,
                p.comparison,
                p.conditions_text(),
                p.unit,
                p.value,
                p.uncertainty,
                float(raw[i]),
                float(compared[i]),
                float(err[i]),
                float(rel[i]),
                agrees[i],
                r.scalars["flow_factor_floored_fraction"] if r is not None else float("nan"),
                r.scalars["fluid_load_fraction"] if r is not None else float("nan"),
                statuses[i],
                p.source,
            )
        )
    # verdict
    n_fail_solve = int((~ok).sum())
    if ds.kind == "model_prediction":
        verdict, reason = "n/a", "model-to-model comparison: errors only, no verdict"
    elif ds.comparison == "shape":
        if loo_model is None:
            verdict, reason = "fail", f"{n_fail_solve} of {len(pts)} points have no equilibrium"
        elif loo_model < loo_mean:
            verdict = "pass"
            reason = f"leave-one-out error {loo_model:.3g} < {loo_mean:.3g} of predicting the mean"
            if loo_preston is not None and np.isfinite(loo_preston):
                reason += "; " + ("also beats" if loo_model < loo_preston else "but worse than") + f" Preston s*P*U ({loo_preston:.3g})"
        else:
            verdict = "fail"
            reason = f"leave-one-out error {loo_model:.3g} is not below {loo_mean:.3g} of predicting the mean: the model's shape adds nothing"
    else:
        verdicts = [a for a in agrees if a is not None]
        if not verdicts:
            verdict, reason = "n/a", "no uncertainty given: errors only"
        elif all(verdicts):
            verdict, reason = "pass", {"absolute": "every point within 2 uncertainties", "range": "inside the measured range", "order": "within a factor 10^0.5 at every point"}[ds.comparison]
        else:
            bad = [i for i, a in enumerate(agrees) if a is False]
            if ds.comparison == "range":
                i = bad[0]
                reason = f"model {raw[i]:.3g} {unit} outside the measured range {pts[i].value - pts[i].uncertainty:.3g}-{pts[i].value + pts[i].uncertainty:.3g} {unit}"
            elif ds.comparison == "order":
                ratios = [raw[i] / pts[i].value for i in bad if np.isfinite(raw[i])]
                reason = f"{len(bad)} of {len(pts)} points off by more than a factor 3.16 (model/measured {min(ratios):.3g}-{max(ratios):.3g})" if ratios else "no equilibrium"
            else:
                reason = f"{len(bad)} of {len(pts)} points outside 2 uncertainties"
            verdict = "fail"
        if n_fail_solve:
            reason += f"; {n_fail_solve} point(s) without equilibrium"
    summary = DatasetSummary(
        ds.name,
        ds.kind,
        q if len({p.quantity for p in pts}) == 1 else ds.quantity,
        ds.comparison,
        unit if len({p.unit for p in pts}) == 1 else "mixed",
        len(pts),
        int(ok.sum()),
        _rms(err) if len({p.unit for p in pts}) == 1 else float("nan"),
        _rms(rel),
        scale,
        loo_model,
        loo_mean,
        loo_preston,
        verdict,
        reason,
        ds.citation,
        str(ds.path or ""),
    )
    return rows, summary


def solve_points(points, config: Config, relative: bool = False, warm: dict | None = None, advance: Callable[[], None] | None = None):
    """Model value, result and status of each measured point; returns (values, results, statuses, equilibria).

    Points at identical conditions share one equilibrium. Each new equilibrium starts from
    ``warm[conditions]`` when a ``warm`` dict is given (it is updated in place with every
    converged position, as calibration needs across its iterations), otherwise from the
    previous converged point.
    """
    values, results, statuses = [], [], []
    same: dict[tuple, tuple] = {}
    previous = None
    for p in points:
        key = tuple(sorted(p.conditions.items()))
        if key not in same:
            start = warm.get(key) if warm is not None else previous
            same[key] = solve_point(point_config(config, p.conditions), start=start, relative=relative)
        res, msg = same[key]
        if res is None:
            values.append(float("nan"))
            results.append(None)
            statuses.append(f"no equilibrium: {msg}")
        else:
            previous = res.solution.state.u
            if warm is not None:
                warm[key] = previous
            values.append(model_value(res, p.quantity))
            results.append(res)
            floored = res.scalars["flow_factor_floored_fraction"]
            statuses.append("ok" if floored == 0 else f"ok (flow factors regularised on {100 * floored:.0f} % of faces)")
        if advance is not None:
            advance()
    return values, results, statuses, len(same)


def run_dataset(ds: Dataset, config: Config, relative: bool = False, advance: Callable[[], None] | None = None):
    """Solve every point of a data set (warm start from the previous point). Returns (values, results, statuses)."""
    return solve_points(ds.points, config, relative=relative, advance=advance)[:3]


def validate(paths=None, config: Config | None = None, grid: str | None = None, progress: bool = False) -> ValidationReport:
    """Run the model at every point of the data sets and compare.

    Parameters
    ----------
    paths : path, Dataset or sequence of them, optional
        Data files (format: ``cmpsim/data/README.md``); default every data set shipped with
        the package.
    config : Config, optional
        Inputs not set by a data point (default :meth:`Config.default`), e.g. a calibrated
        configuration written by ``cmpsim calibrate``.
    grid : str, optional
        Grid preset overriding ``config``'s.
    progress : bool
        Show a rich progress bar.

    Returns
    -------
    ValidationReport
    """
    import time

    t0 = time.perf_counter()
    datasets = _as_datasets(paths)
    config = config or Config.default()
    if grid is not None:
        config = config.replace(grid=grid)
    total = sum(len(d.points) for d in datasets)
    points: list[PointResult] = []
    summaries: list[DatasetSummary] = []
    ctx = _progress(progress, total, "validate")
    with ctx as advance:
        for ds in datasets:
            values, results, statuses = run_dataset(ds, config, advance=advance)
            rows, summary = evaluate_dataset(ds, values, results, statuses)
            points.extend(rows)
            summaries.append(summary)
    n_eq = sum(len({tuple(sorted(p.conditions.items())) for p in ds.points}) for ds in datasets)
    return ValidationReport(points, summaries, config, equilibria=n_eq, elapsed_s=time.perf_counter() - t0)


class _progress:
    """Context manager yielding an ``advance()`` callable; a rich bar when enabled."""

    def __init__(self, enabled: bool, total: int, label: str):
        self.enabled, self.total, self.label = enabled, total, label
        self._bar = None

    def __enter__(self):
        if not self.enabled:
            return lambda: None
        from rich.progress import BarColumn, MofNCompleteColumn, Progress, TextColumn, TimeElapsedColumn

        self._bar = Progress(TextColumn("{task.description}"), BarColumn(), MofNCompleteColumn(), TimeElapsedColumn(), transient=False)
        self._bar.__enter__()
        task = self._bar.add_task(self.label, total=self.total)
        return lambda: self._bar.advance(task)

    def __exit__(self, *exc):
        if self._bar is not None:
            self._bar.__exit__(*exc)
        return False
