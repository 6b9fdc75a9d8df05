"""The paper's parameter study: its curves, its figures, and the equilibria behind them.

Curves (the paper's section 3): load 2-6 psi at 60 rpm, speed 30-90 rpm at 4 psi, every
other input from :meth:`Config.default` (or the ``config`` given). Identical operating points
are solved once and shared between figures; each curve is warm-started point by point.
"""

from __future__ import annotations

import time
from dataclasses import dataclass
from typing import Any

import numpy as np

from ..inputs import units
from ..inputs.config import Config
from ..solver.model import build_problem, reference_config
from ..solver.points import PointCache, Progress, config_key, predict_start

__all__ = ["CURVES", "FIGURES", "LOADS_PSI", "SPEEDS_RPM", "Curve", "FigureSpec", "Point", "RunData"]

#: Applied loads (psi) and rotation speeds (rpm) of the sweeps (the paper's Table 1 ranges).
LOADS_PSI = tuple(float(x) for x in np.linspace(2.0, 6.0, 9))
SPEEDS_RPM = tuple(float(x) for x in np.linspace(30.0, 90.0, 9))
BASE_LOAD_PSI = 4.0
BASE_SPEED_RPM = 60.0

@dataclass(frozen=True)
class Curve:
    key: str
    label: str  # legend text, as in the paper
    overrides: dict[str, str]


CURVES: dict[str, Curve] = {
    c.key: c
    for c in [
        Curve("hydro_s20", "σ = 20 μm (hydrodynamic)", {"model": "hydrodynamic", "particle_diameter": 100e-9, "pad_roughness": 20e-6}),
        Curve("lep_s15", "σ = 15 μm (LEP)", {"model": "lep", "particle_diameter": 100e-9, "pad_roughness": 15e-6}),
        Curve("hydro_s10", "σ = 10 μm (hydrodynamic)", {"model": "hydrodynamic", "particle_diameter": 100e-9, "pad_roughness": 10e-6}),
        Curve("d100", "d = 100 nm", {"model": "lep", "particle_diameter": 100e-9, "pad_roughness": 15e-6}),
        Curve("d200", "d = 200 nm", {"model": "lep", "particle_diameter": 200e-9, "pad_roughness": 15e-6}),
        Curve("a", "(a) d = 100 nm, σ = 15 μm", {"model": "lep", "particle_diameter": 100e-9, "pad_roughness": 15e-6}),
        Curve("b", "(b) d = 100 nm, σ = 20 μm", {"model": "lep", "particle_diameter": 100e-9, "pad_roughness": 20e-6}),
        Curve("c", "(c) d = 200 nm, σ = 20 μm", {"model": "lep", "particle_diameter": 200e-9, "pad_roughness": 20e-6}),
    ]
}


@dataclass(frozen=True)
class FigureSpec:
    number: int
    name: str
    title: str
    sweep: str  # "load" or "speed"
    curves: tuple[str, ...]
    panels: tuple[tuple[str, str, float, bool], ...]  # (output key, axis label, factor, log scale)


_H = ("film_thickness_center", "Film thickness at the wafer centre (μm)", 1e6, False)
_TH = ("attack_angle", "Attack angle (10⁻⁵ rad)", 1e5, False)
_AE = ("contact_area_ratio_elastic", "Elastic contact area ratio (-)", 1.0, False)
_AEP = ("contact_area_ratio_elastoplastic", "Elastoplastic contact area ratio (-)", 1.0, False)
_RR = ("removal_rate_relative", "Relative removal rate (-)", 1.0, False)

FIGURES: tuple[FigureSpec, ...] = (
    FigureSpec(3, "fig03_film_vs_load", "Film thickness vs applied load (d = 100 nm, 60 rpm)", "load", ("hydro_s20", "lep_s15", "hydro_s10"), (_H,)),
    FigureSpec(4, "fig04_film_vs_speed", "Film thickness vs rotation speed (d = 100 nm, 4 psi)", "speed", ("hydro_s20", "lep_s15", "hydro_s10"), (_H,)),
    FigureSpec(5, "fig05_film_angle_vs_load", "Film thickness and attack angle vs applied load (LEP, σ = 15 μm)", "load", ("d100", "d200"), (_H, _TH)),
    FigureSpec(6, "fig06_film_angle_vs_speed", "Film thickness and attack angle vs rotation speed (LEP, σ = 15 μm)", "speed", ("d100", "d200"), (_H, _TH)),
    FigureSpec(7, "fig07_elastic_area_vs_load", "Elastic contact area ratio vs applied load", "load", ("a", "b", "c"), (_AE,)),
    FigureSpec(8, "fig08_elastoplastic_area_vs_load", "Elastoplastic contact area ratio vs applied load", "load", ("a", "b", "c"), (_AEP,)),
    FigureSpec(9, "fig09_elastic_area_vs_speed", "Elastic contact area ratio vs rotation speed", "speed", ("a", "b", "c"), (_AE,)),
    FigureSpec(10, "fig10_elastoplastic_area_vs_speed", "Elastoplastic contact area ratio vs rotation speed", "speed", ("a", "b", "c"), (_AEP,)),
    FigureSpec(11, "fig11_removal_rate_vs_load", "Relative removal rate vs applied load (normalised to d = 100 nm, σ = 15 μm, 4 psi, 60 rpm)", "load", ("a", "b", "c"), (_RR,)),
    FigureSpec(12, "fig12_removal_rate_vs_speed", "Relative removal rate vs rotation speed (normalised to d = 100 nm, σ = 15 μm, 4 psi, 60 rpm)", "speed", ("a", "b", "c"), (_RR,)),
)

