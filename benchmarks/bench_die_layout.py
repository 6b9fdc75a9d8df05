"""The whole `cmpsim die` run on a real layout against KLayout's TilingProcessor computing the densities alone.

    python benchmarks/bench_die_layout.py [--macro FILE.gds.gz] [--steps 8] [--pitch 1170e-6 764.3e-6] [--window 20e-6]
                                          [--layer 68/20] [--process oxide]

The chip: the real macro (../shared/layouts, SKY130, Apache-2.0) stepped N x N by a new top cell
(benchmarks/bench_layout.py's `step_chip`; default pitch 1170 x 764.3 um: 8.54 x 5.70 mm with gaps,
427 x 286 windows of 20 um). Timed in the same run:

(a) `cmpsim die CHIP --layer L --window W --process P --spec ... --out DIR --json` in a fresh
    process (interpreter start, imports, extraction, wafer solve at --set grid=coarse, die model,
    hotspots, die.nc, PNG maps, CSV, lyrdb, JSON);
(b) KLayout's TilingProcessor: read + the density of every window (tile = window, 2 threads).

Prints both times and the ratio (a)/(b) (the issue's target: at most 0.25).
"""

from __future__ import annotations

import argparse
import gzip
import json
import shutil
import subprocess
import sys
import tempfile
import time
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parent))
from bench_layout import DEFAULT_MACRO, klayout_densities, step_chip  # noqa: E402


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--macro", type=Path, default=DEFAULT_MACRO)
    ap.add_argument("--layer", default="68/20")
    ap.add_argument("--window", type=float, default=20e-6)
    ap.add_argument("--steps", type=int, default=8)
    ap.add_argument("--pitch", type=float, nargs=2, default=(1170e-6, 764.3e-6), metavar=("PX", "PY"))
    ap.add_argument("--process", default="oxide", choices=["oxide", "copper"])
    ap.add_argument("--grid", default="coarse", help="grid of the wafer solve (default coarse)")
    args = ap.parse_args(argv)
    if not args.macro.is_file():
        sys.exit(f"macro {args.macro} not found (give --macro)")
    tmp = Path(tempfile.mkdtemp(prefix="bench_die_layout_"))
    try:
        gds = tmp / "macro.gds"
        with (gzip.open(args.macro, "rb") if args.macro.suffix == ".gz" else open(args.macro, "rb")) as src, open(gds, "wb") as dst:
            shutil.copyfileobj(src, dst)
        chip = tmp / "chip.gds"
        px, py, _ = step_chip(gds, chip, args.steps, (args.pitch[0] / 1e-6, args.pitch[1] / 1e-6))
        cmd = [sys.executable, "-m", "cmpsim.cli", "die", str(chip), "--layer", args.layer, "--window", f"{args.window}m",
               "--process", args.process, "--set", f"grid={args.grid}", "--spec", "thickness=5nm", "--spec", "step_height=20nm",
               "--spec", "dishing=30nm", "--spec", "erosion=20nm", "--out", str(tmp / "out"), "--json"]
        t = time.perf_counter()
        run = subprocess.run(cmd, capture_output=True, text=True)
        t_cmpsim = time.perf_counter() - t
        if run.returncode != 0:
            sys.exit(f"cmpsim die failed: {run.stderr}")
        d = json.loads(run.stdout)
        w = d["windows"]
        print(f"chip {args.steps} x {args.steps} steps at {px * 1e6:g} x {py * 1e6:g} um: {w['nx']} x {w['ny']} windows of {w['window'] * 1e6:g} um")
        print(f"(a) cmpsim die (whole run: extraction, wafer solve, die model, hotspots, outputs): {t_cmpsim:.2f} s")
        print(f"    {args.process}: thickness range {d['thickness_range'] * 1e9:.3f} nm, {d['hotspot_count']} hotspots, "
              f"time {d['time']:.1f} s, files: {', '.join(sorted(p.name for p in (tmp / 'out').iterdir()))}")
        try:
            import klayout.db  # noqa: F401
        except ImportError:
            print("klayout not installed: no comparison")
            return
        shape = (w["ny"], w["nx"])
        t = time.perf_counter()
        klayout_densities(chip, [tuple(int(v) for v in args.layer.split("/"))], w["window"], w["origin"], shape, threads=2)
        t_k = time.perf_counter() - t
        print(f"(b) KLayout TilingProcessor (read, density only, tile = window, 2 threads): {t_k:.2f} s")
        print(f"ratio (a)/(b) = {t_cmpsim / t_k:.3f}  (target <= 0.25)")
    finally:
        shutil.rmtree(tmp, ignore_errors=True)


if __name__ == "__main__":
    main()
