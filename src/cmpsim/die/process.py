"""The inputs of the die model: the film stack of the process and the pad's contact height.

Every input has its SI unit, default, valid range and source in :data:`DIE_PARAMETERS`;
:class:`DieProcess` holds one set (SI floats) and checks each against its range. Values may be
given with units (``DieProcess.from_values(step_height="0.8 um")``; ``cmpsim die --param
step_height=0.8um``).
"""

from __future__ import annotations

from dataclasses import dataclass, fields, replace

from .stacks import STACKS

__all__ = ["DieProcess", "DIE_PARAMETERS", "PROCESSES"]

#: The processes (film stacks, :data:`cmpsim.die.stacks.STACKS`): oxide inter-level dielectric
#: (ILD/STI-like: one material, two levels) and copper damascene (copper overburden on a barrier
#: over oxide with copper lines).
PROCESSES = tuple(STACKS)

#: name -> (SI unit, default, (low, high) closed range, meaning, source)
DIE_PARAMETERS: dict[str, tuple[str, float, tuple[float, float], str, str]] = {
    "step_height": ("m", 1.0e-6, (0.0, 1e-4), "oxide: initial step height between the oxide over the lines and over the spaces",
                    "the metal thickness of the MIT ILD test wafers, about 1 um (Ouma et al., SPIE 1997: 1000 nm features under 2000 nm TEOS; second-hand)"),
    "contact_height": ("m", 1.0e-7, (1e-10, 1e-4), "step height below which the pad also touches the lower level (contact height of the step-height model)",
                       "Lee, Boning & Economikos, CMP-MIC 2001: 1000 A fitted (second-hand); Smith et al. / Boning et al., MRS 1999: contact heights of this order"),
    "trench_depth": ("m", 0.5e-6, (0.0, 1e-4), "copper: depth of the line trenches in the oxide",
                     "assumed: a typical damascene metal level (no source for the MIT copper mask stack was read)"),
    "copper_thickness": ("m", 1.0e-6, (1e-9, 1e-4), "copper: plated copper thickness over the field (overburden)",
                         "assumed: about twice the trench depth, as plated for fill"),
    "barrier_thickness": ("m", 25e-9, (0.0, 1e-6), "copper: barrier (Ta/TaN) thickness on the field", "assumed: 10-30 nm Ta/TaN liners"),
    "barrier_selectivity": ("1", 0.05, (1e-6, 100.0), "copper: barrier removal rate / copper removal rate",
                            "assumed; Cu:Ta selectivities up to about 500 are claimed for copper slurries (US 6,332,989 B1)"),
    "oxide_selectivity": ("1", 0.02, (1e-6, 100.0), "copper: oxide removal rate / copper removal rate", "assumed: a copper slurry selective to oxide"),
    "planarity": ("m", 10e-9, (1e-12, 1e-4), "step height under which a cell counts as planarized (time_to_planarize)", "a choice: 10 nm"),
    "summit_radius": ("m", 0.0, (0.0, 1e-3), "radius of the pad summits reaching into a gap (the sagitta b^2/8R of the contact height); 0: the pad's asperity_radius",
                      "0: the wafer model's asperity_radius (docs/model.md 13d); a calibration may set it (docs/calibrate-die.md)"),
    "feature_modulus": ("Pa", 0.0, (0.0, 1e12), "Young's modulus of the pad body at the scale of a line array (the bulge into a gap, cmpsim.die.reach); 0: the top pad's bulk modulus",
                        "0: the wafer model's pad_bulk_modulus; the surface layer's own modulus at 10-100 um is not known (docs/model.md 18.5): a calibration may set it"),
    "over_polish": ("1", 0.3, (0.0, 10.0), "default end time: the end point (all planarized, oxide; all cleared, copper) times (1 + over_polish)",
                    "15-35 % over-polish (Nitta Haas tungsten report 2014, second-hand); 30 % chosen"),
}


@dataclass(frozen=True)
class DieProcess:
    """One set of die-model inputs, SI (see :data:`DIE_PARAMETERS`); ``kind`` is ``"oxide"`` or ``"copper"``."""

    kind: str = "oxide"
    step_height: float = DIE_PARAMETERS["step_height"][1]
    contact_height: float = DIE_PARAMETERS["contact_height"][1]
    trench_depth: float = DIE_PARAMETERS["trench_depth"][1]
    copper_thickness: float = DIE_PARAMETERS["copper_thickness"][1]
    barrier_thickness: float = DIE_PARAMETERS["barrier_thickness"][1]
    barrier_selectivity: float = DIE_PARAMETERS["barrier_selectivity"][1]
    oxide_selectivity: float = DIE_PARAMETERS["oxide_selectivity"][1]
    planarity: float = DIE_PARAMETERS["planarity"][1]
    summit_radius: float = DIE_PARAMETERS["summit_radius"][1]
    feature_modulus: float = DIE_PARAMETERS["feature_modulus"][1]
    over_polish: float = DIE_PARAMETERS["over_polish"][1]

    def __post_init__(self) -> None:
        if self.kind not in PROCESSES:
            raise ValueError(f"process must be one of {', '.join(PROCESSES)}; got {self.kind!r}")
        for name, (unit, _, (lo, hi), _, _) in DIE_PARAMETERS.items():
            v = getattr(self, name)
            if not (isinstance(v, (int, float)) and lo <= v <= hi):
                raise ValueError(f"{name} = {v!r} {unit} is outside its valid range [{lo:g}, {hi:g}] {unit}")

    @classmethod
    def from_values(cls, kind: str = "oxide", **values) -> "DieProcess":
        """A process from values with units (``"0.8 um"``) or SI numbers; unknown names are refused."""
        from ..inputs.units import to_si

        out = {}
        for name, value in values.items():
            if name not in DIE_PARAMETERS:
                raise ValueError(f"unknown die input {name!r}; valid names: {', '.join(DIE_PARAMETERS)}")
            unit = DIE_PARAMETERS[name][0]
            out[name] = to_si(value, "" if unit == "1" else unit, name)
        return cls(kind=kind, **out)

    def replace(self, **values) -> "DieProcess":
        """A copy with some inputs changed (SI)."""
        return replace(self, **values)

    def to_dict(self) -> dict:
        """Every input, SI."""
        return {f.name: getattr(self, f.name) for f in fields(self)}
