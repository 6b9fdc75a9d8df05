"""Cost of one equilibrium on a compliant (Winkler) pad against the rigid pad, same grid, same run.

Run: python benchmarks/bench_compliance.py [--grid default] [--repeat 7]

All solves are `cmpsim.solve(Config.paper(), ..., relative=False)` at the base case (the paper's
model, whose rigid pad is the reference of the cost target); the only difference is
``pad_compliance`` ("rigid", "winkler", "layer"; default IC1000-on-Suba-IV stack). They are timed
alternately (best of ``--repeat`` each, after one untimed run of each), so that load from other
jobs on the machine hits all alike; the ratios are what to compare across machines. Also
printed: Newton iterations and sparse LU factorisations.
"""

from __future__ import annotations

import argparse
import statistics
import time

import cmpsim


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__)
    ap.add_argument("--grid", default="default")
    ap.add_argument("--repeat", type=int, default=7)
    args = ap.parse_args()
    base = cmpsim.Config.paper().replace(grid=args.grid)  # the paper's model: its rigid pad converges
    configs = {name: base.replace(pad_compliance=name) for name in ("rigid", "winkler", "layer")}
    results = {name: cmpsim.solve(cfg, relative=False) for name, cfg in configs.items()}  # warm caches
    times: dict[str, list[float]] = {name: [] for name in configs}
    for _ in range(args.repeat):
        for name, cfg in configs.items():
            t = time.perf_counter()
            cmpsim.solve(cfg, relative=False)
            times[name].append(time.perf_counter() - t)
    g = results["rigid"].grid
    print(f"grid {g.n_r}x{g.n_theta} ({g.size} cells), best of {args.repeat}, alternating runs")
    for name, r in results.items():
        best, med = min(times[name]), statistics.median(times[name])
        print(
            f"{name:>8}: {best * 1e3:7.1f} ms (median {med * 1e3:7.1f} ms); Newton iterations {r.iterations}, "
            f"LU factorisations {r.factorizations}; mean RR {r.removal_rate_mean * 6e10:.2f} nm/min"
        )
    for name in ("winkler", "layer"):
        ratio = min(times[name]) / min(times["rigid"])
        ratio_med = statistics.median(times[name]) / statistics.median(times["rigid"])
        target = " (target <= 2)" if name == "winkler" else ""
        print(f"RESULT {name} / rigid = {ratio:.2f} (best), {ratio_med:.2f} (median){target}")


if __name__ == "__main__":
    main()
