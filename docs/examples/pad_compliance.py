"""# Pad compliance: rigid against compliant pads, and the pad stack

The paper's pad deforms only in its asperity layer: under the 5 µm dome of the base case the
wafer then presses hardest at its centre, and the rotation-averaged removal rate falls about
five-fold from the centre to the edge. With `pad_compliance = "winkler"` the bulk of the pad
and its subpad deflect too, as a bed of springs of stiffness k = 1 / Σ tᵢ/Mᵢ (layers in series,
Mᵢ the constrained modulus; [model, section 13c](../model.md#13c-pad-compliance-beyond-the-paper)). The default stack
is an IC1000-like top pad (1.27 mm, 300 MPa) on a Suba IV-like subpad (1.27 mm, 2.3 MPa),
k ≈ 1.8 GPa/m: the wafer sinks about 15 µm into the pad, three times its dome height, and the
pad takes up most of the dome.

This script solves the base case (3-inch wafer, 4 psi, 60 rpm) on a rigid and on the default
compliant pad, then varies the subpad's thickness and modulus.

![Rotation-averaged removal profiles, rigid and compliant pads](profiles.png)

![Mean removal rate and non-uniformity against the stack compliance](stack_trend.png)

What it shows (the script asserts each statement):

- **The profile flattens, the mean rate hardly moves.** The within-wafer non-uniformity
  (area-weighted standard deviation over the mean of the ring means, 3 mm edge exclusion) falls
  from about 40 % on the rigid pad to about 9 % on the default stack, while the wafer-mean
  removal rate changes by less than 3 %. The pad stack redistributes the load; it does not
  change it. The slurry's share of the load falls too (the wafer tilts less, the wedge is
  weaker).
- **Thicker or softer stack → flatter profile.** The non-uniformity falls monotonically as the
  stack becomes more compliant (thicker or softer subpad). The mean rate goes through a shallow
  minimum near the default stack: evening out the pressure lowers the mean of a removal law
  that grows faster than linearly with the pressure (σₙτ), while the lower fluid share raises the
  summit friction that dominates τ.
- **On a Winkler bed only k matters.** A subpad twice as thick and a subpad half as stiff give
  the same k, and the same results to round-off: the thickness and modulus sweeps fall on one
  curve against 1/k.

The profile and its non-uniformity are computed here from `result.polar["removal_rate"]`
(rings × sectors: the ring mean is the rotation average, since the wafer turns through every
angle). A Winkler bed has no lateral coupling, so it cannot produce the stress concentration
(and the fast or slow band a few millimetres wide) at the wafer edge of a real polisher; see the
[limitations](../limitations.md#a-local-winkler-pad-no-edge-effect).
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
    return result.grid.r[:, 0], result.polar[field].mean(axis=1)


def nonuniformity(result, edge_exclusion=EDGE_EXCLUSION):
    """Area-weighted std / mean of the ring-mean removal rate for r <= R_w - edge_exclusion."""
    r, rr = ring_profile(result)
    keep = r <= result.grid.radius - edge_exclusion
    a = r[keep]  # ring area is proportional to r dr
    mean = np.sum(a * rr[keep]) / np.sum(a)
    return float(np.sqrt(np.sum(a * (rr[keep] - mean) ** 2) / np.sum(a)) / mean)


base = cmpsim.Config.default().replace(grid=GRID)
rigid = cmpsim.solve(base, relative=False)
compliant = cmpsim.solve(base.replace(pad_compliance="winkler"), relative=False)
k_default = compliant.problem.foundation.stiffness

# the stack: subpad thickness and subpad modulus sweeps (everything else at the defaults)
thicknesses_mm = np.array([0.0, 0.32, 0.64, 1.27, 1.91, 2.54, 3.81])
moduli_mpa = np.array([1.0, 1.6, 2.3, 4.0, 8.0, 20.0])
sweeps = {"subpad thickness": [], "subpad modulus": []}
for t in thicknesses_mm:
    sweeps["subpad thickness"].append(cmpsim.solve(base.replace(pad_compliance="winkler", subpad_thickness=f"{t} mm"), relative=False))
for e in moduli_mpa:
    sweeps["subpad modulus"].append(cmpsim.solve(base.replace(pad_compliance="winkler", subpad_modulus=f"{e} MPa"), relative=False))

print(f"grid {GRID}; edge exclusion {EDGE_EXCLUSION * 1e3:g} mm")
print(f"{'pad':>30} {'k (GPa/m)':>10} {'mean w (um)':>12} {'RR (nm/min)':>12} {'WIWNU':>7} {'fluid share':>12} {'theta (urad)':>13}")


def row(label, r):
    f = r.problem.foundation
    k = f"{f.stiffness * 1e-9:10.3g}" if f is not None else f"{'inf':>10}"
    print(
        f"{label:>30} {k} {r.polar['pad_deflection'].mean() * 1e6:12.2f} {r.removal_rate_nm_per_min:12.2f}"
        f" {100 * nonuniformity(r):6.1f}% {r.fluid_load_fraction:12.4f} {r.attack_angle_rad * 1e6:13.2f}"
    )


row("rigid", rigid)
for label, values, unit in (("subpad thickness", thicknesses_mm, "mm"), ("subpad modulus", moduli_mpa, "MPa")):
    for v, r in zip(values, sweeps[label]):
        row(f"{label} {v:g} {unit}", r)

# ---- the statements of the page
w_rigid, w_compliant = nonuniformity(rigid), nonuniformity(compliant)
assert w_rigid > 0.3 and w_compliant < 0.5 * w_rigid, (w_rigid, w_compliant)
assert abs(compliant.removal_rate / rigid.removal_rate - 1.0) < 0.03
assert compliant.fluid_load_fraction < rigid.fluid_load_fraction
all_runs = sweeps["subpad thickness"] + sweeps["subpad modulus"]
compliance = np.array([1.0 / r.problem.foundation.stiffness for r in all_runs])
order = np.argsort(compliance)
w_sorted = np.array([nonuniformity(all_runs[i]) for i in order])
# (the default stack is in both sweeps: equal compliance, equal result)
assert np.all(np.diff(w_sorted) <= 1e-12), "non-uniformity must fall as the stack becomes more compliant"
rr_all = np.array([r.removal_rate for r in all_runs])
assert np.all(np.abs(rr_all / rigid.removal_rate - 1.0) < 0.03)
# only k matters: twice the thickness = half the modulus
thick = cmpsim.solve(base.replace(pad_compliance="winkler", subpad_thickness="2.54 mm"), relative=False)
soft = cmpsim.solve(base.replace(pad_compliance="winkler", subpad_modulus=base.subpad_modulus / 2), relative=False)
assert abs(thick.problem.foundation.stiffness / soft.problem.foundation.stiffness - 1) < 1e-14
assert abs(nonuniformity(thick) - nonuniformity(soft)) < 1e-9
assert abs(thick.removal_rate / soft.removal_rate - 1.0) < 1e-9

# ---- figure 1: profiles
fig, axes = plt.subplots(1, 3, figsize=(14, 4.2), layout="constrained")
R_mm = base.wafer_diameter / 2 * 1e3
for r, label, style in ((rigid, "rigid pad", "o-"), (compliant, f"compliant, k = {k_default * 1e-9:.2f} GPa/m", "s-")):
    rad, rr = ring_profile(r)
    axes[0].plot(rad * 1e3, rr * 6e10, style, ms=3, label=f"{label}: WIWNU {100 * nonuniformity(r):.1f} %")
    rad, p = ring_profile(r, "total_pressure")
    axes[1].plot(rad * 1e3, p * 1e-3, style, ms=3, label=label)
    rad, h = ring_profile(r, "film_thickness")
    axes[2].plot(rad * 1e3, h * 1e6, style, ms=3, label=f"{label}: film")
rad, w = ring_profile(compliant, "pad_deflection")
axes[2].plot(rad * 1e3, w * 1e6, "^--", ms=3, color="C2", label="compliant: pad deflection")
for ax in axes:
    ax.axvspan(R_mm - EDGE_EXCLUSION * 1e3, R_mm, color="0.9", zorder=0)
    ax.set_xlabel("radius (mm)")
    ax.grid(alpha=0.3)
    ax.legend(fontsize=8)
axes[0].set_ylabel("rotation-averaged removal rate (nm/min)")
axes[1].set_ylabel("ring-mean total pressure (kPa)")
axes[2].set_ylabel("ring mean (um)")
axes[0].set_ylim(bottom=0)
fig.suptitle(f"Base case, 4 psi, 60 rpm: rigid pad against the IC1000-on-Suba IV stack (grid {GRID}; grey: 3 mm edge exclusion)")
fig.savefig(OUT / "profiles.png", dpi=80)
plt.close(fig)

# ---- figure 2: the stack trend against the compliance 1/k
fig, axes = plt.subplots(1, 2, figsize=(11, 4.2), layout="constrained")
for (label, runs), style in zip(sweeps.items(), ("o-", "s--")):
    c = np.array([1.0 / r.problem.foundation.stiffness for r in runs]) * 1e9  # um per kPa
    axes[0].plot(c, [r.removal_rate_nm_per_min for r in runs], style, label=label)
    axes[1].plot(c, [100 * nonuniformity(r) for r in runs], style, label=label)
axes[0].axhline(rigid.removal_rate_nm_per_min, color="k", lw=0.8, ls=":", label="rigid pad")
axes[1].axhline(100 * w_rigid, color="k", lw=0.8, ls=":", label="rigid pad")
axes[0].axvline(1e9 / k_default, color="0.6", lw=0.8)
axes[1].axvline(1e9 / k_default, color="0.6", lw=0.8)
axes[0].set_ylabel("wafer-mean removal rate (nm/min)")
axes[1].set_ylabel("WIWNU, 3 mm edge exclusion (%)")
for ax in axes:
    ax.set_xlabel("stack compliance 1/k (um/kPa); grey line: default stack")
    ax.grid(alpha=0.3)
    ax.legend(fontsize=8)
axes[1].set_ylim(bottom=0)
fig.suptitle(f"Thicker or softer subpad: same mean rate, flatter profile (grid {GRID})")
fig.savefig(OUT / "stack_trend.png", dpi=80)
plt.close(fig)
