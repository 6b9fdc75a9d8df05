"""Tools for the tests and benchmarks of cmpsim: reference solutions and synthetic data.

* :mod:`cmpsim.testing.references`: independent evaluations (mpmath, printed equations,
  closed forms) that the kernels are tested and benchmarked against; needs mpmath.
* :func:`synthetic_dataset`: a data file made by the model itself with known inputs.

Nothing in cmpsim imports this package.
"""

from __future__ import annotations

from .synthetic import synthetic_dataset

__all__ = ["synthetic_dataset"]
