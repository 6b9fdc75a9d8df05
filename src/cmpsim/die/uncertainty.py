"""Hotspots with their uncertainty: the fit's covariance carried through a die run (docs/calibrate-die.md).

A calibration of the die model (:func:`cmpsim.calibration.die.calibrate_die`) leaves its constants
theta (planarization length, contact height, ...) with a covariance Sigma of z = ln theta.
:class:`DieUncertainty` holds them; ``simulate(..., uncertainty=...)`` then gives every window
the standard deviation of each quantity with a limit, and every hotspot

* ``interval`` [low, high] (m): the 95 % interval value -+ 1.96 sigma, and
* ``probability``: the probability that the quantity exceeds its limit in magnitude,
  P(|X| > limit) = Phi((v - limit)/sigma) + Phi((-limit - v)/sigma), X ~ N(v, sigma^2)  (U2).

**Linearisation, not sampling.** sigma^2 = g^T Sigma g (U1), with the gradient g_k = dF/dz_k of
every window's quantity F by central differences of step delta_k = max(sigma_k, 10^-3) in z_k
(a secant over one standard error: it follows the model's curvature over the range the
interval covers, where a tangent would not). Why: every window of the die costs one evolution
per evaluation, so 2p evolutions (p free constants, 2-6) give sigma for every window of a chip at
once, where a sample of the covariance needs hundreds of evolutions for a stable tail
probability of the windows near their limit; the die outputs are smooth in the constants except
at the events (a field clearing, a step reaching the contact height), where a linearisation
and a sample both describe a distribution that is not normal. Checked against a sample of 400
draws of the covariance in ``tests/test_calibrate_die.py``.

A run without an uncertainty keeps today's hotspots (no ``interval`` nor ``probability`` key).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

__all__ = ["DieUncertainty", "exceedance_probability", "window_sigma", "perturbations", "sigma_from_differences"]


@dataclass(frozen=True)
class DieUncertainty:
    """Fitted die constants (``names``, SI ``values``) and the covariance of their logarithms (p x p)."""

    names: tuple
    values: tuple
    covariance: np.ndarray

    def __post_init__(self) -> None:
        from .process import DIE_PARAMETERS

        valid = ("planarization_length",) + tuple(DIE_PARAMETERS)
        cov = np.asarray(self.covariance, dtype=float)
        p = len(self.names)
        if len(self.values) != p or cov.shape != (p, p):
            raise ValueError(f"DieUncertainty: {p} names, {len(self.values)} values and a covariance of shape {cov.shape} do not match")
        for n, v in zip(self.names, self.values):
            if n not in valid:
                raise ValueError(f"DieUncertainty: unknown die constant {n!r}; valid: {', '.join(valid)}")
            if not (math.isfinite(v) and v > 0):
                raise ValueError(f"DieUncertainty: {n} = {v!r} must be > 0")
        scale = max(1.0, float(np.abs(cov).max())) if np.all(np.isfinite(cov)) else math.nan
        if not (math.isfinite(scale) and np.allclose(cov, cov.T, rtol=1e-9, atol=1e-12 * scale)
                and not np.any(np.linalg.eigvalsh(0.5 * (cov + cov.T)) < -1e-12 * scale)):
            raise ValueError("DieUncertainty: the covariance must be finite, symmetric and positive semi-definite")
        object.__setattr__(self, "covariance", cov)

    @property
    def stderr_log(self) -> np.ndarray:
        return np.sqrt(np.clip(np.diag(self.covariance), 0.0, None))

    def to_dict(self) -> dict:
        return {"names": list(self.names), "values": list(self.values), "covariance_log": self.covariance.tolist(),
                "method": "linearisation (central differences over one standard error)"}

    @classmethod
    def from_dict(cls, d: dict) -> "DieUncertainty":
        return cls(tuple(d["names"]), tuple(float(v) for v in d["values"]), np.asarray(d["covariance_log"], dtype=float))


def exceedance_probability(value, sigma, limit):
    """P(|X| > limit) for X ~ N(value, sigma^2) (eq. U2); sigma = 0: 1 where |value| > limit, else 0."""
    from scipy.special import ndtr

    v, s, lim = np.broadcast_arrays(*(np.asarray(a, dtype=float) for a in (value, sigma, limit)))
    with np.errstate(divide="ignore", invalid="ignore"):
        p = ndtr((v - lim) / s) + ndtr((-lim - v) / s)
    return np.clip(np.where(s > 0, p, (np.abs(v) > lim).astype(float)), 0.0, 1.0)


def perturbations(uncertainty: DieUncertainty) -> list[tuple[dict, dict, float]]:
    """The central differences of eq. U1: per constant k, (values with theta_k x exp(+d), values with
    theta_k x exp(-d), d), d = max(sigma_k, 1e-3) in ln theta; values: name -> SI of every constant."""
    names = list(uncertainty.names)
    base = dict(zip(names, uncertainty.values))
    se = uncertainty.stderr_log
    out = []
    for k, n in enumerate(names):
        d = max(float(se[k]), 1e-3)
        out.append(({**base, n: base[n] * math.exp(d)}, {**base, n: base[n] * math.exp(-d)}, d))
    return out


def sigma_from_differences(pairs, uncertainty: DieUncertainty) -> dict:
    """sigma (m) of every field (eq. U1) from ``pairs`` [(fields up, fields down, d), ...] in the order of
    :func:`perturbations` (fields: kind -> array). A field undefined (NaN) on a side counts as 0 there."""
    grads = [{kind: (np.nan_to_num(up[kind]) - np.nan_to_num(dn[kind])) / (2 * d) for kind in up} for up, dn, d in pairs]
    out = {}
    kinds = grads[0].keys() if grads else []
    for kind in kinds:
        g = np.stack([gr[kind] for gr in grads], axis=-1)  # (..., p)
        var = np.einsum("...i,ij,...j->...", g, uncertainty.covariance, g)
        out[kind] = np.sqrt(np.clip(var, 0.0, None))
    return out


def window_sigma(evaluate, uncertainty: DieUncertainty) -> dict:
    """sigma (m) of every field that ``evaluate(values) -> {kind: (ny, nx) array}`` returns (eq. U1).

    ``values`` is a dict name -> SI value of the constants of ``uncertainty``.
    """
    return sigma_from_differences([(evaluate(up), evaluate(dn), d) for up, dn, d in perturbations(uncertainty)], uncertainty)
