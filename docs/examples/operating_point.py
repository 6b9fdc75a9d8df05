"""# One operating point and its wafer maps

Solve one operating point, read its scalar outputs (SI units), and draw and save the wafer
maps of every field. Inputs take units as strings (`"3 psi"`, `"75 rpm"`, `"150 nm"`), pint
quantities, or plain numbers in SI; every input, its unit, valid range and source is listed by
`cmpsim params` and in the [parameter table](../model.md#14-parameter-table).

The same run from the command line writes the maps, the removal profile, the fields and
scalars (CF NetCDF), the result (JSON) and the full input set (TOML) to one folder:

```bash
cmpsim run --set applied_pressure=3psi --set rotation_speed=75rpm --set particle_diameter=150nm --out results/
```

The result object holds every scalar as an attribute in SI (`result.attack_angle`, in rad;
the names, units and meanings are in the [output table](../model.md#16-outputs)),
`result.fields` (an `xarray.Dataset` of the wafer maps on a Cartesian grid, in SI, with units in
the attributes and NaN outside the wafer), the rotation-averaged profiles
(`result.radius`, `result.removal_rate_profile`, `result.film_thickness_profile`),
`result.summary()`, `result.to_json()` (the object of `cmpsim run --json`),
`result.to_netcdf(path)` and `result.provenance` (model variant, version, and every parameter
with its value and source).

The four default maps: film thickness (the wafer is domed by 5 µm, but on the default model's
compliant pad stack the pad takes up most of the dome, so the film varies by a few per cent (under
10 %) over the wafer; on the paper's rigid pad, `cmpsim.Config.paper()`, it is thinnest near the centre),
the slurry gauge pressure
(positive where the film converges, upstream, sub-ambient downstream), the pad contact pressure
and the local removal rate:

![Default wafer maps](maps.png)

All fields, including the real contact area ratio of each contact regime and the two stresses
of the removal law RR = K σ<sub>n</sub> τ:

![Every field](all_fields.png)

Profiles through the wafer centre along the sliding direction (x) and across it (y):

![Profiles through the centre](profiles.png)

What the wafer actually loses: it turns under this stationary map, so a point at radius r
loses the average of the map along the circle r. That rotation-averaged removal profile gives
the within-wafer non-uniformity (1σ / mean inside the 3 mm edge exclusion) and the range;
`cmpsim run --out` writes the same plot as `profile.png`:

![Rotation-averaged removal and film profiles](uniformity.png)
"""

import os
from pathlib import Path

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt

import cmpsim

GRID = os.environ.get("CMPSIM_DOCS_GRID", "default")
OUT = Path(os.environ.get("CMPSIM_DOCS_OUT", Path(__file__).parent / "_output" / Path(__file__).stem))
OUT.mkdir(parents=True, exist_ok=True)

# Inputs: the base case with three changes (a Config can also come from a TOML file:
# cmpsim.Config.from_toml("case.toml")).
config = cmpsim.Config.default().replace(
    applied_pressure="3 psi", rotation_speed="75 rpm", particle_diameter="150 nm", grid=GRID
)
config.to_toml(OUT / "config.toml")  # every input, SI, reproducible

result = cmpsim.solve(config)
print(result.summary())
print()
print(f"film thickness at the centre: {result.film_thickness_center * 1e6:.3f} um")
print(f"attack angle:                 {result.attack_angle:.3e} rad")
print(f"load carried by the slurry:   {100 * result.fluid_load_fraction:.2f} %")
print(f"removal rate (wafer mean):    {result.removal_rate_mean * 1e9 * 60:.1f} nm/min")
print(f"within-wafer non-uniformity:  {100 * result.within_wafer_nonuniformity:.1f} % (1 sigma / mean)")
if result.flow_factor_floored_fraction > 0:
    print("warning: flow factors were regularised; see the limitations page")

# Wafer maps: a matplotlib Figure, and the fields as an xarray Dataset.
fig = result.plot()
fig.savefig(OUT / "maps.png", dpi=80)
plt.close(fig)

every_field = (
    "film_thickness", "granular_pressure", "slurry_pressure", "contact_pressure",
    "contact_area_ratio_elastic", "contact_area_ratio_elastoplastic", "normal_stress", "shear_stress",
)
fig = result.plot(fields=every_field)
fig.savefig(OUT / "all_fields.png", dpi=70)
plt.close(fig)

ds = result.fields
print()
print(ds)
film = result.polar["film_thickness"]
assert film.max() - film.min() < 0.1 * result.film_thickness_mean  # the page says so (about 2 % on the default grid)
result.to_netcdf(OUT / "fields.nc")  # open later with xarray.open_dataset

# Profiles through the centre, straight from the Dataset.
fig, axes = plt.subplots(1, 3, figsize=(13, 3.6), layout="constrained")
centre_row = ds.sel(y=0.0, method="nearest")
centre_col = ds.sel(x=0.0, method="nearest")
for data, coord, label in ((centre_row, "x", "along x (sliding)"), (centre_col, "y", "along y")):
    pos_mm = data[coord].values * 1e3
    axes[0].plot(pos_mm, data.film_thickness.values * 1e6, label=label)
    axes[1].plot(pos_mm, data.slurry_pressure.values * 1e-3, label=label)
    axes[2].plot(pos_mm, data.removal_rate.values * 1e9 * 60, label=label)
for ax, ylabel in zip(axes, ("film thickness (um)", "slurry gauge pressure (kPa)", "removal rate (nm/min)")):
    ax.set_xlabel("position (mm)")
    ax.set_ylabel(ylabel)
    ax.grid(alpha=0.3)
axes[0].legend()
fig.suptitle("Profiles through the wafer centre")
fig.savefig(OUT / "profiles.png", dpi=80)
plt.close(fig)

# The rotation-averaged profiles: one value per ring of the grid, at the ring-centre radius.
print()
print("radius (mm)  removal rate (nm/min)  film thickness (um)")
for r, rr, h in zip(result.radius, result.removal_rate_profile, result.film_thickness_profile):
    print(f"{r * 1e3:11.2f}  {rr * 1e9 * 60:21.1f}  {h * 1e6:19.3f}")
fig = result.plot_profiles()
fig.savefig(OUT / "uniformity.png", dpi=80)
plt.close(fig)
