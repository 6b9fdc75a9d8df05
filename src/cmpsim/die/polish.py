"""One die, and every die of a wafer: :func:`simulate` and :func:`simulate_wafer`.

The blanket removal rate of a die comes from a wafer-scale solve (:func:`cmpsim.solve`): its
wafer-mean removal rate for one die, the rotation-averaged removal-rate profile at each die's
radius for a wafer of dies (the wafer turns under the carrier-frame maps, so a die at radius r
loses the ring mean of the rate at r; docs/model.md section 15). Every local rate of the die
model is a blanket rate times a pressure ratio, so a die polished at rate K for a time t is in
the state of the reference die polished at K_ref for t K / K_ref: a wafer of dies costs one
wafer solve and one die evolution, read at each die's equivalent time.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np

from .density import GaussianWeighting, PadWeighting, effective_density
from .evolution import DieEvolution
from .layout import BUILTIN_LAYOUTS, Layout, builtin_layout, read_layout
from .pad import pad_stack, planarization_length_from_pad
from .process import DieProcess
from .stacks import film_stack
from .elliptic import DEFAULT_TRUNCATION, EllipticWeighting, planarization_length_elliptic_from_pad
from .reach import FEATURE_CONTACTS, FeatureContact

__all__ = ["simulate", "DieResult", "load_layout"]


def load_layout(layout, cell_size: float | None = None) -> Layout:
    """A :class:`Layout` from a Layout, a built-in die name (``cell_size`` m, default 50 um) or a CSV path."""
    if isinstance(layout, Layout):
        return layout
    name = str(layout)
    if name in BUILTIN_LAYOUTS:
        return builtin_layout(name, cell_size or 50e-6)
    if cell_size is not None:
        raise ValueError("cell_size applies to the built-in dies only: a layout file gives its own")
    return read_layout(name)


def _finite(v):
    return None if v is None or not math.isfinite(v) else float(v)


def _config(config):
    from ..inputs.config import Config

    return config if config is not None else Config.default()


def _weighting(config, planarization_length, weighting):
    """(weighting, the length derived from the pad in the weighting's own convention)."""
    derived = planarization_length_from_pad(config)
    length = derived if planarization_length is None else float(planarization_length)
    if weighting == "gaussian":
        return GaussianWeighting(length), derived
    if weighting == "pad":
        if planarization_length is not None:
            raise ValueError("weighting = 'pad' takes its length from the pad stack: leave planarization_length unset")
        return PadWeighting(pad_stack(config), derived), derived
    if weighting == "elliptic":
        derived = planarization_length_elliptic_from_pad(config)
        return EllipticWeighting(derived if planarization_length is None else float(planarization_length)), derived
    raise ValueError(f"weighting must be 'gaussian', 'pad' or 'elliptic'; got {weighting!r}")


def _conventions(config) -> dict:
    """The planarization length derived from the pad stack in each convention (m), and the elliptic kernel's truncation."""
    return {"gaussian": planarization_length_from_pad(config), "elliptic": planarization_length_elliptic_from_pad(config),
            "elliptic_truncation": DEFAULT_TRUNCATION}


def _feature(config, feature_contact):
    if feature_contact not in FEATURE_CONTACTS:
        raise ValueError(f"feature_contact must be one of {', '.join(FEATURE_CONTACTS)}; got {feature_contact!r}")
    return FeatureContact.from_config(config) if feature_contact == "elastic" else None


@dataclass
class DieResult:
    """A die after polishing for ``time`` (s) at ``blanket_rate`` (m/s). Heights from the original field oxide top (m)."""

    layout: Layout
    process: DieProcess
    time: float
    blanket_rate: float
    planarization_length: float
    planarization_length_from_pad: float
    weighting: str
    effective_density: np.ndarray = field(repr=False)
    evolution: DieEvolution = field(repr=False)
    #: the length derived from the pad in each convention ("gaussian", "elliptic", m) and "elliptic_truncation" (r_t / a)
    conventions: dict = field(default_factory=dict, repr=False)
    feature_contact: str = "summit"
    #: hotspot limits, kind -> m (:mod:`cmpsim.die.hotspots`)
    spec: dict = field(default_factory=dict)
    #: the level's name in a stack (None: a single level)
    level: str | None = None
    #: ``cmpsim die --fill``: the JSON ``fill`` object ({before, after, added_area, ...}); this die is then the filled one
    fill: dict | None = None
    #: a calibrated run (``simulate(..., uncertainty=)``): the fit's :class:`cmpsim.die.uncertainty.DieUncertainty`
    uncertainty: object = None
    #: and the standard deviation of every field with a limit, kind -> (ny, nx) m (docs/calibrate-die.md)
    sigma: dict | None = field(default=None, repr=False)

    @property
    def thickness_range(self) -> float:
        """Max - min of the final mean surface height over the die (m)."""
        h = self.evolution.mean_height
        return float(np.max(h) - np.min(h))

    def fields(self) -> dict:
        """The per-window quantities that have limits (m): thickness, step_height, dishing, erosion."""
        ev = self.evolution
        return {"thickness": ev.thickness, "step_height": ev.step_height, "dishing": ev.dishing, "erosion": ev.erosion}

    def hotspots(self, spec: dict | None = None) -> list[dict]:
        """The windows over a limit (:func:`cmpsim.die.hotspots.find_hotspots`; default limits :attr:`spec`), with their window boxes."""
        from .hotspots import find_hotspots

        x, y = self.layout.coordinates()
        return find_hotspots(self.fields(), x, y, self.layout.cell_size, self.layout.extent, self.spec if spec is None else spec, self.level,
                             self.sigma)

    def at_risk(self, spec: dict | None = None) -> list[dict]:
        """A calibrated run's windows under a limit whose 95 % interval reaches it (:func:`cmpsim.die.hotspots.find_at_risk`);
        empty for an uncalibrated run."""
        from .hotspots import find_at_risk

        x, y = self.layout.coordinates()
        return find_at_risk(self.fields(), x, y, self.layout.cell_size, self.layout.extent, self.spec if spec is None else spec,
                            self.sigma, self.level)

    def hotspot_count(self, spec: dict | None = None) -> int:
        """The number of hotspots (windows x quantities over their limits)."""
        from .hotspots import count_hotspots

        spec = self.spec if spec is None else spec
        if not spec:
            return 0
        x, y = self.layout.coordinates()
        return count_hotspots(self.fields(), x, y, self.layout.cell_size, self.layout.extent, spec)

    @property
    def time_to_planarize(self) -> float:
        """Time (s) by which every cell's step falls below ``planarity`` (copper: in the bulk stage, or its field clears), also when later than :attr:`time`."""
        return float(self.evolution.t_planar.max())

    @property
    def time_to_clear(self) -> float:
        """Copper: time (s) by which the barrier clears from the field of every cell (also when later than :attr:`time`); oxide: the time to planarize."""
        return float(self.evolution.t_clear.max())

    def regions(self) -> list[dict]:
        """Per block or line array, at its measurement site (the cell deepest inside it): density, line_width, step_height, dishing, erosion (SI)."""
        if self.layout.windowed:  # a real layout: every window is its own "region"; the maps are the result
            return []
        ev = self.evolution
        x, y = self.layout.coordinates()
        out = []
        for r in self.layout.regions():
            iy, ix = r.site
            out.append(
                {
                    "index": r.index,
                    "density": r.density,
                    "line_width": r.line_width,
                    "pitch": r.pitch,
                    "x": float(x[ix]),
                    "y": float(y[iy]),
                    "effective_density": float(self.effective_density[iy, ix]),
                    "step_height": _finite(float(ev.step_height[iy, ix])),
                    "dishing": _finite(float(ev.dishing[iy, ix])),
                    "erosion": _finite(float(ev.erosion[iy, ix])),
                    "time_to_planarize": _finite(float(ev.t_planar[iy, ix])),
                    "time_to_clear": _finite(float(ev.t_clear[iy, ix])) if ev.stack.metal else None,
                }
            )
        return out

    def scalars(self, hotspot_count: int | None = None) -> dict:
        """The die's scalars of :meth:`to_dict` (SI; null where not reached or not applying): time, blanket_rate,
        time_to_planarize, time_to_clear, step_height_max, dishing_max, erosion_max, thickness_range, hotspot_count
        (counted against :attr:`spec` unless given) without the list of hotspots."""
        ev = self.evolution
        return {
            "time": self.time,
            "blanket_rate": self.blanket_rate,
            "time_to_planarize": _finite(self.time_to_planarize),
            "time_to_clear": _finite(self.time_to_clear) if ev.stack.metal else None,
            "step_height_max": _finite(float(np.nanmax(ev.step_height))) if np.isfinite(ev.step_height).any() else None,
            "dishing_max": _max(ev.dishing),
            "erosion_max": _max(ev.erosion),
            "thickness_range": self.thickness_range,
            "hotspot_count": self.hotspot_count() if hotspot_count is None else int(hotspot_count),
        }

    def to_dict(self) -> dict:
        """The object of ``cmpsim die --json`` (SI units; null where a quantity does not apply or was not reached)."""
        from .hotspots import public

        hot = self.hotspots() if self.spec else []
        out = {
            "layout": self.layout.name,
            "process": self.process.kind,
            "time": self.time,
            "blanket_rate": self.blanket_rate,
            "planarization_length": self.planarization_length,
            "planarization_length_from_pad": self.planarization_length_from_pad,
            "weighting": self.weighting,
            "weighting_definition": WEIGHTING_DEFINITIONS.get(self.weighting, ""),
            "planarization_length_gaussian_from_pad": self.conventions.get("gaussian"),
            "planarization_length_elliptic_from_pad": self.conventions.get("elliptic"),
            "elliptic_truncation": self.conventions.get("elliptic_truncation"),
            "feature_contact": self.feature_contact,
            "film": self.evolution.stack.film,
            **self.scalars(hotspot_count=len(hot)),
            "spec": dict(self.spec),
            "hotspots": public(hot),
            "inputs": self.process.to_dict(),
            "units": dict(_UNITS),
        }
        lay = self.layout
        if lay.windowed:
            ny, nx = lay.shape
            out["windows"] = {"nx": nx, "ny": ny, "window": lay.cell_size, "origin": list(lay.origin), "bbox": list(lay.bbox),
                              "layers": [f"{a}/{b}" for a, b in lay.layers], "top": lay.name}
        else:
            out["regions"] = self.regions()
        if self.fill is not None:
            out["fill"] = dict(self.fill)
            out["units"]["added_area"] = "m^2"
        if self.uncertainty is not None:
            out["uncertainty"] = self.uncertainty.to_dict()
            out["units"].update(interval="m", probability="1")
            risk = self.at_risk() if self.spec else []
            out["at_risk"] = public(risk)  # under their limit, but their 95 % interval reaches it
            out["at_risk_count"] = len(risk)
        return out

    def dataset(self):
        """The die maps as an ``xarray.Dataset`` on x, y (m) with CF attributes (units, long_name)."""
        ev = self.evolution
        x, y = self.layout.coordinates()
        finite = {"time_to_planarize": ev.t_planar, "time_to_clear": ev.t_clear}
        maps = {"density": self.layout.density, "effective_density": self.effective_density, "line_width": self.layout.widths(),
                "space": self.layout.spaces(), "upper_height": ev.upper_height, "lower_height": ev.lower_height, "mean_height": ev.mean_height,
                "thickness": ev.thickness, "step_height": ev.step_height,
                "dishing": ev.dishing, "erosion": ev.erosion, **{k: np.where(np.isfinite(v), v, np.nan) for k, v in finite.items()}}
        where = "window centre, layout coordinates" if self.layout.windowed else "position on the die"
        coords = {"x": ("x", x, {"units": "m", "long_name": where, "axis": "X"}),
                  "y": ("y", y, {"units": "m", "long_name": where, "axis": "Y"})}
        scalars = {"time": self.time, "blanket_rate": self.blanket_rate, "planarization_length": self.planarization_length,
                   "planarization_length_from_pad": self.planarization_length_from_pad,
                   **{f"planarization_length_{k}_from_pad": self.conventions[k] for k in ("gaussian", "elliptic") if k in self.conventions}}
        scalars["thickness_range"] = self.thickness_range
        ds = _cf_dataset(("y", "x"), maps, MAP_OUTPUTS, scalars, coords, f"cmpsim die: {self.layout.name}, {self.process.kind}")
        if self.fill is not None:
            ds.attrs["fill"] = ("the maps are those of the die with the model-based fill added (cmpsim die --fill); "
                                f"thickness range {self.fill['before']['thickness_range']:.6g} m drawn, "
                                f"{self.fill['after']['thickness_range']:.6g} m filled; added area {self.fill['added_area']:.6g} m^2")
        if self.layout.windowed:
            ds.attrs["layers"] = ", ".join(f"{a}/{b}" for a, b in self.layout.layers)
            ds.attrs["window"] = f"{self.layout.cell_size:g} m"
        ds.attrs["references"] = "Stine et al., IEEE TSM 11, 129 (1998); Ouma et al., IEEE TSM 15, 232 (2002); docs/model.md section 18"
        return ds

    def plot(self):
        """Maps: layout density, effective density, final mean surface height, step height or dishing. A matplotlib Figure."""
        import matplotlib.pyplot as plt

        ev = self.evolution
        lay = self.layout
        ny, nx = lay.shape
        ext = [lay.origin[0], lay.origin[0] + nx * lay.cell_size, lay.origin[1], lay.origin[1] + ny * lay.cell_size]
        ext = [v * 1e3 for v in ext]
        last = ("dishing", ev.dishing) if ev.stack.metal else ("step height", ev.step_height)
        panels = [("local density", lay.density, "1", None), ("effective density", self.effective_density, "1", None),
                  ("mean surface height", ev.mean_height * 1e9, "nm", "thickness"), (last[0], last[1] * 1e9, "nm", last[0].replace(" ", "_"))]
        if ev.stack.metal:
            panels.append(("erosion", ev.erosion * 1e9, "nm", "erosion"))
        hot = self.hotspots() if self.spec else []
        cols = 3 if len(panels) > 4 else 2
        fig, axes = plt.subplots(2, cols, figsize=(5 * cols, 8.4), layout="constrained")
        for ax in axes.flat[len(panels):]:
            ax.set_visible(False)
        for ax, (title, data, unit, kind) in zip(axes.flat, panels):
            im = ax.imshow(data, origin="lower", extent=ext, cmap="viridis", interpolation="nearest")
            ax.set_title(title, fontsize=10)
            ax.set_xlabel("x (mm)")
            ax.set_ylabel("y (mm)")
            fig.colorbar(im, ax=ax, label=f"{title} ({unit})")
            mark = [h for h in hot if h["kind"] == kind] if kind else []
            if kind == "thickness":  # the final surface carries the hotspots of every kind
                mark = hot
            if mark:
                ax.plot([h["x"] * 1e3 for h in mark], [h["y"] * 1e3 for h in mark], "s", mfc="none", mec="red", ms=4, mew=0.8,
                        label=f"{len(mark)} hotspots")
                ax.legend(loc="upper right", fontsize=7)
        fig.suptitle(f"die {self.layout.name!r}{' with model-based fill' if self.fill is not None else ''}, {self.process.kind}, t = {self.time:.0f} s, K = {self.blanket_rate * 6e10:.0f} nm/min, "
                     f"PL = {self.planarization_length * 1e3:.2f} mm")
        return fig


def _cf_dataset(dims, arrays, table, scalars, coords, title):
    """An xarray Dataset of arrays on ``dims`` and 0-d scalars, with ``units`` and ``long_name`` from ``table`` or :data:`SCALAR_OUTPUTS`."""
    import xarray as xr

    from .._version import __version__

    def attrs(name):
        unit, long = table.get(name) or SCALAR_OUTPUTS[name]
        return {"units": unit, "long_name": long}

    ds = xr.Dataset({k: (dims, np.asarray(v, dtype=float), attrs(k)) for k, v in arrays.items()}, coords=coords)
    for k, v in scalars.items():
        ds[k] = ((), float(v), attrs(k))
    ds.attrs.update(Conventions="CF-1.11", title=title, source=f"cmpsim {__version__}")
    return ds


def _max(a):
    return float(np.nanmax(a)) if np.isfinite(a).any() else None


#: The die maps of :meth:`DieResult.dataset`: name -> (SI unit, long name).
MAP_OUTPUTS = {
    "density": ("1", "local pattern density (area fraction of the lines)"),
    "effective_density": ("1", "effective pattern density seen by the pad"),
    "line_width": ("m", "line width"),
    "upper_height": ("m", "height of level A (oxide: over the lines; copper: the field) above the original field oxide top"),
    "lower_height": ("m", "height of level B (oxide: over the spaces; copper: the lines) above the original field oxide top"),
    "mean_height": ("m", "area-weighted mean surface height of the cell"),
    "step_height": ("m", "step height between the two levels"),
    "dishing": ("m", "copper dishing: depth of the line below the cleared field"),
    "erosion": ("m", "field oxide lost below its original top"),
    "time_to_planarize": ("s", "time at which the cell's step fell below the planarity threshold"),
    "time_to_clear": ("s", "time at which the cell cleared (copper: barrier off the field)"),
    "space": ("m", "line space"),
    "thickness": ("m", "final mean surface height of the cell off the die's mean"),
}
#: The scalars of a die run: name -> (SI unit, long name).
SCALAR_OUTPUTS = {
    "time": ("s", "polishing time"),
    "blanket_rate": ("m s-1", "blanket removal rate of the die"),
    "planarization_length": ("m", "planarization length used"),
    "planarization_length_from_pad": ("m", "planarization length derived from the pad stack, in the convention of the weighting used"),
    "planarization_length_gaussian_from_pad": ("m", "planarization length derived from the pad stack, Gaussian convention (peak and integral of a square window of side L)"),
    "planarization_length_elliptic_from_pad": ("m", "planarization length derived from the pad stack, Ouma's elliptic convention (L = 2a, the weight at 2/pi of its peak)"),
    "thickness_range": ("m", "max - min of the final mean surface height over the die"),
}
#: What L means in each weighting (the JSON's ``weighting_definition``).
WEIGHTING_DEFINITIONS = {
    "gaussian": "w(r) = exp(-pi r^2 / L^2) / L^2: the peak and the integral of Stine's square window of side L",
    "pad": "w = the pad stack's normalised compliance C(q) / C(0); L quoted in the Gaussian convention",
    "elliptic": "Ouma's elliptic weighting: the deflection of an elastic half-space under a uniform disc of radius a = L / 2 "
                "(the weight at r = L/2 is 2/pi of its peak), cut at r = elliptic_truncation x a, unit integral",
}
#: The per-die outputs of :meth:`WaferDies.dataset`: name -> (SI unit, long name).
WAFER_OUTPUTS = {
    "x": ("m", "die centre, x"),
    "y": ("m", "die centre, y"),
    "blanket_rate": ("m s-1", "rotation-averaged blanket removal rate at the die centre"),
    "time_to_clear": ("s", "time to clear the die (copper: barrier off every field; oxide: planarized)"),
    "time_to_planarize": ("s", "time by which every cell of the die planarized"),
    "dishing_max": ("m", "largest copper dishing on the die"),
    "erosion_max": ("m", "largest oxide erosion on the die"),
    "step_height_max": ("m", "largest step height on the die"),
    "thickness_range": ("m", "max - min of the die's final mean surface height"),
    "hotspot_count": ("1", "number of hotspots on the die (windows x quantities over their limits)"),
}

#: The unit of every key of the JSON of a die run (``"units"`` of :meth:`DieResult.to_dict`).
_UNITS = {k: unit for table in (MAP_OUTPUTS, SCALAR_OUTPUTS, WAFER_OUTPUTS) for k, (unit, _) in table.items()} | {"pitch": "m", "wafer_diameter": "m", "elliptic_truncation": "1", "hotspots": "m", "spec": "m", "window": "m",
                                                                                            "origin": "m", "bbox": "m", "hotspot_count": "1"}


def _end_point(ev: DieEvolution) -> float:
    """Polish until every cell has planarized (oxide) or cleared (copper); return that time (s)."""
    chunk = max(ev.stack.end_depth() / ev.rate, 1e-9) * 0.25
    for _ in range(400):
        if np.all(np.isfinite(ev.t_clear)):
            return float(ev.t_clear.max())
        ev.advance_to(ev.t + chunk)
        chunk *= 1.2
    raise ValueError("the die did not reach its end point within 400 polishing steps: check the inputs (contact_height, selectivities)")


def _at(ev: DieEvolution, time: float, fresh) -> DieEvolution:
    """``ev`` advanced to ``time``; a ``fresh()`` one if ``ev`` is already past it, with the event times of ``ev``."""
    if time >= ev.t:
        ev.advance_to(time)
        return ev
    new = fresh()
    new.advance_to(time)
    new.t_planar, new.t_copper_clear, new.t_clear = ev.t_planar.copy(), ev.t_copper_clear.copy(), ev.t_clear.copy()
    return new


def _prepare(layout, config, process, planarization_length, weighting, cell_size, feature_contact="elastic", **process_values):
    config = _config(config)
    layout = load_layout(layout, cell_size)
    if process is None or isinstance(process, str):
        process = DieProcess.from_values(process or "oxide", **process_values)
    elif process_values:
        raise ValueError("give the die inputs either as a DieProcess or as keywords, not both")
    film = film_stack(process).film  # the wafer solve polishes the film of the process
    if getattr(config, "film", film) != film:
        config = config.replace(film=film)
    w, derived = _weighting(config, planarization_length, weighting)
    eff = effective_density(layout.density, layout.cell_size, w)
    return config, layout, process, w, derived, eff, _feature(config, feature_contact)


def simulate(layout, time: float | None = None, *, config=None, blanket_rate: float | None = None, process=None,
             planarization_length: float | None = None, weighting: str = "gaussian", cell_size: float | None = None,
             feature_contact: str = "elastic", incoming=None, spec=None, uncertainty=None, **process_values) -> DieResult:
    """Polish one die (docs/model.md, section 18).

    Parameters
    ----------
    layout : Layout, str or path
        A :class:`Layout`, the name of a built-in die (:data:`BUILTIN_LAYOUTS`) or a layout CSV.
    time : float, optional
        Polishing time (s). Default: the end point (every cell planarized, oxide; cleared, copper)
        times 1 + ``over_polish``.
    config : cmpsim.Config, optional
        The wafer-scale inputs (default :meth:`Config.default`): the pad stack gives the
        planarization length and the summit radius; solved once for the blanket rate.
    blanket_rate : float, optional
        Blanket removal rate (m/s); default the wafer-mean removal rate of ``cmpsim.solve(config)``.
    process : DieProcess or "oxide" / "copper"
        The film stack; keywords (``step_height="0.8 um"``, ...) set its inputs with units.
    planarization_length : float, optional
        Override the length (m) derived from the pad stack.
    weighting : "gaussian", "pad" or "elliptic"
        The weighting function of the effective density (:mod:`cmpsim.die.density`); the
        planarization length (given or derived) is in that weighting's convention.
    cell_size : float, optional
        Cell size (m) of a built-in die (default 50 um).
    feature_contact : "elastic" or "summit"
        The contact height of a gap: the summit sagitta plus the pad body's elastic bulge into
        it (default, :mod:`cmpsim.die.reach`), or the summit sagitta alone (cmpsim 0.3).
    incoming : (height, step), optional
        The topography a level below left on every cell (m; :meth:`DieEvolution.topography`).
    spec : dict, optional
        Hotspot limits, kind -> m or text with units (:mod:`cmpsim.die.hotspots`).
    uncertainty : cmpsim.die.uncertainty.DieUncertainty, optional
        A calibration's constants and covariance (:meth:`cmpsim.calibration.die.DieCalibration.uncertainty`):
        the run uses the fitted constants, and every hotspot gets its 95 % ``interval`` and the
        ``probability`` that it exceeds its limit (linearisation, :mod:`cmpsim.die.uncertainty`).
    """
    from .hotspots import parse_spec

    spec = parse_spec(spec)
    process, planarization_length, process_values = _fitted(uncertainty, process, planarization_length, process_values)
    config, layout, process, w, derived, eff, fc = _prepare(layout, config, process, planarization_length, weighting, cell_size,
                                                            feature_contact, **process_values)
    if blanket_rate is None:
        from ..solver.model import solve

        blanket_rate = float(solve(config, relative=False).removal_rate_mean)
    if time is not None and not (math.isfinite(time) and time >= 0):
        raise ValueError(f"time must be >= 0 s; got {time!r}")
    result = _polish(layout, process, config, float(blanket_rate), time, eff, fc, incoming,
                     DieResult(layout, process, 0.0, float(blanket_rate), w.length, derived, weighting, eff, None, _conventions(config),
                               feature_contact, spec))
    return _with_sigma(result, config, fc, incoming, uncertainty)


def _fitted(uncertainty, process, planarization_length, process_values):
    """(process, planarization length, process keywords) with a calibration's fitted constants over them."""
    if uncertainty is None:
        return process, planarization_length, process_values
    fitted = dict(zip(uncertainty.names, uncertainty.values))
    if "planarization_length" in fitted:
        planarization_length = fitted.pop("planarization_length")
    if isinstance(process, DieProcess):
        return process.replace(**fitted), planarization_length, process_values
    return process, planarization_length, {**process_values, **fitted}


def _with_sigma(result: DieResult, config, fc, incoming, uncertainty) -> DieResult:
    """``result`` with the standard deviation of every field with a limit (:func:`cmpsim.die.uncertainty.window_sigma`), or as it is."""
    if uncertainty is None:
        return result
    from dataclasses import replace as _replace

    from .uncertainty import window_sigma

    layout, weighting = result.layout, result.weighting
    if weighting == "pad" and "planarization_length" in uncertainty.names:
        raise ValueError("weighting = 'pad' takes its length from the pad stack: a calibrated planarization_length needs 'gaussian' or 'elliptic'")

    def evaluate(values: dict) -> dict:
        values = dict(values)
        length = values.pop("planarization_length", result.planarization_length)
        wt, _ = _weighting(config, None if weighting == "pad" else length, weighting)
        e = effective_density(layout.density, layout.cell_size, wt)
        ev = DieEvolution(layout, result.process.replace(**values), e, result.blanket_rate, config.asperity_radius, fc, incoming)
        ev.advance_to(result.time)
        return {"thickness": ev.thickness, "step_height": ev.step_height, "dishing": ev.dishing, "erosion": ev.erosion}

    return _replace(result, uncertainty=uncertainty, sigma=window_sigma(evaluate, uncertainty))


def _polish(layout, process, config, blanket_rate, time, eff, fc, incoming, template: DieResult) -> DieResult:
    """Evolve the die to ``time`` (default the end point x (1 + over_polish)); the result is ``template`` with the evolution and time set."""
    from dataclasses import replace

    ev = DieEvolution(layout, process, eff, blanket_rate, config.asperity_radius, fc, incoming)
    start = ev.copy()  # the conditioned start (the pad's bulge into every gap is computed once)
    t_end = _end_point(ev)  # also gives every cell's event times, reached or not by `time`
    if time is None:
        time = t_end * (1.0 + process.over_polish)
    ev = _at(ev, float(time), start.copy)
    return replace(template, time=float(time), evolution=ev)


# ------------------------------------------------------------------------------ the wafer