_UNITS = {"load": "psi", "speed": "rpm"}


# --------------------------------------------------------------------------- data of a run
@dataclass
class Point:
    """One operating point of a curve."""

    curve: str
    sweep: str
    x: float  # psi or rpm
    config: Config
    scalars: dict[str, Any] | None
    status: str

    @property
    def ok(self) -> bool:
        return self.scalars is not None

    def get(self, key: str) -> float:
        if self.scalars is None:
            return float("nan")
        if key == "film_thickness_ratio":
            return self.scalars["film_thickness_center"] / self.config.pad_roughness
        return float(self.scalars[key])


class RunData:
    """Curves of a run: ``data.curve("a", "load")`` -> list of :class:`Point` in sweep order."""

    def __init__(self):
        self.curves: dict[tuple[str, str], list[Point]] = {}

    def curve(self, key: str, sweep: str) -> list[Point]:
        return self.curves[(key, sweep)]

    def xy(self, key: str, sweep: str, output: str) -> tuple[np.ndarray, np.ndarray]:
        pts = self.curve(key, sweep)
        return np.array([p.x for p in pts]), np.array([p.get(output) for p in pts])

    def subset(self, spec: "FigureSpec") -> "RunData":
        """The curves of one figure only (what its plot needs; smaller to send to another process)."""
        out = RunData()
        out.curves = {(c, spec.sweep): self.curves[(c, spec.sweep)] for c in spec.curves if (c, spec.sweep) in self.curves}
        return out

    def at_base(self, key: str, output: str) -> float:
        for p in self.curve(key, "load"):
            if p.x == BASE_LOAD_PSI:
                return p.get(output)
        return float("nan")


# --------------------------------------------------------------------------- solving
def _plan(base: Config) -> list[tuple[str, str, float, Config]]:
    """Every (curve, sweep, x, config) needed, in solve order (along each curve); inputs in SI."""
    needed: list[tuple[str, str]] = []
    for f in FIGURES:
        for c in f.curves:
            if (c, f.sweep) not in needed:
                needed.append((c, f.sweep))
    plan = []
    for c, sweep in needed:
        cfg_c = base.replace(**CURVES[c].overrides)
        for x in LOADS_PSI if sweep == "load" else SPEEDS_RPM:
            load, speed = (x, BASE_SPEED_RPM) if sweep == "load" else (BASE_LOAD_PSI, x)
            cfg = cfg_c.replace(applied_pressure=units.convert(load, "psi", "Pa"), rotation_speed=units.convert(speed, "rpm", "rad/s"))
            plan.append((c, sweep, x, cfg))
    return plan


def _solve_all(base: Config, progress: bool, on_curve=None) -> tuple[RunData, int, int, list[str], float]:
    """Solve the plan, each distinct point once, warm-started along each curve.

    ``on_curve(data, (curve, sweep))``, if given, is called when a curve is complete (the
    figures of that curve can be drawn while the next ones are solved).

    The relative removal rate is normalised by this run's own solve of the reference case
    (:class:`cmpsim.solver.points.PointCache`), one of the planned points: exactly 1 there.
    """
    plan = _plan(base)
    total = len({config_key(cfg) for *_, cfg in plan} | {config_key(reference_config(cfg)) for *_, cfg in plan})
    data = RunData()
    failures: list[str] = []
    t0 = time.perf_counter()
    with Progress(progress, total, "reproduce") as bar:
        cache = PointCache(relative=True, advance=bar.advance)
        curve, prev, prev2 = None, None, None
        for c, sweep, x, cfg in plan:
            if (c, sweep) != curve:
                if curve is not None and on_curve is not None:
                    on_curve(data, curve)
                curve, prev, prev2 = (c, sweep), None, None
            # warm start predicted from the two previous points of the curve, as in a sweep chain
            # (also for a point the cache holds: its cold base serves the next prediction)
            try:
                problem = build_problem(cfg)
                start, cold = predict_start(cfg, problem, x, prev, prev2)
            except ValueError:
                problem, start, cold = None, None, None  # the solve reports the input error
            out = cache.solve(cfg, start, problem=problem)
            rec = {"status": "ok" if out.ok else "failed", "x": x, "cold_base": cold,
                   "u": out.result.solution.state.u if out.ok else None}
            prev2, prev = prev, rec
            if not out.ok:
                failures.append(f"{CURVES[c].label}, {x:g} {_UNITS[sweep]}: {out.error}")
            scalars = dict(out.result.scalars) if out.ok else None
            data.curves.setdefault((c, sweep), []).append(Point(c, sweep, x, cfg, scalars, "ok" if out.ok else out.error))
    if curve is not None and on_curve is not None:
        on_curve(data, curve)
    return data, len(cache), cache.factorizations, failures, time.perf_counter() - t0
