"""What every study does with its operating points: the runner shared by sweeps, validation,
reproduction and calibration.

* :func:`solve_point` solves one point from a warm start when one is given and, if that fails,
  again from the cold start; it never raises: the :class:`Outcome` holds the result or the
  diagnosis, and which start succeeded.
* :class:`PointCache` solves each distinct configuration of a study once (the config cache),
  counts the equilibria and pressure solves, and gives the relative removal rate against the
  study's own solve of the reference case (:func:`cmpsim.solver.model.reference_config`), so that
  it is exactly 1 there.
* :class:`Progress` is the progress bar of a study (rich, on stderr).

The tables of the reports are in :mod:`cmpsim.tables`.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any, Callable

import numpy as np

from ..inputs.config import Config

__all__ = ["Outcome", "diagnosis", "solve_point", "config_key", "PointCache", "Progress", "predict_start"]


@dataclass
class Outcome:
    """What solving one point gave: the result, or the diagnosis of why there is none."""

    result: Any  # cmpsim.results.result.Result, or None
    start: str  # "warm", "cold" or "cold-retry" (the warm start failed, the cold one was tried)
    error: str = ""  # "" when solved; otherwise the diagnosis

    @property
    def ok(self) -> bool:
        return self.result is not None


def diagnosis(exc: Exception) -> str:
    """The message of a failed solve: the solver's diagnosis, or the input error as ``cmpsim run`` prints it."""
    from .equilibrium import EquilibriumError

    if isinstance(exc, EquilibriumError):
        return f"no equilibrium: {exc}"
    if isinstance(exc, ValueError):
        return str(exc)
    return f"{type(exc).__name__}: {exc}"


def solve_point(config: Config, start=None, relative: bool = False, problem=None, reference_removal_rate: float | None = None) -> Outcome:
    """Solve one point from ``start`` (warm) and, if that fails, from the cold start; never raises.

    Parameters
    ----------
    config : Config
    start : array_like, optional
        Newton start (h0 [m], attack angle [rad], cross tilt [rad]); None: the cold start only.
    relative : bool
        Also give ``removal_rate_relative`` (see :func:`cmpsim.solver.model.solve`).
    problem : WaferProblem, optional
        The problem of ``config`` if the caller built it already (used by the first attempt;
        the cold retry builds a fresh one, so its counts are its own).
    reference_removal_rate : float, optional
        The removal rate of the reference case, if the caller solved it (see
        :func:`cmpsim.solver.model.solve`).
    """
    from .model import solve

    options = {"relative": relative, "reference_removal_rate": reference_removal_rate}
    try:
        return Outcome(solve(config, start=start, problem=problem, **options), "cold" if start is None else "warm")
    except Exception as exc:  # reported, not raised: a study goes on with its other points
        if start is None:
            return Outcome(None, "cold", diagnosis(exc))
    try:
        return Outcome(solve(config, **options), "cold-retry")
    except Exception as exc:
        return Outcome(None, "cold-retry", diagnosis(exc))


def _solved(rec) -> bool:
    return isinstance(rec, dict) and rec.get("status") == "ok" and rec.get("u") is not None


def predict_start(cfg: Config, problem, x: float | None, prev, prev2):
    """Newton start predicted from the converged previous points of the chain (or None).

    For the contact models the cold start (the h0 at which the pad contact alone carries the
    load) already costs no pressure solve and is good; the prediction keeps it and adds the
    neighbours' converged offset from *their* cold start, extrapolated linearly along the
    chain (secant). For the hydrodynamic model the offset is the position itself. This choice
    was measured (docs/sweeps.md, 'Warm start'): it never cost more Newton iterations than the
    cold start on the axes tried, while a plain copy of the neighbour's position sometimes
    did (e.g. along pad_roughness or pad_modulus).
    ``prev`` and ``prev2`` are records of the two previous points (dicts with ``status``
    ("ok" if solved), ``u`` (their position), ``cold_base`` (their cold start) and ``x`` (their
    coordinate along the chain)); ``x`` is this point's coordinate.
    Returns (start, cold_base) where cold_base is this point's cold start (stored for the next).
    """
    cold = None
    if cfg.model != "hydrodynamic":
        try:
            cold = problem.contact_only_start()
        except Exception:
            return None, None  # the cold solve will say why
    if not _solved(prev):
        return None, cold
    zero = np.zeros(3)

    def offset(rec):
        c = rec.get("cold_base")
        if cfg.model != "hydrodynamic" and c is None:
            return None
        return np.asarray(rec["u"], dtype=float) - (np.asarray(c, dtype=float) if c is not None else zero)

    d1 = offset(prev)
    if d1 is None:
        return None, cold
    d = d1
    if _solved(prev2) and x is not None and prev.get("x") is not None and prev2.get("x") is not None:
        d2 = offset(prev2)
        dx = prev["x"] - prev2["x"]
        if d2 is not None and dx != 0:
            d = d1 + (x - prev["x"]) / dx * (d1 - d2)
    start = d + (cold if cold is not None else zero)
    if not np.all(np.isfinite(start)):
        return None, cold
    return start, cold


