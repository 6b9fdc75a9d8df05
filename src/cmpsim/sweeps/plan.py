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
