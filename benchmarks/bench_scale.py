"""The default model at 300 mm and on the edge-graded grids against b10a4ba (issue 23), in one run.

Run: python benchmarks/bench_scale.py [--repeat 5] [--rounds 3] [--json FILE] (about 15 min on
a shared 2-core VM, most of it b10a4ba's 300 mm fine grid); ``--report FILE`` prints the report
of a ``--json`` file again.

The baseline (commit b10a4ba, before issue 23) is extracted from this repository's history
(``git archive b10a4ba src/cmpsim``) into a temporary directory and put first on the
``PYTHONPATH`` of a child process of the same interpreter: same numpy, scipy and SuperLU, only
cmpsim's own code differs. The two versions alternate for ``--rounds`` rounds and each case
keeps its best CPU time (``time.process_time``, best of ``--repeat`` in a warm process, once
for a case above 2 s); the
ratios are what to compare across machines, never the absolute times.

Cases (default model unless said; 300 mm: ``wafer_diameter = 300 mm``, ``centre_distance =
0.2 m``; ``first``: ``cmpsim.solve(config)`` with its default arguments after the process's
cache of reference solves was emptied, i.e. a first solve including any reference solve):

* ``paper 3in 24x64``: the paper preset, the reference time of the 3-inch criterion;
* ``default 3in 24x64``: the default model on the same equal-ring grid (both versions);
* ``shear-power 3in 24x64``: the same with b10a4ba's default removal law (issue 24 changed the
  default law after b10a4ba), whose scalars must agree within ``--rtol`` (1e-6);
* ``default 3in preset``, ``default 300mm preset``, ``default 300mm fine``: the named grids
  ("default", "fine": edge-graded now, equal rings 24x64 and 48x128 in b10a4ba), warm and
  ``first``;
* ``default 300mm 48x128``: the same equal-ring grid in both versions (the factorisation alone).

It prints the times, the ratios b10a4ba / now, the growth exponent p of cost ~ N^p from the
default preset to the fine one (four times the cells) at 300 mm, the largest relative
difference of the scalars on the shared 3-inch grid, how much the graded default grid moves the
3-inch answers against the equal-ring 24x64 one (that grid's truncation error), and the LU
factorisations of each case.
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

BASELINE_COMMIT = "b10a4ba"
REPO = Path(__file__).resolve().parents[1]

#: The measuring script of each version's child process; prints one JSON line.
CHILD = r"""
import json, sys, time
import cmpsim
import cmpsim.solver.model as model
from cmpsim.inputs.config import Config

repeat, cases = int(sys.argv[1]), json.loads(sys.argv[2])
KEEP = ("removal_rate_mean", "within_wafer_nonuniformity", "h0", "attack_angle", "cross_tilt",
        "film_thickness_center", "film_thickness_min", "fluid_load_fraction", "contact_area_ratio", "shear_stress_mean")
out = {}
for preset in ("paper", "default"):  # warm: contact tables, imports
    cmpsim.solve(Config.preset(preset).replace(grid="coarse"), relative=False)
for name, (preset, overrides, first) in cases.items():
    cfg = Config.preset(preset).replace(**overrides)
    times = []
    for _ in range(repeat):
        t = time.process_time()
        r = cmpsim.solve(cfg, relative=False)
        times.append(time.process_time() - t)
        if times[-1] > 2.0:  # a slow case: once is enough
            break
    row = {"warm_s": min(times), "cells": r.grid.n_r * r.grid.n_theta, "grid": f"{r.grid.n_r}x{r.grid.n_theta}",
           "factorizations": int(r.scalars["factorizations"]), "scalars": {k: r.scalars[k] for k in KEEP}}
    if first:
        model._REFERENCE_CACHE.clear()
        t = time.process_time()
        cmpsim.solve(cfg)
        row["first_s"] = time.process_time() - t
    out[name] = row
