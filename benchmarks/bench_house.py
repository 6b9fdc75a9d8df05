"""The house of issue 22 costs nothing: this checkout against b10a4ba, measured in one run.

Run: python benchmarks/bench_house.py [--repeat 5] [--rounds 3] [--baseline-src DIR]

Two measurements, both as ratios (never absolute times):

1. **Equilibria, this checkout vs b10a4ba.** The source of b10a4ba (the commit before the
   models registry and the split of ``equilibrium.py`` / ``compliance.py``) is taken from this
   repository's history (``git archive``; or ``--baseline-src``, a checkout's ``src`` folder) and
   put first on ``PYTHONPATH`` of a child process; this checkout runs in another child of the
   same interpreter (same numpy, scipy, SuperLU). The two alternate for ``--rounds`` rounds and
   each keeps its best CPU time (``time.process_time``, best of ``--repeat`` solves after one
   untimed), so a change of load on the shared machine hits both alike. Cases:
   ``default`` (``Config.default()``: Newtonian, Gumbel, Winkler pad; the issue's target),
   ``paper`` (``Config.paper()``, rigid pad) and ``layer`` (``Config.paper()`` with
   ``pad_compliance = "layer"``, where GMRES runs). The scalars must agree (``--rtol``).
2. **GMRES of the layered pad, scipy vs hand-written.** In this checkout, the Newton systems of
   one equilibrium of the coupled (phi, w) solve of the layered pad (``Config.paper()`` with
   ``pad_compliance = "layer"``, default grid) are solved with the hand-written unrestarted
   GMRES :func:`cmpsim.operators.compliance._gmres` and with ``scipy.sparse.linalg.gmres`` (same Krylov
   space: ``restart`` = 200, one cycle, same relative tolerance), alternately, best of
   ``--repeat`` each. The hand-written one stays only while scipy's is slower here.
"""

from __future__ import annotations

import argparse
import json
import os
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import numpy as np

BASELINE = "b10a4ba"
REPO = Path(__file__).resolve().parents[1]

#: Run by each version's child process: prints one JSON line of CPU times and scalars.
CHILD = r"""
import json, sys, time, warnings
warnings.simplefilter("ignore")
import cmpsim
from cmpsim.inputs.config import Config
repeat = int(sys.argv[1])
cases = {
    "default": Config.default(),
    "paper": Config.paper(),
    "layer": Config.paper().replace(pad_compliance="layer"),
}
out = {"file": cmpsim.__file__, "cases": {}}
for name, cfg in cases.items():
    res = cmpsim.solve(cfg, relative=False)  # imports, caches
    times = []
    for _ in range(repeat):
        t = time.process_time()
        cmpsim.solve(cfg, relative=False)
        times.append(time.process_time() - t)
    best = min(times)
    values = {k: float(v) for k, v in res.scalars.items() if isinstance(v, float)}
    out["cases"][name] = {"cpu_s": best, "iterations": int(res.iterations), "values": values}
print("RESULT " + json.dumps(out))
"""

#: Not results: solver diagnostics.
DIAGNOSTICS = {"load_residual", "moment_residual"}


def baseline_src(tmp: Path) -> Path:
    """The ``src`` folder of b10a4ba, extracted from git history into ``tmp``."""
    archive = subprocess.run(["git", "-C", str(REPO), "archive", BASELINE, "src"], check=True, capture_output=True).stdout
    subprocess.run(["tar", "-x", "-C", str(tmp)], input=archive, check=True)
    return tmp / "src"


def run_child(pythonpath: Path | None, repeat: int) -> dict:
    env = dict(os.environ)
    if pythonpath is not None:
        env["PYTHONPATH"] = str(pythonpath)  # ahead of this checkout's editable install
    proc = subprocess.run([sys.executable, "-c", CHILD, str(repeat)], env=env, capture_output=True, text=True)
    if proc.returncode != 0:
        raise SystemExit(f"measurement failed:\n{proc.stderr}")
    line = next(ln for ln in proc.stdout.splitlines() if ln.startswith("RESULT "))
    return json.loads(line[len("RESULT ") :])


def keep_best(kept: dict | None, new: dict) -> dict:
    if kept is not None:
        for name, case in new["cases"].items():
            if case["cpu_s"] < kept["cases"][name]["cpu_s"]:
                kept["cases"][name] = case
        return kept
    return new


