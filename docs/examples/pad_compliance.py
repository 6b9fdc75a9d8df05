"""# Pad compliance: rigid against compliant pads, and the pad stack

The paper's pad deforms only in its asperity layer: under the 5 µm dome of the base case the
wafer then presses hardest at its centre, and the rotation-averaged removal rate falls about
five-fold from the centre to the edge. `pad_compliance` adds the bulk of the pad and its subpad
([model, section 13c](../model.md#13c-pad-compliance-beyond-the-paper)):

- `"winkler"`: a bed of independent springs of stiffness k = 1 / Σ tᵢ/Mᵢ (layers in series,
  Mᵢ the constrained modulus). The default stack is an IC1000-like top pad (1.27 mm, 300 MPa)
  on a Suba IV-like subpad (1.27 mm, 2.3 MPa), k ≈ 1.8 GPa/m: the wafer sinks about 15 µm into
  the pad, three times its dome height, and the pad takes up most of the dome.
- `"layer"`: the same stack with lateral coupling: the top pad bends as a plate over the subpad,
  an elastic layer bonded to the platen (its kernel integrated over each grid cell). Far from
  the edge it deflects like the bed; near the edge the unloaded pad outside holds the pad
  surface up, which concentrates the pressure over a few millimetres.

This script solves the base case (3-inch wafer, 4 psi, 60 rpm) with the three pads, then varies
the subpad's thickness (both compliant models) and modulus (Winkler).

![Rotation-averaged removal profiles, rigid and compliant pads](profiles.png)

![Mean removal rate and non-uniformity against the stack compliance](stack_trend.png)

What it shows (the script asserts each statement):

- **The profile flattens, the mean rate hardly moves.** On the Winkler bed the within-wafer
  non-uniformity (area-weighted standard deviation over the mean of the ring means, 3 mm edge
  exclusion) falls from about 40 % on the rigid pad to about 9 %, while the wafer-mean removal
  rate changes by less than 3 %: the pad stack redistributes the load, it does not change it.
  The slurry's share of the load falls too (the wafer tilts less, the wedge is weaker).
- **On the bed, thicker or softer stack → flatter profile.** The non-uniformity falls
  monotonically as the stack becomes more compliant. The mean rate goes through a shallow
  minimum near the default stack: evening out the pressure lowers the mean of a removal law that
  grows faster than linearly with the pressure (σₙτ), while the lower fluid share raises the
  summit friction that dominates τ. On a Winkler bed only k matters: a subpad twice as thick and
  a subpad half as stiff give identical results.
- **With lateral coupling, an edge band.** The layered pad takes up the dome like the bed in the
  interior but presses harder at the wafer edge, behind a slower band a few millimetres inside it
  (on the default grid, 24 rings of 1.6 mm, the edge ring polishes faster than the centre). The
  thicker the subpad, the stronger the edge effect relative to the centre, so the non-uniformity
  no longer falls without end: it is least at an intermediate subpad thickness, and the mean
  rate rises with the fast edge. The same direction as the finite-element result of Lo & Lin
  (2005): a thicker pad, a larger edge-to-centre stress ratio.

Everything here is the paper's model (`cmpsim.Config.paper()`) with only the pad changed, so
that the rigid pad is the paper's. The profile is the output `removal_rate_profile` (the ring
mean of the removal-rate map is the rotation average, since the wafer turns through every angle)
and the non-uniformity `within_wafer_nonuniformity` (3 mm edge exclusion). The default model of
[section 13d](../model.md#13d-the-default-model-beyond-the-paper-and-the-presets) stands on the
Winkler stack already; the script prints its two compliant variants at the end. The edge band is only a few cells wide on the default grid; for edge studies use
`grid = "fine"` ([limitations](../limitations.md#a-local-winkler-pad-no-edge-effect)).
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
EDGE_EXCLUSION = 3e-3  # m


def ring_profile(result, field="removal_rate"):
    """Rotation-averaged profile: (ring-centre radii in m, ring means of a polar field)."""
    return result.profiles["radius"], result.polar[field].mean(axis=1)


def nonuniformity(result):
    """Area-weighted std / mean of the removal-rate profile, 3 mm edge exclusion (the output)."""
    return result.within_wafer_nonuniformity


def nm_per_min(result):
    """Wafer-mean removal rate, nm/min."""
    return result.removal_rate_mean * 6e10


base = cmpsim.Config.paper().replace(grid=GRID)
rigid = cmpsim.solve(base, relative=False)
compliant = cmpsim.solve(base.replace(pad_compliance="winkler"), relative=False)
layered = cmpsim.solve(base.replace(pad_compliance="layer"), relative=False)
k_default = compliant.problem.foundation.stiffness

# the stack: subpad thickness and subpad modulus sweeps (everything else at the defaults)
thicknesses_mm = np.array([0.0, 0.32, 0.64, 1.27, 1.91, 2.54, 3.81])
moduli_mpa = np.array([1.0, 1.6, 2.3, 4.0, 8.0, 20.0])
sweeps = {"subpad thickness": [], "subpad modulus": [], "subpad thickness, layer": []}
for t in thicknesses_mm:
    sweeps["subpad thickness"].append(cmpsim.solve(base.replace(pad_compliance="winkler", subpad_thickness=f"{t} mm"), relative=False))
    sweeps["subpad thickness, layer"].append(cmpsim.solve(base.replace(pad_compliance="layer", subpad_thickness=f"{t} mm"), relative=False))
for e in moduli_mpa:
    sweeps["subpad modulus"].append(cmpsim.solve(base.replace(pad_compliance="winkler", subpad_modulus=f"{e} MPa"), relative=False))

print(f"grid {GRID}; edge exclusion {EDGE_EXCLUSION * 1e3:g} mm")
print(f"{'pad':>30} {'k (GPa/m)':>10} {'mean w (um)':>12} {'RR (nm/min)':>12} {'WIWNU':>7} {'fluid share':>12} {'theta (urad)':>13}")


def row(label, r):
    f = r.problem.foundation
    k = f"{f.stiffness * 1e-9:10.3g}" if f is not None else f"{'inf':>10}"
    print(
        f"{label:>30} {k} {r.polar['pad_deflection'].mean() * 1e6:12.2f} {nm_per_min(r):12.2f}"
        f" {100 * nonuniformity(r):6.1f}% {r.fluid_load_fraction:12.4f} {r.attack_angle * 1e6:13.2f}"
    )


row("rigid", rigid)
for label, values, unit in (("subpad thickness", thicknesses_mm, "mm"), ("subpad modulus", moduli_mpa, "MPa")):
    for v, r in zip(values, sweeps[label]):
        row(f"{label} {v:g} {unit}", r)
for v, r in zip(thicknesses_mm, sweeps["subpad thickness, layer"]):
    _, rr = ring_profile(r)
    row(f"layer, subpad {v:g} mm", r)
    print(f"{'':>30} edge ring / centre {rr[-1] / rr[0]:.2f}, slowest of the last rings / centre {rr[-5:-1].min() / rr[0]:.2f}")

# ---- the statements of the page
w_rigid, w_compliant = nonuniformity(rigid), nonuniformity(compliant)
assert w_rigid > 0.3 and w_compliant < 0.5 * w_rigid, (w_rigid, w_compliant)
assert abs(compliant.removal_rate_mean / rigid.removal_rate_mean - 1.0) < 0.03
assert compliant.fluid_load_fraction < rigid.fluid_load_fraction
all_runs = sweeps["subpad thickness"] + sweeps["subpad modulus"]  # the Winkler bed
compliance = np.array([1.0 / r.problem.foundation.stiffness for r in all_runs])
order = np.argsort(compliance)
w_sorted = np.array([nonuniformity(all_runs[i]) for i in order])
# (the default stack is in both sweeps: equal compliance, equal result)
assert np.all(np.diff(w_sorted) <= 1e-12), "non-uniformity must fall as the stack becomes more compliant"
rr_all = np.array([r.removal_rate_mean for r in all_runs])
assert np.all(np.abs(rr_all / rigid.removal_rate_mean - 1.0) < 0.03)
# only k matters: twice the thickness = half the modulus
thick = cmpsim.solve(base.replace(pad_compliance="winkler", subpad_thickness="2.54 mm"), relative=False)
soft = cmpsim.solve(base.replace(pad_compliance="winkler", subpad_modulus=base.subpad_modulus / 2), relative=False)
assert abs(thick.problem.foundation.stiffness / soft.problem.foundation.stiffness - 1) < 1e-14
assert abs(nonuniformity(thick) - nonuniformity(soft)) < 1e-9
assert abs(thick.removal_rate_mean / soft.removal_rate_mean - 1.0) < 1e-9
# the layered pad: the edge gains on the centre as the subpad thickens; the non-uniformity is
# least at an intermediate thickness; every compliant layered stack is more uniform than the rigid pad
runs = sweeps["subpad thickness, layer"]
edge_ratio = np.array([ring_profile(r)[1][-1] / ring_profile(r)[1][0] for r in runs])
assert np.all(np.diff(edge_ratio) > 0), edge_ratio
w_layer = np.array([nonuniformity(r) for r in runs])
assert 0 < int(np.argmin(w_layer)) < len(runs) - 1, w_layer
assert np.all(w_layer[1:] < w_rigid) and nonuniformity(layered) < 0.5 * w_rigid
bed_edge = np.array([ring_profile(r)[1][-1] / ring_profile(r)[1][0] for r in sweeps["subpad thickness"]])
assert np.all(edge_ratio[1:] > bed_edge[1:])  # the edge effect a bed cannot make
_, rr_layer = ring_profile(layered)
assert rr_layer[-5:-1].min() < 0.85 * rr_layer[0]  # the slow band inside the edge

# ---- figure 1: profiles
fig, axes = plt.subplots(1, 3, figsize=(14, 4.2), layout="constrained")
R_mm = base.wafer_diameter / 2 * 1e3
for r, label, style in ((rigid, "rigid pad", "o-"), (compliant, f"Winkler, k = {k_default * 1e-9:.2f} GPa/m", "s-"), (layered, "layer (same stack)", "d-")):
    rad, rr = ring_profile(r)
    axes[0].plot(rad * 1e3, rr * 6e10, style, ms=3, label=f"{label}: WIWNU {100 * nonuniformity(r):.1f} %")
    rad, p = ring_profile(r, "total_pressure")
    axes[1].plot(rad * 1e3, p * 1e-3, style, ms=3, label=label)
    rad, h = ring_profile(r, "film_thickness")
    axes[2].plot(rad * 1e3, h * 1e6, style, ms=3, label=f"{label}: film")
for r, label, color in ((compliant, "Winkler", "C1"), (layered, "layer", "C2")):
    rad, w = ring_profile(r, "pad_deflection")
    axes[2].plot(rad * 1e3, w * 1e6, "--", color=color, label=f"{label}: pad deflection")
for ax in axes:
    ax.axvspan(R_mm - EDGE_EXCLUSION * 1e3, R_mm, color="0.9", zorder=0)
    ax.set_xlabel("radius (mm)")
    ax.grid(alpha=0.3)
    ax.legend(fontsize=8)
axes[0].set_ylabel("rotation-averaged removal rate (nm/min)")
axes[1].set_ylabel("ring-mean total pressure (kPa)")
axes[2].set_ylabel("ring mean (um)")
axes[0].set_ylim(bottom=0)
fig.suptitle(f"Base case, 4 psi, 60 rpm: rigid pad against the IC1000-on-Suba IV stack, Winkler and layered (grid {GRID}; grey: 3 mm edge exclusion)")
fig.savefig(OUT / "profiles.png", dpi=80)
plt.close(fig)

# ---- figure 2: the stack trend against the compliance 1/k, and the layered profiles
fig, axes = plt.subplots(1, 3, figsize=(15, 4.2), layout="constrained")
for (label, runs), style in zip(sweeps.items(), ("o-", "s--", "d-")):
    c = np.array([1.0 / r.problem.foundation.stiffness for r in runs]) * 1e9  # um per kPa
    model = "layer" if "layer" in label else "Winkler"
    axes[0].plot(c, [nm_per_min(r) for r in runs], style, label=f"{model}: {label.split(',')[0]}")
    axes[1].plot(c, [100 * nonuniformity(r) for r in runs], style, label=f"{model}: {label.split(',')[0]}")
axes[0].axhline(nm_per_min(rigid), color="k", lw=0.8, ls=":", label="rigid pad")
axes[1].axhline(100 * w_rigid, color="k", lw=0.8, ls=":", label="rigid pad")
for ax in axes[:2]:
    ax.axvline(1e9 / k_default, color="0.6", lw=0.8)
    ax.set_xlabel("stack compliance 1/k (um/kPa); grey line: default stack")
    ax.grid(alpha=0.3)
    ax.legend(fontsize=8)
axes[0].set_ylabel("wafer-mean removal rate (nm/min)")
axes[1].set_ylabel("WIWNU, 3 mm edge exclusion (%)")
axes[1].set_ylim(bottom=0)
for t, r in zip(thicknesses_mm, sweeps["subpad thickness, layer"]):
    if t in (0.64, 1.27, 2.54, 3.81):
        rad, rr = ring_profile(r)
        axes[2].plot(rad * 1e3, rr / rr.mean(), ".-", label=f"subpad {t:g} mm")
axes[2].axvspan(R_mm - EDGE_EXCLUSION * 1e3, R_mm, color="0.9", zorder=0)
axes[2].set_xlabel("radius (mm)")
axes[2].set_ylabel("ring-mean removal rate / mean of the ring means")
axes[2].set_title("layered pad: the edge band grows with the subpad", fontsize=10)
axes[2].grid(alpha=0.3)
axes[2].legend(fontsize=8)
fig.suptitle(f"Thicker or softer subpad: the mean rate holds, the profile flattens, the edge effect grows (grid {GRID})")
fig.savefig(OUT / "stack_trend.png", dpi=80)
plt.close(fig)

# ---- the default model (section 13d) on its Winkler stack, and on the layered one
print("\ndefault model (Newtonian slurry, IC1000 summits, shear-power removal):")
for name in ("winkler", "layer"):
    r = cmpsim.solve(cmpsim.Config.default().replace(grid=GRID, pad_compliance=name), relative=False)
    print(
        f"{name:>8}: mean {nm_per_min(r):.1f} nm/min, WIWNU {100 * nonuniformity(r):.2f} %, "
        f"slurry share of the load {r.fluid_load_fraction:+.3f}"
    )
