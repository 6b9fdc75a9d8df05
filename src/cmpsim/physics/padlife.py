"""Pad life: glazing of the pad's summits while it polishes and their renewal by conditioning (issue 32).

Pure kernels, SI units. A reduced model of the summit-height density phi(z, t) of a
Greenwood–Williamson pad (summit density eta, radius R, Gaussian heights of std sigma truncated at
``cutoff`` sigma, as in cmpsim's contact model), in the class of the pad-wear models of Borucki
(J. Eng. Math. 43, 105 (2002)), Borucki, Witelski et al. (J. Eng. Math. 50, 1 (2004)) and Shi & Ring
(2010): summits in contact are worn down (dz/dt = -k_w p U) and the conditioner renews the
surface (a source of fresh summits and a sink of worn ones). The equations of those papers were not
available here (read in transcription only); the reduction below is derived for this module and
stated in ``docs/polisher.md`` ("Pad life"):

1. **Glazing front.** The pad's summits are soft and wear where they touch; the tallest touch first.
   After a worn volume W per unit pad area, the summits are cut flat at the *front* height z_f:
   every summit taller than z_f has lost its cap above z_f, which is the volume

       W = eta pi R sigma^2 J2(zeta_f),   J2(zeta) = int_zeta^c (x - zeta)^2 phi(x) dx / Phi(c)      (L1)

   (spherical caps, pi R w^2 for a cap of height w << R; zeta = z/sigma, phi and Phi the standard
   normal density and distribution, c the cutoff). J2 falls steeply with zeta, so equal increments of
   W move the front less and less: the Gaussian tail makes the glazing slow down like a logarithm.
2. **Wear and conditioning.** Archard's law for the pad, dW/dt = k_w P U (wear coefficient k_w, 1/Pa;
   nominal pressure P, sliding speed U), and the conditioner renewing the worn surface at the rate
   r_c (1/s; a share r_c dt of the worn volume is cut away and replaced by fresh texture):

       dW/dt = k_w P U - r_c W,   W(t) = W* + (W0 - W*) exp(-r_c t),   W* = k_w P U / r_c      (L2)

   exact over a step of constant P U (no time-step error). r_c = k_c F_d s_d for a disk of down
   force F_d (N) sweeping a share s_d of the pad track, with the rate constant k_c (1/(N s)).
3. **Summit constants of the worn pad** (relative to the fresh pad's), from the worn density: the
   Gaussian below the front plus the summits cut flat at it (an atom of mass Phi(c) - Phi(zeta_f)):
   the std sigma_s (closed form, :func:`worn_moments`), the summit density (unchanged: wear flattens
   summits, it does not remove them), the radius of the unworn summits (unchanged), the front
   (``cutoff``), and the flattened share of the pad area G = 2 pi eta R sigma J1(zeta_f)
   (J1(zeta) = int_zeta^c (x - zeta) phi dx / Phi(c); a cap cut at depth w has a flat of area 2 pi R w).
4. **Rate factor** (a calibrated proxy, not a mechanism): RR/RR_fresh = 1 / (1 + G / G_c). cmpsim's
   contact model puts the pad's summits in plastic contact at its default constants (A_r = P/H), so
   the Greenwood–Williamson real contact area does not change with glazing at all and cannot carry
   the measured rate decay; G_c is fitted to Jeong et al. (2024) and the model's time dependence is
   compared with Lawing (2004) as the validation.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, replace

import numpy as np
from scipy.special import ndtr

__all__ = [
    "GLAZING_CONSTANTS",
    "default_constants",
    "check_constants",
    "CONDITIONING",
    "FreshPad",
    "ConditionerDisk",
    "PadLifeState",
    "SummitConstants",
    "cap_volume",
    "flat_area",
    "front_height",
    "worn_moments",
    "summit_constants",
    "renewal_rate",
    "advance_pad_life",
    "condition_ex_situ",
    "rate_factor",
    "JEONG_2024",
    "LAWING_2004",
    "CALIBRATION",
]

#: The conditioning modes of a step.
CONDITIONING = ("none", "ex_situ", "in_situ")

_INV_SQRT_2PI = 1.0 / math.sqrt(2.0 * math.pi)


def _pdf(x):
    return _INV_SQRT_2PI * np.exp(-0.5 * np.asarray(x, dtype=float) ** 2)


@dataclass(frozen=True)
class FreshPad:
    """The fresh (freshly conditioned) pad: summit-height std ``sigma`` (m), summit density
    ``density`` eta (1/m^2), summit radius ``radius`` R (m), heights truncated at ``cutoff`` sigma,
    and the pad's Archard wear coefficient ``wear_coefficient`` k_w (1/Pa: worn volume per unit
    area and sliding distance per unit pressure). Defaults: cmpsim's default pad (5 um, 2e8 /m^2,
    7 um, 3 sigma; config.py and docs/model.md section 13) and k_w calibrated to Jeong et al. (2024);
    ``critical_glazed_area`` G_c of eq. L4 (0: the calibrated default; a lot's own from
    :func:`cmpsim.calibration.padlife.calibrate_padlife`)."""

    sigma: float = 5e-6
    density: float = 2.0e8
    radius: float = 7e-6
    cutoff: float = 3.0
    wear_coefficient: float = 0.0  # replaced by CALIBRATION below
    #: G_c of the rate proxy (eq. L4) for this pad; 0 = the calibrated CALIBRATION["critical_glazed_area"]
    critical_glazed_area: float = 0.0

    def __post_init__(self) -> None:
        for name in ("sigma", "density", "radius", "cutoff"):
            v = getattr(self, name)
            if not (np.isfinite(v) and v > 0):
                raise ValueError(f"FreshPad.{name} must be finite and > 0; got {v!r}")
        if not (np.isfinite(self.wear_coefficient) and self.wear_coefficient >= 0):
            raise ValueError(f"FreshPad.wear_coefficient must be finite and >= 0 1/Pa; got {self.wear_coefficient!r}")
        if not (np.isfinite(self.critical_glazed_area) and self.critical_glazed_area >= 0):
            raise ValueError(f"FreshPad.critical_glazed_area must be finite and >= 0; got {self.critical_glazed_area!r}")

    @property
    def critical_area(self) -> float:
        """G_c in effect for this pad (1, eq. L4): its own, or the calibrated default when 0."""
        return self.critical_glazed_area or float(CALIBRATION["critical_glazed_area"])

    @property
    def volume_scale(self) -> float:
        """eta pi R sigma^2, m: the worn volume per area that moves the front by about one sigma near the mean."""
        return self.density * math.pi * self.radius * self.sigma**2


@dataclass(frozen=True)
class ConditionerDisk:
    """A diamond conditioning disk: ``down_force`` F_d (N), ``sweep_duty`` s_d (share of the pad
    track the disk works per unit time, in [0, 1]), ``rate_constant`` k_c (1/(N s)): the renewal
    rate r_c = k_c F_d s_d (1/s). The linear dependence on the down force is an assumption (a
    Preston-like cut rate of the disk); the default k_c is calibrated to Jeong et al. (2024)'s
    recovery by one minute of conditioning at an assumed 5 lbf (22.2 N)."""

    down_force: float = 22.24
    sweep_duty: float = 1.0
    rate_constant: float = 0.0  # replaced by CALIBRATION below

    def __post_init__(self) -> None:
        if not (np.isfinite(self.down_force) and self.down_force >= 0):
            raise ValueError(f"ConditionerDisk.down_force must be finite and >= 0 N; got {self.down_force!r}")
        if not (0.0 <= self.sweep_duty <= 1.0):
            raise ValueError(f"ConditionerDisk.sweep_duty must be in [0, 1]; got {self.sweep_duty!r}")
        if not (np.isfinite(self.rate_constant) and self.rate_constant >= 0):
            raise ValueError(f"ConditionerDisk.rate_constant must be finite and >= 0 1/(N s); got {self.rate_constant!r}")


@dataclass(frozen=True)
class PadLifeState:
    """The pad's glazing state: ``worn_volume`` W (m^3 of summit caps worn per m^2 of pad, i.e. m;
    0 = fresh; array for a batch of pad radii), ``polish_time`` (s of polishing since the state was
    fresh), carried between steps and wafers."""

    worn_volume: np.ndarray | float = 0.0
    polish_time: float = 0.0


@dataclass(frozen=True)
class SummitConstants:
    """The worn pad's summit constants relative to the fresh pad's (``docs/polisher.md``, "Pad life"):
    ``sigma`` sigma_s/sigma_s,fresh, ``density`` eta/eta_fresh, ``radius`` R/R_fresh of the summits
    below the front, ``cutoff`` the front height zeta_f (in fresh sigma from the fresh mean plane),
    ``mean_shift`` the mean summit height's drop (fresh sigma), ``glazed_summits`` the share of summits
    cut flat, ``glazed_area`` G (share of the pad's nominal area that is flattened summit tops) and
    ``rate_factor`` RR/RR_fresh of the calibrated proxy."""

    sigma: np.ndarray
    density: np.ndarray
    radius: np.ndarray
    cutoff: np.ndarray
    mean_shift: np.ndarray
    glazed_summits: np.ndarray
    glazed_area: np.ndarray
    rate_factor: np.ndarray


def _j1(zeta, c):
    """int_zeta^c (x - zeta) phi(x) dx (not normalised), zeta <= c."""
    z = np.asarray(zeta, dtype=float)
    return _pdf(z) - _pdf(c) - z * (ndtr(c) - ndtr(z))


def _j2(zeta, c):
    """int_zeta^c (x - zeta)^2 phi(x) dx = (1 + zeta^2)(Phi(c) - Phi(zeta)) - (c - 2 zeta) phi(c) - zeta phi(zeta)."""
    z = np.asarray(zeta, dtype=float)
    return (1.0 + z**2) * (ndtr(c) - ndtr(z)) - (c - 2.0 * z) * _pdf(c) - z * _pdf(z)


def cap_volume(zeta, cutoff: float = 3.0):
    """Normalised worn volume J2(zeta) = int_zeta^c (x - zeta)^2 phi dx / Phi(c) above the front (eq. L1), dimensionless."""
    return _j2(zeta, cutoff) / ndtr(cutoff)


def flat_area(zeta, cutoff: float = 3.0):
    """Normalised flat area J1(zeta) = int_zeta^c (x - zeta) phi dx / Phi(c) of the summits cut at zeta, dimensionless."""
    return _j1(zeta, cutoff) / ndtr(cutoff)


def front_height(worn_volume, pad: FreshPad):
    """Front height zeta_f (fresh sigma) at which the worn volume W (m) equals the caps above it (eq. L1).

    Inverse of W = eta pi R sigma^2 J2(zeta_f) by bisection (J2 decreases monotonically; 80
    halvings, to 1e-15 sigma); zeta_f = cutoff for W = 0. Vectorised over W.
    """
    target = np.asarray(worn_volume, dtype=float) / pad.volume_scale
    if np.any(target < 0) or not np.all(np.isfinite(target)):
        raise ValueError("worn_volume must be finite and >= 0 m")
    if target.ndim == 0:  # one pad radius (a recipe's time step): the same bisection on scalars, ten times faster
        return np.asarray(_front_scalar(float(target), float(pad.cutoff)))
    lo = np.full(target.shape, -40.0)
    hi = np.full(target.shape, float(pad.cutoff))
    for _ in range(80):
        mid = 0.5 * (lo + hi)
        above = cap_volume(mid, pad.cutoff) > target
        lo = np.where(above, mid, lo)
        hi = np.where(above, hi, mid)
    return np.where(target == 0, float(pad.cutoff), 0.5 * (lo + hi))


def _front_scalar(target: float, c: float) -> float:
    """:func:`front_height` of one normalised volume W / (eta pi R sigma^2), by the same 80 halvings on floats."""
    if target == 0.0:
        return c
    def pdf(x: float) -> float:
        return _INV_SQRT_2PI * math.exp(-0.5 * x * x)

    def cdf(x: float) -> float:
        return 0.5 * math.erfc(-x / math.sqrt(2.0))

    nc, pc = cdf(c), pdf(c)
    lo, hi = -40.0, c
    for _ in range(80):
        z = 0.5 * (lo + hi)
        j2 = ((1.0 + z * z) * (nc - cdf(z)) - (c - 2.0 * z) * pc - z * pdf(z)) / nc
        if j2 > target:
            lo = z
        else:
            hi = z
    return 0.5 * (lo + hi)


def worn_moments(zeta_f, cutoff: float = 3.0):
    """Mean and std (fresh sigma) of the worn summit heights: the normal density below zeta_f plus
    the atom Phi(c) - Phi(zeta_f) of summits cut flat at zeta_f, all over Phi(c).

    M0 = Phi(zeta), M1 = -phi(zeta), M2 = Phi(zeta) - zeta phi(zeta) (the truncated normal's
    moments) plus the atom's m zeta and m zeta^2. Returns (mean, std).
    """
    z = np.asarray(zeta_f, dtype=float)
    nc = ndtr(cutoff)
    atom = (nc - ndtr(z)) / nc
    m1 = -_pdf(z) / nc + atom * z
    m2 = (ndtr(z) - z * _pdf(z)) / nc + atom * z**2
    return m1, np.sqrt(np.maximum(m2 - m1**2, 0.0))


def renewal_rate(conditioning: str, disk: ConditionerDisk | None = None) -> float:
    """Renewal rate r_c (1/s) of a polishing step: k_c F_d s_d in situ, 0 otherwise ("none";
    "ex_situ" conditions between wafers only, :func:`condition_ex_situ`)."""
    if conditioning not in CONDITIONING:
        raise ValueError(f"conditioning must be one of {CONDITIONING}; got {conditioning!r}")
    if conditioning != "in_situ":
        return 0.0
    d = disk if disk is not None else DEFAULT_DISK
    return d.rate_constant * d.down_force * d.sweep_duty


def _relax(w0, source, rate, dt):
    """W(dt) of dW/dt = source - rate W, exact: w0 exp(-r dt) + source dt (1 - exp(-r dt))/(r dt) (stable as r -> 0)."""
    x = rate * dt
    phi1 = 1.0 - x / 2.0 if x < 1e-8 else -math.expm1(-x) / x
    return w0 * math.exp(-x) + source * dt * phi1


def advance_pad_life(state: PadLifeState, pressure, sliding_speed, dt: float, conditioning: str = "none",
                     disk: ConditionerDisk | None = None, pad: FreshPad | None = None) -> PadLifeState:
    """Advance the glazing over ``dt`` s of polishing at nominal ``pressure`` P (Pa) and
    ``sliding_speed`` U (m/s) (scalars or arrays over pad radii), eq. L2, exact for P U constant
    over the step. ``conditioning`` "none" | "ex_situ" (no disk during the step: condition between
    wafers with :func:`condition_ex_situ`) | "in_situ" (the disk renews at r_c during the step)."""
    if not (np.isfinite(dt) and dt >= 0):
        raise ValueError(f"dt must be finite and >= 0 s; got {dt!r}")
    p = pad if pad is not None else DEFAULT_PAD
    P = np.asarray(pressure, dtype=float)
    U = np.asarray(sliding_speed, dtype=float)
    if np.any(P < 0) or np.any(U < 0):
        raise ValueError("pressure and sliding_speed must be >= 0")
    rate = renewal_rate(conditioning, disk)
    w = _relax(np.asarray(state.worn_volume, dtype=float), p.wear_coefficient * P * U, rate, dt)
    return PadLifeState(w, state.polish_time + dt)


def condition_ex_situ(state: PadLifeState, dt: float, disk: ConditionerDisk | None = None) -> PadLifeState:
    """Condition the idle pad for ``dt`` s between wafers: W -> W exp(-r_c dt), r_c = k_c F_d s_d (eq. L2 with P = 0)."""
    if not (np.isfinite(dt) and dt >= 0):
        raise ValueError(f"dt must be finite and >= 0 s; got {dt!r}")
    d = disk if disk is not None else DEFAULT_DISK
    rate = d.rate_constant * d.down_force * d.sweep_duty
    return PadLifeState(np.asarray(state.worn_volume, dtype=float) * math.exp(-rate * dt), state.polish_time)


def rate_factor(glazed_area, critical_area: float | None = None):
    """Calibrated removal-rate proxy RR/RR_fresh = 1 / (1 + G / G_c), dimensionless (eq. L4)."""
    gc = CALIBRATION["critical_glazed_area"] if critical_area is None else critical_area
    return 1.0 / (1.0 + np.asarray(glazed_area, dtype=float) / gc)


def summit_constants(state: PadLifeState, pad: FreshPad | None = None) -> SummitConstants:
    """The worn pad's summit constants relative to the fresh pad's (eq. L3) and the rate proxy (L4)."""
    p = pad if pad is not None else DEFAULT_PAD
    zf = front_height(state.worn_volume, p)
    mean0, std0 = worn_moments(p.cutoff, p.cutoff)
    mean, std = worn_moments(zf, p.cutoff)
    nc = ndtr(p.cutoff)
    glazed = (nc - ndtr(zf)) / nc
    G = 2.0 * math.pi * p.density * p.radius * p.sigma * flat_area(zf, p.cutoff)
    one = np.ones_like(zf)
    return SummitConstants(sigma=std / std0, density=one, radius=one, cutoff=zf, mean_shift=mean0 - mean,
                           glazed_summits=glazed, glazed_area=G, rate_factor=rate_factor(G, p.critical_area))


# ----------------------------------------------------------------------------- data and calibration

#: Jeong et al., Materials 17, 1817 (2024), doi 10.3390/ma17081817, IC1000 at 2 psi without
#: conditioning (read in a transcription, /work/shared/LITERATURE.md; "graph" values read off a
#: figure by the transcriber): normalised removal rate 1.00 at 1 min -> 0.835 at 10 min; contacting
#: summits 109 -> 56; summit-height spread 4.51 um -> 3.2-3.9 um; 1 min of conditioning restored the
#: contacting summits to 114. Their sliding speed was not in the transcription: 1 m/s is assumed.
JEONG_2024 = {
    "pressure": 2 * 6894.757,
    "sliding_speed": 1.0,
    "times": (60.0, 600.0),
    "rate": (1.00, 0.835),
    "contacting_summits": (109, 56),
    "spread": (4.51e-6, 3.55e-6),  # 3.2-3.9 um: the middle
    "spread_range": (3.2e-6, 3.9e-6),
    "recovery": (56, 114),
    "conditioning_time": 60.0,
}

#: Lawing (NCCAVS CMP users group, 2004): the oxide rate after conditioning stops, read off a graph
#: by the transcriber (A/min): fumed silica 2280 -> 1480 in 31 min; colloidal silica 2950 -> 2730 in
#: 20 min, "about logarithmic". Pressure and speed not in the transcription.
LAWING_2004 = {
    "fumed": {"times": (0.0, 31 * 60.0), "rate": (2280.0, 1480.0)},
    "colloidal": {"times": (0.0, 20 * 60.0), "rate": (2950.0, 2730.0)},
}

#: Calibrated constants (docs/polisher.md, "Pad life: calibration"): k_w from Jeong's spread
#: (sigma_s(10 min)/sigma_s(1 min) = 3.55/4.51), G_c from Jeong's rate (0.835), k_c from Jeong's
#: recovery (95 % of the worn volume renewed in 60 s at 22.24 N). Filled in below by _calibrate();
#: tests/test_padlife.py checks the values reproduce their targets.
CALIBRATION: dict = {}

DEFAULT_PAD = FreshPad()
DEFAULT_DISK = ConditionerDisk()


def _bisect(f, lo, hi, n=200):
    """Root of an increasing f on [lo, hi] (log-bisection for positive brackets)."""
    for _ in range(n):
        mid = math.sqrt(lo * hi)
        if f(mid) > 0:
            hi = mid
        else:
            lo = mid
    return math.sqrt(lo * hi)


def _calibrate() -> None:
    global DEFAULT_PAD, DEFAULT_DISK
    CALIBRATION["critical_glazed_area"] = 1.0  # placeholder while k_w is fitted (sigma does not depend on it)
    j = JEONG_2024
    PU = j["pressure"] * j["sliding_speed"]
    target_sigma = j["spread"][1] / j["spread"][0]

    def sigma_ratio(kw):
        pad = replace(DEFAULT_PAD, wear_coefficient=kw)
        s1 = summit_constants(PadLifeState(kw * PU * j["times"][0]), pad).sigma
        s2 = summit_constants(PadLifeState(kw * PU * j["times"][1]), pad).sigma
        return float(s2 / s1)

    kw = _bisect(lambda k: target_sigma - sigma_ratio(k), 1e-18, 1e-12)
    DEFAULT_PAD = replace(DEFAULT_PAD, wear_coefficient=kw)
    g1 = float(summit_constants(PadLifeState(kw * PU * j["times"][0])).glazed_area)
    g2 = float(summit_constants(PadLifeState(kw * PU * j["times"][1])).glazed_area)
    target_rate = j["rate"][1] / j["rate"][0]
    # rate(t2)/rate(t1) = (Gc + g1)/(Gc + g2) = target  ->  Gc = (g1 - target g2)/(target - 1)
    gc = (g1 - target_rate * g2) / (target_rate - 1.0)
    CALIBRATION["wear_coefficient"] = kw
    CALIBRATION["critical_glazed_area"] = gc
    rate = -math.log(0.05) / j["conditioning_time"]
    kc = rate / DEFAULT_DISK.down_force
    CALIBRATION["conditioner_rate_constant"] = kc
    DEFAULT_DISK = replace(DEFAULT_DISK, rate_constant=kc)


_calibrate()


#: The pad life's calibratable constants: name -> (unit, (low, high) valid range, what it is).
GLAZING_CONSTANTS: dict[str, tuple[str, tuple[float, float], str]] = {
    "pad_wear_coefficient": ("1/Pa", (1e-19, 1e-9), "Archard wear of the summit caps k_w (eq. L2)"),
    "critical_glazed_area": ("1", (1e-9, 1.0), "glazed area G_c at which the rate is halved (eq. L4)"),
    "conditioner_rate_constant": ("1/(N s)", (1e-7, 100.0), "the disk's renewal constant k_c, r_c = k_c F_d s_d (eq. L2)"),
}


def default_constants() -> dict[str, float]:
    """The uncalibrated constants (SI): those calibrated to Jeong et al. (2024) (:data:`cmpsim.physics.padlife.CALIBRATION`)."""
    return {"pad_wear_coefficient": float(CALIBRATION["wear_coefficient"]), "critical_glazed_area": float(CALIBRATION["critical_glazed_area"]),
            "conditioner_rate_constant": float(CALIBRATION["conditioner_rate_constant"])}


def check_constants(constants: dict, where: str = "pad life constants") -> dict:
    """``constants`` checked: known names, numbers inside their valid range (ValueError naming the one that is not)."""
    out = {}
    for n, v in (constants or {}).items():
        if n not in GLAZING_CONSTANTS:
            raise ValueError(f"{where}: {n} is not a pad life constant; valid: {', '.join(GLAZING_CONSTANTS)}")
        lo, hi = GLAZING_CONSTANTS[n][1]
        if isinstance(v, bool) or not isinstance(v, (int, float)) or not (lo <= float(v) <= hi):
            raise ValueError(f"{where}: {n} = {v!r} must be a number in [{lo:g}, {hi:g}] {GLAZING_CONSTANTS[n][0]}")
        out[n] = float(v)
    return out
