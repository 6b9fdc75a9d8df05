"""# A real layout end to end: windows, hotspots, a stack, a wafer

`cmpsim die` reads a real layout (GDSII, gzipped GDSII, OASIS), extracts every window's density,
line width and line space ([layouts](../layouts.md)), polishes every window with the die model
([model, section 18](../model.md#18-from-the-wafer-to-the-die-cmpsimdie)) and reports where the
result breaks a limit. This example ships a real layout: a 150 × 150 µm corner of a SkyWater
SKY130 macro (met1 and met2; Apache-2.0, see `docs/examples/data/NOTICE.md`).

1. **One level.** The corner, stepped 6 × 4 with empty space between the steps (a floorplan
   of unfilled macros), met1 polished as a copper damascene level at 10 µm windows, the blanket
   rate from the wafer solve. Every window has its own density, width and space; the
   planarization length (millimetres) spans the whole chip, so the empty space pulls the
   effective density down at the chip's edges and the macros near it come out higher.
2. **Hotspots.** Limits per quantity (`--spec thickness=...`, `dishing`, `erosion`,
   `step_height`) mark the windows that exceed them; `hotspots.lyrdb` opens on top of the
   layout in KLayout (*Tools → Marker Browser*, or `klayout chip.gds -m hotspots.lyrdb`).
3. **A stack.** met1 then met2, each copper: the topography met1 leaves (its surface map and
   its residual steps) is the incoming topography of met2.
4. **The wafer.** With `--wafer` and the `300mm` preset's zoned profile, every die is polished
   at the rate at its site and counts its own hotspots.

![One level: density, effective density, final surface with hotspots, dishing, erosion](die_layout_met1.png)

![Stack: met2 over the topography met1 left](die_layout_stack.png)

![Wafer: hotspots per die](die_layout_wafer.png)
"""

import json
import os
import shutil
import subprocess
import sys
from pathlib import Path

import gdstk
import numpy as np
import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt

from cmpsim.die.chip import DieModel, layout_die

GRID = os.environ.get("CMPSIM_DOCS_GRID", "default")
OUT = Path(os.environ.get("CMPSIM_DOCS_OUT", Path(__file__).parent / "_output" / Path(__file__).stem))
OUT.mkdir(parents=True, exist_ok=True)
DATA = Path(__file__).resolve().parent / "data" / "sky130_caravelhost_cut.gds.gz"

# a floorplan: the real corner stepped 6 x 4 at a 250 um pitch (100 um of empty space between)
tmp = OUT / "work"
tmp.mkdir(exist_ok=True)
raw = tmp / "cut.gds"
import gzip

with gzip.open(DATA, "rb") as src, open(raw, "wb") as dst:
    shutil.copyfileobj(src, dst)
lib = gdstk.read_gds(str(raw), unit=1e-6)
macro = lib.top_level()[0]
chip = gdstk.Cell("CHIP")
chip.add(gdstk.Reference(macro, (0, 0), columns=6, rows=4, spacing=(250.0, 250.0)))
chip.add(gdstk.rectangle((0, 0), (1500.0, 1000.0), layer=235, datatype=4))  # the die's outline (SKY130 prBoundary)
lib.add(chip)
chip_gds = tmp / "chip.gds"
lib.write_gds(str(chip_gds))

# 1-2. one level from the command line: met1 as copper, 10 um windows, limits
cli = [sys.executable, "-m", "cmpsim.cli", "die", str(chip_gds), "--layer", "met1", "--pdk", "sky130", "--window", "10um",
       "--process", "copper", "--set", f"grid={GRID}", "--spec", "thickness=2nm", "--spec", "dishing=5nm",
       "--spec", "erosion=15nm", "--json", "--out", str(tmp / "met1")]
d = json.loads(subprocess.run(cli, check=True, capture_output=True, text=True).stdout)
w = d["windows"]
print(f"{w['nx']} x {w['ny']} windows of {w['window'] * 1e6:g} um over {w['bbox'][2] * 1e3:g} x {w['bbox'][3] * 1e3:g} mm, layers {w['layers']}")
print(f"blanket rate {d['blanket_rate'] * 6e10:.1f} nm/min, polished {d['time']:.0f} s; thickness range {d['thickness_range'] * 1e9:.2f} nm, "
      f"dishing max {d['dishing_max'] * 1e9:.2f} nm, erosion max {d['erosion_max'] * 1e9:.2f} nm")
