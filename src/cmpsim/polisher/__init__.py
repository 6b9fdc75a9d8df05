"""The polisher over time (issue 32): recipes of steps with an end point, the pad's temperature and
life carried through the steps and from wafer to wafer, and the run-to-run control of a lot.

Lives on the studies floor beside :mod:`cmpsim.head`. May import: :mod:`cmpsim.head`, the driver
(:mod:`cmpsim.solver`) and every floor below it, and the utilities.
"""