def config_key(config: Config) -> tuple:
    """A hashable identity of a Config: its SI inputs."""
    return tuple(sorted(config.to_dict().items()))


class PointCache:
    """Solve each distinct configuration of a study once.

    ``relative=True`` gives every result its ``removal_rate_relative`` against this cache's
    own solve of the reference case (solved from the cold start the first time it is
    needed, and shared with the study's point at the same inputs, if any). ``advance(ok)``
    is called after each new solve (a progress bar).
    """

    def __init__(self, relative: bool = False, advance: Callable[[bool], None] | None = None):
        self.relative = relative
        self.advance = advance
        self.outcomes: dict[tuple, Outcome] = {}
        self.factorizations = 0

    def __len__(self) -> int:
        """The number of distinct configurations solved (equilibria)."""
        return len(self.outcomes)

    def solve(self, config: Config, start=None, problem=None) -> Outcome:
        """The outcome of ``config``: solved now (warm from ``start``, on ``problem`` if given, see
        :func:`solve_point`) or taken from the cache."""
        key = config_key(config)
        if key not in self.outcomes:
            rate = self._reference_removal_rate(config, key) if self.relative else None
            out = solve_point(config, start=start, relative=self.relative, problem=problem, reference_removal_rate=rate)
            self.outcomes[key] = out
            if out.ok:
                self.factorizations += int(out.result.scalars["factorizations"])
            if self.advance is not None:
                self.advance(out.ok)
        return self.outcomes[key]

    def _reference_removal_rate(self, config: Config, key: tuple) -> float | None:
        from .model import reference_config

        ref = reference_config(config)
        if config_key(ref) == key:
            return None  # the reference case itself: relative rate 1
        out = self.solve(ref)
        return out.result.removal_rate_mean if out.ok else float("nan")


class Progress:
    """The progress bar of a study on stderr (rich), or nothing when disabled.

    ``with Progress(True, total, "validate") as bar: ... bar.advance(ok)``; ``done`` and
    ``failed`` start the counts (a resumed study).
    """

    def __init__(self, enabled: bool, total: int, label: str, done: int = 0, failed: int = 0):
        self.enabled = enabled
        self.total, self.done, self.failed = total, done, failed
        self._bar = None
        if enabled:
            from rich.console import Console
            from rich.progress import BarColumn, Progress, TextColumn, TimeElapsedColumn, TimeRemainingColumn

            self._bar = Progress(
                TextColumn(label),
                BarColumn(),
                TextColumn("{task.fields[done]} done, {task.fields[failed]} failed, {task.fields[left]} remaining"),
                TimeElapsedColumn(),
                TextColumn("ETA"),
                TimeRemainingColumn(),
                console=Console(stderr=True),
            )
            self._task = self._bar.add_task(label, total=total, completed=done, **self._fields())

    def _fields(self) -> dict:
        return {"done": self.done, "failed": self.failed, "left": self.total - self.done}

    def __enter__(self) -> "Progress":
        if self._bar is not None:
            self._bar.start()
        return self

    def __exit__(self, *exc) -> None:
        if self._bar is not None:
            self._bar.stop()

    def advance(self, ok: bool = True) -> None:
        """One more point done (``ok=False``: it failed)."""
        self.done += 1
        self.failed += 0 if ok else 1
        if self._bar is not None:
            self._bar.update(self._task, advance=1, **self._fields())
