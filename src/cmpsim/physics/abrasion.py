"""Abrasive removal: particles trapped in the pad's real contact area plough the film.

Pure vectorised kernels (SI units) of the removal law ``removal_law = "abrasive"``, after Luo &
Dornfeld (IEEE Trans. Semicond. Manuf. 14, 112 (2001); 16, 469 (2003)), Zhao & Chang (Wear 252,
220 (2002)) and Jeng & Huang (J. Electrochem. Soc. 152, G80 (2005)). The chain, derived in
``docs/model.md`` ("Abrasive removal"), at each point of the wafer:

1. **Particles in the real contact.** A slurry of solid volume fraction phi and a (log-normal)
   number distribution of diameters x holds N_v = phi / <pi x^3 / 6> particles per unit volume.
   The particles trapped between a pad summit in contact and the wafer are those of the layer
   as thick as their own diameter (Luo & Dornfeld 2001): n(x) = N_v f(x) x per unit real
   contact area. They cover a share c = sum n pi x^2 / 4 = (3/2) phi of it.
2. **Load per particle.** The soft pad flows around each trapped particle and presses it with
   its flow pressure p_pad = min(H_pad, 4 E_pad' / (3 pi)) (the lesser of the pad hardness and
   the Hertz mean pressure at an interference of one particle radius) over the embedded section:
   F = p_pad pi (2 r e - e^2), e the embedding (e <= r; p_pad pi r^2 beyond). Where the particles
   cannot carry the summits' mean real contact pressure p_r = p_c / (A_r/A_n) alone, the pad
   touches the wafer between them and each is embedded by its diameter (g = 0); otherwise the
   pad rests on the largest particles at the gap g > 0 where sum n F(x - g) = p_r (the size
   distribution then decides which particles work: Luo & Dornfeld 2003).
2b. **Summit by summit** (:func:`summit_sharing`, when the summits in contact per area N are
   given): a summit contact of mean area A_1 = (A_r/A_n)/N holds a Poisson number k of
   particles (mean M = A_1 sum n); it touches the wafer around them while k <= k* = F_s / F_w
   (F_s = p_r A_1 its load, F_w = p_pad <pi x^2/4> the most the pad presses a particle with) and
   rests on them, sharing F_s, beyond. The continuum rule of step 2 is its limit A_1 -> infinity.
3. **Indentation into the film.** A sphere of radius x/2 pressed on the film with force F sinks
   by the interference omega of the elastic (Hertz) / elastoplastic (Zhao–Maietta–Chang) /
   plastic law of the pad summits (``cmpsim.physics.contact``), with the particle-film effective modulus
   E* and the hardness and K = 0.454 + 0.41 nu of the softer body; the film takes the share
   C_f / (C_f + C_a) of it (C = (1 - nu^2)/E, each body's Hertz compliance): delta = omega C_f / (C_f + C_a).
   A film with an indentation size length R* > 0 is harder under small particles,
   H(r) = H_0 sqrt(1 + R*/r) (:func:`size_hardness`; Nix & Gao 1998, Swadener et al. 2002).
4. **Ploughed volume.** Sliding with the pad at |u_pad - u_wafer|, the particle sweeps the
   circular segment of depth delta of its own section: A_g = r^2 (theta - sin theta cos theta),
   cos theta = 1 - delta / r. A share k_a (``abrasion_efficiency``) of the ploughed groove
   leaves as debris (three-body abrasion).
5. **Rate.** RR = k_a (A_r/A_n) |du| sum n A_g (m/s).

With s = 1 the per-particle quantities do not depend on the load, so RR = C (A_r/A_n) |du|:
wherever the real contact area grows in proportion to the contact load (Greenwood–Williamson
summits with exponential heights, or fully plastic summits: A_r = P/H), this is Preston's law
RR = k_p p_c |du| with k_p = C / p_r.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from scipy.special import gammaln, pdtr, xlogy

__all__ = [
    "poisson_pmf",
    "poisson_cdf",
    "AbrasiveContact",
    "AbrasionResult",
    "size_nodes",
    "sphere_load",
    "interference",
    "groove_area",
    "pad_force",
    "pad_gap",
    "summit_sharing",
    "size_hardness",
    "abrasive_removal_rate",
    "PLASTIC_RATIO",
]

#: omega_p / omega_e of the Zhao–Maietta–Chang law (as in cmpsim.physics.contact).
PLASTIC_RATIO = 54.0
#: Gauss–Hermite nodes of the log-normal size distribution.
SIZE_NODES = 16
_BISECTIONS = 60
#: Summit particle counts k evaluated per block in :func:`summit_sharing`.
_K_CHUNK = 256


@dataclass(frozen=True)
class AbrasiveContact:
    """The particles, the pad that presses them and the film they plough (SI).

    Parameters
    ----------
    diameter : float
        Number-mean particle diameter, m (> 0).
    diameter_std : float
        Standard deviation of the number distribution of diameters, m (>= 0; 0: all alike).
    volume_fraction : float
        Solid volume fraction phi of the slurry, in [0, 1).
    pad_pressure : float
        Largest pressure p_pad of the pad on an embedded particle, Pa (> 0).
    e_star : float
        Particle-film effective modulus E*, 1/E* = C_a + C_f, Pa.
    hardness : float
        Hardness of the softer of particle and film, Pa.
    k_factor : float
        K = 0.454 + 0.41 nu of the softer body.
    film_share : float
        C_f / (C_a + C_f): the share of the interference taken by the film, in (0, 1].
    efficiency : float
        k_a: share of the ploughed groove removed, in [0, 1].
    size_length : float
        R*, m (>= 0): the indentation size length of the film's hardness under a sphere,
        H(r) = hardness sqrt(1 + R*/r) for a particle of radius r (:func:`size_hardness`);
        0 (default): no size effect, ``hardness`` for every particle.
    hardness_limit : float
        Pa (> 0): the most :func:`size_hardness` gives (the hardness of the other body, beyond which
        the particle is the one that yields); inf (default): no limit.
    """

    diameter: float
    diameter_std: float
    volume_fraction: float
    pad_pressure: float
    e_star: float
    hardness: float
    k_factor: float
    film_share: float
    efficiency: float
    size_length: float = 0.0
    hardness_limit: float = float("inf")

    def __post_init__(self):
        checks = (
            ("diameter", self.diameter > 0, "(0, inf) m"),
            ("diameter_std", self.diameter_std >= 0, "[0, inf) m"),
            ("volume_fraction", 0 <= self.volume_fraction < 1, "[0, 1)"),
            ("pad_pressure", self.pad_pressure > 0, "(0, inf) Pa"),
            ("e_star", self.e_star > 0, "(0, inf) Pa"),
            ("hardness", self.hardness > 0, "(0, inf) Pa"),
            ("k_factor", 0 < self.k_factor <= 1, "(0, 1]"),
            ("film_share", 0 < self.film_share <= 1, "(0, 1]"),
            ("efficiency", 0 <= self.efficiency <= 1, "[0, 1]"),
            ("size_length", self.size_length >= 0, "[0, inf) m"),
        )
        for name, ok, rng in checks:
            if not (ok and np.isfinite(getattr(self, name))):
                raise ValueError(f"{name} must be in {rng}; got {getattr(self, name)!r}")
        if not self.hardness_limit > 0:  # inf allowed: no limit
            raise ValueError(f"hardness_limit must be in (0, inf] Pa; got {self.hardness_limit!r}")

    def hardness_at(self, diameter):
        """Hardness (Pa) the film opposes to a particle of ``diameter`` (m): :func:`size_hardness`
        at radius diameter/2 with this contact's size length and limit (``hardness`` when R* = 0)."""
        return size_hardness(0.5 * np.asarray(diameter, dtype=float), self.hardness, self.size_length, self.hardness_limit)

    @property
    def coverage(self) -> float:
        """Share of the real contact area covered by trapped particles, c = (3/2) phi."""
        return 1.5 * self.volume_fraction


