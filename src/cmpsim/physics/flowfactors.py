"""Average-flow (Patir–Cheng / Tripp) flow factors for grain flow over rough surfaces.

Pure vectorised kernels of the paper's eq. 8–17. Surface 1 is the pad, surface 2 the
wafer; roughness angles are measured from the sliding direction x, in radians.

The pressure flow-factor tensor of eq. 8–10 is a perturbation result, valid for
(sigma/h)^2 small. For isotropic pad roughness it reads 1 + (sigma/h)^2 (g - f^2/2), which
turns non-positive for h/sigma below about 1.22. :func:`regularize_pressure_tensor` is the
one gate through which the tensor reaches a solver: it continues each eigenvalue below a
matching value by a C1 power law in h (:func:`continue_pressure_eigenvalues`), projects the
tensor onto symmetric matrices with every eigenvalue >= a floor and reports where it did
either (``docs/model.md``, section "Flow-factor validity").
"""

from __future__ import annotations

from dataclasses import dataclass
from functools import lru_cache

import numpy as np

__all__ = [
    "RoughnessGeometry",
    "orientation_coefficients",
    "pressure_flow_factors",
    "shear_flow_factors",
    "shear_stress_factors",
    "regularize_pressure_tensor",
    "continue_pressure_eigenvalues",
    "perturbation_validity_limit",
]


@dataclass(frozen=True)
class RoughnessGeometry:
    """Statistical roughness of the two surfaces (paper eq. 8–17 notation).

    Attributes
    ----------
    sigma_pad, sigma_wafer : float
        Standard deviations sigma_1 (pad) and sigma_2 (wafer) of the surface heights, m.
        At least one must be > 0; the combined sigma = sqrt(sigma_1^2 + sigma_2^2).
    gamma_pad, gamma_wafer : float
        Peklenik numbers gamma_i > 0 (1 = isotropic), dimensionless.
    theta_pad, theta_wafer : float
        Roughness orientation angles theta_i from the sliding direction, rad.
    """

    sigma_pad: float
    sigma_wafer: float = 0.0
    gamma_pad: float = 1.0
    gamma_wafer: float = 1.0
    theta_pad: float = 0.0
    theta_wafer: float = 0.0

    def __post_init__(self) -> None:
        for name in ("sigma_pad", "sigma_wafer"):
            v = getattr(self, name)
            if not np.isfinite(v) or v < 0:
                raise ValueError(f"{name} must be finite and >= 0 m (valid range: [0, inf)); got {v!r}")
        if self.sigma == 0:
            raise ValueError("sigma_pad and sigma_wafer are both zero: the combined roughness must be > 0 m")
        for name in ("gamma_pad", "gamma_wafer"):
            v = getattr(self, name)
            if not np.isfinite(v) or v <= 0:
                raise ValueError(f"{name} must be finite and > 0 (valid range: (0, inf)); got {v!r}")
        for name in ("theta_pad", "theta_wafer"):
            v = getattr(self, name)
            if not np.isfinite(v):
                raise ValueError(f"{name} must be a finite angle in rad; got {v!r}")

    @property
    def sigma(self) -> float:
        """Combined roughness sigma = sqrt(sigma_1^2 + sigma_2^2), m."""
        return float(np.hypot(self.sigma_pad, self.sigma_wafer))

    def rotated(self) -> "RoughnessGeometry":
        """The same surfaces with both orientation angles replaced by 90 deg - theta_i (eq. 10, 13)."""
        return RoughnessGeometry(
            self.sigma_pad,
            self.sigma_wafer,
            self.gamma_pad,
            self.gamma_wafer,
            0.5 * np.pi - self.theta_pad,
            0.5 * np.pi - self.theta_wafer,
        )

    def weighted_orientation(self) -> tuple[float, float, float, float]:
        """Weights (sigma_i/sigma)^2 times the orientation coefficients.

        Returns ``(omega_1, omega_2, psi_1, psi_2)`` already multiplied by (sigma_i/sigma)^2.
        """
        return _weighted_orientation(
            self.sigma_pad, self.sigma_wafer, self.gamma_pad, self.gamma_wafer, self.theta_pad, self.theta_wafer
        )


@lru_cache(maxsize=256)
def _weighted_orientation(sigma_1, sigma_2, gamma_1, gamma_2, theta_1, theta_2) -> tuple[float, float, float, float]:
    s2 = sigma_1**2 + sigma_2**2
    w1, w2 = sigma_1**2 / s2, sigma_2**2 / s2
    om1, ps1 = orientation_coefficients(theta_1, gamma_1)
    om2, ps2 = orientation_coefficients(theta_2, gamma_2)
    return float(w1 * om1), float(w2 * om2), float(w1 * ps1), float(w2 * ps2)


