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

Rooms: ``data`` (the file format, the quantities, reading),
``compare`` (the model's values and the verdicts),
``report`` (tables and the parity plot); :func:`validate` runs them in
order.
"""

from __future__ import annotations

from ..inputs.config import Config
from ..solver.points import Progress
from .compare import (
    DatasetSummary,
    PointResult,
    _loo,
    _rms,
    evaluate_dataset,
    fit_scale,
    model_value,
    run_dataset,
    solve_points,
)
from .data import (
    COMPARISONS,
    EXTRA_CONDITIONS,
    META_COLUMNS,
    ORDER_TOLERANCE_DECADES,
    QUANTITIES,
    DataError,
    DataPoint,
    Dataset,
    _as_datasets,
    from_si,
    load_dataset,
    load_datasets,
    point_config,
    shipped_dataset_paths,
    to_si,
)
from .report import ValidationReport

__all__ = [
    "QUANTITIES",
    "COMPARISONS",
    "DataError",
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
    n_eq = 0
    kept = {}
    with Progress(progress, total, "validate") as bar:
        for ds in datasets:
            values, results, statuses, solved = solve_points(ds.points, config, advance=bar.advance)
            rows, summary = evaluate_dataset(ds, values, results, statuses)
            points.extend(rows)
            summaries.append(summary)
            n_eq += solved
            kept[ds.name] = (ds, values, results)
    return ValidationReport(points, summaries, config, equilibria=n_eq, elapsed_s=time.perf_counter() - t0, solved=kept)
