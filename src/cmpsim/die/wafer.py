"""A wafer of dies: every die site of a wafer polished at the blanket rate the wafer solve gives
there (one reference die polished once, each die read at its own time), with the wafer maps of the
dies' results and hotspot counts. Split from :mod:`cmpsim.die.polish` (one die), which it uses.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np

from .evolution import DieEvolution
from .stacks import film_stack
from .process import DieProcess
from .polish import DieResult, WAFER_OUTPUTS, _at, _cf_dataset, _conventions, _end_point, _finite, _fitted, _max, _prepare, _weighting, _with_sigma

__all__ = ["die_sites", "blanket_rates", "WaferDies", "WAFER_EXACT_DIES", "simulate_wafer"]


def die_sites(die_size: tuple[float, float], wafer_diameter: float, edge_exclusion: float) -> tuple[np.ndarray, np.ndarray]:
    """Centres (x, y) (m) of the whole dies on a wafer: a grid with a die corner at the wafer centre,
    keeping the dies whose four corners lie within wafer radius - edge_exclusion."""
    wx, wy = die_size
    limit = 0.5 * wafer_diameter - edge_exclusion
    if limit <= 0:
        raise ValueError(f"edge_exclusion = {edge_exclusion:g} m leaves no wafer (radius {0.5 * wafer_diameter:g} m)")
    nx, ny = int(limit // wx) + 1, int(limit // wy) + 1
    cx = (np.arange(-nx, nx) + 0.5) * wx
    cy = (np.arange(-ny, ny) + 0.5) * wy
    X, Y = np.meshgrid(cx, cy)
    far = np.hypot(np.abs(X) + 0.5 * wx, np.abs(Y) + 0.5 * wy)
    keep = far <= limit * (1 + 1e-12)
    if not keep.any():
        raise ValueError(f"no {wx * 1e3:g} x {wy * 1e3:g} mm die fits inside {limit * 1e3:g} mm of the wafer centre")
    return X[keep], Y[keep]


def blanket_rates(result, x, y) -> np.ndarray:
    """The rotation-averaged removal rate of a wafer solve at the points (x, y) (m/s): its
    ``removal_rate_profile`` interpolated linearly in radius (constant inside the first and beyond the last ring centre)."""
    r = np.hypot(np.asarray(x, dtype=float), np.asarray(y, dtype=float))
    return np.interp(r, np.asarray(result.radius), np.asarray(result.removal_rate_profile))


@dataclass
class WaferDies:
    """Every die of a wafer after ``time`` (s): one wafer solve, one die evolution read at each die's equivalent time."""

    die: DieResult  # the reference die at the end time at the reference rate
    result: object = field(repr=False)  # the wafer solve (cmpsim.Result)
    time: float = 0.0
    x: np.ndarray = field(default=None, repr=False)
    y: np.ndarray = field(default=None, repr=False)
    blanket_rate: np.ndarray = field(default=None, repr=False)
    time_to_clear: np.ndarray = field(default=None, repr=False)
    time_to_planarize: np.ndarray = field(default=None, repr=False)
    dishing_max: np.ndarray = field(default=None, repr=False)
    erosion_max: np.ndarray = field(default=None, repr=False)
    step_height_max: np.ndarray = field(default=None, repr=False)
    thickness_range: np.ndarray = field(default=None, repr=False)
    hotspot_count: np.ndarray = field(default=None, repr=False)
    #: how the dies were read: "exact" (each at its own equivalent time) or "sampled" (interpolated between sampled times)
    reading: str = "exact"
    #: a calibrated run (``uncertainty=``): per die the expected number of hotspots, those that fail for sure and the
    #: windows at risk (:func:`cmpsim.die.hotspots.risk_counts`); None otherwise
    hotspot_expected: np.ndarray | None = field(default=None, repr=False)
    hotspot_sure: np.ndarray | None = field(default=None, repr=False)
    at_risk_count: np.ndarray | None = field(default=None, repr=False)

    def to_dict(self) -> dict:
        """The object of ``cmpsim die --wafer --json``: the die at the reference rate plus the list ``dies``."""
        out = self.die.to_dict()
        out["time"] = self.time
        out["wafer_diameter"] = float(self.result.config.wafer_diameter)
        out["die_reading"] = self.reading
        out["dies"] = [
            {"x": float(a), "y": float(b), "blanket_rate": float(k), "time_to_clear": _finite(float(tc)),
             "time_to_planarize": _finite(float(tp)), "dishing_max": _finite(float(d)), "erosion_max": _finite(float(e)),
             "step_height_max": _finite(float(s)), "thickness_range": _finite(float(r)), "hotspot_count": int(n)}
            for a, b, k, tc, tp, d, e, s, r, n in zip(self.x, self.y, self.blanket_rate, self.time_to_clear, self.time_to_planarize,
                                                       self.dishing_max, self.erosion_max, self.step_height_max, self.thickness_range,
                                                       self.hotspot_count)
        ]
        out["wafer_hotspot_count"] = int(np.sum(self.hotspot_count))
        if self.hotspot_expected is not None:
            for d, e, s, r in zip(out["dies"], self.hotspot_expected, self.hotspot_sure, self.at_risk_count):
                d.update(hotspot_expected=float(e), hotspot_sure=int(s), at_risk_count=int(r))
            out["wafer_hotspot_expected"] = float(np.sum(self.hotspot_expected))
            out["units"].update({k: u for k, (u, _) in WAFER_RISK_OUTPUTS.items()})
        return out

    def dataset(self):
        """The dies as an ``xarray.Dataset`` on the ``die`` dimension (CF attributes)."""
        table = dict(WAFER_OUTPUTS) | (WAFER_RISK_OUTPUTS if self.hotspot_expected is not None else {})
        vars_ = {name: getattr(self, name) for name in table}
        return _cf_dataset(("die",), vars_, table, {"time": self.time}, {},
                           f"cmpsim die --wafer: {self.die.layout.name}, {self.die.process.kind}")

    def plot(self):
        """Wafer maps per die: dishing, erosion and time to clear (copper); step height and time to planarize (oxide). A matplotlib Figure."""
        import matplotlib.pyplot as plt
        from matplotlib.collections import PatchCollection
        from matplotlib.patches import Circle, Rectangle

        wx, wy = self.die.layout.size
        radius = 0.5 * self.result.config.wafer_diameter * 1e3
        if self.die.evolution.stack.metal:
            panels = [("dishing_max", self.dishing_max, "nm", 1e9), ("erosion_max", self.erosion_max, "nm", 1e9), ("time_to_clear", self.time_to_clear, "s", 1.0)]
        else:  # oxide: no dishing or erosion; its end point is planarity
            panels = [("step_height_max", self.step_height_max, "nm", 1e9), ("time_to_planarize", self.time_to_planarize, "s", 1.0)]
        if self.die.spec:
            panels.append(("hotspot_count", self.hotspot_count, "1", 1.0))
        elif self.die.layout.windowed:
            panels.append(("thickness_range", self.thickness_range, "nm", 1e9))
        fig, axes = plt.subplots(1, len(panels), figsize=(5 * len(panels), 4.8), layout="constrained")
        for ax, (name, values, unit, scale) in zip(axes, panels):
            lw = 0.3 if len(self.x) < 2000 else 0.0
            rects = [Rectangle(((a - 0.5 * wx) * 1e3, (b - 0.5 * wy) * 1e3), wx * 1e3, wy * 1e3) for a, b in zip(self.x, self.y)]
            pc = PatchCollection(rects, cmap="magma_r" if name == "hotspot_count" else "viridis", edgecolor="white", linewidth=lw)
            vals = np.asarray(values, dtype=float) * scale
            pc.set_array(np.where(np.isfinite(vals), vals, np.nan))
            ax.add_collection(pc)
            ax.add_patch(Circle((0, 0), radius, fill=False, color="k", lw=1))
            ax.set_xlim(-radius * 1.02, radius * 1.02)
            ax.set_ylim(-radius * 1.02, radius * 1.02)
            ax.set_aspect("equal")
            ax.set_title(name.replace("_", " "), fontsize=10)
            ax.set_xlabel("x (mm)")
            ax.set_ylabel("y (mm)")
            fig.colorbar(pc, ax=ax, label=f"{name.replace('_', ' ')} ({unit})")
        fig.suptitle(f"{len(self.x)} dies {self.die.layout.name!r}, {self.die.process.kind}, t = {self.time:.0f} s")
        return fig


