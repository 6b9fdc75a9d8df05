"""How deep the pad reaches into a wide gap: the elastic pad surface bending into a line array.

The step-height model (:mod:`cmpsim.die.stepheight`) presses the lower level of a cell once the
step is below the contact height h. For a gap of width b the summits alone reach b^2 / 8R into
it (:func:`cmpsim.die.evolution.contact_heights`), which saturates at the pad's contact height
h_c from b of a few micrometres. What keeps the dishing of wide lines growing (Park et al., VMIC
1998; Tugbawa, PhD MIT 2002; Vasilev et al., IEEE TSM 24, 338, 2011: the pad bending into a
wide trench) is that the pad's body is elastic too: where the up level carries the load, the pad
surface over the lower level is pushed back less, and it bulges into the gap by an amount that
grows with the gap's width. This module computes that bulge from the pad's own elasticity.

**The bulge.** A line array of pitch lambda, the lower level a strip of width b = beta lambda,
the upper level (fraction u = 1 - beta) carrying a pressure contrast Delta p over the lower one
(the step-height model's pressures, with both levels flat). The top pad is an elastic layer of
thickness t bonded to a rigid base (the subpad's compliance acts at millimetre wavelengths, the
planarization length's, not at the pitch of a line array). Its surface deflects by C(q) p(q) at
wave number q (C of :func:`cmpsim.physics.padstack.layer_stiffness`; the half space 2 / (E* q) for
q t >> 1). The deflection averaged over the upper level minus that at the centre of the lower
level, per unit contrast, is (Fourier series of the strip pattern, q_n = 2 pi n / lambda)

    G(b, lambda) = 2 sum_{n>=1} C(q_n) [ sin^2(n pi beta) / (pi^2 n^2 u) + sin(n pi beta) / (pi n) ]     (m/Pa).

For the half space the sums are closed: with theta = pi beta,

    G_hs = (2 lambda / (pi^2 E*)) [ S3(theta) / (pi u) + Cl2(theta) ],
    Cl2(theta) = sum sin(n theta) / n^2  (Clausen's function),   S3(theta) = sum sin^2(n theta) / n^3 = (1/2) int_0^{2 theta} Cl2,

evaluated by Gauss-Legendre quadrature of their smooth parts; the finite-thickness correction
2 sum (C - C_hs)(q_n) [...] decays as exp(-2 q_n t) and is summed directly. An isolated line
(beta -> 0) gives G -> (2 b / (pi E*)) (1 + ln(lambda / (pi b))), the strip on a half space with
the logarithm cut off by the array's pitch, or by the pad's thickness for lambda >> t.

**In the contact model.** The pad's asperity layer and its body are in series, both linear in
the pressure (the step-height model's linear spring): when the down level just loses contact the
contrast is P / u_eff (P the applied pressure, u_eff the upper level's effective fraction), so
the contact height of the gap becomes

    h(b, lambda) = h_c (1 - exp(-b^2 / (8 R h_c))) + P G(b, lambda) / u_eff.

With the default IC1000-like top pad (300 MPa, nu 0.3, 1.27 mm) and 4 psi the second term is
0.2 nm at 1 um lines, 1.8 nm at 10 um and 18 nm at 100 um lines at 50 % density: a mechanism
for growth, not a large one (docs/validation.md compares it with the published dishing).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

__all__ = ["clausen2", "sin2_cubed_sum", "FeatureContact", "FEATURE_CONTACTS"]

#: The models of the gap's contact height: "summit" (the summit sagitta only, cmpsim 0.3) and
#: "elastic" (the sagitta plus the pad body's bulge into the gap, this module: the default).
FEATURE_CONTACTS = ("elastic", "summit")

_X, _W = np.polynomial.legendre.leggauss(48)


def _g(s):
    """ln(2 sin(s/2) / s), smooth on [0, pi] (0 at s = 0)."""
    return np.log(np.sinc(s / (2.0 * np.pi)))


#: Above this many points the smooth integrals below come from cubic splines through 4097 exact values
#: (round-off: 1e-15 absolute, against 1e-16 for the 48-point quadrature) instead of the quadrature itself:
#: a whole chip's million windows cost 0.1 s instead of 10 s.
TABLE_ABOVE = 4096
_TABLES: dict = {}


def _int_g(th):
    """int_0^theta g(s) ds (48-point Gauss-Legendre; g is smooth on [0, pi])."""
    s = 0.5 * th[..., None] * (_X + 1.0)
    return 0.5 * th * np.sum(_W * _g(s), axis=-1)


def _int2_g(phi):
    """int_0^phi (phi - s) g(s) ds (48-point Gauss-Legendre)."""
    s = 0.5 * phi[..., None] * (_X + 1.0)
    return 0.5 * phi * np.sum(_W * (phi[..., None] - s) * _g(s), axis=-1)


def _smooth(kind: str, x: np.ndarray) -> np.ndarray:
    """The smooth integral ``kind`` ("g" or "g2") at x in [0, pi]: quadrature, or its spline table for many points."""
    exact = _int_g if kind == "g" else _int2_g
    if x.size <= TABLE_ABOVE:
        return exact(x)
    if kind not in _TABLES:
        from scipy.interpolate import CubicSpline

        grid = np.linspace(0.0, np.pi, 4097)
        _TABLES[kind] = CubicSpline(grid, exact(grid))
    return _TABLES[kind](x)


def clausen2(theta):
    """Cl2(theta) = sum_{n>=1} sin(n theta) / n^2 for theta in [0, pi] (to round-off)."""
    th = np.asarray(theta, dtype=float)
    if np.any((th < 0) | (th > np.pi)):
        raise ValueError("clausen2 takes theta in [0, pi]")
    integral = _smooth("g", th)
    with np.errstate(divide="ignore", invalid="ignore"):
        out = th - th * np.log(th) - integral
    return np.where(th > 0, out, 0.0)


def sin2_cubed_sum(theta):
    """S3(theta) = sum_{n>=1} sin^2(n theta) / n^3 for theta in [0, pi]: (1/2) int_0^{2 theta'} Cl2, theta' = min(theta, pi - theta)."""
    th = np.asarray(theta, dtype=float)
    if np.any((th < 0) | (th > np.pi)):
        raise ValueError("sin2_cubed_sum takes theta in [0, pi]")
    phi = 2.0 * np.minimum(th, np.pi - th)
    smooth = _smooth("g2", phi)
    with np.errstate(divide="ignore", invalid="ignore"):
        whole = 0.75 * phi**2 - 0.5 * phi**2 * np.log(phi) - smooth
    return 0.5 * np.where(phi > 0, whole, 0.0)


@dataclass(frozen=True)
class FeatureContact:
    """The pad body at the scale of a line array: applied pressure (Pa) and the top pad's E (Pa), nu, thickness (m).

    ``compliance`` (optional): C(q) (m/Pa) of the top pad on a rigid base; the half space
    2 (1 - nu^2) / (E q) if None.
    """

    pressure: float
    modulus: float
    poisson: float
    thickness: float
    compliance: object = None

    @classmethod
    def from_config(cls, config) -> "FeatureContact":
        """The top pad and the applied pressure of a :class:`cmpsim.Config`."""
        from .pad import top_layer

        return cls(float(config.applied_pressure), float(config.pad_bulk_modulus), float(config.pad_poisson),
                   float(config.pad_thickness), top_layer(config).compliance)

    @property
    def e_star(self) -> float:
        return self.modulus / (1.0 - self.poisson**2)

    def _half_space(self, beta, pitch):
        u = 1.0 - beta
        theta = np.pi * beta
        return 2.0 * pitch / (np.pi**2 * self.e_star) * (sin2_cubed_sum(theta) / (np.pi * u) + clausen2(theta))

    def compliance_difference(self, gap, pitch) -> np.ndarray:
        """G(b, lambda) (m/Pa): mean deflection of the upper level minus that at the gap's centre, per unit pressure contrast.

        NaN where the gap or the pitch is not finite or the gap fills the pitch.
        """
        b, lam = np.broadcast_arrays(np.asarray(gap, dtype=float), np.asarray(pitch, dtype=float))
        out = np.full(b.shape, np.nan)
        ok = np.isfinite(b) & np.isfinite(lam) & (b > 0) & (lam > b)
        if not ok.any():
            return out
        pairs, inverse = np.unique(np.stack([b[ok], lam[ok]], axis=-1), axis=0, return_inverse=True)
        bb, ll = pairs[:, 0], np.minimum(pairs[:, 1], 1e3 * self.thickness)  # beyond 1000 t an isolated line: converged
        beta = bb / ll
        g = self._half_space(beta, ll)
        if self.compliance is not None:
            # finite thickness: (C - C_hs)(q_n) decays as exp(-2 q_n t); the layer's own formula is the half space beyond q t = 40
            n_max = np.ceil(40.0 * ll / (2.0 * np.pi * self.thickness)).astype(int)
            for n in range(1, int(n_max.max()) + 1):
                sel = n <= n_max
                q = 2.0 * np.pi * n / ll[sel]
                dc = np.asarray(self.compliance(q), dtype=float) - 2.0 / (self.e_star * q)
                bt = beta[sel]
                g[sel] += 2.0 * dc * (np.sin(n * np.pi * bt) ** 2 / (np.pi**2 * n**2 * (1.0 - bt)) + np.sin(n * np.pi * bt) / (np.pi * n))
        out[ok] = g[inverse.ravel()]
        return out

    def bulge(self, gap, pitch, up_fraction) -> np.ndarray:
        """P G(b, lambda) / u_eff (m): the pad body's extra reach into the gap when the lower level just loses contact; 0 where G is NaN."""
        g = self.compliance_difference(gap, pitch)
        return np.where(np.isfinite(g), self.pressure * np.nan_to_num(g) / np.asarray(up_fraction, dtype=float), 0.0)
