"""The membrane carrier's solve against the Anderson fixed point it replaced (main at 0042658), in one run.

Run: python benchmarks/bench_membrane.py [--repeat 3] [--rounds 2] [--layered] [--preset] [--json FILE]
(about 3 min on a shared 2-core VM; ``--layered`` adds a 300 mm head on the layered pad, a few
minutes more for the baseline; ``--preset`` the 300mm preset's equilibrium and tune-zones, with
``--baseline 72d45d2`` (the last commit before the preset's tuning finished: its tuning takes
about 7 min and fails, and is reported as failed), or a commit before issue 32 to compare the smooth
preset with the grooved one (the tuning with the ring is then reported as failed).

The baseline's ``src/cmpsim`` is taken from this repository's history (``git archive 0042658``;
``--baseline REF`` for another) into a temporary folder that a child process of the same
interpreter puts first on its ``PYTHONPATH``: the same numpy, scipy and SuperLU, only cmpsim's
code differs. The two versions take turns for ``--rounds`` rounds and each case keeps its best
CPU time (``time.process_time``, best of ``--repeat`` in a warm process; a tuning once a round),
so that other work on a shared machine hits both alike. The ratios baseline / now are what to
compare across machines, never the absolute times.

Cases (the default model with ``carrier = "membrane"`` on the default grid and the Winkler pad;
300 mm: ``wafer_diameter = 300 mm``, ``centre_distance = 0.2 m``):

* ``3in one zone``: the default operating point, cold;
* ``300mm one zone``: the issue's cost criterion (one 300 mm membrane equilibrium, <= 1 s);
* ``300mm five zones``: zones 50, 100, 130, 145, 150 mm at 3, 3, 3.5, 4, 2 psi, cold;
* ``300mm tune-zones``: ``cmpsim.tune_zones`` on the same five zones from uniform pressure
  (the criterion: <= 1 min), with its solves and the tuned non-uniformity;
* ``300mm layered 12x32`` (``--layered``): a 775 um wafer on the layered pad, 12x32 grid.

For each case it prints the CPU times, the ratio, the equilibrium solves of the bending and
the LU factorisations, and the largest relative difference of the scalars between the versions
(both converge the bending to the same tolerance, 1e-6 sigma on the fixed-point residual; the
differences are that tolerance seen through each output).
"""

from __future__ import annotations

import argparse
import json
import os
import subprocess
import sys
import tempfile
from pathlib import Path

from bench_versus_0_1 import max_rel_diff  # the largest relative difference of two dicts of scalars

BASELINE = "0042658"
REPO = Path(__file__).resolve().parents[1]
SCALARS = ("film_thickness_center", "attack_angle", "removal_rate_mean", "within_wafer_nonuniformity", "fluid_load_fraction")
BIG = {"wafer_diameter": 0.3, "centre_distance": 0.2, "carrier": "membrane"}
FIVE = {**BIG, "zone_radii": "50,100,130,145,150 mm"}
CASES = {
    "3in one zone": ("solve", {"carrier": "membrane"}),
    "300mm one zone": ("solve", BIG),
    "300mm five zones": ("solve", {**FIVE, "zone_pressures": "3,3,3.5,4,2 psi"}),
    "300mm tune-zones": ("tune", FIVE),
}
LAYERED = {"300mm layered 12x32": ("solve", {**BIG, "pad_compliance": "layer", "grid": "12x32", "wafer_thickness": "775 um"})}
#: ``--preset``: the 300mm preset (layered IC1000/Suba IV, five zones, ring; default grid 40x64), one
#: equilibrium and tune-zones from uniform zones. A baseline without the preset, or whose tuning
#: fails, reports the error in place of a time.
#: Since issue 32 the preset's pad is grooved, and ``300mm preset tune-zones --ring`` tunes the ring with the
#: zones (``tune_zones(ring=True)``; a baseline before issue 32 reports it as an error).
PRESET = {
    "300mm preset": ("solve", {"preset": "300mm"}),
    "300mm preset tune-zones": ("tune", {"preset": "300mm"}),
    "300mm preset tune-zones --ring": ("tune_ring", {"preset": "300mm"}),
}

#: What each version's child process runs; prints one line "RESULT {json}".
CHILD = r"""
import json, sys, time
import cmpsim
from cmpsim.inputs.config import Config

repeat, cases, keep = int(sys.argv[1]), json.loads(sys.argv[2]), json.loads(sys.argv[3])
cmpsim.solve(Config.default().replace(grid="coarse"), relative=False)  # imports, contact tables
rows = {}
for name, (kind, changes) in cases.items():
    changes = dict(changes)
    try:
        cfg = (Config.preset(changes.pop("preset")) if "preset" in changes else Config.default()).replace(**changes)
        best = None
        for _ in range(1 if kind.startswith("tune") else repeat):
            start = time.process_time()
            if kind == "solve":
                out = cmpsim.solve(cfg, relative=False)
            else:
                out = cmpsim.tune_zones(cfg, ring=True) if kind == "tune_ring" else cmpsim.tune_zones(cfg)
            spent = time.process_time() - start
            best = spent if best is None else min(best, spent)
    except Exception as exc:  # a baseline without this case, or one that fails it
        rows[name] = {"error": f"{type(exc).__name__}: {str(exc)[:120]}", "cpu_s": float("inf"), "solves": 0, "scalars": {}}
        continue
    if kind.startswith("tune"):
        row = {"solves": out.solves, "scalars": {"within_wafer_nonuniformity": out.within_wafer_nonuniformity}}
    else:
        carrier = out.problem.carrier
        row = {"solves": carrier.bending_solves, "lu": int(out.scalars["factorizations"]),
               "scalars": {k: out.scalars[k] for k in keep}}
    row["cpu_s"] = best
    rows[name] = row
print("RESULT " + json.dumps(rows))
"""


