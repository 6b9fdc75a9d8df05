"""What a lot leaves: its wafers' records (:class:`WaferRecord`), the lot (:class:`LotResult`: the JSON of
``cmpsim lot --json``, its plot) and the files of ``cmpsim lot --out DIR`` (:func:`write_lot`). SI units;
:data:`UNITS` names them. Split from :mod:`cmpsim.polisher.lot`, which runs the lot."""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

__all__ = ["UNITS", "WaferRecord", "LotResult", "lot_csv", "write_lot"]

UNITS = {
    "polish_time": "s", "removal_rate_mean": "m/s", "final_thickness_mean": "m", "final_thickness_nonuniformity": "1 (std over mean, wafer area)",
    "zone_pressures": "Pa", "incoming_mean": "m", "pad_temperature_end": "K", "rate_factor": "1 (glazed pad / fresh pad)",
    "summit_sigma": "1 (worn / fresh, at the wafer's start)", "target": "m", "idle_time": "s", "wall_time": "s",
    "qualification.removal_rate_mean": "m/s", "qualification.polish_time": "s", "predicted_rate": "m/s",
    "predicted_nonuniformity": "1 (std over mean, wafer area, predicted by the zone feedback)",
    "controller.weight": "1", "controller.drift_weight": "1", "controller.zone_weight": "1",
    "model_wear_coefficient": "1/Pa (the controller's pad-life model, refitted)",
    "model_critical_glazed_area": "1 (the controller's pad-life model, refitted)",
    "step_times": "s (each step's polish time)",
}


@dataclass(frozen=True)
class WaferRecord:
    """One wafer of a lot (SI). The keys ``index``, ``polish_time`` (s), ``removal_rate_mean`` (m/s),
    ``final_thickness_mean`` (m), ``final_thickness_nonuniformity`` (fraction) and ``zone_pressures``
    (Pa) of :meth:`to_dict` are a contract (issue 32); the rest says why."""

    index: int
    polish_time: float
    removal_rate_mean: float
    final_thickness_mean: float
    final_thickness_nonuniformity: float
    zone_pressures: tuple
    incoming_mean: float
    pad_temperature_end: float | None
    rate_factor: float
    summit_sigma: float
    radius: np.ndarray = field(repr=False)
    final_thickness: np.ndarray = field(repr=False)
    #: m/s: the rate the controller predicted for the wafer (eq. C4 or C1, times Z6); None without control
    predicted_rate: float | None = None
    #: 1: the non-uniformity the zone feedback predicted at the wafer's pressures (eq. Z2); None without it
    predicted_nonuniformity: float | None = None
    #: the zone feedback's decision for the wafer (eq. Z4): "accepted", "halved N", "refused"; None without it
    zone_step: str | None = None
    #: 1/Pa: the wear coefficient k_w of the controller's pad-life model after the wafer (``refit_model``, eqs. C6-C7); None without it
    model_wear_coefficient: float | None = None
    #: 1: the critical glazed area G_c of the controller's pad-life model after the wafer (``refit_model``); None without it
    model_critical_glazed_area: float | None = None
    #: s: each step's polish time on the wafer, in the recipe's order (None: not recorded)
    step_times: tuple | None = None

    def to_record(self) -> dict:
        """Every field as JSON-able values (the checkpoint's record; floats round-trip exactly)."""
        return self.to_dict() | {"radius": np.asarray(self.radius, dtype=float).tolist(),
                                 "final_thickness": np.asarray(self.final_thickness, dtype=float).tolist()}

    @classmethod
    def from_dict(cls, data: dict) -> "WaferRecord":
        """The inverse of :meth:`to_record`."""
        d = dict(data)
        d["zone_pressures"] = tuple(d["zone_pressures"])
        if d.get("step_times") is not None:
            d["step_times"] = tuple(d["step_times"])
        d["radius"] = np.asarray(d["radius"], dtype=float)
        d["final_thickness"] = np.asarray(d["final_thickness"], dtype=float)
        return cls(**d)

    def to_dict(self) -> dict:
        return {
            "index": self.index,
            "polish_time": self.polish_time,
            "removal_rate_mean": self.removal_rate_mean,
            "final_thickness_mean": self.final_thickness_mean,
            "final_thickness_nonuniformity": self.final_thickness_nonuniformity,
            "zone_pressures": list(self.zone_pressures),
            "incoming_mean": self.incoming_mean,
            "pad_temperature_end": self.pad_temperature_end,
            "rate_factor": self.rate_factor,
            "summit_sigma": self.summit_sigma,
            "predicted_rate": self.predicted_rate,
            "predicted_nonuniformity": self.predicted_nonuniformity,
            "zone_step": self.zone_step,
            "model_wear_coefficient": self.model_wear_coefficient,
            "model_critical_glazed_area": self.model_critical_glazed_area,
            "step_times": None if self.step_times is None else list(self.step_times),
        }