def scipy_gmres(matvec, b, x0, rtol: float, max_iter: int) -> np.ndarray:
    """The same solve as :func:`cmpsim.operators.compliance._gmres` by ``scipy.sparse.linalg.gmres`` (no restart)."""
    from scipy.sparse.linalg import LinearOperator, gmres

    op = LinearOperator((b.size, b.size), matvec=matvec, dtype=float)
    x, info = gmres(op, b, x0=x0, rtol=rtol, atol=0.0, restart=max_iter, maxiter=1)
    if info > 0:
        raise ValueError(f"scipy GMRES did not converge in {max_iter} iterations")
    return x


def bench_gmres(repeat: int) -> tuple[float, float, float, int]:
    """(best scipy s, best hand-written s, max relative difference of the steps, Newton systems) on the layered pad."""
    from cmpsim.operators import compliance
    from cmpsim.inputs.config import Config
    from cmpsim.solver.equilibrium import solve_equilibrium
    from cmpsim.solver.model import build_problem

    problem = build_problem(Config.paper().replace(pad_compliance="layer"))
    systems = []
    real = compliance.CoupledLinearisation._solve_layer

    def record(lin, R, G):  # the Newton systems of one equilibrium
        systems.append((lin, R.copy(), G.copy()))
        return real(lin, R, G)

    compliance.CoupledLinearisation._solve_layer = record
    try:
        solve_equilibrium(problem)
    finally:
        compliance.CoupledLinearisation._solve_layer = real
    hand = compliance._gmres

    def solve_all(gmres):
        compliance._gmres = gmres
        try:
            t = time.process_time()
            steps = [lin._solve_layer(R, G) for lin, R, G in systems]
            return time.process_time() - t, steps
        finally:
            compliance._gmres = hand

    best_scipy = best_hand = np.inf
    diff = 0.0
    for _ in range(repeat):
        t1, a = solve_all(scipy_gmres)
        t2, b = solve_all(hand)
        best_scipy, best_hand = min(best_scipy, t1), min(best_hand, t2)
        for (pa, wa), (pb, wb) in zip(a, b):
            diff = max(diff, float(np.max(np.abs(pa - pb)) / np.max(np.abs(pb))), float(np.max(np.abs(wa - wb)) / np.max(np.abs(wb))))
    return best_scipy, best_hand, diff, len(systems)


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--repeat", type=int, default=5)
    ap.add_argument("--rounds", type=int, default=3, help="alternating rounds of b10a4ba and this checkout (best kept)")
    ap.add_argument("--baseline-src", type=Path, help="the src folder of a b10a4ba checkout (default: git archive)")
    ap.add_argument("--rtol", type=float, default=1e-9, help="largest relative difference of the scalars")
    args = ap.parse_args()
    with tempfile.TemporaryDirectory() as tmp:
        src = args.baseline_src or baseline_src(Path(tmp))
        base = now = None
        for _ in range(args.rounds):
            base = keep_best(base, run_child(src, args.repeat))
            now = keep_best(now, run_child(None, args.repeat))
        assert Path(base["file"]).is_relative_to(src.resolve()), base["file"]
    g_scipy, g_hand, g_diff, n_sys = bench_gmres(args.repeat)
    print(f"this checkout vs {BASELINE}: CPU time, best of {args.repeat} x {args.rounds} alternating rounds")
    print(f"{'case':<10} {BASELINE:>10} {'now':>10} {'now/base':>9}  max rel diff of the scalars")
    ok = True
    for name, b in base["cases"].items():
        n = now["cases"][name]
        diff = max(
            (abs(v - n["values"][k]) / max(abs(v), 1e-300) for k, v in b["values"].items() if k in n["values"] and k not in DIAGNOSTICS),
            default=0.0,
        )
        ok &= diff <= args.rtol
        print(f"{name:<10} {1e3 * b['cpu_s']:>8.1f}ms {1e3 * n['cpu_s']:>8.1f}ms {n['cpu_s'] / b['cpu_s']:>9.3f}  {diff:.1e}")
    print(
        f"GMRES of the layered pad ({n_sys} Newton systems of one equilibrium): scipy {1e3 * g_scipy:.1f} ms, "
        f"hand-written {1e3 * g_hand:.1f} ms, scipy/hand = {g_scipy / g_hand:.3f}; steps agree to {g_diff:.1e}"
    )
    ratio = now["cases"]["default"]["cpu_s"] / base["cases"]["default"]["cpu_s"]
    print(f"RESULT default equilibrium now/{BASELINE} = {ratio:.3f}; GMRES scipy/hand = {g_scipy / g_hand:.3f}; scalars {'OK' if ok else 'DIFFER'}")
    if not ok:
        raise SystemExit(1)


if __name__ == "__main__":
    main()
