"""The die model on real layouts: per-window fields, stacks of levels, and one call per re-simulation.

A real layout (GDSII/OASIS) is turned into windows by :mod:`cmpsim.layout` (density, line width
and line space of the merged shapes of the chosen layers in every window); the die is then those
windows, each with its own fields (:meth:`cmpsim.die.layout.Layout.from_windows`): no regions are
looked for, the per-window maps are the result. The evolution is the one of every die
(:class:`cmpsim.die.evolution.DieEvolution`, vectorised over cells), the effective density the
planarization-length weighting over the whole chip (periodic: the die is stepped), the blanket
rate the wafer solve's.

* :class:`DieModel`: everything that does not depend on the layout's fields (one wafer solve per
  film, the weighting, the pad's feature contact), and :meth:`DieModel.run` polishing a die of
  given fields: the call to re-simulate a die with other densities (e.g. with fill), at the cost
  of one FFT and one evolution (about a second for 120,000 windows).
* :func:`layout_die`: the die of a layout file's layers.
* :func:`read_stack`, :func:`simulate_stack`: an ordered list of levels, the topography left by
  one the incoming topography of the next (docs/model.md, section 18.10).
"""

from __future__ import annotations

import contextlib
import math
import os
from dataclasses import dataclass, field
from pathlib import Path

from .layout import Layout
from .polish import DieResult, _config, _conventions, _feature, _polish, _weighting
from .process import DIE_PARAMETERS, PROCESSES, DieProcess
from .stacks import film_stack

__all__ = ["DieModel", "layout_die", "is_layout_file", "StackLevel", "StackResult", "read_stack", "simulate_stack"]

_MAGIC = (b"\x00\x06\x00\x02", b"%SEMI-OASIS\r\n", b"\x1f\x8b")
LAYOUT_SUFFIXES = (".gds", ".gds.gz", ".oas", ".oas.gz", ".gdsii", ".gds2")


def is_layout_file(path) -> bool:
    """Whether ``path`` names a GDSII/OASIS layout: by its suffix, or by its first bytes."""
    name = str(path).lower()
    if name.endswith(LAYOUT_SUFFIXES):
        return True
    p = Path(path)
    if not p.is_file():
        return False
    with open(p, "rb") as fh:
        head = fh.read(16)
    return any(head.startswith(m) for m in _MAGIC)


def layout_die(layout, layers, window: float = 20e-6, *, top: str | None = None, pdk: str | None = None, layer_map=None,
               origin=None, progress=None) -> Layout:
    """The die of a layout's layers (:func:`cmpsim.layout.extract_windows`: .gds, .gds.gz, .oas), one cell per window.

    ``layout`` is a path or a :class:`cmpsim.layout.Layout` already read. ValueError (naming the
    parameter) for a file that is not a layout, a layer it lacks, an empty layer, a window
    larger than the die. ``progress`` (stage, done, total) is told how the extraction goes.
    """
    from ..layout import extract_windows

    if isinstance(layers, tuple) and all(isinstance(x, str) for x in layers):
        layers = list(layers)  # a tuple of names, not a (layer, datatype) pair
    try:
        w = extract_windows(layout, layers, window, top=top, pdk=pdk, layer_map=layer_map, origin=origin, progress=progress)
    except FileNotFoundError as exc:
        raise ValueError(str(exc)) from None
    return Layout.from_windows(w)


def _as_layout(layout) -> Layout:
    if isinstance(layout, Layout):
        return layout
    if hasattr(layout, "density") and hasattr(layout, "window"):  # cmpsim.layout.LayoutWindows
        return Layout.from_windows(layout)
    raise TypeError(f"expected a cmpsim.die.layout.Layout or a cmpsim.layout.LayoutWindows; got {type(layout).__name__}")


