"""Speed of this checkout against cmpsim 0.1.0 (commit d1cfb40), measured in one run.

Run: python benchmarks/bench_versus_0_1.py [--repeat 5] [--rounds 2] [--no-reproduce] [--json FILE]

cmpsim 0.1.0 is installed from this repository's history (``git archive d1cfb40``, then
``pip install --no-deps --target``) into a temporary directory, and both versions are measured
by child processes of the same interpreter with the same numpy, scipy and SuperLU: only
cmpsim's own code differs. The two versions alternate for ``--rounds`` rounds and each keeps
its best, so that a change of load on a shared machine hits both alike. Each case is timed in CPU time (``time.process_time``, best of
``--repeat``) so that other work on the machine disturbs it less; the ratios 0.1.0 / now are
what to compare across machines, never the absolute times.

Cases (the paper's model: ``Config.paper()`` in this checkout, the defaults in 0.1.0):

* ``lep default``: one LEP equilibrium at the base case on the default grid (24x64);
* ``hydrodynamic cold``: one hydrodynamic equilibrium from the cold start (default grid);
* ``lep 48x128`` and ``lep 96x256``: the growth of the cost with the grid, as the exponent
  p of cost ~ N^p between them (N = cells);
* ``reproduce``: the LU factorisations and the wall time of ``cmpsim reproduce`` (default grid).

It also checks that the same discrete problem is solved: every scalar output of the four
equilibria agrees within ``--rtol`` (1e-6) relative, and prints the largest difference.
Current-model defaults (the predictive model) are timed too, for information.
"""

from __future__ import annotations

import argparse
import json
import math
import os
import subprocess
import sys
import tempfile
from pathlib import Path

BASELINE_COMMIT = "d1cfb40"
REPO = Path(__file__).resolve().parents[1]

#: The measuring script, run by each version's child process; prints one JSON object.
CHILD = r"""
import json, sys, time, tempfile
import cmpsim
from cmpsim.inputs.config import Config

repeat, do_reproduce = int(sys.argv[1]), sys.argv[2] == "1"
paper = Config.paper() if hasattr(Config, "paper") else Config.default()
SKIP = {"load_residual", "moment_residual", "iterations", "factorizations", "converged"}

def schema1(result):
    f = getattr(result, "to_schema1", None)
    return f() if f is not None else result.to_dict()

def best(fn, n):
    times, out = [], None
    for _ in range(n):
        t = time.process_time()
        out = fn()
        times.append(time.process_time() - t)
    return min(times), out

cases = {
    "lep default": (paper, repeat),
    "hydrodynamic cold": (paper.replace(model="hydrodynamic"), max(2, repeat // 2)),
    "lep 48x128": (paper.replace(grid="48x128"), max(2, repeat // 2)),
    "lep 96x256": (paper.replace(grid="96x256"), 2),
}
cmpsim.solve(paper.replace(grid="coarse"), relative=False)  # imports and caches
out = {"version": cmpsim.__version__, "file": cmpsim.__file__, "cases": {}}
for name, (cfg, n) in cases.items():
    t, res = best(lambda: cmpsim.solve(cfg, relative=False), n)
    vals = {k: v for k, v in schema1(res).items() if isinstance(v, float) and k not in SKIP}
    out["cases"][name] = {"cpu_s": t, "factorizations": int(res.scalars["factorizations"]),
                          "iterations": int(res.scalars["iterations"]), "cells": res.grid.size, "values": vals}
default = Config.default()
if default != paper:
    t, res = best(lambda: cmpsim.solve(default, relative=False), repeat)
    out["cases"]["defaults (predictive model)"] = {"cpu_s": t, "factorizations": int(res.scalars["factorizations"]),
        "iterations": int(res.scalars["iterations"]), "cells": res.grid.size, "values": {}}
if do_reproduce:
    from cmpsim.reproduction import reproduce
    with tempfile.TemporaryDirectory() as tmp:
        t0 = time.perf_counter()
        rep = reproduce(out=tmp, grid="default", progress=False)
        out["reproduce"] = {"wall_s": time.perf_counter() - t0, "solve_s": rep.solve_s,
                            "factorizations": rep.factorizations, "equilibria": rep.equilibria}
print("RESULT " + json.dumps(out))
"""


def install_baseline(tmp: Path) -> Path:
    """cmpsim 0.1.0 from git history into ``tmp/site``; returns that directory."""
    src, site = tmp / "src", tmp / "site"
    src.mkdir()
    archive = subprocess.run(["git", "-C", str(REPO), "archive", BASELINE_COMMIT], check=True, capture_output=True).stdout
    subprocess.run(["tar", "-x", "-C", str(src)], input=archive, check=True)
    subprocess.run(
        [sys.executable, "-m", "pip", "install", "-q", "--no-deps", "--target", str(site), str(src)],
        check=True,
    )
    return site


def measure(pythonpath: str | None, repeat: int, reproduce: bool) -> dict:
    env = dict(os.environ)
    if pythonpath:
        env["PYTHONPATH"] = pythonpath  # ahead of this checkout's editable install
    proc = subprocess.run(
        [sys.executable, "-c", CHILD, str(repeat), "1" if reproduce else "0"], env=env, capture_output=True, text=True
    )
    if proc.returncode != 0:
        raise SystemExit(f"measurement failed:\n{proc.stderr}")
    line = next(ln for ln in proc.stdout.splitlines() if ln.startswith("RESULT "))
    return json.loads(line[len("RESULT ") :])


