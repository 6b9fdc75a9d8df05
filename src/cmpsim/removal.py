"""Shear stress on the wafer and the Runnels–Eyman removal rate RR = K sigma_n tau.

Pure vectorised kernels (SI units). See ``docs/model.md``, section "Removal rate".
"""

from __future__ import annotations

import numpy as np

__all__ = ["slurry_shear_stress", "contact_shear_stress", "removal_rate"]


def slurry_shear_stress(p_abs, grad_p, h, du, particle_diameter, fluctuation_velocity, t_over_a, phi_fs, phi_fp):
    """Average shear stress of the grain flow on the wafer (Patir–Cheng form, eq. 14–15), Pa.

    tau = eta du / h (1 + Phi_fs) - Phi_fp (h/2) grad p, with the Haff viscosity
    eta = (a/t) p d / v (eq. 1) of the local absolute granular pressure p.

    Parameters
    ----------
    p_abs : array
        Absolute granular pressure p, Pa.
    grad_p : tuple of arrays
        (dp/dx, dp/dy), Pa/m.
    h : array
        Film thickness, m.
    du : tuple of arrays
        Relative velocity u_pad - u_wafer, m/s.
    particle_diameter, fluctuation_velocity, t_over_a : float
        d (m), v (m/s), t/a (-).
    phi_fs, phi_fp : array
        Shear-stress factors (eq. 14, 15), dimensionless.

    Returns
    -------
    (tau_x, tau_y) : tuple of arrays, Pa (the drag of the slurry on the wafer).
    """
    eta = np.asarray(p_abs) * particle_diameter / (t_over_a * fluctuation_velocity)
    couette = eta / h * (1.0 + phi_fs)
    half = 0.5 * phi_fp * h
    return couette * du[0] - half * grad_p[0], couette * du[1] - half * grad_p[1]


def contact_shear_stress(p_contact, du, friction_coefficient):
    """Coulomb shear of the pad asperities on the wafer, mu p_c along u_pad - u_wafer, Pa."""
    speed = np.hypot(du[0], du[1])
    with np.errstate(invalid="ignore", divide="ignore"):
        ex = np.where(speed > 0, du[0] / speed, 0.0)
        ey = np.where(speed > 0, du[1] / speed, 0.0)
    tau = friction_coefficient * np.asarray(p_contact)
    return tau * ex, tau * ey


def removal_rate(normal_stress, shear_stress, preston_coefficient):
    """Runnels–Eyman removal rate RR = K sigma_n |tau|, m/s.

    ``normal_stress`` sigma_n in Pa, ``shear_stress`` as (tau_x, tau_y) in Pa,
    ``preston_coefficient`` K in m/(s Pa^2).
    """
    tau = np.hypot(shear_stress[0], shear_stress[1])
    return preston_coefficient * np.asarray(normal_stress) * tau
