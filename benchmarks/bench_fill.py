"""Model-based fill on a floorplan of real unfilled macros: fill sites, thickness range before and after, cost.

    python benchmarks/bench_fill.py [--macro FILE.gds.gz] [--window 20e-6] [--layer 68/20] [--out DIR]

A 10 x 10 mm die (a boundary rectangle on 235/4, no metal) holds six placements of the SKY130
macro of ../shared/layouts (sky130_Caravel_Chameleon_storage: 0.44 x 0.95 mm, 620 000 met1
shapes under 230 cells) with empty space between, written with KLayout. With the sky130 fill
rules (cmpsim.layout.fill.FILL_RULES; assumed values, see there) the fill sites are found
(the number docs/fill.md quotes), the model-based fill chosen (cmpsim.die.fill.plan_fill: oxide
ILD, the default pad and process, the blanket rate of one wafer solve), written as fill.oas and
fill.gds, and checked by KLayout on the merged layout: a fill of every free site against the
drawn shapes (separation check, Euclidean, at the keep-out, deep mode) must give no pair. Prints
times, before/after {hotspot_count, thickness_range} and the added area. No number here is
tuned: the die model is the one `cmpsim die` runs. --sites-only stops after the fill sites.
"""

from __future__ import annotations

import argparse
import json
import sys
import tempfile
import time
from pathlib import Path

import klayout.db as kdb

from cmpsim.layout import extract_windows
from cmpsim.layout.fill import fill_rules, fill_sites, select_fill, write_fill
from cmpsim.die.fill import plan_fill

DEFAULT_MACRO = Path(__file__).resolve().parents[2] / "shared/layouts/sky130_Caravel_Chameleon_storage.gds.gz"

#: (x, y) of the lower-left corner (mm), columns, rows of each placement of the macro: six single ones.
FLOORPLAN = [((0.5, 0.5), 1, 1), ((6.0, 1.0), 1, 1), ((1.0, 6.5), 1, 1), ((5.0, 5.0), 1, 1), ((7.5, 7.0), 1, 1), ((3.5, 3.0), 1, 1)]
#: --arrays: the floorplan of the earlier measurements (80 placements of a 0.35 mm macro: 6 x 6, 3 x 3 and 8 x 4 arrays, three single).
ARRAYS = [((0.5, 0.5), 6, 6), ((6.0, 1.0), 3, 3), ((1.0, 6.5), 8, 4), ((5.0, 5.0), 1, 1), ((8.5, 8.5), 1, 1), ((8.0, 4.5), 1, 1)]


def build_floorplan(macro: Path, out: Path, plan=FLOORPLAN) -> tuple[Path, str]:
    """Write the 10 x 10 mm floorplan (GDS, the macro's cells as they are) and return (path, macro top cell)."""
    ly = kdb.Layout()
    ly.read(str(macro))
    (cell,) = [c for c in ly.top_cells() if c.name != "$$$CONTEXT_INFO$$$"]
    box = cell.bbox()
    mm = round(1e-3 / (ly.dbu * 1e-6))
    top = ly.create_cell("FLOORPLAN")
    top.shapes(ly.layer(235, 4)).insert(kdb.Box(0, 0, 10 * mm, 10 * mm))
    for (x, y), cols, rows in plan:
        at = kdb.Trans(kdb.Vector(round(x * mm) - box.left, round(y * mm) - box.bottom))
        top.insert(kdb.CellInstArray(cell.cell_index(), at, kdb.Vector(box.width(), 0), kdb.Vector(0, box.height()), cols, rows))
    ly.write(str(out))
    return out, cell.name


def build_stepped(macro: Path, out: Path, size_mm: float = 20.0, gap: float = 5e-6) -> Path:
    """Write a size_mm x size_mm die stepping the macro as one array (5 um apart): a whole chip, cell FLOORPLAN."""
    ly = kdb.Layout()
    ly.read(str(macro))
    (cell,) = [c for c in ly.top_cells() if c.name != "$$$CONTEXT_INFO$$$"]
    box = cell.bbox()
    um = round(1e-6 / (ly.dbu * 1e-6))
    side, g = round(size_mm * 1000 * um), round(gap * 1e6 * um)
    top = ly.create_cell("FLOORPLAN")
    top.shapes(ly.layer(235, 4)).insert(kdb.Box(0, 0, side, side))
    nx, ny = (side - g) // (box.width() + g), (side - g) // (box.height() + g)
    top.insert(kdb.CellInstArray(cell.cell_index(), kdb.Trans(kdb.Vector(g - box.left, g - box.bottom)),
                                 kdb.Vector(box.width() + g, 0), kdb.Vector(0, box.height() + g), nx, ny))
    ly.write(str(out))
    return out