class DieModel:
    """A die model ready to polish dies of any fields: the wafer solve, the weighting and the pad's feature contact, computed once.

    ``process`` is a :class:`DieProcess` or ``"oxide"``/``"copper"`` (keywords set its inputs with
    units); ``blanket_rate`` (m/s) defaults to the wafer-mean rate of ``cmpsim.solve(config)`` for the
    process's film (solved once, at construction); ``spec`` the hotspot limits; ``uncertainty`` a
    calibration's covariance (every :meth:`run` then gives its hotspots ``interval`` and
    ``probability``, :mod:`cmpsim.die.uncertainty`). Other arguments as :func:`cmpsim.die.simulate`.
    """

    def __init__(self, config=None, process="oxide", *, blanket_rate: float | None = None, planarization_length: float | None = None,
                 weighting: str = "gaussian", feature_contact: str = "elastic", spec=None, uncertainty=None, **process_values):
        from .hotspots import parse_spec
        from .polish import _fitted

        config = _config(config)
        process, planarization_length, process_values = _fitted(uncertainty, process, planarization_length, process_values)
        self.uncertainty = uncertainty  # a calibration's covariance: hotspots with interval and probability (cmpsim.die.uncertainty)
        if process is None or isinstance(process, str):
            process = DieProcess.from_values(process or "oxide", **process_values)
        elif process_values:
            raise ValueError("give the die inputs either as a DieProcess or as keywords, not both")
        film = film_stack(process).film
        if getattr(config, "film", film) != film:
            config = config.replace(film=film)
        self.config, self.process, self.weighting, self.feature_contact = config, process, weighting, feature_contact
        self.spec = parse_spec(spec)
        self.weight, self.derived = _weighting(config, planarization_length, weighting)
        self.feature = _feature(config, feature_contact)
        self.conventions = _conventions(config)
        if blanket_rate is None:
            from ..solver.model import solve

            blanket_rate = float(solve(config, relative=False).removal_rate_mean)
        if not (math.isfinite(blanket_rate) and blanket_rate > 0):
            raise ValueError(f"blanket_rate must be > 0 m/s; got {blanket_rate!r}")
        self.blanket_rate = float(blanket_rate)
        self._eff: dict = {}
        self._token = object()  # marks the dies whose conditions this model set (DieModel.resume)

    def run(self, layout, time: float | None = None, *, density=None, width=None, space=None, incoming=None,
            level: str | None = None) -> DieResult:
        """Polish a die: ``layout`` a die :class:`Layout` or a :class:`cmpsim.layout.LayoutWindows`.

        ``density``, ``width``, ``space`` ((ny, nx) arrays; width and space in m) replace the
        layout's fields (a die with fill: its new density, and the width and space of the
        merged drawn + fill shapes); ``incoming`` = (height, step) the topography a level below
        left (m); ``time`` (s) defaults to the end point x (1 + over_polish). Returns a
        :class:`DieResult` whose per-window maps are ``evolution.thickness``, ``.step_height``,
        ``.dishing``, ``.erosion``, with ``thickness_range`` and ``hotspots()``.
        """
        from .density import effective_density

        lay = _as_layout(layout)
        if density is not None or width is not None or space is not None:
            lay = lay.with_fields(density, width, space)
        if time is not None and not (math.isfinite(time) and time >= 0):
            raise ValueError(f"time must be >= 0 s; got {time!r}")
        eff = effective_density(lay.density, lay.cell_size, self.weight)
        template = DieResult(lay, self.process, 0.0, self.blanket_rate, self.weight.length, self.derived, self.weighting, eff, None,
                             self.conventions, self.feature_contact, dict(self.spec), level)
        from .polish import _with_sigma

        result = _polish(lay, self.process, self.config, self.blanket_rate, time, eff, self.feature, incoming, template)
        return _with_sigma(result, self.config, self.feature, incoming, self.uncertainty)

    # a die through the steps of a recipe: start once, then resume step after step (cmpsim.polisher.ride)
    def _effective(self, lay):
        from .density import effective_density

        key = id(lay)
        if key not in self._eff:  # the weighting's FFT once per layout (the layout kept alive with it)
            self._eff[key] = (lay, effective_density(lay.density, lay.cell_size, self.weight))
        return self._eff[key][1]

    def _result(self, lay, ev, rate, level) -> DieResult:
        return DieResult(lay, self.process, float(ev.t), float(rate), self.weight.length, self.derived, self.weighting, self._effective(lay),
                         ev, self.conventions, self.feature_contact, dict(self.spec), level)

    def start(self, layout, *, incoming=None, level: str | None = None) -> DieResult:
        """The die before polishing (time 0, as deposited, over ``incoming``): the state :meth:`resume` continues."""
        from .evolution import DieEvolution

        lay = _as_layout(layout)
        ev = DieEvolution(lay, self.process, self._effective(lay), self.blanket_rate, self.config.asperity_radius, self.feature, incoming)
        ev.conditioned_by = self._token
        return self._result(lay, ev, self.blanket_rate, level)

    def resume(self, previous: DieResult, duration: float, *, blanket_rate: float | None = None) -> DieResult:
        """Polish a die on from its state ``previous`` (a :meth:`start` or an earlier :meth:`resume`) for ``duration`` s more.

        The die keeps its heights, remaining films and event times; from now on it is polished with
        this model's conditions: its blanket rate (or ``blanket_rate``, m/s), the pressure of its
        config (the pad's bulge into wide gaps) and its weighting. Every rate of the die model is
        the blanket rate times a pressure ratio, so a step at a rate varying in time is polished
        exactly by its mean rate over the step. ``previous`` is left as it was. The result's
        ``time`` is the total polishing time; its event times (time_to_clear, ...) those reached so far.
        """
        rate = self.blanket_rate if blanket_rate is None else float(blanket_rate)
        if not (math.isfinite(duration) and duration >= 0):
            raise ValueError(f"duration must be >= 0 s; got {duration!r}")
        lay = previous.layout
        if previous.process != self.process:
            raise ValueError("resume: the die was started with another process (film stack) than this model's")
        ev = previous.evolution.copy()
        if ev.conditioned_by is self._token:  # this model's pressure and weighting already: only the rate
            ev.set_rate(rate)
        else:
            ev.condition(rate, self._effective(lay), self.config.asperity_radius, self.feature)
            ev.conditioned_by = self._token
        ev.advance_to(ev.t + float(duration))
        return self._result(lay, ev, rate, previous.level)