def extract(ref: str, into: Path) -> Path:
    """The ``src`` folder of commit ``ref`` of this repository, unpacked under ``into``."""
    tar = subprocess.run(["git", "-C", str(REPO), "archive", ref, "src"], check=True, capture_output=True).stdout
    subprocess.run(["tar", "-x", "-C", str(into)], input=tar, check=True)
    return into / "src"


def child(src: Path, repeat: int, cases: dict) -> dict:
    """Run the cases in a fresh interpreter with ``src`` first on its path."""
    env = dict(os.environ, PYTHONPATH=str(src))
    proc = subprocess.run(
        [sys.executable, "-c", CHILD, str(repeat), json.dumps(cases), json.dumps(SCALARS)],
        env=env, capture_output=True, text=True, check=False,
    )
    line = [x for x in proc.stdout.splitlines() if x.startswith("RESULT ")]
    if proc.returncode or not line:
        raise SystemExit(f"the child with {src} failed:\n{proc.stderr[-3000:]}")
    return json.loads(line[-1][len("RESULT "):])


def merge(kept: dict | None, new: dict) -> dict:
    """Keep each case's smaller CPU time over the rounds."""
    if kept is None:
        return new
    for name, row in new.items():
        if row["cpu_s"] < kept[name]["cpu_s"]:
            kept[name] = row
    return kept


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--repeat", type=int, default=3)
    ap.add_argument("--rounds", type=int, default=2)
    ap.add_argument("--baseline", default=BASELINE, help="git ref of the baseline (default: the Anderson solver, %(default)s)")
    ap.add_argument("--layered", action="store_true", help="add the 300 mm head on the layered pad")
    ap.add_argument("--preset", action="store_true", help="add the 300mm preset: one equilibrium and tune-zones (use --baseline 72d45d2 or later)")
    ap.add_argument("--json", help="write the measurements to this file")
    args = ap.parse_args()
    cases = {**CASES, **(LAYERED if args.layered else {}), **(PRESET if args.preset else {})}
    with tempfile.TemporaryDirectory() as tmp:
        old_src = extract(args.baseline, Path(tmp))
        old = new = None
        for _ in range(args.rounds):
            old = merge(old, child(old_src, args.repeat, cases))
            new = merge(new, child(REPO / "src", args.repeat, cases))
    print(f"membrane carrier, CPU time, best of {args.repeat} x {args.rounds} rounds (tuning: best of {args.rounds})")
    print(f"{'case':30s} {args.baseline:>9s} {'now':>9s} {'ratio':>7s}  {'solves':>9s}  {'LU':>9s}  largest scalar difference")
    for name in cases:
        a, b = old[name], new[name]
        if "error" in a or "error" in b:
            said = [f"{who}: {r['error'] if 'error' in r else format(r['cpu_s'], '.3f') + ' s'}" for who, r in ((args.baseline, a), ("now", b))]
            print(f"{name:30s} " + "; ".join(said))
            continue
        diff, which = max_rel_diff(a["scalars"], b["scalars"])
        lu = f"{a['lu']:>4d}>{b['lu']:<4d}" if "lu" in a else " " * 9
        print(
            f"{name:30s} {a['cpu_s']:8.3f}s {b['cpu_s']:8.3f}s {a['cpu_s'] / b['cpu_s']:6.2f}x  "
            f"{a['solves']:>4d}>{b['solves']:<4d}  {lu}  {diff:.1e} ({which})"
        )
    if "300mm tune-zones" in new:
        t = new["300mm tune-zones"]
        print(f"tune-zones 300 mm, five zones: {t['cpu_s']:.2f} s CPU, {t['solves']} solves, non-uniformity "
              f"{t['scalars']['within_wafer_nonuniformity']:.3e} (criterion: <= 60 s)")
    for name in PRESET:
        if name in new and "error" not in new[name]:
            t = new[name]
            extra = f", {t['solves']} solves, non-uniformity {t['scalars']['within_wafer_nonuniformity']:.3e}" if "tune" in name else ""
            print(f"{name}: {t['cpu_s']:.3f} s CPU{extra} (criterion: {'<= 60 s' if 'tune' in name else '<= 1 s'})")
    one = new["300mm one zone"]["cpu_s"]
    print(f"one 300 mm membrane equilibrium: {one:.3f} s CPU (criterion: <= 1 s)")
    if args.json:
        Path(args.json).write_text(json.dumps({"baseline": args.baseline, "old": old, "new": new}, indent=1))


if __name__ == "__main__":
    main()
