"""The incoming film thickness of the wafers of a lot (issue 32).

By default each wafer's profile varies from the nominal as deposition does: its mean by a random
relative spread (2 % at one sigma) and its shape by a random tilt of the profile from the centre
to the edge (1 % at one sigma, t(r) = m (1 + s (r/R - 2/3)), which keeps the wafer-area mean m),
drawn from ``numpy.random.default_rng(seed)``, so that a lot is reproducible with ``--seed``.
Given profiles replace the draw.

The lot's controller sees the wafers through metrology: with a ``metrology_noise`` sigma each
radius of the incoming and the post-polish profile is measured with an independent normal error
(:func:`measurement_errors`, drawn once per lot from the lot's seed, in a stream of its own).
"""

from __future__ import annotations

import numpy as np

__all__ = ["incoming_profiles", "measurement_errors"]


def incoming_profiles(count: int, radius, nominal: float, spread: float = 0.02, tilt: float = 0.01, seed: int | None = None) -> np.ndarray:
    """(count, radii) incoming thickness profiles (m) about the ``nominal`` mean thickness (m).

    ``spread`` and ``tilt`` are relative standard deviations of the mean and of the centre-to-edge
    tilt; ``radius`` (m) the radii of the profile, the last being the wafer's edge.
    """
    if count < 1:
        raise ValueError(f"the lot needs at least 1 wafer; got {count!r}")
    if not (np.isfinite(nominal) and nominal > 0):
        raise ValueError(f"the incoming thickness must be > 0 m; got {nominal!r}")
    if spread < 0 or tilt < 0:
        raise ValueError(f"spread and tilt are standard deviations >= 0; got {spread!r}, {tilt!r}")
    r = np.asarray(radius, dtype=float)
    rng = np.random.default_rng(seed)
    mean = nominal * (1.0 + spread * rng.standard_normal(count))
    slope = tilt * rng.standard_normal(count)
    return mean[:, None] * (1.0 + slope[:, None] * (r[None, :] / r.max() - 2.0 / 3.0))


def measurement_errors(count: int, rings: int, sigma: float, seed: int | None = None) -> tuple[np.ndarray, np.ndarray]:
    """The metrology's errors (m) on the ``count`` wafers' incoming and post-polish profiles at ``rings``
    radii: two (count, rings) arrays of independent normal errors of standard deviation ``sigma`` (m),
    from ``numpy.random.default_rng((seed, 1))`` (a stream apart from :func:`incoming_profiles`', so that
    the same seed gives the same wafers with and without noise; fresh entropy without a seed)."""
    if not (np.isfinite(sigma) and sigma >= 0):
        raise ValueError(f"metrology_noise must be a standard deviation >= 0 m; got {sigma!r}")
    rng = np.random.default_rng(None if seed is None else (seed, 1))
    return sigma * rng.standard_normal((count, rings)), sigma * rng.standard_normal((count, rings))
