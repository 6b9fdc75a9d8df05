"""The report of a validation run: tables (text, Markdown, CSV) and the parity plot."""

from __future__ import annotations

import csv
import io
import math
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from ..inputs.config import Config
from ..tables import markdown_table, text_table
from .compare import DatasetSummary, PointResult
from .data import DEPTH_QUANTITIES, QUANTITIES, from_si, to_si

__all__ = ["ValidationReport"]


@dataclass
class ValidationReport:
    """Per-point rows and per-data-set errors of a validation run."""

    points: list[PointResult]
    datasets: list[DatasetSummary]
    config: Config
    equilibria: int = 0
    elapsed_s: float = 0.0
    #: data set name -> (its values SI, its solved results): what a study above (leave-one-out calibration) reuses
    solved: dict = field(default_factory=dict, repr=False)
    #: leave-one-out of the calibrated model per removal series (:func:`cmpsim.calibration.heldout.compare_with_preston`)
    calibrated_loo: list = field(default_factory=list)

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
        return text_table(self.POINT_HEADER, self.point_rows()) + "\n\n" + text_table(self.DATASET_HEADER, self.dataset_rows())

    def to_markdown(self) -> str:
        """Markdown tables: data sets, then points."""
        return markdown_table(self.DATASET_HEADER, self.dataset_rows()) + "\n" + markdown_table(self.POINT_HEADER, self.point_rows())

    def to_csv(self, path) -> Path:
        """Per-point table as CSV (atomic)."""
        from ..io import atomic_write_text

        buf = io.StringIO()
        rows = [p.as_row() for p in self.points]
        w = csv.DictWriter(buf, fieldnames=list(rows[0]) if rows else ["dataset"])
        w.writeheader()
        for r in rows:
            w.writerow({k: (f"{v:.8g}" if isinstance(v, float) else v) for k, v in r.items()})
        atomic_write_text(Path(path), buf.getvalue())
        return Path(path)

    def summary_csv(self, path) -> Path:
        from ..io import atomic_write_text

        buf = io.StringIO()
        w = csv.writer(buf)
        w.writerow(["dataset", "kind", "quantity", "comparison", "unit", "n", "n_solved", "rms_error", "rms_relative_error", "scale", "loo_rms_model", "loo_rms_mean", "loo_rms_preston", "verdict", "reason"]
                   + (["loo_rms_calibrated", "calibrated_inputs"] if self.calibrated_loo else []))
        loo = {s.name: s for s in self.calibrated_loo}
        for d in self.datasets:
            extra = ([_g(loo[d.name].calibrated), " ".join(loo[d.name].inputs)] if d.name in loo else ["", ""]) if self.calibrated_loo else []
            w.writerow([d.name, d.kind, d.quantity, d.comparison, d.unit, d.n, d.n_solved, _g(d.rms_error), _g(d.rms_relative_error), _g(d.scale), _g(d.loo_rms_model), _g(d.loo_rms_mean), _g(d.loo_rms_preston), d.verdict, d.reason] + extra)
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
            disp = QUANTITIES[fam][1] if fam in QUANTITIES else (DEPTH_QUANTITIES[fam][1] if fam in DEPTH_QUANTITIES else QUANTITIES[fam + "_mean"][1])
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
            ax.set_title(titles.get(fam, QUANTITIES[fam][2] if fam in QUANTITIES else DEPTH_QUANTITIES.get(fam, ("", "", name))[2]), fontsize=9)
            ax.legend(fontsize=7)
        for ax in list(axes.flat)[len(quantities):]:
            ax.set_visible(False)
        fig.suptitle(f"cmpsim validation: model vs data (grid {self.config.numerics.grid}, model {self.config.model})")
        if path is not None:
            from ..io import atomic_path

            with atomic_path(Path(path), suffix=".png") as tmp:
                fig.savefig(tmp, dpi=110, format="png")
            plt.close(fig)
        return fig


def _g(x) -> str:
    return "" if x is None or (isinstance(x, float) and not np.isfinite(x)) else f"{x:.6g}"
