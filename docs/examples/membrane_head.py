"""# The polishing head: membrane zones, a bending wafer, the retaining ring, zone tuning

`carrier = "membrane"` presses the wafer from behind in concentric zones (`zone_radii`,
`zone_pressures`) and lets it bend as a free Kirchhoff plate of `wafer_thickness`
([model, section 13f](../model.md#13f-carrier-rigid-or-membrane-beyond-the-paper)). Zone
inputs are lists, one string of numbers and one unit:

    cmpsim run --set carrier=membrane --set "zone_radii=10,20,30,38.1 mm" --set "zone_pressures=4,4.2,3.9,4 psi"
    cmpsim tune-zones --set carrier=membrane --set "zone_radii=10,20,30,38.1 mm" --json

This script solves the default operating point (3-inch wafer, 4 psi, 60 rpm) with the rigid
carrier and with a four-zone membrane at uniform pressure, tunes the zone pressures, and, on
the laterally coupled pad, raises the retaining ring's pressure.

![Removal profiles: rigid carrier, membrane, tuned zones; the wafer's bending](head.png)

![Edge removal against the retaining ring's pressure (layered pad)](ring.png)

What it shows (the script asserts each statement):

- **The bending wafer evens out the pressure.** Under uniform zones the wafer bends by about
  2.5 µm (half its 5 µm dome), the total pressure under it stays within about 1 % of the membrane's,
  and the non-uniformity falls from 0.34 % to 0.035 %.
- **Tuning flattens what the zones can reach.** `cmpsim.tune_zones` lowers the non-uniformity
  several-fold with pressures within 10 % of the start; each zone moves the wafer's rate as a
  whole rather than the rate under it (`zone_response_inside`), because the 8 µm slurry film
  carries a zone's extra load. Without `keep="pressure"` the tuner may change the load: here the
  mean pressure rises by under 2 %, and the mean rate with it.
- **The response width at each boundary** (`tuned.response_widths`, or
  `cmpsim.head.zone_response.zone_response(config)` at given pressures): over how many millimetres the
  rate's answer to a pressure step at a zone boundary falls from 90 % to 10 %.
- **The production case** is a preset: `cmpsim tune-zones --preset 300mm --ring --json` (a 300 mm
  wafer, five zones, a retaining ring on the layered pad with the production pad's concentric
  grooves; `--ring` tunes the ring's pressure with the zones; about 35 s of CPU per tuning, so not
  run here; its numbers are in [model, section 13f](../model.md#13f-carrier-rigid-or-membrane-beyond-the-paper)).
- **The ring tames the edge of the layered pad.** On `pad_compliance = "layer"` the ring's
  pressure pushes the pad away from the wafer's edge and the edge ring's rate falls
  monotonically with it.
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
NM_MIN = 6e10

base = cmpsim.Config.default().replace(grid=GRID)
head = base.replace(carrier="membrane", zone_radii="10,20,30,38.1 mm")
rigid = cmpsim.solve(base, relative=False)
membrane = cmpsim.solve(head, relative=False)
tuned = cmpsim.tune_zones(head)
print(f"grid {GRID}")
for name, r in (("rigid carrier", rigid), ("membrane, uniform zones", membrane)):
    print(f"{name:26s} non-uniformity {100 * r.scalars['within_wafer_nonuniformity']:.3f} %, "
          f"mean rate {NM_MIN * r.scalars['removal_rate_mean']:.1f} nm/min")
print(f"{'tuned zones':26s} non-uniformity {100 * tuned.within_wafer_nonuniformity:.3f} %, pressures "
      + ", ".join(f"{p / 6894.757:.2f}" for p in tuned.zone_pressures) + " psi")
print("share of each zone's response under the zone:", ", ".join(f"{v:.2f}" for v in tuned.response_inside))
# the 10-90 % width of the rate's answer to a pressure step at each inner zone boundary (cmpsim.head.zone_response)
widths = tuned.response_widths
print("response width at each boundary:", ", ".join(
    f"{1e3 * w.boundary:g} mm: " + ("no fall" if w.width is None else f"{1e3 * w.width:.1f} mm") for w in widths))
assert len(widths) == 3
bending = membrane.profiles["wafer_bending_profile"]
p = membrane.solution.state.p_total / head.applied_pressure
assert 2.0e-6 < np.max(np.abs(bending)) < 3.0e-6
assert 0.985 < p.min() and p.max() < 1.015
# The factor of three holds on the default grid the docs are built on (0.035 % against 0.340 %);
# the coarse grid of the test suite does not resolve a non-uniformity this small (0.288 % against
# 0.485 %, tuned 0.116 %), so there only the direction is checked.
factor = 1.0 if GRID == "coarse" else 3.0
assert membrane.scalars["within_wafer_nonuniformity"] < rigid.scalars["within_wafer_nonuniformity"] / factor
assert tuned.within_wafer_nonuniformity < tuned.before["within_wafer_nonuniformity"] / factor

fig, (a, b) = plt.subplots(1, 2, figsize=(11, 4))
r_mm = 1e3 * np.asarray(rigid.profiles["radius"])
for label, rate in (("rigid carrier", rigid.profiles["removal_rate_profile"]), ("membrane, uniform zones", membrane.profiles["removal_rate_profile"]), ("membrane, tuned zones", tuned.profile["rate"])):
    a.plot(r_mm, NM_MIN * np.asarray(rate), marker=".", label=label)
for edge in (10, 20, 30):
    a.axvline(edge, color="grey", lw=0.5)
a.set_xlabel("radius (mm)")
a.set_ylabel("removal rate (nm/min)")
a.legend()
a.grid(alpha=0.3)
b.plot(r_mm, 1e6 * np.asarray(bending), marker=".")
b.set_xlabel("radius (mm)")
b.set_ylabel("wafer bending, away from the pad (µm)")
b.grid(alpha=0.3)
fig.suptitle(f"Default operating point, four zones (grey: zone boundaries), grid {GRID}")
fig.tight_layout()
fig.savefig(OUT / "head.png", dpi=80)

layer = base.replace(pad_compliance="layer")
pressures = (0.0, 2.0, 4.0, 6.0)
edge = []
for psi in pressures:
    r = cmpsim.solve(layer.replace(retaining_ring_pressure=f"{psi} psi"), relative=False)
    profile = np.asarray(r.profiles["removal_rate_profile"])
    edge.append(profile[-1] / profile.mean())
    print(f"ring {psi:.0f} psi: edge ring / mean rate {edge[-1]:.3f}, non-uniformity {100 * r.scalars['within_wafer_nonuniformity']:.2f} %")
assert all(y < x for x, y in zip(edge, edge[1:]))
fig, ax = plt.subplots(figsize=(5.5, 3.8))
ax.plot(pressures, edge, marker="o")
ax.set_xlabel("retaining ring pressure (psi)")
ax.set_ylabel("edge-ring rate / mean rate")
ax.grid(alpha=0.3)
fig.tight_layout()
fig.savefig(OUT / "ring.png", dpi=80)
