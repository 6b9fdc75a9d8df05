"""# Leaving the model's validity: what the code does

A load sweep far beyond the paper's range (2–6 psi) with the LEP and the elastic variants of
the paper's model (`cmpsim.Config.paper()`: the paper's Patir–Cheng flow factors and summit
constants on a rigid pad), to show the two limits of that model that a user can run into, and
how each is reported. The
[limitations](../limitations.md) page explains them.

1. **The flow factors' validity (h/σ ≲ 1.22).** As the load rises, the film thins. When the
   smallest film falls to about 1.2 pad roughnesses, the perturbation flow factors of the paper
   (eq. 8) stop being positive; the solver then raises their eigenvalues to
   `flow_factor_floor` on the faces concerned and reports the share of such faces as
   `flow_factor_floored_fraction` (`cmpsim run` prints a warning). Results there are returned
   but are outside the model's validity: note the attack angle turning negative and the
   slurry's share of the load rising again, both artefacts of the regularised flow factors.
2. **A load the pad cannot carry.** Past a few hundred psi the asperities cannot carry the
   load before the wafer reaches the pad mean plane: `solve` raises `EquilibriumError` with
   the diagnosis (exit status 3 from `cmpsim run`); no NaN is ever returned.

Bad inputs (a negative dome, a length for a pressure) are refused before any computation with
a `ValueError` that names the parameter and its valid range (exit status 2).

![Validity indicators over a wide load range](validity.png)
"""

import os
from pathlib import Path

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt
import numpy as np

import cmpsim
from cmpsim.solver.equilibrium import EquilibriumError

GRID = os.environ.get("CMPSIM_DOCS_GRID", "default")
OUT = Path(os.environ.get("CMPSIM_DOCS_OUT", Path(__file__).parent / "_output" / Path(__file__).stem))
OUT.mkdir(parents=True, exist_ok=True)

base = cmpsim.Config.paper().replace(grid=GRID)  # the paper's model, whose limits this page shows
pressures_psi = np.geomspace(0.5, 250.0, 13)
names = ("film_thickness_min", "flow_factor_floored_fraction", "attack_angle", "fluid_load_fraction")
data = {}
print(f"{'variant':>8} {'P (psi)':>8} {'h_min/sigma':>12} {'floored':>8} {'theta (urad)':>13} {'slurry %':>9}")
for variant in ("lep", "elastic"):
    rows = []
    for psi in pressures_psi:
        r = cmpsim.solve(base.replace(model=variant, applied_pressure=f"{psi:.4g} psi"), relative=False)
        rows.append([getattr(r, n) for n in names])
        print(
            f"{variant:>8} {psi:8.3g} {r.film_thickness_min / r.config.pad_roughness:12.3f} {r.flow_factor_floored_fraction:8.3f}"
            f" {r.attack_angle * 1e6:13.2f} {100 * r.fluid_load_fraction:9.2f}"
        )
    data[variant] = np.array(rows).T

print()
for overrides in ({"applied_pressure": "400 psi"}, {"dome_height": "-1 um"}, {"applied_pressure": "4 mm"}):
    try:
        cmpsim.solve(base.replace(**overrides))
    except EquilibriumError as exc:
        print(f"{overrides}: EquilibriumError: {exc}")
    except ValueError as exc:
        print(f"{overrides}: ValueError: {exc}")
    else:
        raise AssertionError(f"{overrides} should have been refused")

# The statements of the page.
in_range = (pressures_psi >= 2.0) & (pressures_psi <= 6.0)
lep = dict(zip(names, data["lep"]))
assert np.all(lep["flow_factor_floored_fraction"][in_range] == 0.0)
assert np.all(lep["flow_factor_floored_fraction"][pressures_psi > 50] > 0.5)
assert np.all(lep["attack_angle"][pressures_psi > 50] < 0.0)

sigma = base.pad_roughness
fig, axes = plt.subplots(2, 2, figsize=(10, 7), layout="constrained", sharex=True)
panels = (
    ("film_thickness_min", 1 / sigma, "smallest film / pad roughness"),
    ("flow_factor_floored_fraction", 1.0, "share of regularised flow factors"),
    ("attack_angle", 1e6, "attack angle (urad)"),
    ("fluid_load_fraction", 100.0, "load carried by the slurry (%)"),
)
for ax, (name, scale, label) in zip(axes.flat, panels):
    k = names.index(name)
    for variant, style in (("lep", "o-"), ("elastic", "s--")):
        ax.plot(pressures_psi, data[variant][k] * scale, style, label=variant)
    ax.axvspan(2.0, 6.0, color="0.85", zorder=0, label="paper's range")
    ax.set_xscale("log")
    ax.set_ylabel(label)
    ax.grid(alpha=0.3)
axes[0, 0].axhline(np.sqrt(1.5), color="k", lw=0.8, ls=":", label="h/sigma = 1.22")
axes[0, 0].legend(fontsize=8)
for ax in axes[1]:
    ax.set_xlabel("applied pressure (psi)")
fig.suptitle(f"60 rpm, base case otherwise (grid {GRID})")
fig.savefig(OUT / "validity.png", dpi=80)
plt.close(fig)
