"""# A load and speed study

How the film thickness, attack angle, load sharing and removal rate follow the applied
pressure and the rotation speed over the paper's range (2–6 psi, 30–90 rpm), on the paper's
model (`cmpsim.Config.paper()`: granular slurry, rigid pad), whose trends the page checks. This is a plain
Python loop over `cmpsim.solve`; for larger studies, in parallel, resumable and written to
NetCDF, use a [sweep](sweep.md).

Each solve reuses the previous equilibrium as its Newton start (`start=`), which saves about
one iteration per point; the result does not depend on it (tolerance 1e-9 on the residuals).

![Outputs against load, one line per speed](load_speed.png)

What the model gives (the script asserts each of these trends, so this text cannot drift from
the figures): the film thins with load and thickens with speed; the attack angle and the share
of the load carried by the slurry grow with speed and fall with load; the removal rate rises
with both, and load has the larger effect over this range (the paper's main removal-rate
statement). Speed acts only through the ambient granular pressure p<sub>0</sub> ∝ U² at the
wafer edge (see [the model, section 4](../model.md#4-what-carries-the-speed-dependence-the-ambient-granular-pressure)).

![Removal rate over load and speed](removal_map.png)
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

pressures_psi = [2.0, 3.0, 4.0, 5.0, 6.0]
speeds_rpm = [30.0, 45.0, 60.0, 75.0, 90.0]
outputs = {
    "film_thickness_center": ("film thickness at centre (um)", 1e6),
    "attack_angle": ("attack angle (urad)", 1e6),
    "fluid_load_fraction": ("load carried by slurry (%)", 100.0),
    "removal_rate_mean": ("removal rate (nm/min)", 1e9 * 60),
}
table = {name: np.empty((len(speeds_rpm), len(pressures_psi))) for name in outputs}

base = cmpsim.Config.paper().replace(grid=GRID)  # the paper's model, whose trends this page states
print(f"{'P (psi)':>8} {'speed (rpm)':>12} {'h_c (um)':>9} {'theta (urad)':>13} {'slurry %':>9} {'RR (nm/min)':>12}")
for i, rpm in enumerate(speeds_rpm):
    start = None
    for j, psi in enumerate(pressures_psi):
        r = cmpsim.solve(base.replace(applied_pressure=f"{psi} psi", rotation_speed=f"{rpm} rpm"), start=start)
        start = r.solution.state.u  # warm start for the next load
        assert r.converged and r.flow_factor_floored_fraction == 0.0
        for name in outputs:
            table[name][i, j] = getattr(r, name)
        print(
            f"{psi:8.1f} {rpm:12.0f} {r.film_thickness_center * 1e6:9.3f} {r.attack_angle * 1e6:13.2f}"
            f" {100 * r.fluid_load_fraction:9.2f} {r.removal_rate_mean * 1e9 * 60:12.1f}"
        )

# The trends stated on the documentation page.
h, theta, fluid, rr = (table[n] for n in outputs)
rising_with_load = lambda a: bool(np.all(np.diff(a, axis=1) > 0))
rising_with_speed = lambda a: bool(np.all(np.diff(a, axis=0) > 0))
assert rising_with_load(-h) and rising_with_speed(h)
assert rising_with_load(-theta) and rising_with_speed(theta)
assert rising_with_load(-fluid) and rising_with_speed(fluid)
assert rising_with_load(rr) and rising_with_speed(rr)
load_effect = rr[2, -1] / rr[2, 0]  # 2 -> 6 psi at 60 rpm
speed_effect = rr[-1, 2] / rr[0, 2]  # 30 -> 90 rpm at 4 psi
print(f"removal rate x{load_effect:.2f} from 2 to 6 psi (60 rpm), x{speed_effect:.2f} from 30 to 90 rpm (4 psi)")
assert load_effect > speed_effect

fig, axes = plt.subplots(2, 2, figsize=(10, 7), layout="constrained")
colors = plt.cm.viridis(np.linspace(0.0, 0.9, len(speeds_rpm)))
for ax, (name, (label, scale)) in zip(axes.flat, outputs.items()):
    for i, rpm in enumerate(speeds_rpm):
        ax.plot(pressures_psi, table[name][i] * scale, "o-", color=colors[i], label=f"{rpm:.0f} rpm")
    ax.set_xlabel("applied pressure (psi)")
    ax.set_ylabel(label)
    ax.grid(alpha=0.3)
axes[0, 0].legend(fontsize=8)
fig.suptitle(f"LEP model, base case otherwise (grid {GRID})")
fig.savefig(OUT / "load_speed.png", dpi=80)
plt.close(fig)

fig, ax = plt.subplots(figsize=(5.5, 4.2), layout="constrained")
rr_nm_min = table["removal_rate_mean"] * 1e9 * 60
cs = ax.contourf(pressures_psi, speeds_rpm, rr_nm_min, levels=12, cmap="viridis")
ax.contour(pressures_psi, speeds_rpm, rr_nm_min, levels=12, colors="k", linewidths=0.4)
fig.colorbar(cs, ax=ax, label="removal rate (nm/min)")
ax.set_xlabel("applied pressure (psi)")
ax.set_ylabel("rotation speed (rpm)")
ax.set_title("Wafer-mean removal rate")
fig.savefig(OUT / "removal_map.png", dpi=80)
plt.close(fig)
