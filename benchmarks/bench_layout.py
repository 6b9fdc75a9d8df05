"""Layout extraction: cmpsim (gdstk) against KLayout's TilingProcessor, and exactness on a real macro.

    python benchmarks/bench_layout.py [--macro FILE.gds.gz] [--steps 8] [--window 20e-6] [--layer 68/20]

1. Exactness: on the macro itself (unstepped), written as GDS, gzipped GDS and OASIS (the
   OASIS written by gdstk), cmpsim's window densities against an independent exact
   computation: gdstk flattens the top cell and, window by window, intersects the flattened
   shapes with the window (gdstk.boolean "and") and sums the areas.
2. Speed: a chip made by stepping the macro N x N (a new top cell holding one gdstk
   Reference array, pitch = the macro's size unless --pitch is given), written as GDS.
   Timed in the same run: (a) cmpsim's extract_windows (read + density, width, space) and
   (b) KLayout's TilingProcessor (read + densities only; tile = window, 2 threads).
   Prints the ratio (a)/(b) and the largest density difference between the two.

KLayout (GPL) is used here only, as the reference; src/cmpsim never imports it.
"""

from __future__ import annotations

import argparse
import gzip
import shutil
import sys
import tempfile
import time
from pathlib import Path

import gdstk
import numpy as np

from cmpsim.layout import extract_windows, read_layout, top_cell
from cmpsim.layout.layermaps import parse_layer

DEFAULT_MACRO = Path(__file__).resolve().parents[2] / "shared/layouts/sky130_ExperiarSoC_CaravelHost.gds.gz"


def exact_densities(lib: gdstk.Library, top: str, layers, window_dbu: int, origin, shape):
    """Independent density per window: flatten with gdstk, intersect each window, sum areas."""
    cell = next(c for c in lib.cells if c.name == top)
    polys = []
    for layer, dtype in layers:
        polys.extend(cell.get_polygons(layer=layer, datatype=dtype))
    bb = np.array([p.bounding_box() for p in polys], float).reshape(-1, 4)
    ny, nx = shape
    out = np.zeros(shape)
    w = window_dbu
    for j in range(ny):
        y0 = origin[1] + j * w
        rows = (bb[:, 1] < y0 + w) & (bb[:, 3] > y0)
        for i in range(nx):
            x0 = origin[0] + i * w
            sel = np.nonzero(rows & (bb[:, 0] < x0 + w) & (bb[:, 2] > x0))[0]
            if len(sel) == 0:
                continue
            res = gdstk.boolean([polys[k] for k in sel], gdstk.rectangle((x0, y0), (x0 + w, y0 + w)), "and",
                                precision=1e-6)
            out[j, i] = sum(p.area() for p in res) / (w * w)
    return out


def klayout_densities(path: Path, layers, window: float, origin, shape, threads: int = 2):
    """Densities per window with KLayout's TilingProcessor (tile = window)."""
    import klayout.db as kdb

    ly = kdb.Layout()
    ly.read(str(path))
    top = ly.top_cell()
    region_layers = [ly.find_layer(l, d) for l, d in layers]
    region_layers = [i for i in region_layers if i is not None]
    li = region_layers[0]
    if len(region_layers) > 1:  # merge all given layers into one input layer
        li = ly.layer()
        for i in region_layers:
            ly.copy_layer(i, li)
    ny, nx = shape
    out = np.zeros(shape)

    class Receiver(kdb.TileOutputReceiver):
        def put(self, ix, iy, tile, obj, dbu, clip):
            out[iy, ix] = obj

    tp = kdb.TilingProcessor()
    tp.input("m", ly, top.cell_index(), li)
    tp.dbu = ly.dbu
    tp.tile_size(window * 1e6, window * 1e6)
    tp.tile_origin(origin[0] * 1e6, origin[1] * 1e6)
    tp.tiles(nx, ny)
    tp.threads = threads
    tp.output("o", Receiver())
    tp.queue("_output(o, to_f(m.area(_tile.bbox)) / to_f(_tile.bbox.area))")
    tp.execute("density")
    return out


