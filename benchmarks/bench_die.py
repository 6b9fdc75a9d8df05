"""Cost of the die model: one 20 x 20 mm die at 50 um cells through a full polish, and a 300 mm
wafer of such dies (one wafer-scale solve, then the dies), against one wafer-scale solve.

Run: python benchmarks/bench_die.py [--repeat 3] [--grid default]

Timed in one process, best of ``--repeat`` each, alternating: ``cmpsim.solve`` of the 300 mm
wafer (default model, ``relative=False``), ``cmpsim.die.simulate`` of the built-in dies
``density`` (oxide) and ``lines`` (copper) at 50 um cells (400 x 400 cells) through their end
point plus 30 % over-polish at a given blanket rate, and ``cmpsim.die.simulate_wafer`` of the
``lines`` die on the 300 mm wafer (the wafer solve included). Printed: seconds and the ratios
to the wafer solve (what to compare across machines); the issue's targets are a few seconds per
die and a minute per wafer of dies.
"""

from __future__ import annotations

import argparse
import time

import cmpsim
from cmpsim import die


def _best(fn, repeat):
    times, out = [], None
    for _ in range(repeat):
        t = time.perf_counter()
        out = fn()
        times.append(time.perf_counter() - t)
    return min(times), out


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__)
    ap.add_argument("--repeat", type=int, default=3)
    ap.add_argument("--grid", default="default")
    args = ap.parse_args()
    cfg = cmpsim.Config.default().replace(wafer_diameter="300 mm", grid=args.grid)
    cmpsim.solve(cfg, relative=False)  # warm imports and caches
    oxide = die.builtin_layout("density", 50e-6)
    copper = die.builtin_layout("lines", 50e-6)
    cases = {
        "wafer solve (300 mm)": lambda: cmpsim.solve(cfg, relative=False),
        "die 'density', oxide, 400x400": lambda: die.simulate(oxide, config=cfg, blanket_rate=1.5e-9),
        "die 'lines', copper, 400x400": lambda: die.simulate(copper, config=cfg, blanket_rate=5e-9, process="copper"),
        "wafer of 'lines' dies, copper": lambda: die.simulate_wafer(copper, config=cfg, process="copper"),
    }
    best = {name: _best(fn, args.repeat) for name, fn in cases.items()}
    ref = best["wafer solve (300 mm)"][0]
    for name, (t, out) in best.items():
        extra = ""
        if hasattr(out, "x"):
            extra = f"; {len(out.x)} dies"
        elif hasattr(out, "time_to_clear"):
            extra = f"; polished {out.time:.0f} s"
        print(f"{name:34s} {t:7.2f} s  ({t / ref:5.2f} x the wafer solve){extra}")
    die_t = max(best["die 'density', oxide, 400x400"][0], best["die 'lines', copper, 400x400"][0])
    wafer_t = best["wafer of 'lines' dies, copper"][0]
    print(f"RESULT die {die_t:.2f} s (target: a few seconds); wafer of dies {wafer_t:.2f} s (target <= 60 s)")


if __name__ == "__main__":
    main()
