"""Floor 2, the numerics: the polar grid and its face operators, the finite-volume assembly of
the Reynolds operator, the guarded sparse LU, the Krylov solver, the layered pad on the grid and
the wafer as a plate.

May import: :mod:`cmpsim.physics` and the utilities (:mod:`cmpsim.io`, :mod:`cmpsim.tables`,
:mod:`cmpsim._version`).
"""