#: The per-die outputs of a calibrated wafer (:class:`WaferDies`), name -> (unit, long name).
WAFER_RISK_OUTPUTS = {
    "hotspot_expected": ("1", "expected number of hotspots on the die (sum of every window's probability of exceeding its limit)"),
    "hotspot_sure": ("1", "hotspots on the die that fail for sure (probability > 0.975)"),
    "at_risk_count": ("1", "windows under their limit whose 95 % interval reaches it"),
}

#: Up to this many dies, each die is read at its own equivalent time; beyond, at this many equally spaced times, interpolated.
WAFER_EXACT_DIES = 400


def simulate_wafer(layout, time: float | None = None, *, config=None, result=None, process=None, planarization_length: float | None = None,
                   weighting: str = "gaussian", cell_size: float | None = None, feature_contact: str = "elastic", spec=None,
                   uncertainty=None, **process_values) -> WaferDies:
    """Polish every die of a wafer (docs/model.md, section 18.7).

    One wafer solve (``result``, or ``cmpsim.solve(config)``) gives the blanket rate at each die
    centre (:func:`blanket_rates`); the dies tile the wafer inside its ``edge_exclusion``
    (:func:`die_sites`, die size = layout size). ``time`` (s) defaults to the end point of the
    slowest die times 1 + ``over_polish``. ``spec`` (hotspot limits) gives each die's
    ``hotspot_count``. Up to :data:`WAFER_EXACT_DIES` dies each is read at its own equivalent
    time; a wafer of more (small dies) is read at that many equally spaced equivalent times and
    each die's values interpolated linearly between them (``reading = "sampled"``; hotspot counts
    rounded). ``uncertainty`` (a calibration's :class:`cmpsim.die.uncertainty.DieUncertainty`) applies
    its constants and gives every die ``hotspot_expected``, ``hotspot_sure`` and ``at_risk_count``
    (:func:`cmpsim.die.hotspots.risk_counts`; 2p more die evolutions run in step with the reference
    die, p the constants) and the reference die's hotspots their intervals. Other arguments as :func:`simulate`.
    """
    from .hotspots import parse_spec

    spec = parse_spec(spec)
    if result is not None and config is not None and config.to_dict() != result.config.to_dict():
        raise ValueError("give config or the result of its solve, not a result of other inputs: the dies take the pad and the wafer from result.config")
    if result is not None:
        kind = process.kind if isinstance(process, DieProcess) else (process or "oxide")
        want = film_stack(DieProcess(kind=kind)).film
        if getattr(result.config, "film", want) != want:
            raise ValueError(f"the {kind} process needs the blanket rate of film = {want!r}; the result was solved for film = {result.config.film!r}")
    process, planarization_length, process_values = _fitted(uncertainty, process, planarization_length, process_values)
    config, layout, process, w, derived, eff, fc = _prepare(layout, config if result is None else result.config, process,
                                                            planarization_length, weighting, cell_size, feature_contact, **process_values)
    if result is None:
        from ..solver.model import solve

        result = solve(config, relative=False)
    x, y = die_sites(layout.size, config.wafer_diameter, config.edge_exclusion)
    k = blanket_rates(result, x, y)
    if not np.all(k > 0):
        raise ValueError("the wafer solve removes nothing at some die sites: no blanket rate to polish them")
    k_ref = float(np.max(k))
    if time is not None and not (math.isfinite(time) and time >= 0):
        raise ValueError(f"time must be >= 0 s; got {time!r}")
    ev = DieEvolution(layout, process, eff, k_ref, config.asperity_radius, fc)
    t_end_ref = _end_point(ev)  # the reference (fastest) die's end point, and its event times
    if time is None:
        time = t_end_ref * k_ref / float(np.min(k)) * (1.0 + process.over_polish)
    t_equiv = time * k / k_ref  # each die's time at the reference rate
    order = np.argsort(t_equiv)
    ev = _at(ev, float(t_equiv[order[0]]), lambda: DieEvolution(layout, process, eff, k_ref, config.asperity_radius, fc))
    n = len(x)
    reading = "exact" if n <= WAFER_EXACT_DIES else "sampled"
    times = t_equiv[order] if reading == "exact" else np.linspace(t_equiv[order[0]], t_equiv[order[-1]], WAFER_EXACT_DIES)
    probe = DieResult(layout, process, float(ev.t), k_ref, w.length, derived, weighting, eff, ev, {}, feature_contact, spec)
    twins = _twins(uncertainty, layout, process, config, weighting, w.length, k_ref, fc) if uncertainty is not None and spec else None
    columns = 5 if twins is None else 8
    vals = np.empty((len(times), columns))
    for j, t in enumerate(times):
        ev.advance_to(float(t))
        vals[j, :3] = [np.nan if v is None else v for v in (_max(ev.dishing), _max(ev.erosion), _max(ev.step_height))]
        vals[j, 3] = probe.thickness_range
        vals[j, 4] = probe.hotspot_count()
        if twins is not None:
            vals[j, 5:] = _risk(probe, twins, float(t), uncertainty)
    if reading == "exact":
        per_die = np.empty((n, columns))
        per_die[order] = vals
    else:
        per_die = np.stack([np.interp(t_equiv, times, vals[:, c]) for c in range(columns)], axis=1)
        per_die[:, 4] = np.rint(per_die[:, 4])
        if twins is not None:
            per_die[:, 6:] = np.rint(per_die[:, 6:])
    dish, ero, step, trange, hot = (per_die[:, c] for c in range(5))
    # event times scale back with the rate; events after the reference die's last time are not known
    tc = ev.t_clear.max() * k_ref / k
    tp = ev.t_planar.max() * k_ref / k
    die = DieResult(layout, process, float(ev.t), k_ref, w.length, derived, weighting, eff, ev, _conventions(config), feature_contact, spec)
    die = _with_sigma(die, config, fc, None, uncertainty)
    risk = (None, None, None) if twins is None else (per_die[:, 5], per_die[:, 6].astype(int), per_die[:, 7].astype(int))
    return WaferDies(die, result, float(time), x, y, k, tc, tp, dish, ero, step, trange, hot.astype(int), reading, *risk)