@dataclass(frozen=True)
class AbrasionResult:
    """Removal rate and the particle-level state at each point (arrays shaped like the inputs).

    ``rate`` m/s; ``active_particles`` trapped particles per unit nominal area, 1/m^2;
    ``gap`` g between pad and wafer in the summit contacts, m (0: the pad touches the wafer);
    ``particle_load`` F of a particle of the mean diameter, N;
    ``depth`` delta of a particle of the mean diameter, m.
    """

    rate: np.ndarray
    active_particles: np.ndarray
    gap: np.ndarray
    particle_load: np.ndarray
    depth: np.ndarray


def size_nodes(mean: float, std: float, n: int = SIZE_NODES):
    """Diameters x_i (m) and number weights w_i (sum 1) of the log-normal distribution of given mean and std.

    ln x is normal with sigma^2 = ln(1 + (std/mean)^2) and mu = ln(mean) - sigma^2/2 (moment
    matched), integrated by Gauss–Hermite quadrature; ``std = 0`` gives the single node (mean, 1).
    """
    if std == 0:
        return np.array([float(mean)]), np.array([1.0])
    s2 = np.log1p((std / mean) ** 2)
    t, w = np.polynomial.hermite_e.hermegauss(n)
    return np.exp(np.log(mean) - 0.5 * s2 + np.sqrt(s2) * t), w / w.sum()