# ------------------------------------------------------------------------------ stacks
@dataclass(frozen=True)
class StackLevel:
    """One level of a stack: its name, the layers whose shapes make it, its process (film stack and thicknesses)."""

    name: str
    layers: tuple
    process: DieProcess
    #: the die inputs the stack file set for this level (a calibration may not override them)
    given: tuple = ()


@dataclass
class StackResult:
    """Every level of a stack, bottom first, each polished over the topography the one below left."""

    levels: list
    spec: dict = field(default_factory=dict)

    @property
    def top(self) -> DieResult:
        return self.levels[-1]

    def hotspots(self) -> list[dict]:
        return [h for lv in self.levels for h in lv.hotspots()]

    def to_dict(self) -> dict:
        """The JSON of ``cmpsim die --stack``: ``levels`` [{``name``, the keys of a single-level run}], the hotspots of all levels,
        ``hotspot_count`` and ``thickness_range`` (that of the last level: the final surface of the stack)."""
        from .hotspots import public

        levels = [{"name": lv.level, **lv.to_dict()} for lv in self.levels]
        hot = public(self.hotspots())
        out = {"layout": self.top.layout.name, "levels": levels, "spec": dict(self.spec), "hotspot_count": len(hot), "hotspots": hot,
               "thickness_range": self.top.thickness_range, "units": levels[-1]["units"] | {"thickness_range": "m"}}
        if any("at_risk" in lv for lv in levels):  # a calibration's levels: their windows at risk, all levels
            out["at_risk"] = [h for lv in levels for h in lv.get("at_risk", [])]
            out["at_risk_count"] = len(out["at_risk"])
            out["units"].update(interval="m", probability="1")
        return out

    def dataset(self):
        """The per-window maps of every level as one ``xarray.Dataset`` on (level, y, x)."""
        import xarray as xr

        ds = xr.concat([lv.dataset() for lv in self.levels], dim="level", data_vars="all", coords="minimal", compat="override",
                       join="override")
        ds = ds.assign_coords(level=("level", [lv.level for lv in self.levels], {"long_name": "level of the stack, bottom first"}))
        ds.attrs["title"] = f"cmpsim die --stack: {self.top.layout.name}, levels " + ", ".join(lv.level for lv in self.levels)
        return ds


_STACK_KEYS = {"window", "pdk", "layer_map", "top", "spec", "level"}
_LEVEL_KEYS = {"name", "layers", "process", "spec"}