def _twins(uncertainty, layout, process, config, weighting, length, k_ref, fc):
    """The die evolutions of eq. U1's central differences, [(up, down, d), ...] (:func:`cmpsim.die.uncertainty.perturbations`),
    each from a fresh die at the reference rate, to be advanced in step with the reference die."""
    from .density import effective_density
    from .uncertainty import perturbations

    if weighting == "pad" and "planarization_length" in uncertainty.names:
        raise ValueError("weighting = 'pad' takes its length from the pad stack: a calibrated planarization_length needs 'gaussian' or 'elliptic'")

    def evolution(values):
        values = dict(values)
        wt, _ = _weighting(config, None if weighting == "pad" else values.pop("planarization_length", length), weighting)
        return DieEvolution(layout, process.replace(**values), effective_density(layout.density, layout.cell_size, wt), k_ref,
                            config.asperity_radius, fc)

    return [(evolution(up), evolution(dn), d) for up, dn, d in perturbations(uncertainty)]


def _risk(probe: DieResult, twins, t: float, uncertainty) -> tuple[float, int, int]:
    """(expected hotspots, sure, at risk) of the reference die ``probe`` at time ``t`` (s), the twins advanced to it."""
    from .hotspots import risk_counts
    from .uncertainty import sigma_from_differences

    def fields(ev):
        ev.advance_to(t)
        return {"thickness": ev.thickness, "step_height": ev.step_height, "dishing": ev.dishing, "erosion": ev.erosion}

    sigma = sigma_from_differences([(fields(up), fields(dn), d) for up, dn, d in twins], uncertainty)
    x, y = probe.layout.coordinates()
    return risk_counts(probe.fields(), sigma, x, y, probe.layout.cell_size, probe.layout.extent, probe.spec)
