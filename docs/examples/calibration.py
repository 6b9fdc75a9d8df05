"""# Calibrating to your own measurements

Some inputs of the model are not known for your process: the pad's summit statistics and
hardness, the Runnels–Eyman removal coefficient K (`preston_coefficient`), and above all the
grain-gap ratio d/s (`diameter_gap_ratio`), which sets the edge granular pressure and with it
how strongly speed matters (see [the model, section 4](../model.md#4-what-carries-the-speed-dependence-the-ambient-granular-pressure)).
`cmpsim.calibrate` fits the ones you name to your data by bounded least squares, with
standard errors, 95 % intervals and the correlation of the fitted values, and returns a
configuration that every command accepts.

## 1. Write your measurements as a CSV file

One row per measured value; the operating conditions are columns named as cmpsim inputs
(`applied_pressure`, `rotation_speed`, `particle_diameter`, ..., values with units); `#`
lines above the header carry the citation and provenance. Quantities: `removal_rate`,
`film_thickness`, `film_thickness_mean`, `film_thickness_min`, `film_thickness_max`,
`fluid_load_fraction`, `contact_area_ratio` (and its `_elastic` / `_elastoplastic` parts),
`friction_coefficient`; the unit is any unit of that quantity (`nm/min`, `A/min`, `um`, `%`).
The `uncertainty` column (one standard deviation, same unit) weights each point; without it
the fit uses relative errors. The format is the one of the shipped data sets, described in
`cmpsim/data/README.md` (see [validation](../validation.md)).

```text
# dataset: my_polisher
# kind: measurement
# citation: our lab notebook, 2024-05-14
dataset,quantity,value,unit,uncertainty,comparison,applied_pressure,rotation_speed,source
my_polisher,removal_rate,40.1,nm/min,1.2,absolute,2 psi,30 rpm,run 17
...
```

In this script the "measurements" are **synthetic**: they are made by the paper's model
(`cmpsim.Config.paper()`, whose granular slurry gives d/s its role and whose removal law is the
one K belongs to) with K = 3.5×10⁻¹⁸ m s⁻¹ Pa⁻² and d/s = 40 instead of the preset's values
(2.5×10⁻¹⁸ and 67), plus 3 % Gaussian noise, so that you can see the fit recover known values.
Replace the file with yours.

## 2. Fit

```python
fit = cmpsim.calibrate("my_measurements.csv", free=["preston_coefficient", "diameter_gap_ratio"], config=cmpsim.Config.paper())
print(fit.summary())
fit.to_toml("calibrated.toml")
```

or, from the command line,

```bash
cmpsim calibrate my_measurements.csv --preset paper --free preston_coefficient diameter_gap_ratio --out calibrated.toml
cmpsim run calibrated.toml                                   # the calibrated model (every input in the file)
cmpsim validate my_measurements.csv --config calibrated.toml  # model vs data, point by point
```

Choose free inputs your data can determine: removal rates at several loads and speeds pin
K (the overall scale) and d/s (how the rate grows with speed); they cannot tell the pad
hardness from the summit density. The summary prints the correlation matrix: values near ±1
mean the data cannot separate two inputs, and a singular problem is reported as such.

![Measured and modelled removal rates before and after the fit](calibration.png)
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

base = cmpsim.Config.paper().replace(grid=GRID)  # the paper's model: granular slurry (d/s), the paper's removal law (K)
pressures_psi = (2.0, 4.0, 6.0)
speeds_rpm = (30.0, 60.0, 90.0)

# --- synthetic "measurements" (replace this block by your own file) -------------------
truth = base.replace(preston_coefficient=3.5e-18, diameter_gap_ratio=40.0)
rng = np.random.default_rng(7)
lines = [
    "# dataset: my_polisher",
    "# kind: measurement",
    "# citation: synthetic data made by cmpsim (K = 3.5e-18 m/(s Pa^2), d/s = 40, 3 % noise)",
    "dataset,quantity,value,unit,uncertainty,comparison,applied_pressure,rotation_speed,source",
]
for psi in pressures_psi:
    for rpm in speeds_rpm:
        rr = cmpsim.solve(truth.replace(applied_pressure=f"{psi} psi", rotation_speed=f"{rpm} rpm")).removal_rate_mean * 1e9 * 60
        sd = 0.03 * rr
        lines.append(f"my_polisher,removal_rate,{rr + sd * rng.standard_normal():.1f},nm/min,{sd:.2f},absolute,{psi:g} psi,{rpm:g} rpm,synthetic")
data_file = OUT / "my_measurements.csv"
data_file.write_text("\n".join(lines) + "\n")
print(data_file.read_text())

# --- the fit ------------------------------------------------------------------------------
fit = cmpsim.calibrate(data_file, free=["preston_coefficient", "diameter_gap_ratio"], config=base)
print(fit.summary())
fit.to_toml(OUT / "calibrated.toml")
calibrated = cmpsim.Config.from_toml(OUT / "calibrated.toml")  # what `cmpsim run calibrated.toml` reads

for name, true_value in (("preston_coefficient", 3.5e-18), ("diameter_gap_ratio", 40.0)):
    lo, hi = fit.ci95[name]
    print(f"{name}: fitted {fit.values[name]:.4g}, 95 % interval [{lo:.4g}, {hi:.4g}], true {true_value:.4g}")
    assert lo < true_value < hi, name  # the page says the fit recovers the known values
assert fit.rms_after < fit.rms_before

# --- figure: data, model before and after -------------------------------------------------
measured = np.array([[float(row.split(",")[2]) for row in lines[4:]]]).reshape(len(pressures_psi), len(speeds_rpm))
errors = np.array([[float(row.split(",")[4]) for row in lines[4:]]]).reshape(len(pressures_psi), len(speeds_rpm))
p_line = np.linspace(1.5, 6.5, 6)
fig, ax = plt.subplots(figsize=(7, 4.6), layout="constrained")
for k, rpm in enumerate(speeds_rpm):
    color = f"C{k}"
    for config, style, label in ((base, ":", "paper preset"), (calibrated, "-", "calibrated")):
        rr = [cmpsim.solve(config.replace(applied_pressure=f"{p} psi", rotation_speed=f"{rpm} rpm"), relative=False).removal_rate_mean * 1e9 * 60 for p in p_line]
        ax.plot(p_line, rr, style, color=color, label=f"{rpm:.0f} rpm, {label}")
    ax.errorbar(pressures_psi, measured[:, k], yerr=errors[:, k], fmt="o", color=color, capsize=3, label=f"{rpm:.0f} rpm, data")
ax.set_xlabel("applied pressure (psi)")
ax.set_ylabel("removal rate (nm/min)")
ax.set_title(f"Fit of K and d/s: chi-square {fit.chi2_before:.0f} -> {fit.chi2_after:.1f} ({fit.dof} dof)")
ax.grid(alpha=0.3)
ax.legend(fontsize=7, ncol=3)
fig.savefig(OUT / "calibration.png", dpi=80)
plt.close(fig)
