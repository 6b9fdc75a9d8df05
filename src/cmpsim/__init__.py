"""cmpsim: wafer-scale chemical mechanical polishing simulator.

Grain-flow (Haff) partial hydrodynamic lubrication through an average-flow Reynolds
equation with roughness flow factors, plus elastic / elastoplastic / plastic asperity
contact of the pad, on a domed, tilted wafer balanced in force and moment.

Quick use::

    import cmpsim
    result = cmpsim.solve(applied_pressure="3 psi")
    print(result.summary())

``import cmpsim`` is light: numerical, plotting and parallel libraries load only in the
functions that need them.
"""

from __future__ import annotations

from typing import TYPE_CHECKING, Any

from ._version import __version__

__all__ = ["Config", "Result", "solve", "sweep", "reproduce", "validate", "calibrate", "tune_zones", "polish", "EquilibriumError", "__version__"]

_LAZY = {
    "Config": ("cmpsim.inputs.config", "Config"),
    "Result": ("cmpsim.results.result", "Result"),
    "solve": ("cmpsim.solver.model", "solve"),
    "EquilibriumError": ("cmpsim.solver.equilibrium", "EquilibriumError"),
    "sweep": ("cmpsim.sweeps", "sweep"),
    "reproduce": ("cmpsim.reproduction", "reproduce"),
    "validate": ("cmpsim.validation", "validate"),
    "calibrate": ("cmpsim.calibration", "calibrate"),
    "tune_zones": ("cmpsim.head.tuning", "tune_zones"),
    "polish": ("cmpsim.polisher.engine", "polish"),
    "die": ("cmpsim.die", None),  # the chip-scale model, a package: cmpsim.die.simulate(...)
}

if TYPE_CHECKING:  # pragma: no cover
    from .inputs.config import Config
    from .solver.equilibrium import EquilibriumError
    from .solver.model import solve
    from .results.result import Result


def __getattr__(name: str) -> Any:
    if name in _LAZY:
        import importlib

        module, attr = _LAZY[name]
        value = importlib.import_module(module)
        value = value if attr is None else getattr(value, attr)
        globals()[name] = value
        return value
    raise AttributeError(f"module 'cmpsim' has no attribute {name!r}")


def __dir__() -> list[str]:
    return sorted(list(globals()) + list(_LAZY))
