"""# From the wafer to the die: pattern density, dishing and erosion

`cmpsim.die` polishes a patterned die with the chip-scale density and step-height models of the
MIT group, driven by the wafer-scale solve ([model, section 18](../model.md#18-from-the-wafer-to-the-die-cmpsimdie)).
This example uses the built-in test dies (`cmpsim die --list`) at coarse 250 µm cells, so that
it runs in seconds; the command line does the same with `cmpsim die density`, `cmpsim die lines
--process copper` and `cmpsim die lines --process copper --wafer --set wafer_diameter=300mm`.

1. **The planarization length comes from the pad stack.** The default stack (an IC1000-like top
   pad on a Suba IV-like subpad) bends over a length (D₁/k₂)^¼ ≈ 2.3 mm; the Gaussian weighting
   with the same half-power wave number has L ≈ 6.9 mm. A stiffer top pad lengthens it.
2. **Oxide: the density die.** Blocks of 10–90 % density polish at K/ρ_eff while their steps
   are high; low-density blocks planarize first.
3. **Copper: the line die.** After the bulk copper clears, the lines dish (deeper for wider
   lines: the summits reach the pad's contact height from about 5 µm, and beyond it the pad
   body's elastic bulge into the wide lines adds a few nanometres more up to 100 µm) and dense arrays erode. The
   erosion of the 90 % block is below that of the 70 % one on this die: with a 6.9 mm
   planarization length and 4 mm blocks the pad sees the 90 % block next to the 10 % block of
   the neighbouring die (the die repeats periodically), so its effective density is lower.
4. **A wafer of dies.** One wafer solve gives the rotation-averaged blanket rate at every die
   site; each die is the reference die read at its own equivalent time.

![Oxide die: density, effective density, final surface and step height](die_oxide.png)

![Copper die: dishing against line width, erosion against density](die_copper_trends.png)

![Wafer of copper dies: dishing, erosion and time to clear per die](die_wafer.png)
"""

import os
from pathlib import Path

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt

import cmpsim
from cmpsim import die

GRID = os.environ.get("CMPSIM_DOCS_GRID", "default")
OUT = Path(os.environ.get("CMPSIM_DOCS_OUT", Path(__file__).parent / "_output" / Path(__file__).stem))
OUT.mkdir(parents=True, exist_ok=True)
CELL = 250e-6  # m: coarse cells keep the example fast (the built-in dies default to 50 um)

cfg = cmpsim.Config.default().replace(grid=GRID)

# 1. the planarization length of the pad stack, and how the top pad's stiffness moves it
L = die.planarization_length_from_pad(cfg)
print(f"planarization length from the default pad stack: {L * 1e3:.2f} mm")
stiff = [die.planarization_length_from_pad(cfg.replace(pad_bulk_modulus=f"{e} MPa")) for e in (100, 300, 1000)]
print("top pad 100 / 300 / 1000 MPa:", " / ".join(f"{v * 1e3:.2f}" for v in stiff), "mm")
assert stiff[0] < stiff[1] < stiff[2]

# 2. oxide planarization of the density die, at the wafer-mean rate of the wafer solve
ox = die.simulate("density", config=cfg, cell_size=CELL)
print(f"oxide: blanket rate {ox.blanket_rate * 6e10:.1f} nm/min, time to planarize {ox.time_to_planarize:.0f} s, polished {ox.time:.0f} s")
fig = ox.plot()
fig.savefig(OUT / "die_oxide.png", dpi=90)
plt.close(fig)
regs = ox.to_dict()["regions"]
first = sorted(regs, key=lambda r: r["time_to_planarize"])
print("first planarized block: density", first[0]["density"], "- last:", first[-1]["density"])
assert first[0]["effective_density"] < first[-1]["effective_density"]

# 3. copper on the line die
cu = die.simulate("lines", config=cfg, cell_size=CELL, process="copper")
d = cu.to_dict()
print(f"copper: time to clear {d['time_to_clear']:.0f} s, polished {d['time']:.0f} s; dishing max {d['dishing_max'] * 1e9:.1f} nm, erosion max {d['erosion_max'] * 1e9:.1f} nm")
at50 = sorted((r for r in d["regions"] if r["density"] == 0.5 and r["line_width"] and r["y"] > 12e-3), key=lambda r: r["line_width"])
dense = sorted((r for r in d["regions"] if r["line_width"] == 2e-6 and 8e-3 < r["y"] < 12e-3), key=lambda r: r["density"])
fig, (a, b) = plt.subplots(1, 2, figsize=(10, 4), layout="constrained")
a.semilogx([r["line_width"] * 1e6 for r in at50], [r["dishing"] * 1e9 for r in at50], "o-")
a.set_xlabel("line width (um), 50 % density")
a.set_ylabel("dishing (nm)")
b.plot([r["density"] * 100 for r in dense], [r["erosion"] * 1e9 for r in dense], "o-")
b.set_xlabel("array density (%), 2 um lines")
b.set_ylabel("erosion (nm)")
fig.suptitle(f"copper die 'lines' after {d['time']:.0f} s (30 % over-polish)")
fig.savefig(OUT / "die_copper_trends.png", dpi=90)
plt.close(fig)
dish = [r["dishing"] for r in at50]
narrow = [r["dishing"] for r in at50 if r["line_width"] <= 5e-6]
assert all(y > x for x, y in zip(narrow, narrow[1:])) and dish[-1] > 20 * dish[0]
print("dishing at 50 % density:", ", ".join(f"{r['line_width'] * 1e6:g} um {r['dishing'] * 1e9:.1f} nm" for r in at50))
print("erosion at 2 um lines:", ", ".join(f"{100 * r['density']:.0f} % {r['erosion'] * 1e9:.1f} nm" for r in dense))

# 4. a 200 mm wafer of the copper dies
w = die.simulate_wafer("lines", config=cfg.replace(wafer_diameter="200 mm"), cell_size=CELL, process="copper")
print(f"{len(w.x)} dies; blanket rate {w.blanket_rate.min() * 6e10:.1f}-{w.blanket_rate.max() * 6e10:.1f} nm/min; "
      f"time to clear {w.time_to_clear.min():.0f}-{w.time_to_clear.max():.0f} s; polished {w.time:.0f} s")
fig = w.plot()
fig.savefig(OUT / "die_wafer.png", dpi=80)
plt.close(fig)
