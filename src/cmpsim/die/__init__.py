"""From the wafer to the die: pattern-density planarization, copper dishing and erosion.

The chip-scale density and step-height models of the MIT group (Stine et al. 1998; Ouma et al.
2002; Smith et al.; Tugbawa 2002), driven by cmpsim's wafer-scale solve, with the planarization
length derived from the pad stack (docs/model.md, section 18):

* :func:`simulate`: one die polished at a blanket rate (the wafer-mean rate of a solve by default);
* :func:`simulate_wafer`: every die of a wafer, each at the rotation-averaged rate at its site;
* :class:`Layout`, :func:`read_layout`, :func:`builtin_layout`, :data:`BUILTIN_LAYOUTS`: layouts;
* :func:`planarization_length_from_pad`, :func:`effective_density`: the pad's averaging;
* :class:`DieProcess`: the film stack and the contact height;
* :meth:`cmpsim.die.chip.DieModel.start`, :meth:`~cmpsim.die.chip.DieModel.resume`: a die continued from its
  state at another rate or pressure (the steps of a recipe, :mod:`cmpsim.polisher.ride`).

Lives on the studies floor. May import: the driver (:mod:`cmpsim.solver`) and every floor below it,
:mod:`cmpsim.layout` (the layouts it reads) and the utilities; not :mod:`cmpsim.polisher`, which drives it.
"""

from .density import GaussianWeighting, PadWeighting, effective_density
from .layout import BUILTIN_LAYOUTS, Layout, builtin_layout, read_layout
from .pad import planarization_length_from_pad
from .process import DIE_PARAMETERS, DieProcess
from .polish import DieResult, load_layout, simulate
from .wafer import WaferDies, blanket_rates, die_sites, simulate_wafer

__all__ = [
    "simulate", "simulate_wafer", "DieResult", "WaferDies", "Layout", "read_layout", "builtin_layout", "BUILTIN_LAYOUTS",
    "load_layout", "planarization_length_from_pad", "effective_density", "GaussianWeighting", "PadWeighting", "DieProcess",
    "DIE_PARAMETERS", "die_sites", "blanket_rates",
]
