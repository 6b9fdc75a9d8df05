"""Floor 8 (studies), the polishing head's studies: the response of the removal rate to each
zone's pressure, the tuning of the zone pressures to a flat profile, and the head's sweeps.

May import: :mod:`cmpsim.solver` and every floor below it, its sibling studies on the same
floor, and the utilities.
"""
