"""Reproduce the paper's parameter studies (Figs. 3-12) on the wafer solver: ``cmpsim reproduce``.

For every figure of section 3 of the paper this module solves the equilibria behind it
(warm-started along each curve, identical operating points solved once and shared between
figures), writes the figure as a PNG and the data behind it as a CSV, and evaluates every
qualitative statement the paper makes about the figures against the data of the run. The
verdicts (``reproduced`` = yes / no) are computed by the functions of :data:`STATEMENTS`,
never written by hand; ``REPORT.md`` and ``REPORT.html`` (figures inline) collect them with
the parameter set used.

Curves (the paper's section 3): load 2-6 psi at 60 rpm, speed 30-90 rpm at 4 psi, every
other input from :meth:`Config.default` (or the ``config`` given):

* Figs. 3-4: d = 100 nm; hydrodynamic only with sigma = 20 and 10 um; LEP with sigma = 15 um.
* Figs. 5-6: LEP, sigma = 15 um, d = 100 and 200 nm (film thickness and attack angle).
* Figs. 7-12: LEP, cases (a) d = 100 nm, sigma = 15 um; (b) 100 nm, 20 um; (c) 200 nm, 20 um.
"""

from __future__ import annotations

import base64
import csv
import html
import io
import math
import time
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any, Callable

import numpy as np

from . import __version__
from .config import Config

__all__ = [
    "reproduce",
    "ReproductionReport",
    "StatementResult",
    "Statement",
    "STATEMENTS",
    "FIGURES",
    "CURVES",
    "LOADS_PSI",
    "SPEEDS_RPM",
    "SLIGHT",
    "SIMILAR",
]

#: Applied loads (psi) and rotation speeds (rpm) of the sweeps (the paper's Table 1 ranges).
LOADS_PSI = tuple(float(x) for x in np.linspace(2.0, 6.0, 9))
SPEEDS_RPM = tuple(float(x) for x in np.linspace(30.0, 90.0, 9))
BASE_LOAD_PSI = 4.0
BASE_SPEED_RPM = 60.0
#: "slightly" / "lightly": the change across the whole studied range is smaller than this
#: fraction of the value at the base case (4 psi, 60 rpm).
SLIGHT = 0.5
#: "approximately the same": the largest of the compared values is at most this multiple of the smallest.
SIMILAR = 1.5

PSI = 6894.757293168361


@dataclass(frozen=True)
class Curve:
    key: str
    label: str  # legend text, as in the paper
    overrides: dict[str, str]