def size_hardness(radius, hardness, length, limit=np.inf):
    """Hardness (Pa) of a crystalline film under a sphere of ``radius`` r (m): H = H_0 sqrt(1 + R*/r).

    The indentation size effect of a spherical indenter (Swadener, George & Pharr, J. Mech. Phys.
    Solids 50, 681 (2002), from the model of Nix & Gao, J. Mech. Phys. Solids 46, 411 (1998)):
    a sphere pressed into the film needs geometrically necessary dislocations of density
    rho_G = 1/(b r), whatever its depth, on top of the statistically stored rho_S; with Taylor
    hardening H = H_0 sqrt(1 + rho_G/rho_S) = H_0 sqrt(1 + R*/r), R* = 1/(b rho_S) (``length``,
    m; 0 gives H_0 = ``hardness`` exactly). The result is capped at ``limit`` (Pa; the other
    body's hardness: beyond it that body yields first). Depth-free for a sphere, so the
    interference law of :func:`interference` is solved with H(r) in closed form or by bisection
    as before.
    """
    r = np.asarray(radius, dtype=float)
    if length == 0:
        return np.minimum(np.full_like(r, float(hardness)), limit)
    return np.minimum(hardness * np.sqrt(1.0 + length / r), limit)


def _omega_e(radius, e_star, hardness, k):
    return (3.0 * np.pi * k * hardness / (4.0 * e_star)) ** 2 * radius


def sphere_load(omega, radius, e_star, hardness, k):
    """Force (N) pressing a sphere of ``radius`` (m) into a flat by the interference ``omega`` (m).

    Hertz below omega_e = (3 pi K H / (4 E*))^2 R (paper eq. 27), Zhao–Maietta–Chang between
    omega_e and 54 omega_e, fully plastic 2 pi R omega H above: the per-summit law of
    :mod:`cmpsim.physics.contact` (continuous at both boundaries).
    """
    w = np.asarray(omega, dtype=float)
    R = np.asarray(radius, dtype=float)
    we = _omega_e(R, e_star, hardness, k)
    wp = PLASTIC_RATIO * we
    wc = np.clip(w, we, wp)
    u = (wc - we) / (wp - we)
    area_ep = np.pi * R * wc * (1.0 + u * u * (3.0 - 2.0 * u))
    p_ep = hardness * (1.0 - (1.0 - k) * np.log(wp / wc) / np.log(PLASTIC_RATIO))
    hertz = 4.0 / 3.0 * e_star * np.sqrt(R) * np.maximum(w, 0.0) ** 1.5
    return np.where(w < we, hertz, np.where(w < wp, p_ep * area_ep, 2.0 * np.pi * R * w * hardness))