@dataclass
class LotResult:
    """A polished lot: ``wafers`` (:class:`WaferRecord`), the settings, the ``target`` (m or None),
    the wafer equilibria solved and the wall time (s)."""

    recipe: object
    wafers: list
    control: str
    conditioning: str
    seed: int | None
    target: float | None
    idle_time: float
    solves: int
    wall_time: float
    qualification: dict | None = None
    #: the controller's weights (lambda_1 ``weight``, lambda_2 ``drift_weight``, lambda_z ``zone_weight``) and whether the zone feedback ran; None without control
    controller: dict | None = None

    def to_dict(self) -> dict:
        """The JSON object of ``cmpsim lot --json`` (SI, units in ``units``)."""
        return {
            "recipe": self.recipe.source,
            "control": self.control,
            "conditioning": self.conditioning,
            "seed": self.seed,
            "target": self.target,
            "idle_time": self.idle_time,
            "wafers": [w.to_dict() for w in self.wafers],
            "qualification": self.qualification,
            "controller": self.controller,
            "solves": self.solves,
            "wall_time": self.wall_time,
            "units": dict(UNITS),
        }

    def to_json(self) -> str:
        import json

        return json.dumps(self.to_dict())

    def plot(self, path=None):
        """The lot plot: final thickness (with the target), mean removal rate, polish time and zone
        pressures against the wafer index; saved to ``path`` if given. Returns the figure."""
        import matplotlib.pyplot as plt

        idx = [w.index for w in self.wafers]
        fig, ax = plt.subplots(2, 2, figsize=(10, 6.5), sharex=True)
        ax[0, 0].plot(idx, [w.final_thickness_mean * 1e9 for w in self.wafers], "o-", label="final mean")
        if self.target is not None:
            ax[0, 0].axhline(self.target * 1e9, color="k", ls="--", lw=1, label="target")
            ax[0, 0].axhspan(self.target * 0.99e9, self.target * 1.01e9, color="0.85", label="target +- 1 %")
        ax[0, 0].set_ylabel("remaining thickness (nm)")
        ax[0, 0].legend(fontsize=8)
        ax[0, 1].plot(idx, [w.removal_rate_mean * 6e10 for w in self.wafers], "o-")
        ax[0, 1].set_ylabel("mean removal rate (nm/min)")
        refitted = [(w.index, w.model_wear_coefficient) for w in self.wafers if w.model_wear_coefficient is not None]
        if refitted:  # the controller's refitted pad-life model (--refit-model)
            twin = ax[0, 1].twinx()
            twin.plot([i for i, _ in refitted], [k * 1e15 for _, k in refitted], "s--", ms=3, color="C3", label="controller's k_w")
            twin.set_ylim(0, 1.3e15 * max(k for _, k in refitted))
            twin.set_ylabel("controller's k_w (1e-15 1/Pa)", color="C3")
            twin.legend(fontsize=7, loc="upper right")
        ax[1, 0].plot(idx, [w.polish_time for w in self.wafers], "o-")
        ax[1, 0].set_ylabel("polish time (s)")
        zones = np.array([w.zone_pressures for w in self.wafers], dtype=float) / 6894.757293168361
        for k in range(zones.shape[1] if zones.ndim == 2 else 0):
            ax[1, 1].plot(idx, zones[:, k], "o-", ms=3, label=f"zone {k + 1}")
        ax[1, 1].set_ylabel("zone pressure (psi)")
        if zones.ndim == 2 and zones.shape[1]:
            ax[1, 1].legend(fontsize=7)
        for a in ax[1]:
            a.set_xlabel("wafer")
        fig.suptitle(f"lot of {len(idx)} wafers: control {self.control}, conditioning {self.conditioning}")
        fig.tight_layout()
        if path is not None:
            fig.savefig(path, dpi=110)
            plt.close(fig)
        return fig


def lot_csv(result: LotResult) -> str:
    """One row per wafer (SI units in the header)."""
    head = "index,polish_time_s,removal_rate_mean_m_per_s,final_thickness_mean_m,final_thickness_nonuniformity,incoming_mean_m,rate_factor,pad_temperature_end_K,zone_pressures_Pa"
    rows = [head]
    for w in result.wafers:
        zones = " ".join(f"{p:.6g}" for p in w.zone_pressures)
        temp = "" if w.pad_temperature_end is None else f"{w.pad_temperature_end:.6g}"
        rows.append(f"{w.index},{w.polish_time:.6g},{w.removal_rate_mean:.6g},{w.final_thickness_mean:.6g},{w.final_thickness_nonuniformity:.6g},{w.incoming_mean:.6g},{w.rate_factor:.6g},{temp},{zones}")
    return "\n".join(rows) + "\n"


def write_lot(result: LotResult, out_dir) -> list:
    """Write lot.json, lot.csv and lot.png into ``out_dir`` (each atomically, all computed first)."""
    import json

    from .report import write_files

    texts = {"lot.json": json.dumps(result.to_dict(), indent=1), "lot.csv": lot_csv(result)}
    return write_files(out_dir, texts, {"lot.png": result.plot()})
