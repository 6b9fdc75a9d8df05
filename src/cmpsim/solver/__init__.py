"""Floor 7, the driver that calls the model plug-ins: the set-up of a problem from a
configuration, the wafer problem, load balance and Newton on the wafer position (equilibrium),
the post-processing into a result, :func:`cmpsim.solver.model.solve` (one Config in, one Result
out), and the runner every study shares (:mod:`cmpsim.solver.points`).

May import: :mod:`cmpsim.results`, :mod:`cmpsim.inputs`, :mod:`cmpsim.models` and every floor
below them, and the utilities.
"""