print("RESULT " + json.dumps(out))
"""

_300 = {"wafer_diameter": "300 mm", "centre_distance": "0.2 m"}
CASES = {
    "paper 3in 24x64": ("paper", {"grid": "24x64"}, False),
    "default 3in 24x64": ("default", {"grid": "24x64"}, False),
    # b10a4ba's default removal law, for the agreement check: issue 24 made the abrasive law the
    # default after b10a4ba, so the default's removal rate differs from b10a4ba's by the law itself
    "shear-power 3in 24x64": ("default", {"grid": "24x64", "removal_law": "shear_power"}, False),
    "default 3in preset": ("default", {}, True),
    "default 300mm preset": ("default", dict(_300), True),
    "default 300mm fine": ("default", dict(_300, grid="fine"), True),
    "default 300mm 48x128": ("default", dict(_300, grid="48x128"), False),
}


def extract_baseline(tmp: Path, commit: str = BASELINE_COMMIT) -> Path:
    """``src/cmpsim`` of ``commit`` (b10a4ba) into ``tmp``; returns the directory to put on PYTHONPATH."""
    archive = subprocess.run(["git", "-C", str(REPO), "archive", commit, "src/cmpsim"], check=True, capture_output=True).stdout
    subprocess.run(["tar", "-x", "-C", str(tmp)], input=archive, check=True)
    return tmp / "src"


def measure(pythonpath: str | None, repeat: int, cases: dict, child: str = CHILD) -> dict:
    env = dict(os.environ)
    if pythonpath:
        env["PYTHONPATH"] = pythonpath  # ahead of this checkout's editable install
    proc = subprocess.run([sys.executable, "-c", child, str(repeat), json.dumps(cases)], env=env, capture_output=True, text=True)
    if proc.returncode != 0:
        raise SystemExit(f"measurement failed:\n{proc.stderr}")
    line = next(ln for ln in proc.stdout.splitlines() if ln.startswith("RESULT "))
    return json.loads(line[len("RESULT ") :])


def keep_best(old: dict | None, new: dict) -> dict:
    """The faster of two measurements of each case (per timing)."""
    if old is None:
        return new
    for name, row in new.items():
        for key in ("warm_s", "first_s"):
            if key in row:
                old[name][key] = min(old[name][key], row[key])
    return old


def max_rel_diff(a: dict, b: dict) -> tuple[float, str]:
    """Largest relative difference of two scalar dicts (the cross tilt on the attack angle's scale)."""
    worst, which = 0.0, ""
    for k, va in a.items():
        scale = abs(a["attack_angle"]) if k == "cross_tilt" else abs(va)
        d = abs(va - b[k]) / max(scale, 1e-300)
        if d > worst:
            worst, which = d, k
    return worst, which


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--repeat", type=int, default=5, help="timings per case and round (best kept)")
    ap.add_argument("--rounds", type=int, default=3, help="alternating rounds of the two versions")
    ap.add_argument("--rtol", type=float, default=1e-6, help="agreement required on the shared 3-inch grid")
    ap.add_argument("--json", type=Path, help="also write the measurements here")
    ap.add_argument("--report", type=Path, help="print the report of measurements written before by --json (no run)")
    args = ap.parse_args(argv)
    if args.report:
        data = json.loads(args.report.read_text())
        old, new = data["b10a4ba"], data["now"]
    else:
        with tempfile.TemporaryDirectory(prefix="cmpsim-bench-scale-") as tmp:
            base_path = str(extract_baseline(Path(tmp)))
            new = old = None
            for k in range(args.rounds):
                print(f"round {k + 1}/{args.rounds} ...", flush=True)
                old = keep_best(old, measure(base_path, args.repeat, CASES))
                new = keep_best(new, measure(None, args.repeat, CASES))
    print(f"\n{'case':24s} {'grid now':>9s} {'b10a4ba':>9s} {'now':>9s} {'ratio':>7s}   first solve (incl. reference) b10a4ba / now")
    for name in CASES:
        o, n = old[name], new[name]
        first = f"{o['first_s']:.3f} s / {n['first_s']:.3f} s = {o['first_s'] / n['first_s']:.1f}x" if "first_s" in n else ""
        print(f"{name:24s} {n['grid']:>9s} {o['warm_s']:8.4f}s {n['warm_s']:8.4f}s {o['warm_s'] / n['warm_s']:6.1f}x   {first}")
    p = math.log(new["default 300mm fine"]["warm_s"] / new["default 300mm preset"]["warm_s"]) / math.log(
        new["default 300mm fine"]["cells"] / new["default 300mm preset"]["cells"]
    )
    ratio3 = new["default 3in 24x64"]["warm_s"] / new["paper 3in 24x64"]["warm_s"]
    ratio3_old = old["default 3in 24x64"]["warm_s"] / old["paper 3in 24x64"]["warm_s"]
    diff, which = max_rel_diff(old["shear-power 3in 24x64"]["scalars"], new["shear-power 3in 24x64"]["scalars"])
    uniform, graded = new["default 3in 24x64"]["scalars"], new["default 3in preset"]["scalars"]
    moved = ", ".join(f"{k} {100 * (graded[k] - v) / abs(v):+.2f} %" for k, v in uniform.items())
    wiwnu = {k: new[k]["scalars"]["within_wafer_nonuniformity"] for k in ("default 300mm preset", "default 300mm fine", "default 300mm 48x128")}
    print(f"\ngrowth 300 mm default -> fine (x{new['default 300mm fine']['cells'] / new['default 300mm preset']['cells']:.1f} cells): cost ~ N^{p:.2f}")
    print(f"default / paper preset at 3 in on 24x64: {ratio3:.2f}x now, {ratio3_old:.2f}x in b10a4ba")
    ok = diff <= args.rtol
    print(f"3 in default (shear-power law, b10a4ba's default) on 24x64, now against b10a4ba: largest relative difference {diff:.1e} ({which}) {'OK' if ok else 'FAIL'} (tolerance {args.rtol:g})")
    print(f"3 in default, graded default grid (31x64) against equal-ring 24x64: {moved}")
    print("300 mm WIWNU: " + ", ".join(f"{k.split()[-1]} {100 * v:.3f} %" for k, v in wiwnu.items()))
    print("LU factorisations b10a4ba / now: " + ", ".join(f"{k} {old[k]['factorizations']}/{new[k]['factorizations']}" for k in CASES))
    if args.json:
        args.json.write_text(json.dumps({"b10a4ba": old, "now": new}, indent=1))
    return 0 if ok else 1


if __name__ == "__main__":
    raise SystemExit(main())