def interference(load, radius, e_star, hardness, k):
    """The interference omega (m) at which :func:`sphere_load` equals ``load`` (N); 0 for no load.

    ``load``, ``radius`` and ``hardness`` (Pa) broadcast together (a hardness per particle size:
    :func:`size_hardness`).

    Closed form in the elastic and plastic ranges; bisection on ln omega between omega_e and
    54 omega_e (the law is increasing there) to machine precision.
    """
    F, R, H = np.broadcast_arrays(np.asarray(load, dtype=float), np.asarray(radius, dtype=float), np.asarray(hardness, dtype=float))
    we = _omega_e(R, e_star, H, k)
    wp = PLASTIC_RATIO * we
    f_e = sphere_load(we * (1 - 1e-15), R, e_star, H, k)
    f_p = sphere_load(wp, R, e_star, H, k)
    elastic = (3.0 * np.maximum(F, 0.0) / (4.0 * e_star * np.sqrt(R))) ** (2.0 / 3.0)
    plastic = F / (2.0 * np.pi * R * H)
    # bisect only where the load falls in the elastic-plastic range (elementwise, so the same bits)
    between = (F >= f_e) & (F < f_p)
    ep = np.array(we)  # placeholder outside the range, never selected below
    if np.any(between):
        Fb, Rb, Hb = F[between], R[between], H[between]
        lo, hi = np.log(we[between]), np.log(wp[between])
        for _ in range(_BISECTIONS):
            mid = 0.5 * (lo + hi)
            below = sphere_load(np.exp(mid), Rb, e_star, Hb, k) < Fb
            lo, hi = np.where(below, mid, lo), np.where(below, hi, mid)
        ep[between] = np.exp(0.5 * (lo + hi))
    return np.where(F < f_e, elastic, np.where(F < f_p, ep, plastic))


def groove_area(radius, depth):
    """Section of the groove (m^2) a sphere of ``radius`` ploughs at ``depth`` (m), 0 <= depth <= 2 radius.

    The circular segment r^2 (theta - sin theta cos theta), cos theta = 1 - depth/r, with its
    series (4/3) sqrt(2 r) depth^(3/2) (1 - ...) written through theta for small depth (no cancellation).
    """
    r = np.asarray(radius, dtype=float)
    d = np.asarray(depth, dtype=float)
    theta = 2.0 * np.arcsin(np.sqrt(np.clip(d / (2.0 * r), 0.0, 1.0)))
    small = theta < 1e-2
    t2 = theta * theta
    series = theta**3 * (2.0 / 3.0 - t2 * (2.0 / 15.0 - t2 * (4.0 / 315.0)))
    exact = theta - np.sin(theta) * np.cos(theta)
    return r * r * np.where(small, series, exact)


def pad_force(embedding, radius, pad_pressure):
    """Force (N) of the pad on a particle of ``radius`` (m) embedded ``embedding`` (m) into it.

    The pad flows around the particle at its flow pressure p_pad over the embedded section:
    F = p_pad pi (2 r e - e^2) for e <= r, p_pad pi r^2 beyond (the particle is then held
    over its whole projected area); 0 for e <= 0. Continuous and increasing in e.
    """
    e = np.clip(np.asarray(embedding, dtype=float), 0.0, np.asarray(radius, dtype=float))
    return pad_pressure * np.pi * e * (2.0 * np.asarray(radius) - e)


def pad_gap(real_pressure, diameters, counts, pad_pressure):
    """Gap g (m) between the pad surface and the wafer inside a summit contact.

    g = 0 (the pad touches the wafer between the particles, each embedded by its whole
    diameter) when the particles cannot carry the real contact pressure p_r alone; otherwise the
    g > 0 at which they carry it: sum_i n_i F(x_i - g) = p_r (:func:`pad_force`), found by
    bisection (the sum falls as g grows). ``counts`` n_i per unit real area by size class
    (last axis), ``real_pressure`` p_r per point.
    """
    p_r = np.asarray(real_pressure, dtype=float)[..., None]
    x = np.asarray(diameters, dtype=float)

    def carried(g):
        return np.sum(counts * pad_force(x - g, 0.5 * x, pad_pressure), axis=-1, keepdims=True)

    dense = carried(np.zeros_like(p_r)) > p_r
    gap = np.zeros_like(p_r)
    if np.any(dense):  # bisect only where the particles carry the load (elementwise: the same bits)
        target = p_r[dense][:, None]
        lo = np.zeros_like(target)
        hi = np.full_like(target, x.max())
        for _ in range(_BISECTIONS):
            mid = 0.5 * (lo + hi)
            over = carried(mid) > target
            lo, hi = np.where(over, mid, lo), np.where(over, hi, mid)
        gap[dense] = 0.5 * (lo + hi)[:, 0]
    return gap[..., 0]



