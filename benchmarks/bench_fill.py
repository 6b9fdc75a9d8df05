"""Model-based fill on a floorplan of real unfilled macros: thickness range before and after, cost.

    python benchmarks/bench_fill.py [--macro FILE.gds.gz] [--window 20e-6] [--layer 68/20] [--out DIR]

A 10 x 10 mm die (a boundary rectangle on 235/4, no metal) holds the SKY130 macro of
../shared/layouts (350 x 350 um, met1 density 0.29, no fill) in a floorplan with empty
space between: a 6 x 6 array, a 3 x 3 array, an 8 x 4 array and three single macros. With
the sky130 fill rules (cmpsim.layout.fill.FILL_RULES; assumed values, see there) the fill
sites are found, the model-based fill chosen (cmpsim.die.fill.plan_fill: oxide ILD, the
default pad and process, the blanket rate of one wafer solve), written as fill.oas and
fill.gds, and checked: on every window at a macro's edge (where fill and drawn shapes
meet) gdstk intersects the fill squares with the drawn shapes grown by keep-out - 1 nm;
the result must be empty. Prints times, before/after {hotspot_count, thickness_range} and
the added area. No number here is tuned: the die model is the one `cmpsim die` runs.
"""

from __future__ import annotations

import argparse
import json
import sys
import tempfile
import time
from pathlib import Path

import gdstk
import numpy as np

from cmpsim.layout import extract_windows, read_layout, top_cell
from cmpsim.layout.fill import fill_rules, fill_sites, write_fill
from cmpsim.die.fill import plan_fill

DEFAULT_MACRO = Path(__file__).resolve().parents[2] / "shared/layouts/sky130_ExperiarSoC_CaravelHost.gds.gz"

#: (x, y) of the lower-left corner (mm), columns, rows of each macro array of the floorplan.
FLOORPLAN = [((0.5, 0.5), 6, 6), ((6.0, 1.0), 3, 3), ((1.0, 6.5), 8, 4), ((5.0, 5.0), 1, 1), ((8.5, 8.5), 1, 1), ((8.0, 4.5), 1, 1)]


def build_floorplan(macro: Path, out: Path) -> tuple[Path, str]:
    """Write the 10 x 10 mm floorplan (GDS, the macro's cells as they are) and return (path, macro top cell)."""
    lay = read_layout(macro)
    cell = top_cell(lay)
    lib = lay.library
    (x0, y0), (x1, y1) = cell.bounding_box()
    size = (x1 - x0, y1 - y0)
    mm = 1e-3 / lay.dbu
    top = lib.new_cell("FLOORPLAN")
    top.add(gdstk.rectangle((0, 0), (10 * mm, 10 * mm), layer=235, datatype=4))
    for (ox, oy), cols, rows in FLOORPLAN:
        top.add(gdstk.Reference(cell, (ox * mm - x0, oy * mm - y0), columns=cols, rows=rows, spacing=size))
    lib.write_gds(str(out))
    return out, cell.name


