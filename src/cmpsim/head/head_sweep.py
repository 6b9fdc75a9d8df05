"""The removal averaged over the head's sweep across the pad (issue 25, "kinematics of a real tool").

On a rotary polisher the head does not only turn: it oscillates across the pad, so the
pad-centre to wafer-centre distance e (``centre_distance``) runs through e_0 +- A over a sweep
cycle of seconds to tens of seconds, many wafer turns. Each equilibrium of cmpsim is solved at
one e and its ``removal_rate_profile`` is already the average over the wafer's turn
(docs/model.md, "Within-wafer uniformity"). Over a sweep cycle a point of the wafer at radius r
therefore loses the time average of that profile over e(t): with e(t) = e_0 + A sin(2 pi t/T),
the quadrature of :func:`cmpsim.physics.kinematics.head_sweep_nodes` (Gauss-Chebyshev: equal weights,
exact for a profile polynomial in e of degree below 2n).

Assumptions: the sweep is quasi-static (the film settles within a wafer turn while e changes
over seconds, and the sweep speed, of the order of cm/s, is neglected beside the sliding speed
of about 1 m/s); the wafer stays on the pad and the pad's own wear and conditioning do not
change over the cycle.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from ..inputs.config import Config
from ..solver.equilibrium import EquilibriumError
from ..physics.kinematics import head_sweep_nodes
from ..solver.points import solve_point
from ..results.uniformity import uniformity
from ..inputs.units import to_si

__all__ = ["HeadSweepAverage", "sweep_average"]


@dataclass
class HeadSweepAverage:
    """The removal averaged over one cycle of the head's sweep.

    Attributes
    ----------
    centre_distances, weights : numpy.ndarray
        The quadrature nodes e_k (m) and their weights (sum 1).
    results : list of cmpsim.results.result.Result
        The equilibrium at each node.
    radius : numpy.ndarray
        Ring-centre radii of the profile, m.
    removal_rate_profile : numpy.ndarray
        Removal rate averaged over the wafer's turn and the sweep cycle at each radius, m/s.
    removal_rate_mean : float
        Its wafer mean, m/s.
    within_wafer_nonuniformity : float
        1-sigma / mean of the averaged profile inside the edge exclusion of the config (fraction).
    removal_rate_range : float
        Max - min of the averaged profile inside the edge exclusion, m/s.
    """

    centre_distances: np.ndarray
    weights: np.ndarray
    results: list = field(repr=False)
    radius: np.ndarray
    removal_rate_profile: np.ndarray
    removal_rate_mean: float
    within_wafer_nonuniformity: float
    removal_rate_range: float


def sweep_average(config: Config | None = None, amplitude=0.0, nodes: int = 4, **overrides) -> HeadSweepAverage:
    """Removal profile averaged over the head's sweep e(t) = e_0 + A sin(2 pi t / T).

    Parameters
    ----------
    config : Config, optional
        The operating point; its ``centre_distance`` is the mean e_0 (default: the default model).
    amplitude : float or str
        Sweep amplitude A, m or text with a unit (``"20 mm"``); 0 <= A < e_0.
    nodes : int
        Gauss-Chebyshev nodes (equilibria solved), >= 1.
    **overrides
        Inputs to change, by name, as in :func:`cmpsim.solve`.

    Returns
    -------
    HeadSweepAverage

    Raises
    ------
    ValueError
        Bad amplitude or nodes (named, with the valid range), or a bad input.
    cmpsim.solver.equilibrium.EquilibriumError
        No equilibrium at one of the nodes (the message names its centre distance).
    """
    config = config or Config.default()
    if overrides:
        config = config.replace(**overrides)
    amplitude = to_si(amplitude, "m", "amplitude", example="mm")
    distances, weights = head_sweep_nodes(config.centre_distance, amplitude, nodes)
    results, start = [], None
    for e in distances:
        outcome = solve_point(config.replace(centre_distance=float(e)), start=start)
        if not outcome.ok:
            raise EquilibriumError(f"no equilibrium at centre_distance = {e:.6g} m of the head's sweep: {outcome.error}")
        results.append(outcome.result)
        start = outcome.result.solution.state.u
    profile = np.sum([w * r.removal_rate_profile for w, r in zip(weights, results)], axis=0)
    grid = results[0].grid
    nonuniformity, spread = uniformity(profile, grid.radius, config.edge_exclusion)
    mean = float(sum(w * r.removal_rate_mean for w, r in zip(weights, results)))
    return HeadSweepAverage(distances, weights, results, results[0].profiles["radius"].copy(), profile, mean, float(nonuniformity), float(spread))
