"""Time of `cmpsim reproduce` and the number of equilibria it solves.

Run: python benchmarks/bench_reproduce.py [--grid default] [--compare-cold]

Runs the whole reproduction (Figs. 3-12, CSVs, REPORT.md/.html) into a temporary directory,
as `cmpsim reproduce --grid GRID` does, and prints the wall time, the time spent solving,
the number of equilibria and LU factorisations. Identical operating points are shared
between figures and each curve is warm-started from its previous point; the naive count
(every figure's points solved on their own) is printed for comparison. With
--compare-cold the solve is repeated with warm starts switched off (same sharing), to
measure what the warm starts save.
"""

from __future__ import annotations

import argparse
import os
import platform
import tempfile
import time

import numpy as np

import cmpsim
from cmpsim.reproduction import FIGURES, LOADS_PSI, SPEEDS_RPM, reproduce


def naive_count() -> int:
    n = 0
    for f in FIGURES:
        n += len(f.curves) * (len(LOADS_PSI) if f.sweep == "load" else len(SPEEDS_RPM))
    return n + 1  # + the reference case of the relative removal rate


def run(grid: str, cold: bool = False):
    import cmpsim.solver.points as v  # the study runner: every point of the run goes through its solve_point

    original = v.solve_point
    if cold:
        v.solve_point = lambda config, start=None, **options: original(config, None, **options)
    try:
        with tempfile.TemporaryDirectory() as tmp:
            t = time.perf_counter()
            rep = reproduce(out=tmp, grid=grid, progress=False)
            wall = time.perf_counter() - t
    finally:
        v.solve_point = original
    return rep, wall


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__)
    ap.add_argument("--grid", default="default")
    ap.add_argument("--compare-cold", action="store_true")
    args = ap.parse_args()
    cmpsim.solve(grid="coarse", relative=False)  # imports and caches outside the timing
    rep, wall = run(args.grid)
    shape = rep.config.grid_shape
    print(f"cmpsim {cmpsim.__version__}, Python {platform.python_version()}, numpy {np.__version__}, {os.cpu_count()} cores")
    print(f"grid {args.grid} ({shape[0]}x{shape[1]}): cmpsim reproduce wall time {wall:.1f} s "
          f"(solving {rep.solve_s:.1f} s, figures + CSV + report {wall - rep.solve_s:.1f} s)")
    print(f"equilibria solved: {rep.equilibria} (naive per-figure count {naive_count()}); "
          f"LU factorisations {rep.factorizations} ({rep.factorizations / rep.equilibria:.2f} per equilibrium); "
          f"{1e3 * rep.solve_s / rep.equilibria:.0f} ms per equilibrium")
    print(f"statements reproduced: {rep.n_reproduced} of {len(rep.statements)}; points without equilibrium: {len(rep.failures)}")
    if args.compare_cold:
        rep_c, wall_c = run(args.grid, cold=True)
        print(f"warm starts off: solving {rep_c.solve_s:.1f} s, {rep_c.factorizations} factorisations "
              f"({rep_c.factorizations / rep_c.equilibria:.2f} per equilibrium); warm/cold solve time ratio "
              f"{rep.solve_s / rep_c.solve_s:.2f}; same verdicts: "
              f"{[s.reproduced for s in rep.statements] == [s.reproduced for s in rep_c.statements]}")


if __name__ == "__main__":
    main()
