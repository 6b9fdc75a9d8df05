"""Tools for the tests and benchmarks of cmpsim: reference solutions and synthetic data.

* :mod:`cmpsim.testing.references`: independent evaluations (mpmath, printed equations)
  that the kernels are tested and benchmarked against; needs mpmath.
* :mod:`cmpsim.testing.lubrication`: closed-form and semi-analytic solutions of Reynolds'
  equation (plane slider, cavitated sliders) and the 1-D strip problem of the wafer kernels.
* :func:`synthetic_dataset`: a data file made by the model itself with known inputs.

Nothing in cmpsim imports this package.
"""

from __future__ import annotations

from .synthetic import synthetic_dataset

__all__ = ["synthetic_dataset"]