def poisson_pmf(k, mean):
    """Poisson probability P(K = k) of a count K with mean ``mean`` (k a whole number >= 0).

    exp(k ln m - ln k! - m), as ``scipy.stats.poisson.pmf`` computes it (equal bit for bit,
    ``tests/test_abrasion.py``), without loading ``scipy.stats``. Dimensionless.
    """
    k = np.asarray(k, dtype=float)
    return np.clip(np.exp(xlogy(k, mean) - gammaln(k + 1.0) - mean), 0.0, 1.0)


def poisson_cdf(k, mean):
    """Poisson probability P(K <= k) of a count with mean ``mean``: 0 for k < 0, the regularised
    incomplete gamma function ``pdtr(floor(k), m)`` otherwise, as ``scipy.stats.poisson.cdf``
    computes it (equal bit for bit). Dimensionless."""
    k = np.floor(np.asarray(k, dtype=float))
    return np.where(k >= 0.0, np.clip(pdtr(np.maximum(k, 0.0), mean), 0.0, 1.0), 0.0)

def summit_sharing(mean_count, wrap_count, real_pressure, diameters, counts, pad_pressure, film_groove):
    """Groove section swept per unit real contact area, sum n A_g (m^2 per m^2), with the particles
    counted summit by summit (docs/model.md, 13e.1, step 2b).

    A summit contact of area A_1 holds k particles, Poisson with mean M = A_1 sum_i n_i
    (``mean_count``); the pad can press them, each embedded by its whole diameter, with at
    most k F_w, F_w = p_pad <pi x^2/4> the mean wrapped load. While k F_w <= F_s = p_r A_1, i.e.
    k <= k* = F_s / F_w (``wrap_count``), the pad touches the wafer around them and each
    carries F_w; a summit holding more props itself on them and they share F_s (the gap of
    :func:`pad_gap` at the pressure p_r M / k). With the Poisson identity k P(k; M) / M =
    P(k - 1; M):

        sum n A_g = CDF(floor(k*) - 1; M) sum_i n_i A_g,i(F_w,i)
                    + sum_{k > k*} P(k - 1; M) sum_i n_i A_g,i(F_i(g_k)).

    As M -> infinity (particles far smaller than the summit contact) this is the continuum rule
    of :func:`pad_gap` at p_r; no division by M, so M = 0 (no abrasive) gives 0.
    ``film_groove(load, x)`` is the groove section (m^2) of a particle of diameter x under load.
    """
    shape = np.shape(mean_count)
    M = np.asarray(mean_count, dtype=float).ravel()
    ks = np.broadcast_to(np.asarray(wrap_count, dtype=float), shape).ravel()
    p_r = np.broadcast_to(np.asarray(real_pressure, dtype=float), shape).ravel()
    if not (np.all(np.isfinite(M)) and np.all(M >= 0) and np.all(ks >= 0) and np.all(np.isfinite(ks))):
        raise ValueError("mean_count and wrap_count must be finite and >= 0 (particles per summit contact)")
    x = np.asarray(diameters, dtype=float)
    f_wrap = pad_force(x, 0.5 * x, pad_pressure)
    swept_wrap = np.sum(counts * film_groove(f_wrap, x), axis=-1)
    k_floor = np.floor(ks)
    some = M > 0
    m_safe = np.where(some, M, 1.0)
    out = np.where(some, poisson_cdf(k_floor - 1.0, m_safe), 0.0) * swept_wrap
    # propped summits: k from floor(k*) + 1 to M + 12 sqrt(M) + 40, beyond which the Poisson mass is
    # below exp(-60) (Chernoff: P(K >= M + t) <= exp(-t^2 / (2 (M + t/3))))
    k_hi = np.where(some, np.ceil(M + 12.0 * np.sqrt(M) + 40.0), 0.0)
    first = k_floor + 1.0
    span = int(np.max(np.maximum(k_hi - first, 0.0), initial=0.0))
    for j0 in range(0, span, _K_CHUNK):
        k = first[..., None] + np.arange(j0, min(j0 + _K_CHUNK, span))  # (points, chunk)
        live = k <= k_hi[..., None]
        weight = np.where(live, poisson_pmf(k - 1.0, m_safe[:, None]), 0.0)
        if not np.any(weight > 0):
            continue
        idx = np.nonzero(weight > 0)
        pressure = p_r[idx[0]] * M[idx[0]] / k[idx]
        gap = pad_gap(pressure, x, counts, pad_pressure)
        load = pad_force(x - gap[:, None], 0.5 * x, pad_pressure)
        swept = np.sum(counts * film_groove(load, x), axis=-1)
        np.add.at(out, idx[0], weight[idx] * swept)
    return out.reshape(shape)


