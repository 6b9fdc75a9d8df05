"""The plan of a sweep: its identity, the chains of points, and the warm start along a chain.

Points are grouped into *chains* along the last numeric axis (at most ``chain_length`` points,
a fixed split that does not depend on the number of workers); each point of a chain starts
Newton from a prediction made from the converged records of the one or two previous points.
"""

from __future__ import annotations

import hashlib
import json
import math
from dataclasses import dataclass

import numpy as np

from .._version import __version__
from ..config import Config
from .spec import SweepSpec

__all__ = ["DEFAULT_CHAIN_LENGTH"]

#: Longest chain of warm-started points (one cold start per chain).
DEFAULT_CHAIN_LENGTH = 8
#: Version of the state-directory layout and of the chain/prediction scheme.
_STATE_FORMAT = 1


@dataclass(frozen=True)
class _PlanPoint:
    index: tuple[int, ...]
    key: str
    settings: dict
    x: float | None  # coordinate along the chain dimension


def _canonical(obj) -> str:
    return json.dumps(obj, sort_keys=True, separators=(",", ":"), allow_nan=True)


def _identity(spec: SweepSpec, warm_start: bool, chain_length: int) -> str:
    """Hash of everything that determines the results: base, grid of points, chain layout, version."""
    ident = {
        "format": _STATE_FORMAT,
        "version": __version__,
        "base": spec.base.to_dict(),
        "dims": [[d, list(spec.coords[d])] for d in spec.dims],
        "points": [list(i) for i in spec.requested()],
        "warm_start": bool(warm_start),
        "chain_length": int(chain_length),
    }
    return hashlib.sha256(_canonical(ident).encode()).hexdigest()


def _plan(spec: SweepSpec, identity: str, warm_start: bool, chain_length: int) -> list[list[_PlanPoint]]:
    """Chains of points (each solved in order, warm-starting from its predecessors)."""
    base = spec.base.to_dict()
    chain_dim = spec.chain_dim if warm_start else None
    ci = spec.dims.index(chain_dim) if chain_dim else None

    def make(idx):
        s = spec.settings(idx)
        full = dict(base, **s)
        key = hashlib.sha256((identity + _canonical(full)).encode()).hexdigest()[:24]
        return _PlanPoint(idx, key, s, None if ci is None else float(s[chain_dim]))

    points = [make(i) for i in spec.requested()]
    if ci is None:
        return [[p] for p in points]
    groups: dict[tuple, list[_PlanPoint]] = {}
    for p in points:
        groups.setdefault(p.index[:ci] + p.index[ci + 1 :], []).append(p)
    chains = []
    for g in groups.values():
        g.sort(key=lambda p: p.x)
        n_seg = math.ceil(len(g) / chain_length)
        for part in np.array_split(np.arange(len(g)), n_seg):
            chains.append([g[i] for i in part])
    return chains


def _ok(rec) -> bool:
    return isinstance(rec, dict) and rec.get("status") == "ok" and rec.get("u") is not None


def _predict_start(cfg: Config, problem, x: float | None, prev, prev2):
    """Newton start predicted from the converged previous points of the chain (or None).

    For the contact models the cold start (the h0 at which the pad contact alone carries the
    load) already costs no pressure solve and is good; the prediction keeps it and adds the
    neighbours' converged offset from *their* cold start, extrapolated linearly along the
    chain (secant). For the hydrodynamic model the offset is the position itself. This choice
    was measured (docs/sweeps.md, 'Warm start'): it never cost more Newton iterations than the
    cold start on the axes tried, while a plain copy of the neighbour's position sometimes
    did (e.g. along pad_roughness or pad_modulus).
    Returns (start, cold_base) where cold_base is this point's cold start (stored for the next).
    """
    cold = None
    if cfg.model != "hydrodynamic":
        try:
            cold = problem.contact_only_start()
        except Exception:
            return None, None  # the cold solve will say why
    if not _ok(prev):
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
    if _ok(prev2) and x is not None and prev.get("x") is not None and prev2.get("x") is not None:
        d2 = offset(prev2)
        dx = prev["x"] - prev2["x"]
        if d2 is not None and dx != 0:
            d = d1 + (x - prev["x"]) / dx * (d1 - d2)
    start = d + (cold if cold is not None else zero)
    if not np.all(np.isfinite(start)):
        return None, cold
    return start, cold
