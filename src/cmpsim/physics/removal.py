"""Shear stress on the wafer and the removal laws.

Two removal laws (``removal_law``): the paper's Runnels–Eyman law RR = K sigma_n tau, and
the shear-power law RR = k_s (mu p_c + chi tau_f) |u_pad - u_wafer| (the rate follows the
frictional power delivered to the wafer surface; Borucki et al., ECS J. Solid State Sci.
Technol. 12, 044004 (2023), doi 10.1149/2162-8777/accaa6), which reduces to Preston's law
k_s mu P U in full contact. Pure vectorised kernels (SI units). See ``docs/model.md``,
section "Removal rate".
"""

from __future__ import annotations

import numpy as np

__all__ = ["slurry_shear_stress", "newtonian_shear_stress", "viscous_shear_stress", "contact_shear_stress", "removal_rate", "shear_power_removal_rate", "REMOVAL_LAWS"]

#: Removal laws: the paper's (Runnels–Eyman), the shear-power law and the abrasive law (cmpsim.physics.abrasion).
REMOVAL_LAWS = ("paper", "shear_power", "abrasive")


def slurry_shear_stress(p_abs, grad_p, h, du, grain, *, phi_fs, phi_fp):
    """Average shear stress of the grain flow on the wafer (Patir–Cheng form, eq. 14–15), Pa.

    :func:`viscous_shear_stress` with the Haff viscosity eta = (a/t) p d / v (eq. 1) of the
    local absolute granular pressure p, given by ``grain`` (a
    :class:`cmpsim.physics.grainflow.GrainFlow`: ``grain.viscosity(p)``).

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
    grain : GrainFlow
        The slurry's Haff constants (d, t/a, v).
    phi_fs, phi_fp : array
        Shear-stress factors (eq. 14, 15), dimensionless (keywords).

    Returns
    -------
    (tau_x, tau_y) : tuple of arrays, Pa (the drag of the slurry on the wafer).
    """
    return viscous_shear_stress(grain.viscosity(p_abs), grad_p, h, du, phi_fs, phi_fp)


def viscous_shear_stress(eta, grad_p, h, du, phi_fs, phi_fp):
    """Patir–Cheng average shear stress on the wafer, eta du/h (1 + Phi_fs) - Phi_fp (h/2) grad p, Pa.

    ``eta`` is the viscosity of the Couette term (Pa s, scalar or array), ``grad_p`` (Pa/m),
    ``h`` (m), ``du`` = u_pad - u_wafer (m/s), ``phi_fs``, ``phi_fp`` the shear-stress factors
    (eq. 14-15). Returns (tau_x, tau_y).
    """
    couette = eta / h * (1.0 + phi_fs)
    half = 0.5 * phi_fp * h
    return couette * du[0] - half * grad_p[0], couette * du[1] - half * grad_p[1]


def newtonian_shear_stress(grad_p, h, du, viscosity, phi_fs, phi_fp, fill_fraction=1.0):
    """Average shear stress of the Newtonian slurry on the wafer (Patir & Cheng 1979), Pa.

    tau = theta eta du / h (1 + Phi_fs) - Phi_fp (h/2) grad p. In a JFO-cavitated region the
    gap holds liquid streamers over a share theta (``fill_fraction``) of its width and gas
    elsewhere, which carries no shear: the Couette shear is weighted by theta (the pressure
    gradient vanishes there). theta = 1 on the full film and without cavitation.

    Parameters
    ----------
    grad_p : tuple of arrays
        Gradient of the gauge pressure acting on the wafer, Pa/m.
    h : array
        Film thickness, m.
    du : tuple of arrays
        u_pad - u_wafer, m/s.
    viscosity : float
        eta, Pa s.
    phi_fs, phi_fp : array
        Shear-stress factors (eq. 14-15 at f = 3), dimensionless.
    fill_fraction : float or array
        theta, in (0, 1].

    Returns
    -------
    (tau_x, tau_y) : tuple of arrays, Pa.
    """
    return viscous_shear_stress(viscosity * np.asarray(fill_fraction, dtype=float), grad_p, h, du, phi_fs, phi_fp)


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


def shear_power_removal_rate(contact_pressure, fluid_shear_stress, relative_speed, coefficient, friction_coefficient, fluid_shear_weight):
    """Shear-power removal rate RR = k_s (mu p_c + chi |tau_f|) |du|, m/s.

    The removal follows the shear power delivered to the wafer surface per unit area: the
    summit friction mu p_c and a share chi of the slurry shear |tau_f|, each times the local
    sliding speed |du| (Borucki et al., ECS J. Solid State Sci. Technol. 12, 044004 (2023),
    doi 10.1149/2162-8777/accaa6). In full contact (p_c = P, tau_f = 0) it is Preston's law
    RR = k_s mu P U (Preston, J. Soc. Glass Technol. 11, 214 (1927)).

    Parameters
    ----------
    contact_pressure : array
        Nominal pad-summit contact pressure p_c on the wafer, Pa.
    fluid_shear_stress : array or tuple of arrays
        Slurry shear stress on the wafer tau_f, Pa (a magnitude, or its (x, y) components).
    relative_speed : array
        Local sliding speed |u_pad - u_wafer|, m/s.
    coefficient : float
        k_s, 1/Pa (> 0): the scale of the law.
    friction_coefficient : float
        mu, dimensionless.
    fluid_shear_weight : float
        chi in [0, 1]: share of the slurry's shear power that removes material.
    """
    if isinstance(fluid_shear_stress, tuple):
        fluid_shear_stress = np.hypot(fluid_shear_stress[0], fluid_shear_stress[1])
    power = friction_coefficient * np.asarray(contact_pressure) + fluid_shear_weight * np.abs(fluid_shear_stress)
    return coefficient * power * np.asarray(relative_speed)
