"""Cost of one wafer equilibrium in units of one sparse pressure solve on the same grid.

Run: python benchmarks/bench_equilibrium.py [--grid default] [--repeat 5]

A "sparse solve" is one assembly + SuperLU factorisation + back-substitution of the
Reynolds system at the converged film, the unit the issue asks for. Everything is timed in
the same process and run; ratios are what to compare across machines.
"""

from __future__ import annotations

import argparse
import statistics
import time

import cmpsim
from cmpsim.solver.model import build_problem, solve
from cmpsim.operators.reynolds import ReynoldsSystem


def best_of(fn, repeat):
    times = []
    for _ in range(repeat):
        t = time.perf_counter()
        fn()
        times.append(time.perf_counter() - t)
    return min(times), statistics.median(times)


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__)
    ap.add_argument("--grid", default="default")
    ap.add_argument("--repeat", type=int, default=5)
    args = ap.parse_args()
    cfg = cmpsim.Config.default().replace(grid=args.grid)
    res = solve(cfg, relative=False)  # warm caches (imports)
    problem = build_problem(cfg)
    u = res.solution.state.u

    def one_sparse_solve():
        ReynoldsSystem(problem.grid, problem.face_coefficients(u)).solve()

    t_solve, _ = best_of(one_sparse_solve, args.repeat * 4)
    t_eq, t_eq_med = best_of(lambda: solve(cfg, relative=False), args.repeat)
    g = problem.grid
    print(f"grid {g.n_r}x{g.n_theta} ({g.size} unknowns), best of {args.repeat}")
    print(f"one sparse pressure solve (assemble + LU + solve): {t_solve * 1e3:.2f} ms")
    print(f"one equilibrium (cmpsim.solve, relative=False):      {t_eq * 1e3:.1f} ms (median {t_eq_med * 1e3:.1f} ms)")
    print(f"Newton iterations {res.iterations}, LU factorisations {res.factorizations}")
    print(f"cost of one equilibrium = {t_eq / t_solve:.1f} sparse solves (target <= 10)")


if __name__ == "__main__":
    main()
