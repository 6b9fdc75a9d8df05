"""The default model against the paper preset on the same grid, and the joint Newton against the nested solve (issue 23).

Run: python benchmarks/bench_joint.py [--repeat 15] [--json FILE] (about 1 min).

One process, the cases alternating round by round, each keeping its best CPU time
(``time.process_time`` of ``cmpsim.solve(config, relative=False)``, warm process):

* ``paper 3in 24x64``: the paper preset, the reference time of issue 23's 3-inch criterion
  (the default model at most 1.5x the paper preset's time on the same grid);
* ``default 3in 24x64``: the default model (Winkler pad, Newtonian slurry, abrasive law) on the
  same equal-ring grid, solved by the joint Newton (``cmpsim.operators.jointnewton``);
* ``... nested``: the same with ``WinklerPad.joint = False`` (the nested solve: a coupled state
  at every trial position, a factorisation for every Jacobian), also on the default grid at
  3 in and at 300 mm (``wafer_diameter = 300 mm``, ``centre_distance = 0.2 m``).

It prints the times, the LU factorisations and Newton steps, the ratio default / paper preset,
the speed-up of the joint Newton over the nested solve and the largest relative difference of
the scalars between the two (the cross tilt on the attack angle's scale); exit status 1 if a
difference exceeds ``--rtol`` (1e-6, the issue's tolerance on the default's answers).
"""

from __future__ import annotations

import argparse
import json
import sys
import time
from pathlib import Path

import cmpsim
from cmpsim.inputs.config import Config
from cmpsim.models.pads import WinklerPad

sys.path.insert(0, str(Path(__file__).resolve().parent))
from bench_scale import max_rel_diff  # noqa: E402  (the same comparison of scalars)

KEEP = ("removal_rate_mean", "within_wafer_nonuniformity", "h0", "attack_angle", "cross_tilt",
        "film_thickness_center", "film_thickness_min", "fluid_load_fraction", "contact_area_ratio", "shear_stress_mean")
_300 = {"wafer_diameter": "300 mm", "centre_distance": "0.2 m"}
#: name -> (preset, overrides, joint Newton on)
CASES = {
    "paper 3in 24x64": ("paper", {"grid": "24x64"}, True),
    "default 3in 24x64": ("default", {"grid": "24x64"}, True),
    "default 3in 24x64 nested": ("default", {"grid": "24x64"}, False),
    "default 3in preset": ("default", {}, True),
    "default 3in preset nested": ("default", {}, False),
    "default 300mm preset": ("default", dict(_300), True),
    "default 300mm preset nested": ("default", dict(_300), False),
}
#: joint case -> its nested twin
PAIRS = {name: f"{name} nested" for name in CASES if f"{name} nested" in CASES}


def measure(repeat: int) -> dict:
    configs = {name: Config.preset(preset).replace(**overrides) for name, (preset, overrides, _) in CASES.items()}
    for cfg in configs.values():  # warm: imports, contact tables, grids
        cmpsim.solve(cfg, relative=False)
    rows = {name: {"cpu_s": float("inf")} for name in CASES}
    try:
        for _ in range(repeat):
            for name, (_, _, joint) in CASES.items():
                WinklerPad.joint = joint
                t = time.process_time()
                r = cmpsim.solve(configs[name], relative=False)
                cpu = time.process_time() - t
                row = rows[name]
                row["cpu_s"] = min(row["cpu_s"], cpu)
                row.update(grid=f"{r.grid.n_r}x{r.grid.n_theta}", factorizations=int(r.scalars["factorizations"]),
                           iterations=int(r.scalars["iterations"]), scalars={k: float(r.scalars[k]) for k in KEEP})
    finally:
        WinklerPad.joint = True
    return rows


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--repeat", type=int, default=15, help="alternating rounds (best CPU time kept)")
    ap.add_argument("--rtol", type=float, default=1e-6, help="agreement required between the joint and the nested solve")
    ap.add_argument("--json", type=Path, help="also write the measurements here")
    args = ap.parse_args(argv)
    rows = measure(args.repeat)
    print(f"{'case':30s} {'grid':>7s} {'CPU':>9s} {'LU':>3s} {'steps':>5s}")
    for name, row in rows.items():
        print(f"{name:30s} {row['grid']:>7s} {1e3 * row['cpu_s']:7.2f}ms {row['factorizations']:3d} {row['iterations']:5d}")
    paper = rows["paper 3in 24x64"]["cpu_s"]
    print(f"\ndefault / paper preset at 3 in on 24x64: {rows['default 3in 24x64']['cpu_s'] / paper:.2f}x "
          f"(nested: {rows['default 3in 24x64 nested']['cpu_s'] / paper:.2f}x; goal <= 1.5x)")
    ok = True
    for joint, nested in PAIRS.items():
        diff, which = max_rel_diff(rows[nested]["scalars"], rows[joint]["scalars"])
        ok &= diff <= args.rtol
        print(f"{joint}: joint Newton {rows[nested]['cpu_s'] / rows[joint]['cpu_s']:.2f}x faster than nested, "
              f"LU {rows[nested]['factorizations']} -> {rows[joint]['factorizations']}, "
              f"largest relative difference {diff:.1e} ({which}) {'OK' if diff <= args.rtol else 'FAIL'}")
    if args.json:
        args.json.write_text(json.dumps(rows, indent=1))
    return 0 if ok else 1


if __name__ == "__main__":
    sys.exit(main())