def orientation_coefficients(theta, gamma):
    """Orientation coefficients Omega_i and Psi_i of one surface (eq. 16, 17), dimensionless.

    ``theta`` is the roughness orientation angle (rad), ``gamma`` the Peklenik number (> 0).
    Returns ``(Omega, Psi)`` with Omega = cos^2 / (gamma+1) + sin^2 gamma / (gamma+1) and
    Psi = sin cos (1 - gamma) / (gamma + 1).
    """
    theta = np.asarray(theta, dtype=float)
    gamma = np.asarray(gamma, dtype=float)
    c, s = np.cos(theta), np.sin(theta)
    omega = (c * c + s * s * gamma) / (gamma + 1.0)
    psi = s * c * (1.0 - gamma) / (gamma + 1.0)
    return omega, psi


def _ratio(h_over_sigma) -> np.ndarray:
    hs = np.asarray(h_over_sigma, dtype=float)
    if not np.all(np.isfinite(hs)) or np.any(hs <= 0):
        raise ValueError("h_over_sigma must be finite and > 0 (valid range: (0, inf))")
    return 1.0 / hs


def _phi_p_xx(e, f, g, rough: RoughnessGeometry):
    om1, om2, _, _ = rough.weighted_orientation()
    return 1.0 + e * e * (g - f * f * (om2 + om1))


def pressure_flow_factors(h_over_sigma, f, g, rough: RoughnessGeometry):
    """Pressure flow-factor tensor (eq. 8, 9, 10), as printed (perturbation form).

    Parameters
    ----------
    h_over_sigma : array_like
        Film thickness ratio H_s = h/sigma (> 0), dimensionless.
    f, g : array_like
        Grain-size coefficients from :func:`cmpsim.physics.grainflow.grain_coefficients`.
    rough : RoughnessGeometry

    Returns
    -------
    phi_xx, phi_xy, phi_yy : numpy.ndarray
        Components of the symmetric tensor, dimensionless. Not guaranteed positive: pass
        them through :func:`regularize_pressure_tensor` before a solver sees them.
    """
    e = _ratio(h_over_sigma)
    f = np.asarray(f, dtype=float)
    g = np.asarray(g, dtype=float)
    _, _, ps1, ps2 = rough.weighted_orientation()
    phi_xx = _phi_p_xx(e, f, g, rough)
    phi_yy = _phi_p_xx(e, f, g, rough.rotated())
    phi_xy = -e * e * f * f * (ps2 + ps1)
    return np.broadcast_arrays(phi_xx, phi_xy, phi_yy)


def shear_flow_factors(h_over_sigma, f, rough: RoughnessGeometry):
    """Shear flow-factor tensor (eq. 11, 12, 13), dimensionless.

    Enters the Reynolds equation as the flux (sigma/2) Phi^s . (u_pad - u_wafer); positive
    Phi^s_xx means the rough pad drags extra slurry along with it.
    """
    e = _ratio(h_over_sigma)
    f = np.asarray(f, dtype=float)
    om1, om2, ps1, ps2 = rough.weighted_orientation()
    r_om1, r_om2, _, _ = rough.rotated().weighted_orientation()
    phis_xx = -e * f * (om2 - om1)
    phis_xy = -e * f * (ps2 - ps1)
    phis_yy = -e * f * (r_om2 - r_om1)
    return np.broadcast_arrays(phis_xx, phis_xy, phis_yy)


def shear_stress_factors(h_over_sigma, f, rough: RoughnessGeometry):
    """Shear-stress factors Phi_fs (eq. 14) and Phi_fp (eq. 15), as printed, dimensionless.

    For isotropic roughness (gamma = 1) Psi_i = 0, so Phi_fs = 0 and Phi_fp = 1.
    """
    e = _ratio(h_over_sigma)
    f = np.asarray(f, dtype=float)
    _, _, ps1, ps2 = rough.weighted_orientation()
    phi_fs = -3.0 * e * e * (ps2 - ps1)
    phi_fp = 1.0 - e * e * f * (ps2 + ps1)
    return np.broadcast_arrays(phi_fs, phi_fp)


def perturbation_validity_limit(f, g, rough: RoughnessGeometry, floor: float = 0.0) -> np.ndarray:
    """Smallest h/sigma at which Phi^p_xx and Phi^p_yy of eq. 8/10 are both >= ``floor``.

    Returns 0 where the correction term is non-negative (eq. 8 is then positive for any h).
    """
    f = np.asarray(f, dtype=float)
    g = np.asarray(g, dtype=float)
    out = np.zeros(np.broadcast(f, g).shape)
    for r in (rough, rough.rotated()):
        om1, om2, _, _ = r.weighted_orientation()
        c = g - f * f * (om1 + om2)
        with np.errstate(invalid="ignore", divide="ignore"):
            lim = np.where(c < 0, np.sqrt(-c / max(1.0 - floor, 1e-300)), 0.0)
        out = np.maximum(out, lim)
    return out


