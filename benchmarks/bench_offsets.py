"""One block at many offsets against the window grid: KLayout's rasteriser per offset against
cmpsim's one exact integration for all of them (issue 37: hand-written geometry stays only where
a benchmark shows it beats KLayout and stays exact).

A macro stepped at a pitch that is not a whole number of windows sits at a different offset
against the grid at every step (45 x 21 offsets for the SKY130 register file stepped into a 20 mm
chip). KLayout rasterises the merged macro once per offset (`Region.rasterize`, exact); cmpsim
reads the merged outline out once and integrates it on the union of every offset's window lines
(`cmpsim.layout.segments.rasterise_lines`), then sums sub-cells into windows per offset. Both
give the area per window; the script checks they agree (exit status 1 above 1e-6 of a window)
and prints the time of each and their ratio, measured in the same run.

    python benchmarks/bench_offsets.py [MACRO.gds[.gz]] [--layer 68/20] [--offsets 8 8] [--window 20]
"""

from __future__ import annotations

import argparse
import sys
import time
from pathlib import Path

import klayout.db as kdb
import numpy as np

from cmpsim.layout import read_layout, top_cell
from cmpsim.layout.blocks import edges_to_segments, merged_region
from cmpsim.layout.segments import rasterise_lines, window_lines

DEFAULT = Path(__file__).resolve().parents[2] / "shared" / "layouts" / "sky130_Caravel_Chameleon_storage.gds.gz"


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("macro", nargs="?", default=str(DEFAULT))
    ap.add_argument("--layer", default="68/20")
    ap.add_argument("--offsets", type=int, nargs=2, default=(8, 8), metavar=("NX", "NY"), help="distinct offsets in x and y")
    ap.add_argument("--window", type=float, default=20.0, help="window side, um")
    args = ap.parse_args()
    if not Path(args.macro).is_file():
        print(f"no macro at {args.macro}: give one", file=sys.stderr)
        return 2
    lay = read_layout(args.macro)
    cell = top_cell(lay)
    l, d = map(int, args.layer.split("/"))
    region = merged_region(cell, [lay.db.find_layer(l, d)], kdb.DeepShapeStore())
    box = region.bbox()
    w = int(round(args.window * 1e-6 / lay.dbu))
    rng = np.random.default_rng(1)
    phx = rng.choice(w, args.offsets[0], replace=False)
    phy = rng.choice(w, args.offsets[1], replace=False)
    nx = -(-(box.right - box.left) // w) + 3
    ny = -(-(box.top - box.bottom) // w) + 3
    # KLayout: one exact rasterisation per (x, y) offset
    t0 = time.perf_counter()
    ref = {}
    for fx in phx:
        for fy in phy:
            ox = (box.left - w) - ((box.left - w - int(fx)) % w)  # a grid line of this offset, a window left of the box
            oy = (box.bottom - w) - ((box.bottom - w - int(fy)) % w)
            ref[(int(fx), int(fy))] = (ox, oy, np.asarray(region.rasterize(kdb.Point(ox, oy), kdb.Vector(w, w), nx, ny)))
    t_klayout = time.perf_counter() - t0
    # cmpsim: the outline once, one integration on the union of the offsets' lines, sums per offset
    t0 = time.perf_counter()
    seg = edges_to_segments(region.edges())
    xs = window_lines(phx, w, box.left, box.right)
    ys = window_lines(phy, w, box.bottom, box.top)
    area, _ = rasterise_lines(seg, xs, ys)
    c = np.zeros((area.shape[0] + 1, area.shape[1] + 1))
    c[1:, 1:] = area.cumsum(0).cumsum(1)
    worst = 0.0
    sums = {}
    for (fx, fy), (ox, oy, _) in ref.items():
        ix = np.searchsorted(xs, ox + np.arange(nx + 1) * w)
        iy = np.searchsorted(ys, oy + np.arange(ny + 1) * w)
        ix, iy = np.clip(ix, 0, len(xs) - 1), np.clip(iy, 0, len(ys) - 1)
        sums[(fx, fy)] = c[np.ix_(iy[1:], ix[1:])] - c[np.ix_(iy[:-1], ix[1:])] - c[np.ix_(iy[1:], ix[:-1])] + c[np.ix_(iy[:-1], ix[:-1])]
    t_cmpsim = time.perf_counter() - t0
    for key, (_, _, a) in ref.items():
        worst = max(worst, float(np.max(np.abs(sums[key] - a))) / float(w * w))
    n = len(ref)
    print(f"{Path(args.macro).name} {args.layer}: {region.count():,} merged polygons, {len(seg):,} outline segments, {n} offsets, "
          f"{nx} x {ny} windows of {args.window:g} um")
    print(f"KLayout Region.rasterize per offset:       {t_klayout:7.2f} s ({1e3 * t_klayout / n:.1f} ms each)")
    print(f"cmpsim one integration for every offset:   {t_cmpsim:7.2f} s")
    print(f"RESULT speed-up {t_klayout / t_cmpsim:.1f}x at {n} offsets; max |difference| {worst:.2e} of a window")
    return 0 if worst <= 1e-6 else 1


if __name__ == "__main__":
    sys.exit(main())