CURVES: dict[str, Curve] = {
    c.key: c
    for c in [
        Curve("hydro_s20", "σ = 20 μm (hydrodynamic)", {"model": "hydrodynamic", "particle_diameter": "100 nm", "pad_roughness": "20 um"}),
        Curve("lep_s15", "σ = 15 μm (LEP)", {"model": "lep", "particle_diameter": "100 nm", "pad_roughness": "15 um"}),
        Curve("hydro_s10", "σ = 10 μm (hydrodynamic)", {"model": "hydrodynamic", "particle_diameter": "100 nm", "pad_roughness": "10 um"}),
        Curve("d100", "d = 100 nm", {"model": "lep", "particle_diameter": "100 nm", "pad_roughness": "15 um"}),
        Curve("d200", "d = 200 nm", {"model": "lep", "particle_diameter": "200 nm", "pad_roughness": "15 um"}),
        Curve("a", "(a) d = 100 nm, σ = 15 μm", {"model": "lep", "particle_diameter": "100 nm", "pad_roughness": "15 um"}),
        Curve("b", "(b) d = 100 nm, σ = 20 μm", {"model": "lep", "particle_diameter": "100 nm", "pad_roughness": "20 um"}),
        Curve("c", "(c) d = 200 nm, σ = 20 μm", {"model": "lep", "particle_diameter": "200 nm", "pad_roughness": "20 um"}),
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


_H = ("film_thickness_center_m", "Film thickness at the wafer centre (μm)", 1e6, False)
_TH = ("attack_angle_rad", "Attack angle (10⁻⁵ rad)", 1e5, False)
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

#: Columns of every figure CSV (SI unless the name says otherwise).
CSV_COLUMNS = (
    "figure",
    "curve",
    "label",
    "model",
    "particle_diameter_nm",
    "pad_roughness_um",
    "applied_pressure_psi",
    "rotation_speed_rpm",
    "film_thickness_center_um",
    "film_thickness_ratio",
    "attack_angle_rad",
    "contact_area_ratio_elastic",
    "contact_area_ratio_elastoplastic",
    "contact_area_ratio_plastic",
    "fluid_load_fraction",
    "removal_rate_nm_per_min",
    "removal_rate_relative",
    "flow_factor_floored_fraction",
    "converged",
    "status",
)


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
        if key == "contact_area_ratio_total":
            s = self.scalars
            return s["contact_area_ratio_elastic"] + s["contact_area_ratio_elastoplastic"] + s["contact_area_ratio_plastic"]
        if key == "film_thickness_ratio":
            return self.scalars["film_thickness_center_m"] / self.config.pad_roughness
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

    def at_base(self, key: str, output: str) -> float:
        for p in self.curve(key, "load"):
            if p.x == BASE_LOAD_PSI:
                return p.get(output)
        return float("nan")


# --------------------------------------------------------------------------- statements
@dataclass(frozen=True)
class Statement:
    """A qualitative statement of the paper and the function that checks it on the data.

    ``check(data) -> (reproduced, evidence, why_not)``: the evidence quotes the numbers of the
    run, ``why_not`` the part that fails (empty when reproduced). ``hint`` is appended to
    ``why_not`` when the statement is not reproduced (a known reason, or empty).
    """

    id: str
    figure: str
    text: str
    criterion: str
    check: Callable[[RunData], tuple[bool, str]]
    hint: str = ""


@dataclass
class StatementResult:
    id: str
    figure: str
    text: str
    criterion: str
    reproduced: bool
    evidence: str
    why_not: str

    def as_row(self) -> list[str]:
        return [self.id, self.figure, self.text, self.criterion, "yes" if self.reproduced else "no", self.evidence, self.why_not]


_UNITS = {"load": "psi", "speed": "rpm"}
_SHORT = {
    "film_thickness_center_m": ("film", 1e6, "μm"),
    "attack_angle_rad": ("attack angle", 1.0, "rad"),
    "contact_area_ratio_elastic": ("elastic ratio", 1.0, ""),
    "contact_area_ratio_elastoplastic": ("elastoplastic ratio", 1.0, ""),
    "contact_area_ratio_total": ("total contact ratio", 1.0, ""),
    "removal_rate_relative": ("relative RR", 1.0, ""),
    "film_thickness_ratio": ("h/σ", 1.0, ""),
}
_CURVE_SHORT = {"hydro_s20": "hydro σ=20", "hydro_s10": "hydro σ=10", "lep_s15": "LEP σ=15", "d100": "d=100", "d200": "d=200", "a": "(a)", "b": "(b)", "c": "(c)"}


def _missing(data: RunData, curves, sweep) -> str:
    bad = [f"{_CURVE_SHORT[c]} at {p.x:g} {_UNITS[sweep]}" for c in curves for p in data.curve(c, sweep) if not p.ok]
    return ("no equilibrium: " + ", ".join(bad[:4]) + (" ..." if len(bad) > 4 else "")) if bad else ""


def _floored_note(data: RunData, curve: str, sweep: str) -> str:
    """Text saying that the curve lies where the flow factors were regularised (empty if not)."""
    fl = np.array([p.get("flow_factor_floored_fraction") for p in data.curve(curve, sweep) if p.ok])
    if fl.size == 0 or not np.any(fl > 0):
        return ""
    return f"; flow factors regularised on {100 * fl.min():.0f}-{100 * fl.max():.0f} % of faces: outside the validity of eq. 8"


def _fmt(v: float, factor: float = 1.0) -> str:
    return f"{v * factor:.4g}"


def monotone(curves: tuple[str, ...], sweep: str, output: str, increasing: bool) -> Callable[[RunData], tuple[bool, str]]:
    """Strictly monotone along the sweep for every curve."""

    def check(data: RunData):
        miss = _missing(data, curves, sweep)
        if miss:
            return False, miss, miss
        name, f, unit = _SHORT[output]
        parts, why, ok_all = [], [], True
        for c in curves:
            x, y = data.xy(c, sweep, output)
            d = np.diff(y)
            ok = bool(np.all(d > 0) if increasing else np.all(d < 0))
            ok_all &= ok
            parts.append(f"{_CURVE_SHORT[c]}: {_fmt(y[0], f)} → {_fmt(y[-1], f)}{(' ' + unit) if unit else ''}")
            if not ok:
                i = int(np.argmax(d <= 0) if increasing else np.argmax(d >= 0))
                why.append(
                    f"{_CURVE_SHORT[c]}: {name} {'falls' if increasing else 'rises'} between {x[i]:g} and {x[i + 1]:g} {_UNITS[sweep]} "
                    f"({_fmt(y[i], f)} → {_fmt(y[i + 1], f)}){_floored_note(data, c, sweep)}"
                )
        return ok_all, f"{name}, {x[0]:g} → {x[-1]:g} {_UNITS[sweep]}: " + "; ".join(parts), "; ".join(why)

    return check


def slight(curves: tuple[str, ...], sweep: str, output: str, increasing: bool) -> Callable[[RunData], tuple[bool, str]]:
    """Monotone in the stated direction and |change over the range| < SLIGHT x base-case value."""
    mono = monotone(curves, sweep, output, increasing)

    def check(data: RunData):
        ok_m, ev, why_m = mono(data)
        if _missing(data, curves, sweep):
            return False, ev, why_m
        parts, why, ok_all = [], ([why_m] if why_m else []), ok_m
        for c in curves:
            x, y = data.xy(c, sweep, output)
            base = data.at_base(c, output)
            rel = abs(y[-1] - y[0]) / abs(base) if base else float("inf")
            ok_all &= rel < SLIGHT
            parts.append(f"{_CURVE_SHORT[c]}: change {100 * rel:.0f} % of the base value")
            if rel >= SLIGHT:
                why.append(f"{_CURVE_SHORT[c]} changes by {100 * rel:.0f} % of its base value (not slight: ≥ {100 * SLIGHT:.0f} %)")
        return bool(ok_all), "; ".join(parts), "; ".join(why)

    return check


def ordered(high: str, low: str, sweeps: tuple[str, ...], outputs: tuple[str, ...]) -> Callable[[RunData], tuple[bool, str]]:
    """Curve ``high`` above curve ``low`` at every point of the sweeps, for every output."""

    def check(data: RunData):
        miss = "; ".join(m for s in sweeps if (m := _missing(data, (high, low), s)))
        if miss:
            return False, miss, miss
        parts, why, ok_all = [], [], True
        for out in outputs:
            name, f, unit = _SHORT[out]
            for s in sweeps:
                x, yh = data.xy(high, s, out)
                _, yl = data.xy(low, s, out)
                ok = bool(np.all(yh > yl))
                ok_all &= ok
                ratio = yh / yl
                parts.append(f"{name} vs {s}: {_CURVE_SHORT[high]}/{_CURVE_SHORT[low]} = {ratio.min():.4g}-{ratio.max():.4g}")
                if not ok:
                    bad = x[~(yh > yl)]
                    why.append(
                        f"{name}: {_CURVE_SHORT[high]} not above {_CURVE_SHORT[low]} at {len(bad)} of {len(x)} {s} points "
                        f"({', '.join(f'{v:g}' for v in bad[:3])}{' ...' if len(bad) > 3 else ''} {_UNITS[s]}; ratio down to {ratio.min():.4g})"
                    )
        return ok_all, "; ".join(parts), "; ".join(why)

    return check


def stronger_effect(curves: tuple[str, ...], output: str) -> Callable[[RunData], tuple[bool, str]]:
    """The ratio max/min of ``output`` over 2-6 psi exceeds that over 30-90 rpm, for every curve."""

    def check(data: RunData):
        miss = "; ".join(m for s in ("load", "speed") if (m := _missing(data, curves, s)))
        if miss:
            return False, miss, miss
        parts, why, ok_all = [], [], True
        name = _SHORT[output][0]
        for c in curves:
            _, yl = data.xy(c, "load", output)
            _, ys = data.xy(c, "speed", output)
            rl = yl.max() / yl.min()
            rs = ys.max() / ys.min()
            ok_all &= bool(rl > rs)
            parts.append(f"{_CURVE_SHORT[c]}: ×{rl:.3g} over 2-6 psi vs ×{rs:.3g} over 30-90 rpm")
            if not rl > rs:
                why.append(f"{_CURVE_SHORT[c]}: speed moves {name} more (×{rs:.3g}) than load (×{rl:.3g})")
        return ok_all, f"{name}: " + "; ".join(parts), "; ".join(why)

    return check


def similar(curves: tuple[str, ...], output: str) -> Callable[[RunData], tuple[bool, str]]:
    """At every load and speed the largest of the curves is at most SIMILAR x the smallest."""

    def check(data: RunData):
        miss = "; ".join(m for s in ("load", "speed") if (m := _missing(data, curves, s)))
        if miss:
            return False, miss, miss
        worst = 0.0
        for s in ("load", "speed"):
            ys = np.array([data.xy(c, s, output)[1] for c in curves])
            worst = max(worst, float((ys.max(axis=0) / ys.min(axis=0)).max()))
        base = ", ".join(f"{_CURVE_SHORT[c]} {data.at_base(c, output) * 1e6:.3g} μm (h/σ {data.at_base(c, 'film_thickness_ratio'):.3g})" for c in curves)
        ok = worst <= SIMILAR
        return ok, f"largest/smallest up to {worst:.3g}; at 4 psi, 60 rpm: {base}", "" if ok else f"the films differ by up to a factor {worst:.3g} (> {SIMILAR:g}); at 4 psi, 60 rpm: {base}"

    return check


def not_available(reason: str) -> Callable[[RunData], tuple[bool, str]]:
    def check(data: RunData):
        return False, "-", reason

    return check



STATEMENTS: tuple[Statement, ...] = (
    Statement("S01", "3", "Film thickness decreases as the applied load increases (LEP, σ = 15 μm)", "strictly decreasing over 2-6 psi", monotone(("lep_s15",), "load", "film_thickness_center_m", False)),
    Statement("S02", "3", "Film thickness decreases as the applied load increases (hydrodynamic, σ = 20 μm)", "strictly decreasing over 2-6 psi", monotone(("hydro_s20",), "load", "film_thickness_center_m", False)),
    Statement("S03", "3", "Film thickness decreases as the applied load increases (hydrodynamic, σ = 10 μm)", "strictly decreasing over 2-6 psi", monotone(("hydro_s10",), "load", "film_thickness_center_m", False)),
    Statement("S04", "4", "Film thickness increases with rotation speed (LEP, σ = 15 μm)", "strictly increasing over 30-90 rpm", monotone(("lep_s15",), "speed", "film_thickness_center_m", True)),
    Statement("S05", "4", "Film thickness increases with rotation speed (hydrodynamic, σ = 20 μm)", "strictly increasing over 30-90 rpm", monotone(("hydro_s20",), "speed", "film_thickness_center_m", True)),
    Statement("S06", "4", "Film thickness increases with rotation speed (hydrodynamic, σ = 10 μm)", "strictly increasing over 30-90 rpm", monotone(("hydro_s10",), "speed", "film_thickness_center_m", True)),
    Statement(
        "S07",
        "3-4",
        "The three predictions (σ = 20, 10 μm hydrodynamic; 15 μm LEP) all give approximately the measured film thickness, i.e. approximately the same film",
        f"largest/smallest of the three films ≤ {SIMILAR} at every load and speed",
        similar(("hydro_s20", "lep_s15", "hydro_s10"), "film_thickness_center_m"),
    ),
    Statement(
        "S08",
        "3-4",
        "The applied load influences the asperity deformation more than the rotation speed does (LEP)",
        "max/min of the total contact-area ratio over 2-6 psi exceeds that over 30-90 rpm",
        stronger_effect(("lep_s15",), "contact_area_ratio_total"),
    ),
    Statement(
        "S09",
        "3-4",
        "The LEP prediction agrees well with the film thickness measured by Lu et al. (2004)",
        "model within the measurement's uncertainty",
        not_available("not checkable: Lu et al.'s data are not available to this project (see docs/validation.md); `cmpsim validate` accepts them"),
    ),
    Statement("S10", "5", "At a fixed load the film thickness increases with particle size", "d = 200 nm above d = 100 nm at every load", ordered("d200", "d100", ("load",), ("film_thickness_center_m",))),
    Statement("S11", "5", "The attack angle decreases as the applied load increases", "strictly decreasing over 2-6 psi (both sizes)", monotone(("d100", "d200"), "load", "attack_angle_rad", False)),
    Statement("S12", "5", "... and only slightly ('decreases lightly')", f"monotone and |change over 2-6 psi| < {SLIGHT:g} × the 4 psi value", slight(("d100", "d200"), "load", "attack_angle_rad", False)),
    Statement("S13", "5", "Larger particles have a higher attack angle at any given load", "d = 200 nm above d = 100 nm at every load", ordered("d200", "d100", ("load",), ("attack_angle_rad",))),
    Statement("S14", "6", "The film thickness increases with relative rotation speed", "strictly increasing over 30-90 rpm (both sizes)", monotone(("d100", "d200"), "speed", "film_thickness_center_m", True)),
    Statement("S15", "6", "The attack angle increases with relative rotation speed", "strictly increasing over 30-90 rpm (both sizes)", monotone(("d100", "d200"), "speed", "attack_angle_rad", True)),
    Statement("S16", "6", "... and only slightly ('increases lightly')", f"monotone and |change over 30-90 rpm| < {SLIGHT:g} × the 60 rpm value", slight(("d100", "d200"), "speed", "attack_angle_rad", True)),
    Statement("S17", "6", "Larger particles give a higher film thickness at a fixed rotation speed", "d = 200 nm above d = 100 nm at every speed", ordered("d200", "d100", ("speed",), ("film_thickness_center_m",))),
    Statement("S18", "6", "Larger particles give a higher attack angle at a fixed rotation speed", "d = 200 nm above d = 100 nm at every speed", ordered("d200", "d100", ("speed",), ("attack_angle_rad",))),
    Statement("S19", "7", "The elastic contact-area ratio increases as the applied load increases", "strictly increasing over 2-6 psi, cases (a), (b), (c)", monotone(("a", "b", "c"), "load", "contact_area_ratio_elastic", True)),
    Statement("S20", "8", "The elastoplastic contact-area ratio increases as the applied load increases", "strictly increasing over 2-6 psi, cases (a), (b), (c)", monotone(("a", "b", "c"), "load", "contact_area_ratio_elastoplastic", True)),
    Statement("S21", "8", "... and only slightly ('increases lightly')", f"monotone and |change over 2-6 psi| < {SLIGHT:g} × the 4 psi value", slight(("a", "b", "c"), "load", "contact_area_ratio_elastoplastic", True)),
    Statement(
        "S22",
        "7-8",
        "Smaller particles give higher elastic and elastoplastic contact-area ratios",
        "(b) d = 100 nm above (c) d = 200 nm (both σ = 20 μm) at every load",
        ordered("b", "c", ("load",), ("contact_area_ratio_elastic", "contact_area_ratio_elastoplastic")),
    ),
    Statement(
        "S23",
        "7-8",
        "Larger pad roughness gives higher elastic and elastoplastic contact-area ratios",
        "(b) σ = 20 μm above (a) σ = 15 μm (both d = 100 nm) at every load",
        ordered("b", "a", ("load",), ("contact_area_ratio_elastic", "contact_area_ratio_elastoplastic")),
    ),
    Statement(
        "S24",
        "7-8",
        "... because of their lower film-thickness ratio h/σ",
        "h/σ of (b) below that of (a) and of (c) at every load",
        lambda d: _both(ordered("a", "b", ("load",), ("film_thickness_ratio",))(d), ordered("c", "b", ("load",), ("film_thickness_ratio",))(d)),
    ),
    Statement("S25", "9", "The elastic contact-area ratio decreases as the rotation speed increases", "strictly decreasing over 30-90 rpm, cases (a), (b), (c)", monotone(("a", "b", "c"), "speed", "contact_area_ratio_elastic", False)),
    Statement("S26", "10", "The elastoplastic contact-area ratio also decreases as the rotation speed increases", "strictly decreasing over 30-90 rpm, cases (a), (b), (c)", monotone(("a", "b", "c"), "speed", "contact_area_ratio_elastoplastic", False)),
    Statement("S27", "11", "The removal rate increases with applied load", "strictly increasing over 2-6 psi, cases (a), (b), (c)", monotone(("a", "b", "c"), "load", "removal_rate_relative", True)),
    Statement("S28", "12", "The removal rate increases with rotational speed", "strictly increasing over 30-90 rpm, cases (a), (b), (c)", monotone(("a", "b", "c"), "speed", "removal_rate_relative", True)),
    Statement(
        "S29",
        "11-12",
        "The applied load has a larger influence on the removal rate than the rotational speed",
        "max/min of RR over 2-6 psi (×3 in load) exceeds that over 30-90 rpm (×3 in speed), every case",
        stronger_effect(("a", "b", "c"), "removal_rate_relative"),
    ),
    Statement(
        "S30",
        "11-12",
        "Larger particle size gives a higher removal rate at any given load / rotational speed",
        "(c) d = 200 nm above (b) d = 100 nm (both σ = 20 μm) at every load and speed",
        ordered("c", "b", ("load", "speed"), ("removal_rate_relative",)),
    ),
    Statement(
        "S31",
        "11-12",
        "The removal rate decreases when the pad roughness increases",
        "(a) σ = 15 μm above (b) σ = 20 μm (both d = 100 nm) at every load and speed",
        ordered("a", "b", ("load", "speed"), ("removal_rate_relative",)),
    ),
)


def _both(r1: tuple[bool, str, str], r2: tuple[bool, str, str]) -> tuple[bool, str, str]:
    return r1[0] and r2[0], r1[1] + "; " + r2[1], "; ".join(w for w in (r1[2], r2[2]) if w)


def evaluate_statements(data: RunData) -> list[StatementResult]:
    """Run every check of :data:`STATEMENTS` on the data of a run."""
    out = []
    for s in STATEMENTS:
        try:
            ok, evidence, why = s.check(data)
        except Exception as exc:  # a check must never abort the report
            ok, evidence, why = False, "-", f"check failed: {type(exc).__name__}: {exc}"
        why = "" if ok else (why or "criterion not met") + (f" — {s.hint}" if s.hint else "")
        out.append(StatementResult(s.id, s.figure, s.text, s.criterion, bool(ok), evidence, why))
    return out


# --------------------------------------------------------------------------- the report object
@dataclass
class FigureResult:
    spec: FigureSpec
    png: Path
    csv: Path
    rows: list[dict[str, Any]]


@dataclass
class ReproductionReport:
    """Everything a ``cmpsim reproduce`` run produced."""

    out: Path
    grid: str
    config: Config
    data: RunData
    figures: list[FigureResult]
    statements: list[StatementResult]
    equilibria: int
    factorizations: int
    failures: list[str]
    elapsed_s: float
    solve_s: float
    report_md: Path
    report_html: Path
    notes: list[str] = field(default_factory=list)

    @property
    def n_reproduced(self) -> int:
        return sum(s.reproduced for s in self.statements)

    def trend_rows(self) -> list[list[str]]:
        return [s.as_row() for s in self.statements]

    def figure(self, number: int) -> FigureResult:
        for f in self.figures:
            if f.spec.number == number:
                return f
        raise KeyError(number)


# --------------------------------------------------------------------------- solving
def _key(cfg: Config) -> tuple:
    return tuple(sorted(cfg.to_dict().items()))


def _same(a: Config, b: Config) -> bool:
    """Equal inputs, floats compared to 1e-12 relative."""
    da, db = a.to_dict(), b.to_dict()
    for k, va in da.items():
        vb = db[k]
        if isinstance(va, float) and isinstance(vb, float):
            if not math.isclose(va, vb, rel_tol=1e-12, abs_tol=0.0):
                return False
        elif va != vb:
            return False
    return True


def _plan(base: Config) -> list[tuple[str, str, float, Config]]:
    """Every (curve, sweep, x, config) needed, in solve order (along each curve)."""
    needed: list[tuple[str, str]] = []
    for f in FIGURES:
        for c in f.curves:
            if (c, f.sweep) not in needed:
                needed.append((c, f.sweep))
    plan = []
    for c, sweep in needed:
        cfg_c = base.replace(**CURVES[c].overrides)
        xs = LOADS_PSI if sweep == "load" else SPEEDS_RPM
        for x in xs:
            if sweep == "load":
                cfg = cfg_c.replace(applied_pressure=f"{x} psi", rotation_speed=f"{BASE_SPEED_RPM} rpm")
            else:
                cfg = cfg_c.replace(applied_pressure=f"{BASE_LOAD_PSI} psi", rotation_speed=f"{x} rpm")
            plan.append((c, sweep, x, cfg))
    return plan


def _solve_all(base: Config, progress: bool) -> tuple[RunData, int, int, list[str], float]:
    from .model import REFERENCE_CASE
    from .validation import solve_point

    plan = _plan(base)
    unique = len({_key(cfg) for *_, cfg in plan})
    ref_cfg = base.replace(model="lep", **REFERENCE_CASE)
    # the reference case is one of the planned points (up to the rounding of unit parsing)
    for *_, cfg in plan:
        if _same(cfg, ref_cfg):
            ref_cfg = cfg
            break
    ref_in_plan = any(_key(cfg) == _key(ref_cfg) for *_, cfg in plan)
    total = unique + (0 if ref_in_plan else 1)
    cache: dict[tuple, tuple[Any, str]] = {}
    data = RunData()
    factorizations = 0
    failures: list[str] = []
    t0 = time.perf_counter()

    from .validation import _progress

    with _progress(progress, total, "cmpsim reproduce: solving equilibria") as advance:

        def get(cfg, start):
            nonlocal factorizations
            k = _key(cfg)
            if k not in cache:
                res, msg = solve_point(cfg, start=start)
                cache[k] = (res, msg)
                if res is not None:
                    factorizations += int(res.scalars["factorizations"])
                advance()
            return cache[k]

        prev_curve = None
        start = None
        for c, sweep, x, cfg in plan:
            if (c, sweep) != prev_curve:
                prev_curve, start = (c, sweep), None
            res, msg = get(cfg, start)
            if res is not None:
                start = res.solution.state.u
                scalars = res.to_schema1()  # the figures keep the 0.1 names until the rename of the studies
            else:
                scalars = None
                failures.append(f"{CURVES[c].label}, {x:g} {_UNITS[sweep]}: {msg}")
            data.curves.setdefault((c, sweep), []).append(Point(c, sweep, x, cfg, scalars, "ok" if res is not None else f"no equilibrium: {msg}"))
        ref, msg = get(ref_cfg, None)
    solve_s = time.perf_counter() - t0
    # relative removal rate: normalised by the paper's reference case with the other inputs equal
    ref_rr = ref.scalars["removal_rate_mean"] if ref is not None else float("nan")
    for pts in data.curves.values():
        for p in pts:
            if p.scalars is not None:
                p.scalars["removal_rate_relative"] = p.scalars["removal_rate"] / ref_rr
    return data, len(cache), factorizations, failures, solve_s


# --------------------------------------------------------------------------- figures and CSV
def _csv_rows(spec: FigureSpec, data: RunData) -> list[dict[str, Any]]:
    rows = []
    for c in spec.curves:
        for p in data.curve(c, spec.sweep):
            cfg = p.config
            r = {
                "figure": spec.number,
                "curve": c,
                "label": CURVES[c].label,
                "model": cfg.model,
                "particle_diameter_nm": cfg.particle_diameter * 1e9,
                "pad_roughness_um": cfg.pad_roughness * 1e6,
                "applied_pressure_psi": cfg.applied_pressure / PSI,
                "rotation_speed_rpm": cfg.rotation_speed * 60 / (2 * math.pi),
            }
            for col, key, f in (
                ("film_thickness_center_um", "film_thickness_center_m", 1e6),
                ("film_thickness_ratio", "film_thickness_ratio", 1.0),
                ("attack_angle_rad", "attack_angle_rad", 1.0),
                ("contact_area_ratio_elastic", "contact_area_ratio_elastic", 1.0),
                ("contact_area_ratio_elastoplastic", "contact_area_ratio_elastoplastic", 1.0),
                ("contact_area_ratio_plastic", "contact_area_ratio_plastic", 1.0),
                ("fluid_load_fraction", "fluid_load_fraction", 1.0),
                ("removal_rate_nm_per_min", "removal_rate_nm_per_min", 1.0),
                ("removal_rate_relative", "removal_rate_relative", 1.0),
                ("flow_factor_floored_fraction", "flow_factor_floored_fraction", 1.0),
            ):
                r[col] = p.get(key) * f
            r["converged"] = "yes" if p.ok else "no"
            r["status"] = p.status
            rows.append(r)
    return rows


def _write_csv(path: Path, rows: list[dict[str, Any]], header_lines: list[str]) -> None:
    from .io import atomic_write_text

    buf = io.StringIO()
    for line in header_lines:
        buf.write(f"# {line}\n")
    w = csv.DictWriter(buf, fieldnames=list(CSV_COLUMNS), lineterminator="\n")
    w.writeheader()
    for r in rows:
        w.writerow({k: (f"{v:.10g}" if isinstance(v, float) else v) for k, v in r.items()})
    atomic_write_text(path, buf.getvalue())


_STYLE = {
    "hydro_s20": dict(color="tab:blue", marker="s", linestyle="--"),
    "lep_s15": dict(color="tab:red", marker="o", linestyle="-"),
    "hydro_s10": dict(color="tab:green", marker="^", linestyle=":"),
    "d100": dict(color="tab:blue", marker="o", linestyle="-"),
    "d200": dict(color="tab:orange", marker="s", linestyle="--"),
    "a": dict(color="tab:blue", marker="o", linestyle="-"),
    "b": dict(color="tab:orange", marker="s", linestyle="--"),
    "c": dict(color="tab:green", marker="^", linestyle=":"),
}


def _plot(spec: FigureSpec, data: RunData, path: Path) -> None:
    import matplotlib

    matplotlib.use("Agg", force=False)
    import matplotlib.pyplot as plt

    from .io import atomic_path

    n = len(spec.panels)
    fig, axes = plt.subplots(1, n, figsize=(max(6.0 * n, 7.5), 5.2), squeeze=False, layout="constrained")
    xlabel = "Applied load (psi)" if spec.sweep == "load" else "Relative rotation speed (rpm)"
    any_floored = False
    for ax, (key, ylabel, factor, log) in zip(axes[0], spec.panels):
        for c in spec.curves:
            x, y = data.xy(c, spec.sweep, key)
            _, fl = data.xy(c, spec.sweep, "flow_factor_floored_fraction")
            st = _STYLE[c]
            label = CURVES[c].label
            floored = np.nan_to_num(fl) > 0
            if floored.any():
                any_floored = True
                label += f" [flow factors regularised on {100 * np.nanmin(fl[floored]):.0f}-{100 * np.nanmax(fl[floored]):.0f} % of faces]"
            ax.plot(x, y * factor, color=st["color"], linestyle=st["linestyle"], marker=st["marker"], mfc="none" if floored.any() else st["color"], label=label)
        ax.set_xlabel(xlabel)
        ax.set_ylabel(ylabel)
        if log:
            ax.set_yscale("log")
        ax.grid(True, alpha=0.3)
        ax.legend(fontsize=8, loc="best")
    import textwrap

    title = textwrap.fill(f"Fig. {spec.number} (cmpsim): {spec.title}", 95 if n > 1 else 80)
    if any_floored:
        title += "\nhollow markers: equilibrium outside the validity of the flow factors (regularised)"
    if spec.number in (3, 4):
        title += "\nexperimental data of Lu et al. (2004): not available to this project, not shown"
    fig.suptitle(title, fontsize=10)
    with atomic_path(path, suffix=".png") as tmp:
        fig.savefig(tmp, dpi=110, format="png")
    plt.close(fig)


# --------------------------------------------------------------------------- report
def _md_escape(text: str) -> str:
    return str(text).replace("|", "\\|").replace("\n", " ")


def _blocks(rep: ReproductionReport, command: str) -> list[tuple]:
    """The report as blocks: ("h", level, text) ("p", text) ("table", header, rows) ("img", png, caption, csv) ("ul", items)."""
    b: list[tuple] = []
    n, m = rep.n_reproduced, len(rep.statements)
    b.append(("h", 1, "cmpsim: reproduction of the paper's parameter study (Figs. 3-12)"))
    b.append(
        (
            "p",
            f"Generated by `{command}` with cmpsim {__version__} on the {rep.grid!r} grid "
            f"({rep.config.grid_shape[0]} rings x {rep.config.grid_shape[1]} sectors): {rep.equilibria} equilibria solved "
            f"({rep.factorizations} sparse LU factorisations) in {rep.solve_s:.1f} s; whole run {rep.elapsed_s:.1f} s. "
            "Every verdict below is computed from the data of this run by the checks in `cmpsim/reproduction.py` (`STATEMENTS`); none is written by hand.",
        )
    )
    b.append(("h", 2, f"Trend table: {n} of {m} statements of the paper reproduced"))
    b.append(
        (
            "p",
            f"Criteria. 'Increases' / 'decreases': strictly monotone over the sampled points ({len(LOADS_PSI)} loads, 2-6 psi; "
            f"{len(SPEEDS_RPM)} speeds, 30-90 rpm). 'Slightly' / 'lightly': monotone and the change across the whole range is "
            f"less than {SLIGHT:g} times the base-case value (4 psi, 60 rpm). 'Approximately the same': largest/smallest ≤ {SIMILAR:g}. "
            "'Higher at any load/speed': above at every sampled point. 'Larger influence': larger max/min ratio over the load range "
            "(×3) than over the speed range (×3).",
        )
    )
    b.append(("table", ["#", "Fig.", "statement of the paper", "criterion", "reproduced", "evidence (this run)", "why not"], rep.trend_rows()))
    b.append(("h", 2, "Notes"))
    b.append(("ul", rep.notes))
    b.append(("h", 2, "Figures"))
    for f in rep.figures:
        b.append(("img", f.png, f"Fig. {f.spec.number}: {f.spec.title}", f.csv))
    if rep.failures:
        b.append(("h", 2, "Operating points without equilibrium"))
        b.append(("ul", rep.failures))
    b.append(("h", 2, "Parameter set"))
    b.append(
        (
            "p",
            "Every input of the run (display units); the curves change only model, particle_diameter, pad_roughness, "
            "applied_pressure and rotation_speed as listed in each CSV.",
        )
    )
    rows = [[name, value, disp or "-", src] for name, value, disp, src in rep.config.describe()]
    b.append(("table", ["parameter", "value", "unit", "source"], rows))
    return b


def _render_md(blocks: list[tuple], out: Path) -> str:
    lines: list[str] = []
    for blk in blocks:
        kind = blk[0]
        if kind == "h":
            lines += ["#" * blk[1] + " " + blk[2], ""]
        elif kind == "p":
            lines += [blk[1], ""]
        elif kind == "ul":
            lines += [f"- {item}" for item in blk[1]] + [""]
        elif kind == "table":
            header, rows = blk[1], blk[2]
            lines.append("| " + " | ".join(header) + " |")
            lines.append("|" + "---|" * len(header))
            lines += ["| " + " | ".join(_md_escape(c) for c in r) + " |" for r in rows]
            lines.append("")
        elif kind == "img":
            png, caption, csvp = blk[1], blk[2], blk[3]
            lines += [f"![{caption}]({png.relative_to(out).as_posix()})", "", f"*{caption}* Data: [`{csvp.relative_to(out).as_posix()}`]({csvp.relative_to(out).as_posix()})", ""]
    return "\n".join(lines)


def _render_html(blocks: list[tuple], out: Path) -> str:
    e = html.escape
    parts = [
        "<!DOCTYPE html><html lang='en'><head><meta charset='utf-8'><title>cmpsim reproduction report</title>",
        "<style>body{font-family:sans-serif;max-width:1300px;margin:2em auto;padding:0 1em;line-height:1.4}"
        "table{border-collapse:collapse;font-size:0.85em;margin:1em 0}td,th{border:1px solid #bbb;padding:3px 6px;vertical-align:top}"
        "th{background:#eee}td.yes{background:#e3f6e3;font-weight:bold}td.no{background:#fbe3e3;font-weight:bold}"
        "img{max-width:100%;border:1px solid #ddd}code{background:#f4f4f4}</style></head><body>",
    ]
    for blk in blocks:
        kind = blk[0]
        if kind == "h":
            parts.append(f"<h{blk[1]}>{e(blk[2])}</h{blk[1]}>")
        elif kind == "p":
            text = e(blk[1])
            # `code` spans
            segs = text.split("`")
            text = "".join(f"<code>{s}</code>" if i % 2 else s for i, s in enumerate(segs))
            parts.append(f"<p>{text}</p>")
        elif kind == "ul":
            parts.append("<ul>" + "".join(f"<li>{e(str(i))}</li>" for i in blk[1]) + "</ul>")
        elif kind == "table":
            header, rows = blk[1], blk[2]
            parts.append("<table><tr>" + "".join(f"<th>{e(h)}</th>" for h in header) + "</tr>")
            for r in rows:
                cells = []
                for c in r:
                    cls = f" class='{c}'" if c in ("yes", "no") else ""
                    cells.append(f"<td{cls}>{e(str(c))}</td>")
                parts.append("<tr>" + "".join(cells) + "</tr>")
            parts.append("</table>")
        elif kind == "img":
            png, caption, csvp = blk[1], blk[2], blk[3]
            data = base64.b64encode(png.read_bytes()).decode("ascii")
            rel = csvp.relative_to(out).as_posix()
            parts.append(f"<figure><img alt='{e(caption)}' src='data:image/png;base64,{data}'><figcaption>{e(caption)} Data: <a href='{e(rel)}'>{e(rel)}</a></figcaption></figure>")
    parts.append("</body></html>")
    return "\n".join(parts)


def _notes(data: RunData, failures: list[str]) -> list[str]:
    notes = []
    for c in ("hydro_s20", "hydro_s10"):
        fl = []
        h = []
        for s in ("load", "speed"):
            fl += [p.get("flow_factor_floored_fraction") for p in data.curve(c, s) if p.ok]
            h += [p.get("film_thickness_ratio") for p in data.curve(c, s) if p.ok]
        if fl:
            notes.append(
                f"{CURVES[c].label}: the equilibrium film is h/σ = {min(h):.3g}-{max(h):.3g}; the pressure flow factor of eq. 8 "
                f"was regularised (floored) on {100 * min(fl):.0f}-{100 * max(fl):.0f} % of the cell faces, i.e. these curves lie "
                "outside the validity of the perturbation flow factors (column flow_factor_floored_fraction of the CSVs)."
            )
    lep_fl = [p.get("flow_factor_floored_fraction") for (c, s), pts in data.curves.items() if not c.startswith("hydro") for p in pts if p.ok]
    if lep_fl:
        notes.append(
            "LEP curves: the flow factors were never regularised (valid everywhere)."
            if max(lep_fl) == 0
            else f"LEP curves: flow factors regularised on at most {100 * max(lep_fl):.1f} % of the faces."
        )
    notes.append(
        "Relative removal rate (Figs. 11-12): removal_rate / removal_rate of the LEP case d = 100 nm, σ = 15 μm, 4 psi, 60 rpm "
        "with every other input equal (cmpsim.model.REFERENCE_CASE), as in the paper."
    )
    notes.append(
        "The paper compares Figs. 3-4 with measurements of Lu et al. (J. Electrochem. Soc. 151, G241, 2004); those data were "
        "not available to this project and are neither shown nor estimated. Statement S09 is therefore not reproduced."
    )
    notes.append("Pad roughness is varied with the configured roughness_scaling (see docs/model.md); the curves of a figure differ only in the inputs named in their legend.")
    if failures:
        notes.append(f"{len(failures)} operating point(s) had no equilibrium; they appear as NaN in the CSVs and make the statements that need them fail.")
    return notes


def reproduce(out=None, grid: str = "default", progress: bool = True, config: Config | None = None, command: str | None = None) -> ReproductionReport:
    """Regenerate Figs. 3-12 of the paper, their CSVs, the trend table and REPORT.md/.html.

    Parameters
    ----------
    out : path, optional
        Output directory (created; default ``./reproduction``).
    grid : {"coarse", "default", "fine"} or "NRxNT"
        Grid of every solve.
    progress : bool
        Show a rich progress bar.
    config : Config, optional
        Inputs the figures do not vary (default :meth:`Config.default`).
    command : str, optional
        Command line recorded in the report.

    Returns
    -------
    ReproductionReport
    """
    from .io import atomic_write_text

    t0 = time.perf_counter()
    out = Path(out if out is not None else "reproduction")
    out.mkdir(parents=True, exist_ok=True)
    base = (config or Config.default()).replace(grid=grid)
    data, n_eq, n_fact, failures, solve_s = _solve_all(base, progress)
    figures = []
    for spec in FIGURES:
        rows = _csv_rows(spec, data)
        csv_path = out / f"{spec.name}.csv"
        png_path = out / f"{spec.name}.png"
        header = [
            f"cmpsim {__version__} reproduction of Fig. {spec.number} of the paper: {spec.title}",
            f"grid {base.numerics.grid}; other inputs: see REPORT.md (parameter set); SI unless the column name says otherwise",
        ]
        _write_csv(csv_path, rows, header)
        _plot(spec, data, png_path)
        figures.append(FigureResult(spec, png_path, csv_path, rows))
    statements = evaluate_statements(data)
    rep = ReproductionReport(
        out=out,
        grid=base.numerics.grid,
        config=base,
        data=data,
        figures=figures,
        statements=statements,
        equilibria=n_eq,
        factorizations=n_fact,
        failures=failures,
        elapsed_s=0.0,
        solve_s=solve_s,
        report_md=out / "REPORT.md",
        report_html=out / "REPORT.html",
        notes=_notes(data, failures),
    )
    rep.elapsed_s = time.perf_counter() - t0
    command = command or f"cmpsim reproduce --out {out} --grid {grid}"
    blocks = _blocks(rep, command)
    atomic_write_text(rep.report_md, _render_md(blocks, out))
    atomic_write_text(rep.report_html, _render_html(blocks, out))
    _write_csv_trends(out / "trends.csv", statements)
    return rep


def _write_csv_trends(path: Path, statements: list[StatementResult]) -> None:
    from .io import atomic_write_text

    buf = io.StringIO()
    w = csv.writer(buf, lineterminator="\n")
    w.writerow(["id", "figure", "statement", "criterion", "reproduced", "evidence", "why_not"])
    for s in statements:
        w.writerow(s.as_row())
    atomic_write_text(path, buf.getvalue())
