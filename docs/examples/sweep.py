"""# Sweeps on a local or an existing Dask cluster

A sweep solves the outer product of a few setting axes, in parallel on `dask.distributed`,
and returns one `xarray.Dataset` with one dimension per axis and every scalar of
`cmpsim run --json` as a variable, plus a `status` and an `error` per point (a point without
equilibrium is recorded, not fatal). With an output path every finished point is saved as it
arrives, so an interrupted sweep continues where it stopped (`resume=True`, `--resume`). The
sweep file format and every option are described on the [sweeps](../sweeps.md) page.

## A sweep file

```toml
[base]                      # any `cmpsim run` setting, values with units
rotation_speed = "60 rpm"

[axes]                      # one key per swept setting: a list, or a range
particle_diameter = ["100 nm", "200 nm"]
pad_roughness = ["10 um", "15 um", "20 um"]
applied_pressure = {start = "2 psi", stop = "6 psi", num = 5}
```

## On this machine

```bash
cmpsim sweep study.toml --out study.nc              # local Dask cluster, one worker per core
cmpsim sweep study.toml --out study.nc --workers 2  # or a chosen number of workers
cmpsim sweep study.toml --out study.nc --resume     # after an interruption: only the missing points
```

or from Python, as this script does: `cmpsim.sweep("study.toml", out="study.nc", workers=2)`.

## On an existing Dask cluster

Start a scheduler and workers wherever you like (every worker needs cmpsim installed, the
same version as the client), then pass the scheduler's address instead of `--workers`:

```bash
dask scheduler                                        # on the head node; prints tcp://10.0.0.5:8786
dask worker tcp://10.0.0.5:8786 --nworkers 8 --nthreads 1   # on each compute node
cmpsim sweep study.toml --out study.nc --scheduler tcp://10.0.0.5:8786
```

```python
import cmpsim
from distributed import Client

ds = cmpsim.sweep("study.toml", out="study.nc", scheduler="tcp://10.0.0.5:8786")
# or with a Client you already hold (it is used as is and not closed):
ds = cmpsim.sweep("study.toml", out="study.nc", scheduler=Client("tcp://10.0.0.5:8786"))
```

The results do not depend on where the points ran or in which order they finished: warm
starts follow a fixed layout of chains along the last axis. (Only the local cluster is run to
build this page.)

## The results

![Film thickness, contact and removal rate over the sweep](sweep.png)
"""

import os
from pathlib import Path

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt
import numpy as np
import xarray as xr

import cmpsim

GRID = os.environ.get("CMPSIM_DOCS_GRID", "default")
OUT = Path(os.environ.get("CMPSIM_DOCS_OUT", Path(__file__).parent / "_output" / Path(__file__).stem))
OUT.mkdir(parents=True, exist_ok=True)

study = OUT / "study.toml"
study.write_text(
    f"""\
[base]
rotation_speed = "60 rpm"
grid = "{GRID}"

[axes]
particle_diameter = ["100 nm", "200 nm"]
pad_roughness = ["10 um", "15 um", "20 um"]
applied_pressure = {{start = "2 psi", stop = "6 psi", num = 5}}
"""
)

if __name__ == "__main__":  # needed on platforms that start Dask workers by spawning
    result_file = OUT / "study.nc"
    result_file.unlink(missing_ok=True)
    ds = cmpsim.sweep(study, out=result_file, workers=2, progress=False)
    print(ds)
    print()
    values, counts = np.unique(ds.status.values, return_counts=True)
    print("status of the points:", {str(v): int(c) for v, c in zip(values, counts)})
    assert (ds.status == "ok").all()

    # The file holds the same dataset (coordinates in SI, units in the attributes).
    with xr.open_dataset(result_file) as on_disk:
        assert np.allclose(on_disk.film_thickness_center.values, ds.film_thickness_center.values)

    # Selecting and plotting: one line per (particle size, pad roughness).
    fig, axes = plt.subplots(1, 3, figsize=(14, 4.2), layout="constrained")
    p_psi = ds.applied_pressure.values / 6894.757293168361
    for d, style in zip(ds.particle_diameter.values, ("-", "--")):
        for k, sigma in enumerate(ds.pad_roughness.values):
            point = ds.sel(particle_diameter=d, pad_roughness=sigma)
            label = f"d = {d * 1e9:.0f} nm, sigma = {sigma * 1e6:.0f} um"
            axes[0].plot(p_psi, point.film_thickness_center * 1e6, style, color=f"C{k}", marker="o", label=label)
            contact = point.contact_area_ratio
            axes[1].plot(p_psi, contact, style, color=f"C{k}", marker="o", label=label)
            axes[2].plot(p_psi, point.removal_rate_relative, style, color=f"C{k}", marker="o", label=label)
    for ax, label in zip(axes, ("film thickness at centre (um)", "real contact area / wafer area", "relative removal rate")):
        ax.set_xlabel("applied pressure (psi)")
        ax.set_ylabel(label)
        ax.grid(alpha=0.3)
    axes[1].legend(fontsize=7, loc="upper left")
    fig.suptitle(f"Sweep of {ds.attrs.get('points_requested', ds.status.size)} points, 60 rpm (grid {GRID})")
    fig.savefig(OUT / "sweep.png", dpi=80)
    plt.close(fig)