def read_stack(path) -> tuple[list[StackLevel], dict]:
    """Read a stack file (TOML): ``[[level]]`` tables with ``name``, ``layers``, ``process`` (oxide|copper) and its inputs.

    Returns (levels, options): options may hold ``window``, ``pdk``, ``layer_map``, ``top`` and
    ``spec`` (a table kind = "5 nm"). ValueError naming the file, the level and the key for
    anything unknown (an unknown process, an unknown input) or missing.
    """
    import tomllib

    p = Path(path)
    if not p.is_file():
        raise ValueError(f"--stack {str(p)!r} is not a file")
    from ..io import read_text

    try:
        data = tomllib.loads(read_text(p, "--stack file"))  # a file not in UTF-8: its line and byte named
    except tomllib.TOMLDecodeError as exc:
        raise ValueError(f"--stack {p.name} is not valid TOML: {exc}") from None
    unknown = set(data) - _STACK_KEYS
    if unknown:
        raise ValueError(f"--stack {p.name}: unknown key(s) {sorted(unknown)}; valid: {sorted(_STACK_KEYS)}")
    raw = data.get("level")
    if not isinstance(raw, list) or not raw:
        raise ValueError(f"--stack {p.name} has no [[level]] tables (each with name, layers, process)")
    levels, names = [], set()
    for i, lv in enumerate(raw):
        where = f"--stack {p.name}, level {i + 1}"
        if not isinstance(lv, dict):
            raise ValueError(f"{where}: a level is a [[level]] table (name, layers, process); got {lv!r}")
        for key in ("name", "layers", "process"):
            if key not in lv:
                raise ValueError(f"{where}: missing {key!r} (each [[level]] needs name, layers, process)")
        name = str(lv["name"])
        if name in names:
            raise ValueError(f"{where}: the name {name!r} is used twice")
        names.add(name)
        if lv["process"] not in PROCESSES:
            raise ValueError(f"{where} ({name}): unknown process {lv['process']!r}; valid: {', '.join(PROCESSES)}")
        layers = lv["layers"]
        if isinstance(layers, str):
            layers = [layers]
        if not isinstance(layers, list) or not layers or not all(isinstance(x, str) for x in layers):
            raise ValueError(f"{where} ({name}): layers must be a list of \"L/D\" or layer names, got {lv['layers']!r}")
        inputs = {k: v for k, v in lv.items() if k not in _LEVEL_KEYS}
        bad = set(inputs) - set(DIE_PARAMETERS)
        if bad:
            raise ValueError(f"{where} ({name}): unknown input(s) {sorted(bad)}; valid: {', '.join(DIE_PARAMETERS)}")
        if "spec" in lv:
            raise ValueError(f"{where} ({name}): give the limits once, in a top-level [spec] table")
        try:
            process = DieProcess.from_values(lv["process"], **inputs)
        except ValueError as exc:
            raise ValueError(f"{where} ({name}): {exc}") from None
        levels.append(StackLevel(name, tuple(layers), process, tuple(inputs)))
    options = {k: data[k] for k in ("window", "pdk", "layer_map", "top", "spec") if k in data}
    if "layer_map" in options and not Path(options["layer_map"]).is_absolute():
        options["layer_map"] = str(p.parent / options["layer_map"])  # relative to the stack file
    if "spec" in options and not isinstance(options["spec"], dict):
        raise ValueError(f"--stack {p.name}: [spec] must be a table, e.g. thickness = \"5 nm\"")
    if "spec" in options:  # checked here, so that a bad limit is named as the file's, not as --spec
        from .hotspots import parse_spec

        parse_spec(options["spec"], what=f"--stack {p.name}: [spec]")
    return levels, options


def _calibrated_level(level: StackLevel, calibration, planarization_length, weighting: str):
    """(process, planarization length, uncertainty) of a stack ``level`` with a calibration's die constants
    applied if it is a level of the calibration's process (else as the level and the run set them).
    ValueError where the stack file or the run sets what the calibration fitted."""
    if calibration is None or level.process.kind != calibration.process:
        return level.process, planarization_length, None
    where = f"--stack level {level.name!r}"
    source = calibration.source or "the calibration"
    clash = [n for n in level.given if n in calibration.constants]
    if clash:
        raise ValueError(f"{where} sets {', '.join(clash)}, calibrated in {source}; remove it from the stack file or use a process file without it")
    consts = dict(calibration.constants)
    if "planarization_length" in consts:
        if planarization_length is not None:
            raise ValueError(f"--planarization-length and the planarization_length calibrated in {source}: give one")
        if weighting != "gaussian":
            raise ValueError(f"--weighting {weighting}: the planarization_length calibrated in {source} is the Gaussian weighting's; "
                             "use --weighting gaussian")
    unc = calibration.uncertainty
    for n in (unc.names if unc is not None else ()):
        consts.pop(n)  # applied by DieModel from the uncertainty's values (cmpsim.die.polish._fitted)
    length = consts.pop("planarization_length", planarization_length)
    return (level.process.replace(**consts) if consts else level.process), length, unc


def stack_settings(options: dict, window, top) -> list[tuple[str, str]]:
    """(option, setting) pairs of a stack file's ``options`` (:func:`read_stack`) that stand for
    ``--window`` or ``--top`` in this run (those not given on the command line)."""
    out = []
    if window is None and "window" in options:
        out.append(("--window", f"window = {options['window']!r}"))
    if not top and options.get("top"):
        out.append(("--top", f"top = {options['top']!r}"))
    return out


