"""The paper's qualitative statements about Figs. 3-12 and the functions that check them on a run.

Every verdict is computed by the check registered with the statement in :data:`STATEMENTS`,
from the data of the run; none is written by hand.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Callable

import numpy as np

from .paper import _UNITS, RunData

__all__ = ["Statement", "StatementResult", "STATEMENTS", "SLIGHT", "SIMILAR", "evaluate_statements"]

#: "slightly" / "lightly": the change across the whole studied range is smaller than this
#: fraction of the value at the base case (4 psi, 60 rpm).
SLIGHT = 0.5
#: "approximately the same": the largest of the compared values is at most this multiple of the smallest.
SIMILAR = 1.5


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


_SHORT = {
    "film_thickness_center": ("film", 1e6, "μm"),
    "attack_angle": ("attack angle", 1.0, "rad"),
    "contact_area_ratio_elastic": ("elastic ratio", 1.0, ""),
    "contact_area_ratio_elastoplastic": ("elastoplastic ratio", 1.0, ""),
    "contact_area_ratio": ("total contact ratio", 1.0, ""),
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


STATEMENTS: tuple[Statement, ...] = (
    Statement("S01", "3", "Film thickness decreases as the applied load increases (LEP, σ = 15 μm)", "strictly decreasing over 2-6 psi", monotone(("lep_s15",), "load", "film_thickness_center", False)),
    Statement("S02", "3", "Film thickness decreases as the applied load increases (hydrodynamic, σ = 20 μm)", "strictly decreasing over 2-6 psi", monotone(("hydro_s20",), "load", "film_thickness_center", False)),
    Statement("S03", "3", "Film thickness decreases as the applied load increases (hydrodynamic, σ = 10 μm)", "strictly decreasing over 2-6 psi", monotone(("hydro_s10",), "load", "film_thickness_center", False)),
    Statement("S04", "4", "Film thickness increases with rotation speed (LEP, σ = 15 μm)", "strictly increasing over 30-90 rpm", monotone(("lep_s15",), "speed", "film_thickness_center", True)),
    Statement("S05", "4", "Film thickness increases with rotation speed (hydrodynamic, σ = 20 μm)", "strictly increasing over 30-90 rpm", monotone(("hydro_s20",), "speed", "film_thickness_center", True)),
    Statement("S06", "4", "Film thickness increases with rotation speed (hydrodynamic, σ = 10 μm)", "strictly increasing over 30-90 rpm", monotone(("hydro_s10",), "speed", "film_thickness_center", True)),
    Statement(
        "S07",
        "3-4",
        "The three predictions (σ = 20, 10 μm hydrodynamic; 15 μm LEP) all give approximately the measured film thickness, i.e. approximately the same film",
        f"largest/smallest of the three films ≤ {SIMILAR} at every load and speed",
        similar(("hydro_s20", "lep_s15", "hydro_s10"), "film_thickness_center"),
    ),
    Statement(
        "S08",
        "3-4",
        "The applied load influences the asperity deformation more than the rotation speed does (LEP)",
        "max/min of the total contact-area ratio over 2-6 psi exceeds that over 30-90 rpm",
        stronger_effect(("lep_s15",), "contact_area_ratio"),
    ),
    Statement(
        "S09",
        "3-4",
        "The LEP prediction agrees well with the film thickness measured by Lu et al. (2004)",
        "model within the measurement's uncertainty",
        not_available("not checkable: Lu et al.'s data are not available to this project (see docs/validation.md); `cmpsim validate` accepts them"),
    ),
    Statement("S10", "5", "At a fixed load the film thickness increases with particle size", "d = 200 nm above d = 100 nm at every load", ordered("d200", "d100", ("load",), ("film_thickness_center",))),
    Statement("S11", "5", "The attack angle decreases as the applied load increases", "strictly decreasing over 2-6 psi (both sizes)", monotone(("d100", "d200"), "load", "attack_angle", False)),
    Statement("S12", "5", "... and only slightly ('decreases lightly')", f"monotone and |change over 2-6 psi| < {SLIGHT:g} × the 4 psi value", slight(("d100", "d200"), "load", "attack_angle", False)),
    Statement("S13", "5", "Larger particles have a higher attack angle at any given load", "d = 200 nm above d = 100 nm at every load", ordered("d200", "d100", ("load",), ("attack_angle",))),
    Statement("S14", "6", "The film thickness increases with relative rotation speed", "strictly increasing over 30-90 rpm (both sizes)", monotone(("d100", "d200"), "speed", "film_thickness_center", True)),
    Statement("S15", "6", "The attack angle increases with relative rotation speed", "strictly increasing over 30-90 rpm (both sizes)", monotone(("d100", "d200"), "speed", "attack_angle", True)),
    Statement("S16", "6", "... and only slightly ('increases lightly')", f"monotone and |change over 30-90 rpm| < {SLIGHT:g} × the 60 rpm value", slight(("d100", "d200"), "speed", "attack_angle", True)),
    Statement("S17", "6", "Larger particles give a higher film thickness at a fixed rotation speed", "d = 200 nm above d = 100 nm at every speed", ordered("d200", "d100", ("speed",), ("film_thickness_center",))),
    Statement("S18", "6", "Larger particles give a higher attack angle at a fixed rotation speed", "d = 200 nm above d = 100 nm at every speed", ordered("d200", "d100", ("speed",), ("attack_angle",))),
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
