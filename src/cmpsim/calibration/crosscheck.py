"""The model (calibrated or not) against held-out test structures, pad records and lots: rows for ``points.csv``.

``cmpsim validate DATA --config FILE`` solves the film rows as before (:func:`cmpsim.validation.validate`)
and hands the other families here: test structures are polished by the die model with the process
file's die constants (:func:`cmpsim.calibration.die.predict_die`), pad records by the pad's heat
balance with its friction and heat removal on the base they were calibrated on
(:func:`cmpsim.calibration.thermal.predict_thermal`). Each point becomes a row with the columns of
the film points (:meth:`cmpsim.validation.compare.PointResult.as_row`), in the unit of its file.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np

__all__ = ["KindComparison", "compare_structures", "compare_pad", "list_lots", "compare_lots", "write_points"]


@dataclass
class KindComparison:
    """One kind's comparison: ``rows`` (dicts of points.csv), the RMS error in ``unit`` and a ``note``."""

    kind: str
    unit: str
    rows: list = field(default_factory=list)
    rms: float = float("nan")
    note: str = ""

    @property
    def n(self) -> int:
        return len(self.rows)


def _row(dataset, quantity, conditions, unit, scale, measured, unc, model, source, status="ok") -> dict:
    m = measured / scale
    v = model / scale if model is not None and math.isfinite(model) else None
    u = unc / scale if unc is not None else None
    err = v - m if v is not None else None
    return {"dataset": dataset, "kind": "measurement", "quantity": quantity, "comparison": "absolute", "conditions": conditions, "unit": unit,
            "measured": m, "uncertainty": "" if u is None else u, "model_raw": "" if v is None else v, "model": "" if v is None else v,
            "error": "" if err is None else err, "relative_error": "" if err is None or m == 0 else err / m,
            "agrees": "" if err is None or u is None else ("yes" if abs(err) <= 2 * u else "no"),
            "flow_factor_floored_fraction": "", "model_fluid_load_fraction": "", "status": status if v is not None else "not reached", "source": source}


def _rms(rows) -> float:
    e = [r["error"] for r in rows if r["error"] != ""]
    return float(np.sqrt(np.mean(np.square(e)))) if e else float("nan")


def compare_structures(records, constants: dict | None, config) -> KindComparison:
    """Test structures against the die model with ``constants`` (the process file's, or None: the defaults); values in nm."""
    from .die import predict_die

    model = predict_die(records, constants or {}, config)
    rows = []
    for r, m in zip(records, model):
        cond = f"process={r.process}, line_width={r.line_width * 1e6:g} um" + (f", line_space={r.line_space * 1e6:g} um" if r.line_space else ", isolated")
        cond += (f", structure_size={r.structure_size * 1e3:g} mm" if r.structure_size else "") + (f", time={r.time:g} s" if r.time else ", end point")
        rows.append(_row(r.dataset, r.quantity, cond, "nm", 1e-9, r.value, r.uncertainty, float(m), r.source))
    return KindComparison("test structures", "nm", rows, _rms(rows), "calibrated die constants" if constants else "die defaults (no [calibration.die])")


def compare_pad(records, base) -> KindComparison:
    """Pad records against the pad's heat balance on ``base`` (its friction and heat removal); K for a rise, 1 for a friction."""
    from .thermal import predict_thermal

    model = predict_thermal(records, None, base)
    rows = []
    for r, m in zip(records, model):
        cond = ", ".join(f"{k}={v}" for k, v in r.conditions.items()) + (f", time={r.time:g} s" if r.time else "")
        rows.append(_row(r.dataset, r.quantity, cond, "K" if r.quantity == "pad_temperature_rise" else "1", 1.0, r.value, r.uncertainty, float(m), r.source))
    rises = [row for row in rows if row["quantity"] == "pad_temperature_rise"]
    return KindComparison("pad", "K", rows, _rms(rises), "RMS of the temperature rises")


def list_lots(records) -> KindComparison:
    """Lot rows, read and checked but not compared (no model value): listed in points.csv with status 'not compared'."""
    rows = [_row(r.dataset, r.quantity, f"wafer={r.wafer}" + (f", film={r.film}" if r.film else ""), "nm", 1e-9, r.value, r.uncertainty, None,
                 r.source, "not compared") | {"status": "not compared"} for r in records]
    return KindComparison("lot", "nm", rows, float("nan"), "read and checked; `cmpsim validate` does not run `cmpsim lot` for them yet")


def compare_lots(records, recipe, overrides: dict | None = None, control: str = "none", seed: int | None = 0,
                 pad_constants: dict | None = None, conditioning: str | None = None, qualification: int = 1) -> KindComparison:
    """Lot rows against ``cmpsim lot`` of ``recipe`` (a path or a parsed recipe) over as many wafers as the rows name.

    ``thickness`` is the wafer's mean top film left (``final_thickness_mean``), ``removal`` its
    incoming mean less that; ``overrides`` the process file's constants (``recipe_overrides``); the
    lot's incoming thicknesses are drawn with ``seed`` (``cmpsim lot --seed``); ``pad_constants`` the
    process file's glazing and conditioning constants (``[calibration.padlife]``); ``conditioning`` and
    ``qualification`` as ``cmpsim lot`` takes them (None: the recipe's conditioning). Values in nm.
    """
    from ..polisher.lot import run_lot
    from ..polisher.recipe import read_recipe

    parsed = read_recipe(recipe) if not hasattr(recipe, "steps") else recipe
    top = parsed.films[0].material
    for r in records:
        if r.film is not None and r.film != top:
            raise ValueError(f"{r.path}:{r.line}: column 'film': {r.film!r} is not the recipe's top film ({top}), the film a lot measures")
    from .lotdata import logged_times, logged_zone_pressures

    n = max(r.wafer for r in records)
    times = logged_times(records)  # a lot under the fab's own control: replayed at its logged times (and zone pressures)
    if times:
        control = "none"
    lot = run_lot(parsed, n, control=control, seed=seed, overrides=overrides or {}, pad_constants=pad_constants, conditioning=conditioning,
                  qualification=qualification, polish_times=times, polish_zone_pressures=logged_zone_pressures(records))
    rows = []
    for r in records:
        w = lot.wafers[r.wafer - 1]
        model = w.final_thickness_mean if r.quantity == "thickness" else w.incoming_mean - w.final_thickness_mean
        rows.append(_row(r.dataset, r.quantity, f"wafer={r.wafer}, film={top}", "nm", 1e-9, r.value, r.uncertainty, float(model), r.source))
    note = (f"cmpsim lot {parsed.source} ({n} wafers, " + ("replayed at the logged polish times" if times else f"control {control}")
            + f", seed {seed}" + (", calibrated pad life)" if pad_constants else ")"))
    return KindComparison("lot", "nm", rows, _rms(rows), note)


def write_points(path, film_rows: list, comparisons: list) -> None:
    """points.csv of every kind: the film points' rows, then each comparison's (atomic)."""
    import csv
    import io
    from pathlib import Path

    from ..io import atomic_write_text

    rows = list(film_rows) + [r for c in comparisons for r in c.rows]
    buf = io.StringIO()
    names = list(rows[0]) if rows else ["dataset"]
    w = csv.DictWriter(buf, fieldnames=names)
    w.writeheader()
    for r in rows:
        w.writerow({k: (f"{v:.8g}" if isinstance(v, float) else v) for k, v in r.items() if k in names})
    atomic_write_text(Path(path), buf.getvalue())