@contextlib.contextmanager
def stack_settings_named(stack_name, settings):
    """Re-raise a ValueError (or LayoutTooLarge) whose message speaks of ``--window`` or ``--top``
    naming the stack file's setting when the value came from there (:func:`stack_settings`)."""
    try:
        yield
    except ValueError as exc:
        said = [text for option, text in settings or () if option in str(exc)]
        if not said:
            raise
        raise type(exc)(f"{exc} (from --stack {stack_name}: {', '.join(said)})") from None


def simulate_stack(layout, levels, window: float | None = None, *, top: str | None = None, pdk: str | None = None, layer_map=None,
                   config=None, blanket_rate: float | None = None, time: float | None = None, spec=None,
                   planarization_length: float | None = None, weighting: str = "gaussian", feature_contact: str = "elastic",
                   progress=None, calibration=None) -> StackResult:
    """Polish the levels of a stack bottom first (docs/model.md, section 18.10).

    ``layout`` is a layout path or a :class:`cmpsim.layout.Layout`, ``levels`` a list of
    :class:`StackLevel` (or a stack file, :func:`read_stack`, whose ``window``, ``pdk``,
    ``layer_map``, ``top`` and ``spec`` apply where not given here). Every level is extracted on
    the same window grid, on one read of the file (:func:`cmpsim.layout.extract_levels`); each is
    polished over the topography the level below left
    (:meth:`cmpsim.die.evolution.DieEvolution.topography`). The wafer is solved once per film.
    ``progress`` (stage, done, total) is told how the extraction goes. ``calibration``: a process
    file's die constants (:class:`cmpsim.calibration.processfile.DieConstants`: ``process``,
    ``constants`` {name: SI}, ``uncertainty``, ``source``) applied to the levels of its process, whose
    hotspots then carry ``interval`` and ``probability`` (:func:`_calibrated_level`).
    """
    from ..layout import read_layout
    from ..inputs.units import to_si
    from .hotspots import parse_spec

    spec = parse_spec(spec)
    from_file = stack_name = None
    if isinstance(levels, (str, os.PathLike)):
        stack_name = Path(levels).name
        levels, options = read_stack(levels)
        from_file = stack_settings(options, window, top)
        if window is None and "window" in options:
            window = to_si(options["window"], "m", "window", "20 um")
        pdk = pdk or options.get("pdk")
        layer_map = layer_map or options.get("layer_map")
        top = top or options.get("top")
        spec = parse_spec(options.get("spec")) | spec
    if window is None:
        window = 20e-6
    if isinstance(layout, (str, os.PathLike)):
        try:
            layout = read_layout(layout)
        except FileNotFoundError as exc:
            raise ValueError(str(exc)) from None
    from ..layout import extract_levels

    specs = [list(lv.layers) if isinstance(lv.layers, tuple) else lv.layers for lv in levels]
    try:
        with stack_settings_named(stack_name, from_file):
            extracted = extract_levels(layout, specs, window, top=top, pdk=pdk, layer_map=layer_map, progress=progress,
                                       names=[lv.name for lv in levels])
    except FileNotFoundError as exc:  # a layer map that is not there: bad input, as in layout_die
        raise ValueError(str(exc)) from None
    dies = [Layout.from_windows(w) for w in extracted]
    config = _config(config)
    rates: dict[str, float] = {}
    out, incoming = [], None
    if calibration is not None and not any(lv.process.kind == calibration.process for lv in levels):
        raise ValueError(f"the die constants of {calibration.source or 'the calibration'} were calibrated on {calibration.process} structures; "
                         f"no level of the stack is {calibration.process} (levels: "
                         + ", ".join(f"{lv.name} {lv.process.kind}" for lv in levels) + ")")
    for lv, lay in zip(levels, dies):
        film = film_stack(lv.process).film
        process, length, unc = _calibrated_level(lv, calibration, planarization_length, weighting)
        model = DieModel(config, process, blanket_rate=blanket_rate if blanket_rate is not None else rates.get(film),
                         planarization_length=length, weighting=weighting, feature_contact=feature_contact, spec=spec, uncertainty=unc)
        rates[film] = model.blanket_rate
        res = model.run(lay, time, incoming=incoming, level=lv.name)
        out.append(res)
        incoming = res.evolution.topography()
    return StackResult(out, dict(spec))