def check_overlap(path: Path, fill_path: Path, layer, keepout: float, dbu: float) -> tuple[int, int]:
    """KLayout's separation check (Euclidean, at the keep-out; deep mode) of every square of ``fill_path``
    against the drawn shapes, on the layout with the fill file read into it: (pairs found, squares checked)."""
    ly = kdb.Layout()
    ly.read(str(path))
    ly.read(str(fill_path))
    store = kdb.DeepShapeStore()
    store.threads = 2
    drawn = kdb.Region(ly.cell("FLOORPLAN").begin_shapes_rec(ly.find_layer(*layer)), store)
    fill = kdb.Region(ly.cell("CMPSIM_FILL").begin_shapes_rec(ly.find_layer(36, 28)), store)
    return drawn.separation_check(fill, round(keepout / dbu)).count(), fill.count()


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
    ap.add_argument("--arrays", action="store_true", help="the 80-placement floorplan of arrays (ARRAYS) instead of six single macros")
    ap.add_argument("--stepped", action="store_true", help="a 20 x 20 mm die stepping the macro instead of the floorplan (implies --sites-only)")
    ap.add_argument("--sites-only", action="store_true", help="stop after the fill sites (their time is the number docs/fill.md quotes)")
    ap.add_argument("--check-only", action="store_true", help="the sites and the keep-out check, no plan")
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
    if a.stepped:
        a.sites_only = True
        path = build_stepped(a.macro, out / "stepped.gds")
    else:
        path, _ = build_floorplan(a.macro, out / "floorplan.gds", ARRAYS if a.arrays else FLOORPLAN)
    times["build"] = time.perf_counter() - t
    t = time.perf_counter()
    w = extract_windows(path, [a.layer], a.window, top="FLOORPLAN")
    times["extract_windows"] = time.perf_counter() - t
    t = time.perf_counter()
    s = fill_sites(path, [a.layer], w, rules, top="FLOORPLAN")
    times["fill_sites"] = time.perf_counter() - t
    if a.check_only:
        t = time.perf_counter()
        write_fill(out / "fill_all.oas", s, select_fill(s, s.capacity), "36/28")
        bad, checked = check_overlap(path, out / "fill_all.oas", layer, rules.keepout, s.dbu)
        times["check"] = time.perf_counter() - t
        print(json.dumps({"seconds": times, "sites": s.stats, "keepout_pairs": bad, "squares_checked": checked}, indent=1, default=float))
        return 0
    if a.sites_only:
        print(json.dumps({"seconds": times, "sites": s.stats, "windows": list(w.density.shape)}, indent=1, default=float))
        return 0
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
    # the check fills every free site (not only the plan's choice): the strongest test of the sites
    if not a.no_check:
        write_fill(out / "fill_all.oas", s, select_fill(s, s.capacity), "36/28")
    bad, checked = (0, 0) if a.no_check else check_overlap(path, out / "fill_all.oas", layer, rules.keepout, s.dbu)
    times["check"] = time.perf_counter() - t
    d = plan.to_dict()
    b, f = d["before"], d["after"]
    cut = 1.0 - f["thickness_range"] / b["thickness_range"]
    report = {
        "die": "10 x 10 mm", "planarization_length": plan.before.planarization_length, "weighting": a.weighting, "windows": list(w.density.shape), "window": a.window, "rules": rules.source,
        "mean_density_before": float(w.density.mean()), "mean_density_after": float(plan.windows.density.mean()),
        "fill": d, "thickness_range_cut": cut, "squares": int(plan.counts.sum()),
        "keepout_pairs": bad, "squares_checked": checked, "sites": s.stats, "plan": plan.stats,
        "seconds": times, "files": {k: (out / k).stat().st_size for k in ("fill.oas", "fill.gds")},
    }
    print(json.dumps(report, indent=1, default=float))
    print(f"thickness range {b['thickness_range'] * 1e9:.2f} -> {f['thickness_range'] * 1e9:.2f} nm ({cut:.1%} cut); "
          f"hotspots {b['hotspot_count']} -> {f['hotspot_count']}; added {d['added_area'] * 1e6:.3f} mm^2; "
          f"keep-out pairs {bad} on {checked} squares (every free site filled)")
    return 0


if __name__ == "__main__":
    sys.exit(main())
