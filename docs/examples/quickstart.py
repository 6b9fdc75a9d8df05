"""# Quick start

Solve the base case with the default model (Newtonian slurry, measured IC1000 summits on a
compliant pad stack, shear-power removal law) and draw its wafer maps: the script behind the
[quick start](../index.md). The paper's own model is `cmpsim.solve(cmpsim.Config.paper())`.
"""

# --8<-- [start:code]
import os
from pathlib import Path

import matplotlib

matplotlib.use("Agg")  # no display needed
import matplotlib.pyplot as plt

import cmpsim

GRID = os.environ.get("CMPSIM_DOCS_GRID", "default")
OUT = Path(os.environ.get("CMPSIM_DOCS_OUT", Path(__file__).parent / "_output" / Path(__file__).stem))
OUT.mkdir(parents=True, exist_ok=True)

result = cmpsim.solve(grid=GRID)  # 3-inch wafer, 4 psi, 60 rpm, 100 nm particles, IC1000 pad (sigma 5 um)
print(result.summary())
fig = result.plot()  # film thickness, slurry pressure, contact pressure, removal rate
fig.savefig(OUT / "maps.png", dpi=90)
plt.close(fig)
# --8<-- [end:code]
