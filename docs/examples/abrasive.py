"""# Particle size, loading, abrasive and film in the abrasive removal law

The default model removes material with the abrasive particles trapped between the pad summits
in contact and the wafer (`removal_law = "abrasive"`,
[model, section 13e](../model.md#13e-abrasive-removal-the-default-removal-law)). This page runs
it over the particle size and the solids loading, for the default pair (silica on oxide, at the
paper's operating point) and for copper polished with alpha-alumina at the conditions of Lai's
size series (48 kPa, 0.70 m/s, 100 mm wafer), and prints the ratio of 3 wt% to 2 wt% at the
points of US 9,499,721 Table 18.

What it shows (the numbers are printed below):

1. **At a fixed solids loading by mass the rate does not depend on the particle size** (50 nm
   to 2 um: the same rate to round-off). The count of trapped particles falls as 1/d², the
   load each one carries (the pad's flow pressure over its section) and the groove it ploughs
   grow as d²: the model has no length against which the particle size could be measured.
   Lai measured a 2.6-fold rise from 50 to 1000 nm for copper and alumina; the model does not
   reproduce it ([validation](../validation.md)).
2. **The rate is proportional to the solids loading** while the pad touches the wafer between
   the particles (up to about 40 wt% silica at 4 psi); it then grows more slowly as the
   particles share the summits' pressure. The 3 wt% / 2 wt% ratio is therefore the ratio of
   the volume fractions, 1.51, where US 9,499,721 measured 1.06-1.11.
3. **The abrasive and the film set the scale**: copper is indented about as deep as oxide
   relative to the particle (softer, but the pad's pressure is the same), alumina is denser than
   silica (fewer particles at the same wt%), ceria denser still.

![Removal rate against particle size and solids loading](abrasive.png)
"""

import os
from pathlib import Path

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt
import numpy as np

import cmpsim

GRID = os.environ.get("CMPSIM_DOCS_GRID", "default")
OUT = Path(os.environ.get("CMPSIM_DOCS_OUT", Path(__file__).parent / "_output" / Path(__file__).stem))
OUT.mkdir(parents=True, exist_ok=True)

NM_PER_MIN = 6e10  # m/s -> nm/min
default = cmpsim.Config.default().replace(grid=GRID)
lai = default.replace(film="copper", abrasive="alumina", applied_pressure="48 kPa", rotation_speed="75 rpm",
                      centre_distance="89.13 mm", wafer_diameter="100 mm")
cases = {"silica on oxide, 4 psi, 0.63 m/s": default, "alumina on copper, Lai's conditions": lai}

sizes_nm = [50, 100, 300, 1000, 2000]
loadings = [0.5, 1, 2, 3, 5, 12.5, 30, 50]
by_size, by_loading = {}, {}
for label, base in cases.items():
    by_size[label] = [cmpsim.solve(base, relative=False, particle_diameter=d / 1e9).removal_rate_mean * NM_PER_MIN for d in sizes_nm]
    by_loading[label] = [cmpsim.solve(base, relative=False, solids_loading=f"{w} %").removal_rate_mean * NM_PER_MIN for w in loadings]
    print(label)
    print("  d (nm)       " + "".join(f"{d:>9}" for d in sizes_nm))
    print("  RR (nm/min)  " + "".join(f"{v:9.2f}" for v in by_size[label]))
    print("  w (wt%)      " + "".join(f"{w:>9}" for w in loadings))
    print("  RR (nm/min)  " + "".join(f"{v:9.2f}" for v in by_loading[label]))

print("\nabrasive and film at the default operating point (12.5 wt%, 100 nm):")
for film in ("oxide", "copper", "tungsten"):
    rates = [cmpsim.solve(default, relative=False, film=film, abrasive=a).removal_rate_mean * NM_PER_MIN for a in ("silica", "ceria", "alumina")]
    print(f"  {film:>9}: silica {rates[0]:7.1f}  ceria {rates[1]:7.1f}  alumina {rates[2]:7.1f} nm/min")

print("\nUS 9,499,721 Table 18 (54 nm silica, 200 mm, 100 rpm): 3 wt% / 2 wt%")
measured = {1.5: 1240 / 1170, 3: 2480 / 2290, 5: 4030 / 3630}
patent = default.replace(rotation_speed="100 rpm", wafer_diameter="200 mm", particle_diameter="54 nm")
for psi, m in measured.items():
    rr = [cmpsim.solve(patent, relative=False, applied_pressure=f"{psi} psi", solids_loading=w).removal_rate_mean for w in ("2 %", "3 %")]
    print(f"  {psi:>3} psi: model {rr[1] / rr[0]:.3f}, measured {m:.3f}, error {100 * (rr[1] / rr[0] / m - 1):+.0f} %")

fig, (a1, a2) = plt.subplots(1, 2, figsize=(10, 4))
for label in cases:
    a1.plot(sizes_nm, by_size[label], "o-", label=label)
    a2.plot(loadings, by_loading[label], "o-", label=label)
a1.plot([50, 300, 1000], [51, 112, 133], "ks", label="Lai 2001, Cu / alumina (measured)")
a1.set(xscale="log", xlabel="particle diameter (nm)", ylabel="removal rate (nm/min)", title="size, 12.5 wt%")
a2.set(xscale="log", yscale="log", xlabel="solids loading (wt%)", ylabel="removal rate (nm/min)", title="loading, 100 nm")
a1.legend(fontsize=7)
fig.tight_layout()
fig.savefig(OUT / "abrasive.png", dpi=110)
