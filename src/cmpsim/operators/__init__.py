"""Floor 3, the coupled operators the model plug-ins use: the sparse Reynolds and cavitation
systems, the pad-coupled Newton matrix, the film coupled with the pad deflection (and with the
wafer position in one Newton iteration), its linear response, the solver state, and the
membrane head's bending.

May import: :mod:`cmpsim.numerics`, :mod:`cmpsim.physics` and the utilities.
"""
