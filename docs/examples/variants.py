"""# Hydrodynamic, elastic and LEP variants

The paper compares three models of the same wafer (input `model`). This page runs them on
the paper's model, `cmpsim.Config.paper()` (granular slurry, rigid pad, the paper's summit
constants): the pure hydrodynamic variant has no pad contact, and the default model's
compliant pad stack (`pad_compliance = "winkler"`) needs contact, so the default refuses it;
on the default model, set `pad_compliance = "rigid"` to run it.

| variant | load carried by | contact law |
|---|---|---|
| `hydrodynamic` | slurry only | none |
| `elastic` | slurry + pad summits | Greenwood–Williamson (Hertz) for every summit, to any interference |
| `lep` (the default; the paper's model) | slurry + pad summits | elastic, elastoplastic (Zhao–Maietta–Chang) and plastic (Abbott–Firestone) by interference |

This script solves all three over the paper's load range at 60 rpm, on `cmpsim.Config.paper()`.

![The three variants against load](variants.png)

What it shows (the script asserts each statement):

- **LEP vs elastic.** Once a summit yields it carries less load for the same interference, so
  the LEP wafer sinks closer to the pad than the elastic one (thinner film) and its contact is
  almost all elastoplastic: the elastic ratio is about 10⁻⁵, the elastoplastic about 10⁻³. The
  elastic model instead puts all contact in the elastic regime, with a real area about half the
  LEP one. The removal rates of the two are close because the summit pressure that dominates τ
  is set by the load, not by the contact law.
- **Hydrodynamic.** Without contact the slurry alone must carry the load. With the paper's
  granular edge pressure p<sub>0</sub> ≈ 32 kPa this happens only at h/σ < 1, where the perturbation
  flow factors of the paper (eq. 8) are no longer positive: the solver regularises them on
  most cell faces (`flow_factor_floored_fraction` ≈ 0.85) and the attack angle comes out
  negative. These results are what the model gives, but they are outside its validity; `cmpsim
  run` prints a warning for them, and the [limitations](../limitations.md) page explains what the
  code does there.

The pressure carried by the slurry and by the summits at 4 psi, for each variant:

![Total pressure maps of the three variants](pressure_maps.png)
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

variants = ("lep", "elastic", "hydrodynamic")
pressures_psi = np.array([2.0, 3.0, 4.0, 5.0, 6.0])
names = (
    "film_thickness_center", "attack_angle", "contact_area_ratio_elastic",
    "contact_area_ratio_elastoplastic", "flow_factor_floored_fraction", "removal_rate_mean",
)
data = {v: {n: [] for n in names} for v in variants}
base_case = {}

base = cmpsim.Config.paper().replace(grid=GRID)  # the paper's model: rigid pad, granular slurry
for variant in variants:
    for psi in pressures_psi:
        r = cmpsim.solve(base.replace(model=variant, applied_pressure=f"{psi} psi"))
        assert r.converged
        for n in names:
            data[variant][n].append(getattr(r, n))
        if psi == 4.0:
            base_case[variant] = r
    data[variant] = {n: np.array(v) for n, v in data[variant].items()}

print(f"{'variant':>13} {'h_c (um)':>9} {'theta (urad)':>13} {'A_el':>10} {'A_ep':>10} {'floored':>8} {'RR (nm/min)':>12}   at 4 psi, 60 rpm")
for variant, r in base_case.items():
    print(
        f"{variant:>13} {r.film_thickness_center * 1e6:9.3f} {r.attack_angle * 1e6:13.2f}"
        f" {r.contact_area_ratio_elastic:10.3e} {r.contact_area_ratio_elastoplastic:10.3e}"
        f" {r.flow_factor_floored_fraction:8.3f} {r.removal_rate_mean * 1e9 * 60:12.2f}"
    )

# The statements of the documentation page.
lep, ela, hyd = data["lep"], data["elastic"], data["hydrodynamic"]
assert np.all(lep["film_thickness_center"] < ela["film_thickness_center"])
assert np.all(lep["contact_area_ratio_elastoplastic"] > 10 * lep["contact_area_ratio_elastic"])
assert np.all(ela["contact_area_ratio_elastoplastic"] == 0.0)
assert np.all(ela["contact_area_ratio_elastic"] < lep["contact_area_ratio_elastic"] + lep["contact_area_ratio_elastoplastic"])
assert np.all(np.abs(ela["removal_rate_mean"] / lep["removal_rate_mean"] - 1) < 0.1)
assert np.all(lep["flow_factor_floored_fraction"] == 0.0) and np.all(ela["flow_factor_floored_fraction"] == 0.0)
assert np.all(hyd["flow_factor_floored_fraction"] > 0.5) and np.all(hyd["attack_angle"] < 0.0)

style = {"lep": "o-", "elastic": "s--", "hydrodynamic": "^:"}
fig, axes = plt.subplots(2, 2, figsize=(10, 7), layout="constrained")
for v in variants:
    d = data[v]
    axes[0, 0].plot(pressures_psi, d["film_thickness_center"] * 1e6, style[v], label=v)
    axes[0, 1].plot(pressures_psi, d["attack_angle"] * 1e6, style[v], label=v)
    axes[1, 1].plot(pressures_psi, d["flow_factor_floored_fraction"], style[v], label=v)
for v in ("lep", "elastic"):
    d = data[v]
    axes[1, 0].semilogy(pressures_psi, d["contact_area_ratio_elastic"], style[v], label=f"{v}: elastic")
axes[1, 0].semilogy(pressures_psi, lep["contact_area_ratio_elastoplastic"], "o-", color="C3", label="lep: elastoplastic")
labels = ("film thickness at centre (um)", "attack angle (urad)", "real contact area / wafer area", "share of regularised flow factors")
for ax, label in zip(axes.flat, labels):
    ax.set_xlabel("applied pressure (psi)")
    ax.set_ylabel(label)
    ax.grid(alpha=0.3)
    ax.legend(fontsize=8)
fig.suptitle(f"Model variants at 60 rpm (grid {GRID})")
fig.savefig(OUT / "variants.png", dpi=80)
plt.close(fig)

fig, axes = plt.subplots(1, 3, figsize=(14, 4.2), layout="constrained")
vmax = max(np.nanmax(r.fields.total_pressure.values) for r in base_case.values()) * 1e-3
for ax, (v, r) in zip(axes, base_case.items()):
    ds = r.fields
    im = ax.pcolormesh(ds.x.values * 1e3, ds.y.values * 1e3, ds.total_pressure.values * 1e-3, shading="auto", vmin=0.0, vmax=vmax)
    ax.set_aspect("equal")
    ax.set_title(f"{v}: h_c = {r.film_thickness_center * 1e6:.1f} um", fontsize=10)
    ax.set_xlabel("x, sliding direction (mm)")
axes[0].set_ylabel("y (mm)")
fig.colorbar(im, ax=axes, label="total pressure on the wafer (kPa)")
fig.suptitle(f"Slurry gauge plus contact pressure at 4 psi, 60 rpm (grid {GRID})")
fig.savefig(OUT / "pressure_maps.png", dpi=80)
plt.close(fig)