kinds = {}
for h in d["hotspots"]:
    kinds[h["kind"]] = kinds.get(h["kind"], 0) + 1
print(f"{d['hotspot_count']} hotspots: {kinds}; worst: {d['hotspots'][0] if d['hotspots'] else None}")
print("files:", ", ".join(sorted(p.name for p in (tmp / "met1").iterdir())))
shutil.copy(tmp / "met1" / "die.png", OUT / "die_layout_met1.png")
print((tmp / "met1" / "hotspots.lyrdb").read_text()[:600])

# the same level from Python, and the call that re-simulates it with other fields (e.g. fill)
model = DieModel(process="copper", spec={"thickness": "2 nm", "dishing": "5 nm", "erosion": "15 nm"})
lay = layout_die(chip_gds, ["met1"], 10e-6, pdk="sky130")
res = model.run(lay)
print(f"Python: thickness range {res.thickness_range * 1e9:.2f} nm, {len(res.hotspots())} hotspots")
# e.g. 2 um squares at 4 um pitch (25 %) in every empty window, polished for the same time
empty = lay.density == 0
filled = model.run(lay, res.time, density=np.where(empty, 0.25, lay.density), width=np.where(empty, 2e-6, lay.line_width),
                   space=np.where(empty, 2e-6, lay.space))
print(f"with 25 % in every empty window: thickness range {filled.thickness_range * 1e9:.2f} nm, {len(filled.hotspots())} hotspots")

# 3. a stack: met1 then met2, both copper
stack = tmp / "stack.toml"
stack.write_text('window = "10 um"\npdk = "sky130"\n[spec]\nthickness = "2 nm"\ndishing = "5 nm"\n'
                 '[[level]]\nname = "met1"\nlayers = ["met1"]\nprocess = "copper"\ntrench_depth = "0.36 um"\ncopper_thickness = "0.8 um"\n'
                 '[[level]]\nname = "met2"\nlayers = ["met2"]\nprocess = "copper"\ntrench_depth = "0.36 um"\ncopper_thickness = "0.8 um"\n')
cli = [sys.executable, "-m", "cmpsim.cli", "die", str(chip_gds), "--stack", str(stack), "--set", f"grid={GRID}", "--json", "--out", str(tmp / "stack")]
s = json.loads(subprocess.run(cli, check=True, capture_output=True, text=True).stdout)
for lv in s["levels"]:
    print(f"stack level {lv['name']}: thickness range {lv['thickness_range'] * 1e9:.2f} nm, dishing max {lv['dishing_max'] * 1e9:.2f} nm, "
          f"{lv['hotspot_count']} hotspots")
alone = DieModel(process=model.process.replace(trench_depth=0.36e-6, copper_thickness=0.8e-6)).run(layout_die(chip_gds, ["met2"], 10e-6, pdk="sky130"))
print(f"met2 alone: thickness range {alone.thickness_range * 1e9:.2f} nm (over met1: {s['levels'][1]['thickness_range'] * 1e9:.2f} nm)")
shutil.copy(tmp / "stack" / "die_met2.png", OUT / "die_layout_stack.png")

# 4. the wafer of these dies, driven by the 300mm preset's zoned profile
cli = [sys.executable, "-m", "cmpsim.cli", "die", str(chip_gds), "--layer", "met1", "--pdk", "sky130", "--window", "10um",
       "--process", "copper", "--wafer", "--preset", "300mm", "--set", f"grid={GRID}", "--spec", "thickness=2nm",
       "--spec", "dishing=5nm", "--spec", "erosion=15nm", "--json", "--out", str(tmp / "wafer")]
wf = json.loads(subprocess.run(cli, check=True, capture_output=True, text=True).stdout)
counts = [x["hotspot_count"] for x in wf["dies"]]
print(f"wafer: {len(counts)} dies ({wf['die_reading']} reading), hotspots per die {min(counts)}-{max(counts)}, {wf['wafer_hotspot_count']} in all")
shutil.copy(tmp / "wafer" / "wafer.png", OUT / "die_layout_wafer.png")
plt.close("all")
shutil.rmtree(tmp, ignore_errors=True)