def best_of(old: dict | None, new: dict) -> dict:
    """Merge two measurements of one version: the faster of each case (and of reproduce)."""
    if old is None:
        return new
    for name, case in new["cases"].items():
        if case["cpu_s"] < old["cases"][name]["cpu_s"]:
            old["cases"][name] = case
    if "reproduce" in new and new["reproduce"]["wall_s"] < old["reproduce"]["wall_s"]:
        old["reproduce"] = new["reproduce"]
    return old


def max_rel_diff(a: dict, b: dict) -> tuple[float, str]:
    worst, where = 0.0, ""
    for k, va in a.items():
        vb = b.get(k)
        if vb is None:
            continue
        scale = max(abs(va), abs(vb))
        d = abs(va - vb) / scale if scale > 0 else 0.0
        if d > worst:
            worst, where = d, k
    return worst, where


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--repeat", type=int, default=5)
    ap.add_argument("--rounds", type=int, default=2, help="alternating rounds of 0.1.0 and now (best kept)")
    ap.add_argument("--no-reproduce", action="store_true", help="skip the two `cmpsim reproduce` runs (~30 s)")
    ap.add_argument("--rtol", type=float, default=1e-6)
    ap.add_argument("--json", type=Path, help="also write both measurements to this file")
    args = ap.parse_args()
    # the two versions alternate, round after round, and each keeps its best: a change of the
    # load on a shared machine then hits both alike instead of whichever ran second
    base = now = None
    with tempfile.TemporaryDirectory() as tmp:
        site = install_baseline(Path(tmp))
        for _ in range(args.rounds):
            base = best_of(base, measure(str(site), args.repeat, not args.no_reproduce))
            now = best_of(now, measure(None, args.repeat, not args.no_reproduce))
        assert Path(base["file"]).is_relative_to(site), base["file"]
    print(f"cmpsim {base['version']} (commit {BASELINE_COMMIT}) vs this checkout ({now['version']}), CPU time, best of {args.repeat}")
    print(f"{'case':<30} {'0.1.0':>10} {'now':>10} {'speed-up':>9} {'LU 0.1.0':>9} {'LU now':>7}  max rel diff")
    ok = True
    for name, b in base["cases"].items():
        n = now["cases"][name]
        diff, key = max_rel_diff(b["values"], n["values"])
        ok &= diff <= args.rtol
        print(
            f"{name:<30} {1e3 * b['cpu_s']:>8.1f}ms {1e3 * n['cpu_s']:>8.1f}ms {b['cpu_s'] / n['cpu_s']:>8.2f}x "
            f"{b['factorizations']:>9d} {n['factorizations']:>7d}  {diff:.1e} ({key})"
        )
    for name, n in now["cases"].items():
        if name not in base["cases"]:
            print(f"{name:<30} {'-':>10} {1e3 * n['cpu_s']:>8.1f}ms {'':>9} {'':>9} {n['factorizations']:>7d}  (new model)")
    for label, d in (("0.1.0", base), ("now", now)):
        c48, c96 = d["cases"]["lep 48x128"], d["cases"]["lep 96x256"]
        p = math.log(c96["cpu_s"] / c48["cpu_s"]) / math.log(c96["cells"] / c48["cells"])
        print(f"cost growth 48x128 -> 96x256, {label}: N^{p:.2f}")
    if "reproduce" in now:
        rb, rn = base["reproduce"], now["reproduce"]
        print(
            f"cmpsim reproduce: LU {rb['factorizations']} -> {rn['factorizations']}, wall {rb['wall_s']:.1f} s -> "
            f"{rn['wall_s']:.1f} s ({rb['wall_s'] / rn['wall_s']:.2f}x), solving {rb['solve_s']:.1f} s -> {rn['solve_s']:.1f} s "
            f"({rb['solve_s'] / rn['solve_s']:.2f}x)"
        )
    # ---- the goals of issue 15, as ratios measured in this run
    sp = {name: base["cases"][name]["cpu_s"] / now["cases"][name]["cpu_s"] for name in base["cases"]}
    c48, c96 = now["cases"]["lep 48x128"], now["cases"]["lep 96x256"]
    growth = math.log(c96["cpu_s"] / c48["cpu_s"]) / math.log(c96["cells"] / c48["cells"])
    goals = [
        ("LEP default >= 2x", sp["lep default"] >= 2.0, f"{sp['lep default']:.2f}x"),
        ("LEP default <= 2 LU", now["cases"]["lep default"]["factorizations"] <= 2, str(now["cases"]["lep default"]["factorizations"])),
        ("hydrodynamic cold >= 3x", sp["hydrodynamic cold"] >= 3.0, f"{sp['hydrodynamic cold']:.2f}x"),
        ("96x256 >= 2.5x", sp["lep 96x256"] >= 2.5, f"{sp['lep 96x256']:.2f}x"),
        ("growth 48x128 -> 96x256 <= N^1.1", growth <= 1.1, f"N^{growth:.2f}"),
    ]
    if "reproduce" in now:
        rb, rn = base["reproduce"], now["reproduce"]
        goals += [
            ("reproduce <= 260 LU", rn["factorizations"] <= 260, f"{rn['factorizations']} ({rn['factorizations'] / rn['equilibria']:.2f} per equilibrium)"),
            ("reproduce >= 2x wall", rb["wall_s"] / rn["wall_s"] >= 2.0, f"{rb['wall_s'] / rn['wall_s']:.2f}x"),
        ]
    print("goals (issue 15):")
    for label, met, value in goals:
        print(f"  {'met    ' if met else 'NOT met'}  {label:<34} {value}")
    print(f"same answers (every scalar within {args.rtol:g} relative): {ok}")
    if args.json:
        args.json.write_text(json.dumps({"baseline": base, "now": now}, indent=1))
    if not ok:
        raise SystemExit(1)


if __name__ == "__main__":
    main()
