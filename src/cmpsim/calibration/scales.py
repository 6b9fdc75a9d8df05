"""Calibrate every scale a set of measurements reaches, in one call: the pad, the films, the die.

``cmpsim calibrate DATA...`` reads the rows of every family (:func:`cmpsim.calibration.mixed.read_all`)
and calibrates, in this order (each on the constants of the one before):

1. **the pad** (``pad_temperature_rise``, ``friction_coefficient``): the summit friction and the
   heat removal (:func:`cmpsim.calibration.thermal.calibrate_thermal`);
2. **the films** (removal rates, depths, profiles): the film chemistry or the ``--free`` inputs
   through the wafer solve (:func:`cmpsim.calibration.calibrate`), with the pad's constants;
3. **the die** (``dishing``, ``erosion``, ``step_height``): the die model's constants
   (:func:`cmpsim.calibration.die.calibrate_die`), timed structures without a ``blanket_rate``
   at the calibrated film's rate;
4. **the pad life** (a lot's rows: ``wafer``, ``thickness`` or ``removal``, with the lot's recipe,
   ``lot``): the glazing and conditioning constants (:func:`cmpsim.calibration.padlife.calibrate_padlife`),
   the lot run with the film's and the pad's constants as ``cmpsim lot --config`` runs it.

Without ``--free`` each scale's data choose their inputs (:mod:`cmpsim.calibration.registry`,
one :class:`~cmpsim.calibration.registry.QuantityKind` per kind, kept where the Jacobian at the
start separates them: :func:`cmpsim.calibration.registry.choose_for`). The result writes one
process file (:mod:`cmpsim.calibration.processfile`).
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

__all__ = ["ScaleCalibration", "calibrate_scales", "split_free"]


@dataclass
class ScaleCalibration:
    """The calibration of every scale: ``film`` (:class:`~cmpsim.calibration.result.CalibrationResult`), ``die`` (:class:`~cmpsim.calibration.die.DieCalibration`),
    ``pad`` (:class:`~cmpsim.calibration.thermal.ThermalCalibration`), each None without its data; ``config`` the process file's
    configuration (the film fit's, with the pad's constants); the choices of the die and the pad."""

    config: object
    film: object = None
    die: object = None
    pad: object = None
    die_choice: object = None
    pad_choice: object = None
    #: the pad life's calibration (:class:`~cmpsim.calibration.padlife.PadLifeCalibration`), None without lot rows and a recipe
    padlife: object = None
    data: list = field(default_factory=list)
    notes: list = field(default_factory=list)
    #: the base of the pad's records: None = the 300mm preset on the coarse grid (no configuration given), else the configuration
    pad_base: object = None

    def constant_rows(self) -> list[list[str]]:
        """[scale, constant, fitted, 95 % interval, unit] of every fitted constant (display units for the film's)."""
        from ..inputs.config import PARAMETERS, format_display
        from .die import DIE_CONSTANTS
        from .scalefit import interval_text
        from .thermal import THERMAL_CONSTANTS

        rows = []
        if self.pad is not None:
            for n in self.pad.free:
                rows.append(["pad", n, f"{self.pad.values[n]:.4g}", interval_text(*self.pad.ci95[n]), THERMAL_CONSTANTS[n][0]])
        if self.film is not None:
            for n in self.film.free:
                lo, hi = self.film.ci95[n]
                rows.append(["film", n, format_display(n, self.film.values[n]),
                             f"[{format_display(n, lo) if np.isfinite(lo) else '-'}, {format_display(n, hi) if np.isfinite(hi) else 'inf' if hi > 0 else '-'}]",
                             PARAMETERS[n].display or "-"])
        if self.die is not None:
            for n in self.die.free:
                rows.append(["die", n, f"{self.die.values[n]:.4g}", interval_text(*self.die.ci95[n]), DIE_CONSTANTS[n][0]])
        if self.padlife is not None:
            from .padlife import GLAZING_CONSTANTS

            for n in self.padlife.free:
                rows.append(["pad life", n, f"{self.padlife.values[n]:.4g}", interval_text(*self.padlife.ci95[n]), GLAZING_CONSTANTS[n][0]])
        return rows

    def summary(self) -> str:
        """The report of every scale: inputs chosen and why, constants with 95 % intervals and correlations,
        what the data cannot separate, residuals before and after; then every constant in one table."""
        from ..tables import text_table

        out = []

        def chosen(choice):
            return ["inputs chosen by the data (no --free):"] + [f"  {line}" for line in choice.lines()] + [""] if choice is not None else []

        if self.pad is not None:
            out += [f"== pad: {len(self.pad.records)} record(s) of its temperature and friction ==", ""] + chosen(self.pad_choice)
            out += [self.pad.summary(), ""]
        if self.film is not None:
            out += [f"== films: {len(self.film.points_before)} point(s) through the wafer solve ==", ""]
            out += [self.film.summary(), ""]
        if self.die is not None:
            proc = self.die.records[0].process
            out += [f"== die ({proc}): {len(self.die.records)} test structure(s) ==", ""] + chosen(self.die_choice)
            out += [self.die.summary(), ""]
        if self.padlife is not None:
            lot = self.padlife.table()
            out += [f"== pad life: {len(self.padlife.records)} wafer row(s) of a lot ({lot['recipe']}, conditioning {lot['conditioning']}, "
                    f"control {lot['control']}) ==", "", self.padlife.summary(), ""]
        out.append("every constant calibrated (95 % intervals):")
        out.append(text_table(["scale", "constant", "fitted", "95 % interval", "unit"], self.constant_rows()))
        out += [f"note: {n}" for n in self.notes]
        return "\n".join(out)

    def to_toml(self, path):
        """Write the one process file of every scale (:func:`cmpsim.calibration.processfile.write_scales_file`)."""
        from .processfile import write_scales_file

        return write_scales_file(self, path)


def split_free(names, measurements) -> tuple[list[str], list[str], list[str], list[str]]:
    """(film, die, pad, pad life) names of ``--free``; ValueError naming a constant whose scale has no rows."""
    from .die import DIE_CONSTANTS
    from .padlife import GLAZING_CONSTANTS
    from .thermal import THERMAL_CONSTANTS

    from ..inputs.config import PARAMETERS

    film, die, pad, life = [], [], [], []
    known = [*GLAZING_CONSTANTS, *DIE_CONSTANTS, *THERMAL_CONSTANTS, *PARAMETERS]
    for n in names or []:
        if n.replace("-", "_") not in known:  # a typo: say so, not which rows its (unknown) scale would need
            import difflib

            near = difflib.get_close_matches(n, known, n=3)
            raise ValueError(f"--free {n}: unknown parameter {n!r}" + (f"; did you mean {', '.join(near)}?" if near else "")
                             + " (inputs: `cmpsim params`; die constants: " + ", ".join(DIE_CONSTANTS) + "; pad: " + ", ".join(THERMAL_CONSTANTS) + ")")
        if n in GLAZING_CONSTANTS:
            if not measurements.lots:
                raise ValueError(f"--free {n}: a pad life constant needs a lot's rows (a wafer column, quantity thickness or removal) and --recipe")
            life.append(n)
        elif n in DIE_CONSTANTS:
            if not measurements.structures:
                raise ValueError(f"--free {n}: a die constant needs test-structure rows (quantity dishing, erosion or step_height)")
            die.append(n)
        elif n in THERMAL_CONSTANTS and measurements.pad:
            pad.append(n)
        elif n == "pad_heat_transfer_coefficient":
            raise ValueError(f"--free {n}: the pad's heat removal needs pad rows (quantity pad_temperature_rise)")
        else:
            film.append(n)
    if film and not measurements.datasets:
        raise ValueError(f"--free {', '.join(film)}: fitted through the wafer solve, these need removal or other wafer-scale rows")
    return film, die, pad, life


def calibrate_scales(measurements, config=None, free=None, *, bounds=None, max_nfev=None, progress=False, pad_config=None,
                     lot=None) -> ScaleCalibration:
    """Calibrate the pad, the films and the die on ``measurements`` (:class:`cmpsim.calibration.mixed.Measurements`).

    ``config``: the starting configuration (default :meth:`~cmpsim.inputs.config.Config.default`); ``pad_config``: the
    base of the pad's records (default ``config`` if given, else the 300mm preset on the coarse
    grid, the base of docs/calibrate.md); ``free``: names of any scale (``--free``), each fitted
    at its scale; a scale with data and no name in ``free`` lets its data choose; ``lot``: how the
    lot rows were run (:class:`cmpsim.calibration.padlife.LotSetting`, its recipe; None: lot rows are
    not calibrated, only noted).
    """
    from ..inputs.config import Config
    from . import calibrate
    from .die import calibrate_die
    from .registry import PAD_HEAT, TEST_STRUCTURES, choose_for
    from .thermal import calibrate_thermal

    cfg = config if config is not None else Config.default()
    film_free, die_free, pad_free, life_free = split_free(free, measurements)
    if life_free and lot is None:
        raise ValueError(f"--free {', '.join(life_free)}: the lot's recipe is needed (--recipe RECIPE.toml)")
    if bounds:
        from .die import DIE_CONSTANTS
        from .thermal import THERMAL_CONSTANTS

        other = [n for n in bounds if n in DIE_CONSTANTS or (n in THERMAL_CONSTANTS and measurements.pad)]
        if other:
            raise ValueError(f"--bounds {', '.join(other)}: bounds apply to the inputs fitted through the wafer solve; the die and pad "
                             "constants are bounded a factor 30 either side of their start (die) or by their valid range (pad)")
    if lot is not None and not measurements.lots:
        raise ValueError("--recipe calibrates the pad life on a lot's rows (a wafer column); the data hold none")
    if not (measurements.datasets or measurements.structures or measurements.pad or (measurements.lots and lot is not None)):
        raise ValueError("nothing to calibrate: the data hold no removal, test-structure or pad rows"
                         + (" (lot rows calibrate the pad life with the lot's recipe: --recipe RECIPE.toml)" if measurements.lots else ""))
    out = ScaleCalibration(cfg, data=list(measurements.paths), pad_base=pad_config)
    if measurements.lots and lot is None:
        out.notes.append(f"{len(measurements.lots)} lot row(s) not calibrated: give the lot's recipe (--recipe RECIPE.toml) to calibrate the "
                         "pad life on them")
    if measurements.pad:
        choice = None
        if not pad_free:
            choice = choose_for(PAD_HEAT, measurements.pad, pad_config)
            pad_free = choice.names
            if not pad_free:
                raise ValueError("the pad rows identify no constant: " + "; ".join(w for _, w in choice.left))
        out.pad = calibrate_thermal(measurements.pad, pad_config, pad_free)
        out.pad_choice = choice
        if choice is not None:
            out.pad.reasons = dict(choice.chosen)
        cfg = cfg.replace(**out.pad.values)
    if measurements.datasets:
        out.film = calibrate(measurements.datasets, film_free or None, config=cfg, bounds=bounds or None, max_nfev=max_nfev, progress=progress)
        cfg = out.film.config
    if measurements.structures:
        kinds = sorted({r.process for r in measurements.structures})
        if len(kinds) > 1:
            raise ValueError(f"test structures of {' and '.join(kinds)}: one process per process file; calibrate each in its own run")
        choice = None
        if not die_free:
            choice = choose_for(TEST_STRUCTURES, measurements.structures, cfg)
            die_free = choice.names
            if not die_free:
                raise ValueError("the test structures identify no die constant: " + "; ".join(w for _, w in choice.left))
        out.die = calibrate_die(measurements.structures, cfg, die_free)
        if choice is not None and any("cannot be separated" in why for _, why in choice.left):
            out.die, choice = _choose_again(out.die, choice, measurements.structures, cfg)
        out.die_choice = choice
        if choice is not None:
            out.die.reasons = dict(choice.chosen)
    if measurements.lots and lot is not None:
        from .padlife import calibrate_padlife

        extra = {}  # the lot runs with this calibration's film and pad constants, as `cmpsim lot --config` would
        if out.film is not None:
            extra.update(out.film.settings)
            extra.update(out.film.values)
        if out.pad is not None:
            extra.update(out.pad.values)
        lot.overrides = {**lot.overrides, **extra}
        out.padlife = calibrate_padlife(measurements.lots, lot, life_free or None)
    out.config = cfg
    return out


def _choose_again(first, choice, records, config):
    """The die's choice made again at the first fit's constants (the start's Jacobian can hide a direction the
    fitted constants show: a wide line's bulge is small at the pad body's 300 MPa); refitted if it keeps more."""
    from .die import calibrate_die, start_jacobian
    from .identify import choose
    from .registry import TEST_STRUCTURES

    cands = TEST_STRUCTURES.candidates(records, config)
    names = [c.name for c in cands]
    J = start_jacobian(records, names, config, values=first.constants)
    max_free = len(records) if all(r.uncertainty is not None for r in records) else max(len(records) - 1, 1)
    again = choose(J, names, [c.why for c in cands], max_free)
    if not set(first.free) < set(again.names):
        return first, choice
    added = [n for n in again.names if n not in first.free]
    again.notes = list(choice.notes) + [f"chosen again at the first fit's values ({', '.join(first.free)}): {', '.join(added)} now separated "
                                        "by the Jacobian there, and fitted"]
    return calibrate_die(records, config, again.names), again