def step_chip(macro_gds: Path, out: Path, steps: int, pitch=None) -> tuple[float, float, str]:
    """Write a chip that steps the macro's top cell steps x steps; returns the pitch (m) and the macro's name."""
    lib = gdstk.read_gds(str(macro_gds), unit=1e-6)  # user unit um
    macro = lib.top_level()[0]
    (x0, y0), (x1, y1) = macro.bounding_box()
    px, py = pitch if pitch else (x1 - x0, y1 - y0)
    chip = gdstk.Cell("CHIP")
    chip.add(gdstk.Reference(macro, (-x0, -y0), columns=steps, rows=steps, spacing=(px, py)))
    lib.add(chip)
    lib.write_gds(str(out))
    return px * lib.unit, py * lib.unit, macro.name


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--macro", type=Path, default=DEFAULT_MACRO, help="real macro (.gds or .gds.gz)")
    ap.add_argument("--layer", default="68/20", help="layer/datatype (default met1 68/20)")
    ap.add_argument("--window", type=float, default=20e-6, help="window side, m (default 20e-6)")
    ap.add_argument("--steps", type=int, default=8, help="steps per axis of the chip (default 8)")
    ap.add_argument("--pitch", type=float, nargs=2, default=None, metavar=("PX", "PY"),
                    help="step pitch in m (default: the macro's size, abutted)")
    ap.add_argument("--repeat", type=int, default=1, help="timed runs of each tool (best kept)")
    ap.add_argument("--skip-exact", action="store_true", help="skip the exactness check on the macro")
    args = ap.parse_args(argv)
    if not args.macro.is_file():
        sys.exit(f"macro {args.macro} not found (give --macro)")
    layers = [parse_layer(args.layer)]
    tmp = Path(tempfile.mkdtemp(prefix="bench_layout_"))
    try:
        gds = tmp / "macro.gds"
        if args.macro.suffix == ".gz":
            with gzip.open(args.macro, "rb") as src, open(gds, "wb") as dst:
                shutil.copyfileobj(src, dst)
        else:
            shutil.copy(args.macro, gds)
        gz = tmp / "macro.gds.gz"
        with open(gds, "rb") as src, gzip.open(gz, "wb") as dst:
            shutil.copyfileobj(src, dst)
        macro_layout = read_layout(gds)
        oas = tmp / "macro.oas"
        macro_layout.library.write_oas(str(oas))
        top = top_cell(macro_layout).name
        print(f"macro {args.macro.name}: top {top}, dbu {macro_layout.dbu:g} m, "
              f"bbox {top_cell(macro_layout).bounding_box()} dbu")

        if not args.skip_exact:
            print(f"\n1. exactness on the macro ({args.layer}, {args.window * 1e6:g} um windows)")
            ref = None
            for path in (gds, gz, oas):
                t = time.perf_counter()
                r = extract_windows(path, [args.layer], args.window)
                dt = time.perf_counter() - t
                if ref is None:
                    lay = read_layout(path)
                    w = round(r.window / lay.dbu)
                    origin = (round(r.origin[0] / lay.dbu), round(r.origin[1] / lay.dbu))
                    t0 = time.perf_counter()
                    ref = exact_densities(lay.library, r.top, layers, w, origin, r.density.shape)
                    print(f"   exact flattened reference: {time.perf_counter() - t0:.1f} s")
                err = np.abs(r.density - ref).max()
                print(f"   {path.name:14s} {r.density.shape[1]} x {r.density.shape[0]} windows, "
                      f"mean density {r.density.mean():.4f}, max |diff| {err:.2e}, {dt:.2f} s")

        print(f"\n2. speed: the macro stepped {args.steps} x {args.steps}")
        chip = tmp / "chip.gds"
        pitch = None
        if args.pitch:
            pitch = (args.pitch[0] / 1e-6, args.pitch[1] / 1e-6)  # gdstk reads in um
        px, py, _ = step_chip(gds, chip, args.steps, pitch)
        best_c, best_k = np.inf, np.inf
        for _ in range(args.repeat):
            t = time.perf_counter()
            res = extract_windows(chip, [args.layer], args.window)
            best_c = min(best_c, time.perf_counter() - t)
        bx = res.bbox
        print(f"   chip {(bx[2] - bx[0]) * 1e3:.3f} x {(bx[3] - bx[1]) * 1e3:.3f} mm "
              f"(pitch {px * 1e6:g} x {py * 1e6:g} um), "
              f"{res.density.shape[1]} x {res.density.shape[0]} windows")
        try:
            import klayout.db  # noqa: F401
        except ImportError:
            print(f"   cmpsim: {best_c:.2f} s; klayout not installed, no comparison")
            return
        for _ in range(args.repeat):
            t = time.perf_counter()
            kd = klayout_densities(chip, layers, res.window, res.origin, res.density.shape, threads=2)
            best_k = min(best_k, time.perf_counter() - t)
        diff = np.abs(kd - res.density).max()
        print(f"   (a) cmpsim extract_windows (read, density, width, space): {best_c:.2f} s")
        print(f"   (b) KLayout TilingProcessor (read, density only, 2 threads): {best_k:.2f} s")
        print(f"   ratio (a)/(b) = {best_c / best_k:.3f}  (target <= 0.25); max |density diff| = {diff:.2e}")
    finally:
        shutil.rmtree(tmp, ignore_errors=True)


if __name__ == "__main__":
    main()
