"""The incoming film thickness of the wafers of a lot (issue 32).

By default each wafer's profile varies from the nominal as deposition does: its mean by a random
relative spread (2 % at one sigma) and its shape by a random tilt of the profile from the centre
to the edge (1 % at one sigma, t(r) = m (1 + s (r/R - 2/3)), which keeps the wafer-area mean m),
drawn from ``numpy.random.default_rng(seed)``, so that a lot is reproducible with ``--seed``.
Given profiles replace the draw.
"""

from __future__ import annotations

import numpy as np

__all__ = ["incoming_profiles"]


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