def abrasive_removal_rate(contact_pressure, area_ratio, sliding_speed, abrasive: AbrasiveContact, spot_density=None) -> AbrasionResult:
    """Mechanical removal rate of the abrasive law at each point, m/s (module docstring, steps 1-5).

    Parameters
    ----------
    contact_pressure : array
        Nominal contact pressure of the pad summits p_c, Pa.
    area_ratio : array
        Real contact area over nominal area A_r/A_n of the summits, dimensionless.
    sliding_speed : array
        |u_pad - u_wafer|, m/s.
    abrasive : AbrasiveContact
    spot_density : array, optional
        Summits in contact per unit nominal area N, 1/m^2 (:func:`cmpsim.physics.contact.contact_spot_density`):
        the particles are then counted summit by summit (:func:`summit_sharing`), with the
        mean summit contact A_1 = (A_r/A_n)/N. ``None``: the limit of summit contacts far larger
        than the particles (A_1 -> infinity), the continuum rule of :func:`pad_gap`.

    Returns
    -------
    AbrasionResult
        Zero rate wherever there is no contact or no abrasive (phi = 0): no particle, no removal.
    """
    a = abrasive
    pc = np.asarray(contact_pressure, dtype=float)
    ar = np.asarray(area_ratio, dtype=float)
    speed = np.asarray(sliding_speed, dtype=float)
    x, w = size_nodes(a.diameter, a.diameter_std)
    n_v = a.volume_fraction / np.sum(w * np.pi * x**3 / 6.0)  # particles per unit volume
    n_i = n_v * w * x  # per unit real contact area, by size class (Luo & Dornfeld 2001)
    in_contact = ar > 0
    p_r = np.where(in_contact, pc / np.where(in_contact, ar, 1.0), 0.0)
    gap = np.where(in_contact, pad_gap(p_r, x, n_i, a.pad_pressure), 0.0)

    def film_groove(load, diameter):
        hardness = a.hardness_at(diameter)  # the film's hardness under each size (indentation size effect)
        return groove_area(0.5 * diameter, a.film_share * interference(load, 0.5 * diameter, a.e_star, hardness, a.k_factor))

    if spot_density is None:
        load = pad_force(x - gap[..., None], 0.5 * x, a.pad_pressure)  # (points, size classes)
        swept = np.sum(n_i * film_groove(load, x), axis=-1)  # m^2 per unit real area
    else:
        N = np.asarray(spot_density, dtype=float)
        spot = np.where(in_contact & (N > 0), ar / np.where(N > 0, N, 1.0), 0.0)  # A_1, m^2
        # k* = F_s / F_w: sections of the mean particle the summit load fills at the pad pressure
        wrap = p_r * spot / (a.pad_pressure * np.pi * np.sum(w * x * x * x) / (4.0 * np.sum(w * x)))
        swept = summit_sharing(spot * np.sum(n_i), wrap, p_r, x, n_i, a.pad_pressure, film_groove)
    rate = np.where(in_contact, a.efficiency * ar * speed * swept, 0.0)
    active = ar * np.sum(n_i * (x > gap[..., None]), axis=-1)
    f_mean = np.where(in_contact, pad_force(a.diameter - gap, 0.5 * a.diameter, a.pad_pressure), 0.0)
    d_mean = a.film_share * interference(f_mean, 0.5 * a.diameter, a.e_star, a.hardness_at(a.diameter), a.k_factor)
    return AbrasionResult(rate=rate, active_particles=active, gap=gap, particle_load=f_mean, depth=d_mean)
