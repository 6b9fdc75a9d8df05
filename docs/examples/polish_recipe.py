"""# Polishing a recipe through time: a film stack, an end point, a pad that warms

`cmpsim polish RECIPE.toml` (Python: `cmpsim.polish`) polishes a recipe step by step: the
film stack per radius of the wafer, the end point seen in the wafer's reflectance, and the pad's
temperature driven by the frictional power of the solved shear field
([the polisher, section 4](../polisher.md#4-recipes-cmpsim-polish)). These are the two recipes of
issue 32, shipped as `src/cmpsim/data/recipe_copper.toml` and `recipe_oxide.toml` and run here as
written (the 300mm preset on the default grid):

```toml
--8<-- "src/cmpsim/data/recipe_copper.toml"
```

```toml
--8<-- "src/cmpsim/data/recipe_oxide.toml"
```

    cmpsim polish src/cmpsim/data/recipe_copper.toml --out copper/
    cmpsim polish src/cmpsim/data/recipe_oxide.toml --json

![Copper recipe: thickness per radius after each step](copper_thickness.png)

![Copper recipe: pad temperature and the end-point signal against time](copper_time.png)

![Oxide recipe: the reflectance fringes of the thinning oxide and the pad temperature](oxide_time.png)

What it shows (the script asserts each statement):

- **The bulk step leaves copper everywhere** (30 s at 3 psi removes about 195 nm of 1.2 µm).
- **The landing step does not reach its end point on the 300mm preset.** At 1.5 psi the slurry
  film carries most of the load on the ungrooved pad: copper is removed at about 33 nm/min, so
  none of it clears in the 240 s allowed and the step ends at its `max_time` (`end = "time"`,
  `endpoint.detected = false`). The issue's criterion (the end point before `max_time`, copper
  cleared on 95 % of the area) is **not met**; the model is not tuned to meet it.
- **The pad warms at high pressure and cools at low pressure**: the bulk step's frictional
  power (about 23 kW/m², an effective friction of 0.56 at 1.95 m/s) raises the pad surface by
  about 43 K in 30 s, far more than the 9.1 K White et al. (2003) measured (see the polisher page);
  the landing step's 3 kW/m² lets it cool back to about 7 K above the slurry, the barrier step
  (2 psi) warms it again by about 10 K.
- **The oxide recipe** removes about 400 nm/min on the 300mm preset, so after its 60 s about 600 nm
  of oxide is left against the target of 500 nm (`target.deviation`); the reflectance swings
  through the oxide's thin-film fringes as it thins.
"""

import os
from pathlib import Path

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt
import numpy as np

import cmpsim

OUT = Path(os.environ.get("CMPSIM_DOCS_OUT", Path(__file__).parent / "_output" / Path(__file__).stem))
OUT.mkdir(parents=True, exist_ok=True)
DATA = Path(cmpsim.__file__).parent / "data"
NM_MIN = 6e10

# the recipes as written: the 300mm preset on its default grid (the coarse grid's bending does not
# converge at 1.5 psi), whatever grid the documentation build uses for the other examples
copper = cmpsim.polish(DATA / "recipe_copper.toml")
oxide = cmpsim.polish(DATA / "recipe_oxide.toml")
for res in (copper, oxide):
    print(res.recipe.source)
    for s in res.steps:
        v = s.pad_temperature["value"]
        print(f"  {s.name:8s} end {s.end:8s} {s.duration:6.1f} s  mean rate {NM_MIN * s.removal_rate_mean:6.1f} nm/min  "
              f"pad {v[0]:.2f} -> {v[-1]:.2f} K  top film {s.top_film} cleared on {100 * s.cleared_fraction:.1f} %")
    print(f"  {res.solves} solves, {res.wall_time:.1f} s")
bulk, landing, barrier = copper.steps
assert bulk.end == "time" and min(bulk.thickness["copper"]) > 0
assert landing.end == "time" and not landing.endpoint["detected"]  # the criterion is not met (see the text)
assert bulk.pad_temperature["value"][-1] > bulk.pad_temperature["value"][0]
assert landing.pad_temperature["value"][-1] < landing.pad_temperature["value"][0]
assert barrier.pad_temperature["value"][-1] > barrier.pad_temperature["value"][0]
rise = bulk.pad_temperature["value"][-1] - bulk.pad_temperature["value"][0]
assert 20 < rise < 80
t = oxide.target
print(f"oxide target {1e9 * t['remaining']:.0f} nm, left {1e9 * t['final_mean']:.1f} nm")
assert t["deviation"] > 0

fig, ax = plt.subplots(figsize=(7, 4))
r_mm = 1e3 * np.asarray(copper.initial.radius)
for s in copper.steps:
    ax.plot(r_mm, 1e9 * np.asarray(s.thickness["copper"]), marker=".", label=f"after {s.name}: copper")
ax.set_xlabel("radius (mm)")
ax.set_ylabel("copper thickness (nm)")
ax.legend()
fig.savefig(OUT / "copper_thickness.png", dpi=110, bbox_inches="tight")

fig, (a, b) = plt.subplots(1, 2, figsize=(11, 4))
for s in copper.steps:
    a.plot(s.pad_temperature["time"], np.asarray(s.pad_temperature["value"]) - 273.15, label=s.name)
    b.plot(s.signals.time, s.signals.reflectance, label=s.name)
a.set_xlabel("time (s)")
a.set_ylabel("pad surface temperature (°C)")
a.legend()
b.set_xlabel("time (s)")
b.set_ylabel("reflectance at 650 nm (area mean)")
b.legend()
fig.savefig(OUT / "copper_time.png", dpi=110, bbox_inches="tight")

fig, (a, b) = plt.subplots(1, 2, figsize=(11, 4))
s = oxide.steps[0]
a.plot(s.signals.time, s.signals.reflectance)
a.set_xlabel("time (s)")
a.set_ylabel("reflectance at 650 nm (area mean)")
b.plot(s.pad_temperature["time"], np.asarray(s.pad_temperature["value"]) - 273.15)
b.set_xlabel("time (s)")
b.set_ylabel("pad surface temperature (°C)")
fig.savefig(OUT / "oxide_time.png", dpi=110, bbox_inches="tight")
