"""The cost of a lot (issue 32: a 25-wafer controlled lot in at most 2 min).

Run: python benchmarks/bench_lot.py [--wafers 25] [--grid default] [--control ewma|single_ewma|none] [--conditioning in_situ]

Polishes the issue's oxide recipe (src/cmpsim/data/recipe_oxide.toml) on the 300mm preset for a lot
with seed 1 and prints the wall and CPU time, the solves, and the final thickness of every wafer
against the target.
"""

from __future__ import annotations

import argparse
import time
from importlib import resources


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--wafers", type=int, default=25)
    ap.add_argument("--grid", default="default")
    ap.add_argument("--control", default="ewma", choices=("none", "ewma", "single_ewma"))
    ap.add_argument("--conditioning", default="in_situ", choices=("none", "ex_situ", "in_situ"))
    args = ap.parse_args()
    from cmpsim.polisher.lot import run_lot

    recipe = (resources.files("cmpsim") / "data" / "recipe_oxide.toml").read_text(encoding="utf-8")
    overrides = {} if args.grid == "default" else {"grid": args.grid}
    wall, cpu = time.perf_counter(), time.process_time()
    lot = run_lot(recipe, args.wafers, conditioning=args.conditioning, control=args.control, seed=1, overrides=overrides)
    wall, cpu = time.perf_counter() - wall, time.process_time() - cpu
    for w in lot.wafers:
        dev = 100 * (w.final_thickness_mean / lot.target - 1)
        print(f"wafer {w.index:2d}: {w.polish_time:6.1f} s, {w.removal_rate_mean * 6e10:6.1f} nm/min, final {w.final_thickness_mean * 1e9:6.1f} nm ({dev:+.2f} %), "
              f"WIWNU {100 * w.final_thickness_nonuniformity:.2f} %, zones {' '.join(f'{p / 6894.757293168361:.2f}' for p in w.zone_pressures)} psi")
    print(f"{args.wafers} wafers, control {args.control}, conditioning {args.conditioning}, grid {args.grid}: "
          f"{wall:.1f} s wall, {cpu:.1f} s CPU, {lot.solves} wafer equilibria (issue 32: <= 120 s)")


if __name__ == "__main__":
    main()
