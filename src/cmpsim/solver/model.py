"""One operating point: from a :class:`~cmpsim.inputs.config.Config` to a :class:`~cmpsim.results.result.Result`.

Builds the problem (:mod:`cmpsim.solver.setup`), solves the equilibrium (:mod:`cmpsim.solver.equilibrium`)
and evaluates every output (:mod:`cmpsim.solver.postprocess`). ``cmpsim.solve`` and ``cmpsim run``
both call :func:`solve`.
"""

from __future__ import annotations

from ..inputs.config import Config
from .equilibrium import EquilibriumError, WaferProblem, scan_moment_roots, solve_equilibrium
from .postprocess import evaluate_outputs
from .setup import HAFF_T, PhysicalSetup, build_problem, effective_modulus, physical_setup

__all__ = ["build_problem", "solve", "PhysicalSetup", "physical_setup", "EquilibriumError", "REFERENCE_CASE", "reference_config", "wants_relative", "HAFF_T", "effective_modulus"]

#: The paper's normalisation point of the relative removal rate (Figs. 11-12) with its base
#: load and speed (Table 1). The pad roughness of the reference case is the configuration's
#: ``reference_roughness`` (15 um in the paper preset, as in the paper; the measured 5 um of
#: the default pad otherwise), see :func:`reference_config`.
REFERENCE_CASE = {"particle_diameter": 100e-9, "applied_pressure": "4 psi", "rotation_speed": "60 rpm"}
_REFERENCE_CACHE: dict[tuple, float] = {}


def reference_config(config: Config) -> Config:
    """The reference case of ``config``: the LEP model at :data:`REFERENCE_CASE` with the pad at its
    ``reference_roughness``, every other input equal (the paper's d = 100 nm, sigma = 15 um, 4 psi,
    60 rpm in the paper preset)."""
    return config.replace(model="lep", pad_roughness=config.reference_roughness, zone_pressures="", **REFERENCE_CASE)


def wants_relative(config: Config) -> bool:
    """Whether :func:`solve` gives ``removal_rate_relative`` unless told: with the paper's removal
    law (the paper preset), whose figures 11-12 are in removal rate relative to the reference
    case. The predictive removal law gives absolute rates (m/s), and its reference solve would
    double the cost of a first solve; ask for it with ``relative=True`` (``--relative``)."""
    from ..models import removal_law

    return removal_law(config).relative_by_default


def _reference_removal_rate(ref: Config) -> float:
    """Removal rate of the reference case ``ref``, solved from the cold start once per process."""
    key = tuple(sorted(ref.to_dict().items()))
    if key not in _REFERENCE_CACHE:
        if len(_REFERENCE_CACHE) > 256:
            _REFERENCE_CACHE.clear()
        _REFERENCE_CACHE[key] = solve(ref, relative=False).scalars["removal_rate_mean"]
    return _REFERENCE_CACHE[key]


def solve(
    config: Config | None = None,
    start=None,
    relative: bool | None = None,
    check_roots: bool = False,
    problem: WaferProblem | None = None,
    reference_removal_rate: float | None = None,
    **overrides,
):
    """Solve one operating point and evaluate every output.

    Parameters
    ----------
    config : Config, optional
        Inputs; default :meth:`Config.default` (the predictive model at the paper's base operating point; :meth:`Config.paper` is the paper's model).
    start : array_like, optional
        Initial (h0 [m], attack angle [rad], cross tilt [rad]) for Newton (warm start).
    relative : bool or None
        Also give ``removal_rate_relative``: the removal rate over that of the reference case
        (:func:`reference_config`: LEP model, d = 100 nm, sigma = reference_roughness (15 um in the paper preset), 4 psi, 60 rpm, other
        inputs equal), solved from the cold start once per process unless given. None (the
        default): only with the paper's removal law (:func:`wants_relative`), whose figures
        are in this ratio; the reference solve costs as much as the point itself.
    check_roots : bool
        Also scan the attack angle for other moment roots (about 13 load balances); adds
        the scalar ``moment_roots_found`` and ``result.root_scan``.
    problem : WaferProblem, optional
        The problem of ``config`` if already built (:func:`build_problem`), e.g. by a sweep
        that predicted its warm start from it; built here otherwise.
    reference_removal_rate : float, optional
        The removal rate of the reference case, when the caller has solved it (a study
        shares its own solve, see :class:`cmpsim.solver.points.PointCache`).
    **overrides
        Inputs to change, by name (``applied_pressure="3 psi"``).

    Returns
    -------
    cmpsim.results.result.Result

    Raises
    ------
    ValueError
        Bad input (names the parameter and its valid range).
    cmpsim.solver.equilibrium.EquilibriumError
        No equilibrium exists or none was found; the message says why.
    """
    from ..results.result import Result

    config = config or Config.default()
    if overrides:
        config = config.replace(**overrides)
    setup = physical_setup(config)
    if problem is None:
        problem = build_problem(config, setup)
    sol = problem.carrier.equilibrium(problem, solve_equilibrium, start=start, tol=config.tolerance, max_iter=config.max_iterations)
    scalars, polar, profiles = evaluate_outputs(config, setup, problem, sol)
    if relative is None:
        relative = wants_relative(config)
    if relative:
        if reference_removal_rate is None:
            ref = reference_config(config)
            same = ref.to_dict() == config.to_dict()  # the reference case itself: ratio 1
            reference_removal_rate = scalars["removal_rate_mean"] if same else _reference_removal_rate(ref)
        if reference_removal_rate > 0:
            scalars["removal_rate_relative"] = scalars["removal_rate_mean"] / reference_removal_rate
        else:  # the reference case removes nothing (e.g. the wafer hydroplanes there): no ratio exists
            import warnings

            warnings.warn(
                "removal_rate_relative is undefined (NaN, null in JSON): the reference case "
                "(LEP, 4 psi, 60 rpm, d = 100 nm, sigma = reference_roughness) removes nothing",
                RuntimeWarning,
                stacklevel=2,
            )
            scalars["removal_rate_relative"] = float("nan")
    scan = None
    if check_roots:
        scan = scan_moment_roots(problem, sol)
        scalars["moment_roots_found"] = len(scan.roots)
    result = Result(config=config, scalars=scalars, polar=polar, grid=setup.grid, problem=problem, solution=sol, profiles=profiles)
    result.root_scan = scan
    return result