def check_overlap(path: Path, fill_path: Path, layer, keepout: float, windows, sites, plan, dbu: float, limit: int = 200):
    """Fill AND (drawn grown by keep-out - 1 nm) on the windows where both are present: the area found (dbu^2)."""
    lay = read_layout(path)
    cell = top_cell(lay, "FLOORPLAN")
    fl = read_layout(fill_path)
    fcell = top_cell(fl)
    both = np.argwhere((windows.density > 0) & (plan.counts > 0))
    if len(both) > limit:
        both = both[np.linspace(0, len(both) - 1, limit).astype(int)]
    W = round(windows.window / dbu)
    ox, oy = round(windows.origin[0] / dbu), round(windows.origin[1] / dbu)
    grow = keepout / dbu - 1.0
    fill_polys = fcell.get_polygons()
    fb = np.array([p.bounding_box() for p in fill_polys], float).reshape(-1, 4)
    drawn = cell.get_polygons(layer=layer[0], datatype=layer[1])
    db = np.array([p.bounding_box() for p in drawn], float).reshape(-1, 4)
    bad = 0.0
    for iy, ix in both:
        x0, y0 = ox + ix * W, oy + iy * W
        fsel = np.nonzero((fb[:, 0] >= x0) & (fb[:, 2] <= x0 + W) & (fb[:, 1] >= y0) & (fb[:, 3] <= y0 + W))[0]
        m = keepout / dbu
        dsel = np.nonzero((db[:, 0] < x0 + W + m) & (db[:, 2] > x0 - m) & (db[:, 1] < y0 + W + m) & (db[:, 3] > y0 - m))[0]
        if not len(fsel) or not len(dsel):
            continue
        grown = gdstk.offset([drawn[k] for k in dsel], grow, join="miter", use_union=True)
        hit = gdstk.boolean([fill_polys[k] for k in fsel], grown, "and")
        bad += sum(p.area() for p in hit)
    return bad, len(both)


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--macro", type=Path, default=DEFAULT_MACRO)
    ap.add_argument("--window", type=float, default=20e-6)
    ap.add_argument("--layer", default="68/20")
    ap.add_argument("--out", type=Path, default=None)
    ap.add_argument("--iterations", type=int, default=3)
    ap.add_argument("--planarization-length", type=float, default=None, help="m (default: derived from the pad)")
    ap.add_argument("--weighting", default="gaussian")
    ap.add_argument("--no-check", action="store_true", help="skip the keep-out check (slow)")
    a = ap.parse_args(argv)
    if not a.macro.is_file():
        print(f"macro {a.macro} not found (give --macro)", file=sys.stderr)
        return 2
    out = a.out or Path(tempfile.mkdtemp(prefix="cmpsim-fill-"))
    out.mkdir(parents=True, exist_ok=True)
    layer = tuple(int(v) for v in a.layer.split("/"))
    rules = fill_rules("sky130", "met1")
    times = {}
    t = time.perf_counter()
    path, _ = build_floorplan(a.macro, out / "floorplan.gds")
    times["build"] = time.perf_counter() - t
    t = time.perf_counter()
    w = extract_windows(path, [a.layer], a.window, top="FLOORPLAN")
    times["extract_windows"] = time.perf_counter() - t
    t = time.perf_counter()
    s = fill_sites(path, [a.layer], w, rules, top="FLOORPLAN")
    times["fill_sites"] = time.perf_counter() - t
    t = time.perf_counter()
    from cmpsim import Config, solve

    rate = float(solve(Config.default(), relative=False).removal_rate_mean)
    times["wafer_solve"] = time.perf_counter() - t
    t = time.perf_counter()
    plan = plan_fill(w, s, blanket_rate=rate, iterations=a.iterations, planarization_length=a.planarization_length,
                     weighting=a.weighting)
    times["plan_fill"] = time.perf_counter() - t
    t = time.perf_counter()
    write_fill(out / "fill.oas", s, plan.chosen, "36/28")
    times["write_oas"] = time.perf_counter() - t
    t = time.perf_counter()
    write_fill(out / "fill.gds", s, plan.chosen, "36/28")
    times["write_gds"] = time.perf_counter() - t
    t = time.perf_counter()
    bad, checked = (0.0, 0) if a.no_check else check_overlap(path, out / "fill.oas", layer, rules.keepout, w, s, plan, s.dbu)
    times["check"] = time.perf_counter() - t
    d = plan.to_dict()
    b, f = d["before"], d["after"]
    cut = 1.0 - f["thickness_range"] / b["thickness_range"]
    report = {
        "die": "10 x 10 mm", "planarization_length": plan.before.planarization_length, "weighting": a.weighting, "windows": list(w.density.shape), "window": a.window, "rules": rules.source,
        "mean_density_before": float(w.density.mean()), "mean_density_after": float(plan.windows.density.mean()),
        "fill": d, "thickness_range_cut": cut, "squares": int(plan.counts.sum()),
        "overlap_area_dbu2": bad, "windows_checked": checked, "sites": s.stats, "plan": plan.stats,
        "seconds": times, "files": {k: (out / k).stat().st_size for k in ("fill.oas", "fill.gds")},
    }
    print(json.dumps(report, indent=1, default=float))
    print(f"thickness range {b['thickness_range'] * 1e9:.2f} -> {f['thickness_range'] * 1e9:.2f} nm ({cut:.1%} cut); "
          f"hotspots {b['hotspot_count']} -> {f['hotspot_count']}; added {d['added_area'] * 1e6:.3f} mm^2; "
          f"overlap {bad} dbu^2 on {checked} windows")
    return 0


if __name__ == "__main__":
    sys.exit(main())
