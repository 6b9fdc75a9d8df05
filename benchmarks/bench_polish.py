"""The copper recipe of issue 32 through ``cmpsim.polish``: its wall and CPU time (target: at most 30 s).

Run: python benchmarks/bench_polish.py [--repeat 1] [--json FILE]

Runs ``src/cmpsim/data/recipe_copper.toml`` as written (the 300mm preset on the default grid:
three wafer equilibria, 300 time steps of 1 s) in a fresh process state and prints the wall time
(``time.perf_counter``), the CPU time (``time.process_time``), the solves and the share of the
time spent in them. On a shared machine the CPU time is the one to compare.
"""

from __future__ import annotations

import argparse
import json
import time
from pathlib import Path


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--repeat", type=int, default=1)
    ap.add_argument("--json", type=Path, default=None)
    args = ap.parse_args()
    import cmpsim
    from cmpsim.polisher import engine

    recipe = Path(cmpsim.__file__).parent / "data" / "recipe_copper.toml"
    solve_time = [0.0]
    original = engine.StepSolve.__init__

    def timed(self, config):
        t = time.perf_counter()
        original(self, config)
        solve_time[0] += time.perf_counter() - t

    engine.StepSolve.__init__ = timed
    runs = []
    for _ in range(args.repeat):
        solve_time[0] = 0.0
        w, c = time.perf_counter(), time.process_time()
        res = cmpsim.polish(recipe)
        runs.append({"wall": time.perf_counter() - w, "cpu": time.process_time() - c, "solves": res.solves, "solve_wall": solve_time[0]})
    best = min(runs, key=lambda r: r["cpu"])
    print(f"copper recipe: wall {best['wall']:.2f} s, CPU {best['cpu']:.2f} s, {best['solves']} solves "
          f"({best['solve_wall']:.2f} s wall in the solves); target <= 30 s: {'met' if best['wall'] <= 30 else 'NOT met'}")
    for s in res.steps:
        print(f"  {s.name}: {s.end}, {s.duration:.0f} s, {6e10 * s.removal_rate_mean:.1f} nm/min")
    if args.json:
        args.json.write_text(json.dumps({"runs": runs, "best": best}, indent=1))


if __name__ == "__main__":
    main()
