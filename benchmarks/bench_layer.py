"""The layered pad (``pad_compliance = "layer"``) against 933f237 (before issue 23's layered-pad work), in one run.

Run: python benchmarks/bench_layer.py [--repeat 3] [--rounds 2] (about 5 min on a shared 2-core VM).

The baseline's ``src/cmpsim`` is extracted from this repository's history into a temporary
directory and put first on the ``PYTHONPATH`` of a child process of the same interpreter (as in
``bench_scale.py``, whose helpers this uses). The two versions alternate for ``--rounds``
rounds; each case keeps its best CPU time (``time.process_time``): ``warm`` with the deflection
operator already built, ``cold`` with it rebuilt (the first layered solve of a process on a
grid). The ratios are what to compare across machines, never the absolute times.

Cases (3 inches unless said; 300 mm: ``wafer_diameter = 300 mm``, ``centre_distance = 0.2 m``):
the paper's model and the default model on the layered pad, on the equal-ring 24x64 grid and on
the default preset (edge-graded for the default model), and the short-coupling limit (every
thickness and modulus x 0.03: the Winkler bed's answer is expected, fluid share +15 %) on the
graded default preset. It prints times, ratios, factorisations, the fluid load share and how
far the answers on equal rings moved (the former operator's truncation error). The default
model at 300 mm is left out: its layered solve does not converge in either version
(docs/limitations.md).
"""

from __future__ import annotations

import argparse
import sys
import tempfile
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parent))
from bench_scale import extract_baseline, measure  # noqa: E402

BASELINE = "933f237"

CHILD = r"""
import json, sys, time
import cmpsim
try:
    from cmpsim.numerics.padgrid import _LAYER_OPERATORS as LAYER_CACHE  # after issue 23
except ImportError:
    from cmpsim.physics.padstack import _LAYER_OPERATORS as LAYER_CACHE
from cmpsim.inputs.config import Config

repeat, cases = int(sys.argv[1]), json.loads(sys.argv[2])
cmpsim.solve(Config.default().replace(grid="coarse"), relative=False)  # imports, contact tables
out = {}
for name, (preset, overrides) in cases.items():
    cfg = Config.preset(preset).replace(pad_compliance="layer", **overrides)
    row = {}
    for label in ("cold", "warm"):
        times = []
        for _ in range(repeat):
            if label == "cold":
                LAYER_CACHE.clear()
            t = time.process_time()
            r = cmpsim.solve(cfg, relative=False)
            times.append(time.process_time() - t)
        row[label + "_s"] = min(times)
    row.update(factorizations=int(r.scalars["factorizations"]), fluid=float(r.fluid_load_fraction),
               rate=float(r.removal_rate_mean), wiwnu=float(r.scalars["within_wafer_nonuniformity"]),
               grid=f"{r.grid.n_r}x{r.grid.n_theta}")
    out[name] = row
print("RESULT " + json.dumps(out))
"""

_SHORT = {"pad_thickness": 1.27e-3 * 0.03, "subpad_thickness": 1.27e-3 * 0.03, "pad_bulk_modulus": 300e6 * 0.03, "subpad_modulus": 2.3e6 * 0.03}
CASES = {
    "paper 3in 24x64": ("paper", {"grid": "24x64"}),
    "paper 300mm default": ("paper", {"wafer_diameter": 0.3, "centre_distance": 0.2}),
    "default 3in 24x64": ("default", {"grid": "24x64"}),
    "default 3in preset": ("default", {}),
    "short coupling, preset": ("default", dict(_SHORT)),
}


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--repeat", type=int, default=3)
    ap.add_argument("--rounds", type=int, default=2)
    args = ap.parse_args(argv)
    best: dict = {"base": None, "now": None}
    with tempfile.TemporaryDirectory() as tmp:
        base_path = str(extract_baseline(Path(tmp), BASELINE))
        for _ in range(args.rounds):
            for key, path in (("base", base_path), ("now", None)):
                got = measure(path, args.repeat, CASES, CHILD)
                if best[key] is None:
                    best[key] = got
                else:
                    for name, row in got.items():
                        for t in ("cold_s", "warm_s"):
                            best[key][name][t] = min(best[key][name][t], row[t])
    print(f"layered pad, CPU time, best of {args.repeat} x {args.rounds} rounds; {BASELINE} = before issue 23's layered-pad work")
    print(f"{'case':<24} {'grid':>7} {'cold ' + BASELINE:>13} {'cold now':>9} {'ratio':>6} {'warm ' + BASELINE:>13} {'warm now':>9} {'ratio':>6}  LU  fluid share (base -> now)")
    for name in CASES:
        b, n = best["base"][name], best["now"][name]
        print(f"{name:<24} {n['grid']:>7} {b['cold_s']:13.3f} {n['cold_s']:9.3f} {b['cold_s'] / n['cold_s']:6.2f} "
              f"{b['warm_s']:13.3f} {n['warm_s']:9.3f} {b['warm_s'] / n['warm_s']:6.2f}  {b['factorizations']}->{n['factorizations']}"
              f"  {b['fluid']:+.4f} -> {n['fluid']:+.4f}")
    for name in ("paper 3in 24x64", "default 3in 24x64"):
        b, n = best["base"][name], best["now"][name]
        print(f"RESULT {name}: answers moved by rate {n['rate'] / b['rate'] - 1:+.2e} (relative), non-uniformity "
              f"{b['wiwnu']:.4f} -> {n['wiwnu']:.4f}, fluid share {b['fluid']:+.4f} -> {n['fluid']:+.4f}")
    for name in CASES:
        print(f"RESULT {name}: {BASELINE} / now = {best['base'][name]['cold_s'] / best['now'][name]['cold_s']:.2f} (cold), "
              f"{best['base'][name]['warm_s'] / best['now'][name]['warm_s']:.2f} (warm)")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