def continue_pressure_eigenvalues(lam, start: float):
    """Eigenvalues of the pressure flow-factor tensor continued below ``start``, dimensionless.

    Eq. 8-10 give each eigenvalue as lam = 1 + beta (sigma/h)^2 (beta < 0 where it falls with the
    film). Below lam_c = ``start`` (reached at h_c) it is continued by the power law
    lam_c (h / h_c)^n that joins it with equal value and slope, n = 2 (1 - lam_c) / lam_c;
    eliminating h, in terms of the eigenvalue of eq. 8 itself,

        lam -> lam                                             for lam >= lam_c,
        lam -> lam_c ((1 - lam_c) / (1 - lam))^((1 - lam_c) / lam_c)   for lam < lam_c,

    continuous with its first derivative (1 at lam_c), increasing, positive, and tending to 0
    only as h -> 0 (lam -> -inf): the film's pressure flow vanishes at the mean plane, the
    percolation threshold of isotropic roughness, where eq. 8 vanishes at h = sqrt(-beta) sigma
    (1.22 sigma for isotropic roughness at x -> 0) and turns negative. ``start`` <= 0 returns lam
    unchanged. ``docs/model.md``, section 5 ("Flow-factor validity"), gives the reasons.
    """
    lam = np.asarray(lam, dtype=float)
    start = float(start)
    if not (np.isfinite(start) and start < 1.0):
        raise ValueError(f"flow_factor_continuation must be finite and in [0, 1) (valid range: [0, 1)); got {start!r}")
    if start <= 0.0:
        return lam.copy()
    n_half = (1.0 - start) / start
    below = lam < start
    with np.errstate(divide="ignore", over="ignore", invalid="ignore"):
        low = start * ((1.0 - start) / (1.0 - np.where(below, lam, 0.0))) ** n_half
    return np.where(below, low, lam)


def regularize_pressure_tensor(phi_xx, phi_xy, phi_yy, floor: float, continuation: float = 0.0):
    """Project a 2x2 symmetric tensor field onto eigenvalues >= ``floor`` (> 0).

    The tensor keeps its eigenvectors; each eigenvalue below ``continuation`` is continued by
    :func:`continue_pressure_eigenvalues` (C1 in the film), then each eigenvalue below ``floor``
    is raised to it. With ``continuation = 0`` only the floor acts (as before
    ``flow_factor_continuation`` existed, and in the paper preset: a kink where an eigenvalue
    meets the floor). This is the documented behaviour outside the validity of the perturbation
    expansion of eq. 8-10 (``docs/model.md``, section 5): no non-positive diffusion coefficient
    reaches the Reynolds solver.

    Returns
    -------
    phi_xx, phi_xy, phi_yy : numpy.ndarray
        The regularised components.
    floored : numpy.ndarray of bool
        True where an eigenvalue was changed (continued or raised to the floor).
    """
    if not (np.isfinite(floor) and floor > 0):
        raise ValueError(f"floor must be finite and > 0 (valid range: (0, inf)); got {floor!r}")
    a, b, c = np.broadcast_arrays(
        np.asarray(phi_xx, float), np.asarray(phi_xy, float), np.asarray(phi_yy, float)
    )
    mean = 0.5 * (a + c)
    rad = np.hypot(0.5 * (a - c), b)
    lam1, lam2 = mean + rad, mean - rad  # lam1 >= lam2
    floored = lam2 < max(floor, continuation)
    if not np.any(floored):
        return a.copy(), b.copy(), c.copy(), floored
    if continuation > 0.0:
        lam1, lam2 = continue_pressure_eigenvalues(lam1, continuation), continue_pressure_eigenvalues(lam2, continuation)
    l1 = np.maximum(lam1, floor)
    l2 = np.maximum(lam2, floor)
    # eigenvector of lam1: angle alpha with tan(2 alpha) = 2b / (a - c)
    alpha = 0.5 * np.arctan2(2.0 * b, a - c)
    ca, sa = np.cos(alpha), np.sin(alpha)
    na = l1 * ca * ca + l2 * sa * sa
    nc = l1 * sa * sa + l2 * ca * ca
    nb = (l1 - l2) * sa * ca
    return (
        np.where(floored, na, a),
        np.where(floored, nb, b),
        np.where(floored, nc, c),
        floored,
    )
