"""The cost of a lot (issue 32: a 25-wafer controlled lot in at most 2 min).

Run: python benchmarks/bench_lot.py [--wafers 25] [--grid default] [--control ewma|single_ewma|none] [--conditioning in_situ]
     python benchmarks/bench_lot.py --refit-vs-fixed --fab-wear 2 --fab-glazed 0.6 --grid coarse --conditioning none

Polishes the issue's oxide recipe (src/cmpsim/data/recipe_oxide.toml) on the 300mm preset for a lot
with seed 1 and prints the wall and CPU time, the solves, and the final thickness of every wafer
against the target.

``--fab-wear K --fab-glazed G`` polish on a "fab pad" whose wear coefficient k_w and critical glazed
area G_c are K and G times cmpsim's defaults, controlled with the default model of the pad;
``--refit-vs-fixed`` runs that lot twice in turn, with the controller's model fixed and refitted
(``--refit-model``, docs/polisher.md C6-C8), and prints each one's largest miss on wafers 5-N and the
ratio of their wall times (refitted / fixed).
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
    ap.add_argument("--fab-wear", type=float, default=1.0, help="the simulated pad's k_w over cmpsim's default")
    ap.add_argument("--fab-glazed", type=float, default=1.0, help="the simulated pad's G_c over cmpsim's default")
    ap.add_argument("--refit-vs-fixed", action="store_true", help="time the lot with the controller's model fixed, then refitted")
    args = ap.parse_args()
    from cmpsim.physics.padlife import default_constants
    from cmpsim.polisher.lot import run_lot

    recipe = (resources.files("cmpsim") / "data" / "recipe_oxide.toml").read_text(encoding="utf-8")
    overrides = {} if args.grid == "default" else {"grid": args.grid}
    d = default_constants()
    fab = {"pad_wear_coefficient": args.fab_wear * d["pad_wear_coefficient"], "critical_glazed_area": args.fab_glazed * d["critical_glazed_area"]}
    if args.refit_vs_fixed:
        walls = {}
        for refit in (False, True):
            wall = time.perf_counter()
            lot = run_lot(recipe, args.wafers, conditioning=args.conditioning, control="ewma", seed=1, overrides=overrides,
                          pad_constants=fab, model_pad_constants=d, refit_model=refit)
            walls[refit] = time.perf_counter() - wall
            miss = [abs(w.final_thickness_mean / lot.target - 1) for w in lot.wafers]
            print(f"model {'refitted' if refit else 'fixed'}: {walls[refit]:.1f} s wall, largest miss on wafers 5-{args.wafers} "
                  f"{100 * max(miss[4:]):.4f} %, model's k_w {lot.wafers[-1].model_wear_coefficient}, G_c {lot.wafers[-1].model_critical_glazed_area}")
        print(f"refitted / fixed wall time: {walls[True] / walls[False]:.2f}")
        return
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
