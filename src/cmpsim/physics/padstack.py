"""The elastic pad stack under the asperity layer: layers, a Winkler bed, and layers with lateral coupling.

Pure kernels of the pad's bulk deformation (``docs/model.md``, "Pad compliance"): the
constrained modulus of a layer, the stiffness of layers in series (a Winkler bed, w = p / k),
the Fourier stiffness of an elastic layer on a rigid base, and the plate-on-layer compliance
C(q) of a top pad on a softer subpad (applied to a pressure field on the polar grid by
:mod:`cmpsim.numerics.padgrid`, from the cell integrals of :mod:`cmpsim.physics.padinfluence`). The coupled solve of the film with this deflection is in
:mod:`cmpsim.operators.compliance`; the pad models that pick one of these stacks by name are in
:mod:`cmpsim.models.pads`.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

__all__ = [
    "PadLayer",
    "constrained_modulus",
    "foundation_stiffness",
    "WinklerFoundation",
    "LayeredFoundation",
    "layer_stiffness",
    "plate_bending_stiffness",
]

def constrained_modulus(youngs_modulus, poisson):
    """Constrained (oedometric, P-wave) modulus M = E (1 - nu) / ((1 + nu)(1 - 2 nu)), Pa.

    The stress over the strain of a layer compressed without lateral expansion, which is the
    state of a thin layer under a load much wider than its thickness.
    """
    e = np.asarray(youngs_modulus, dtype=float)
    nu = np.asarray(poisson, dtype=float)
    return e * (1.0 - nu) / ((1.0 + nu) * (1.0 - 2.0 * nu))


@dataclass(frozen=True)
class PadLayer:
    """One layer of the pad stack: thickness (m), Young's modulus (Pa), Poisson ratio."""

    thickness: float
    modulus: float
    poisson: float

    def __post_init__(self) -> None:
        if not (np.isfinite(self.thickness) and self.thickness >= 0):
            raise ValueError(f"layer thickness must be finite and >= 0 m; got {self.thickness!r}")
        if not (np.isfinite(self.modulus) and self.modulus > 0):
            raise ValueError(f"layer modulus must be finite and > 0 Pa; got {self.modulus!r}")
        if not (0.0 <= self.poisson < 0.5):
            raise ValueError(f"layer Poisson ratio must be in [0, 0.5); got {self.poisson!r}")

    @property
    def compliance(self) -> float:
        """Deflection per unit pressure t / M of the layer, m/Pa."""
        return self.thickness / float(constrained_modulus(self.modulus, self.poisson))


def foundation_stiffness(layers) -> float:
    """Stiffness k = 1 / sum(t_i / M_i) of layers in series, Pa/m (inf for no thickness)."""
    c = sum(layer.compliance for layer in layers)
    return np.inf if c == 0 else 1.0 / c


@dataclass(frozen=True)
class WinklerFoundation:
    """Local elastic foundation of stiffness k (Pa/m): deflection w = p / k."""

    stiffness: float

    def __post_init__(self) -> None:
        if not (self.stiffness > 0):
            raise ValueError(f"foundation stiffness must be > 0 Pa/m; got {self.stiffness!r}")

    @classmethod
    def from_layers(cls, layers) -> "WinklerFoundation":
        """The foundation of a stack of :class:`PadLayer` in series."""
        return cls(foundation_stiffness(layers))

    #: The deflection at a point depends on the pressure there only.
    local = True

    def deflection(self, pressure):
        """Deflection (m) under a pressure (Pa)."""
        return np.asarray(pressure, dtype=float) / self.stiffness


def layer_stiffness(q, thickness: float, modulus: float, poisson: float):
    """Fourier stiffness p~/w~ (Pa/m) of an elastic layer bonded to a rigid base, frictionless top.

    K(q) = (E* q / 2) [(3 - 4 nu) cosh 2qt + 2 (qt)^2 + 5 - 12 nu + 8 nu^2] / [(3 - 4 nu) sinh 2qt - 2qt]
    with E* = E / (1 - nu^2), for the surface wave number q (rad/m) of a normal load. It tends to
    the constrained stiffness M/t as q -> 0 (a Winkler bed) and to the half space E* q / 2 as
    qt -> inf. The same expression is the finite-thickness correction of ContactMechanics'
    ``PeriodicFFTElasticHalfSpace`` (Pastewka et al., MIT licence; after Johnson, Greenwood &
    Higginson, Int. J. Mech. Sci. 27, 383, 1985, for the half space).
    """
    q = np.asarray(q, dtype=float)
    nu, t = poisson, thickness
    e_star = modulus / (1.0 - nu * nu)
    out = np.empty_like(q)
    qt = q * t
    small = qt < 1e-4
    out[small] = float(constrained_modulus(modulus, nu)) / t
    big = qt > 40.0  # the ratio is 1 to round-off
    out[big] = 0.5 * e_star * q[big]
    mid = ~(small | big)
    x = 2.0 * qt[mid]
    a = 3.0 - 4.0 * nu
    num = a * np.cosh(x) + 0.5 * x * x + 5.0 - 12.0 * nu + 8.0 * nu * nu
    den = a * np.sinh(x) - x
    out[mid] = 0.5 * e_star * q[mid] * num / den
    return out


def plate_bending_stiffness(thickness: float, modulus: float, poisson: float) -> float:
    """Bending stiffness D = E t^3 / (12 (1 - nu^2)) of a thin plate, N m."""
    return modulus * thickness**3 / (12.0 * (1.0 - poisson * poisson))


@dataclass(frozen=True)
class LayeredFoundation:
    """Pad stack with lateral coupling: elastic layers bonded to the platen (``pad_compliance="layer"``).

    One layer: an elastic layer of finite thickness, Fourier stiffness :func:`layer_stiffness`.
    Two layers (top pad on a softer subpad): the top pad is a thin plate that bends over the
    subpad, an elastic layer, and compresses locally through its thickness:

        C(q) = t_1 / M_1 + 1 / (D_1 q^4 + K_2(q))        (deflection per pressure, m/Pa).

    C(0) = 1/k of the same layers in series, so a load much wider than the stack deflects it
    like the Winkler bed of :class:`WinklerFoundation`. The pad outside the wafer carries no
    load. The deflection of a pressure field on the polar grid is :func:`cmpsim.numerics.padgrid.layer_deflection`.
    """

    layers: tuple

    local = False

    def __post_init__(self) -> None:
        if not 1 <= len(self.layers) <= 2 or any(layer.thickness <= 0 for layer in self.layers):
            raise ValueError("a layered pad has one or two layers of positive thickness (top pad first)")

    @property
    def stiffness(self) -> float:
        """Long-wavelength stiffness k = 1 / sum t_i / M_i, Pa/m."""
        return foundation_stiffness(self.layers)

    @property
    def local_compliance(self) -> float:
        """Local (through-thickness) compliance of the top pad when it acts as a plate, m/Pa."""
        return self.layers[0].compliance if len(self.layers) == 2 else 0.0

    def nonlocal_compliance(self, q):
        """The part of C(q) that couples neighbouring points, m/Pa."""
        q = np.asarray(q, dtype=float)
        if len(self.layers) == 1:
            top = self.layers[0]
            return 1.0 / layer_stiffness(q, top.thickness, top.modulus, top.poisson)
        top, sub = self.layers
        d = plate_bending_stiffness(top.thickness, top.modulus, top.poisson)
        return 1.0 / (d * q**4 + layer_stiffness(q, sub.thickness, sub.modulus, sub.poisson))

    def compliance(self, q):
        """C(q) = w~/p~, m/Pa."""
        return self.local_compliance + self.nonlocal_compliance(q)

    def annulus_deflection(self, r, inner: float, outer: float, pressure: float) -> np.ndarray:
        """Deflection (m) of the pad surface at radii ``r`` < ``inner`` under a uniform ``pressure`` (Pa) on
        the annulus ``inner`` < r < ``outer`` (m): the load of a retaining ring around the wafer.

        Axisymmetric, by the Hankel transform of order 0 (Sneddon, *Fourier Transforms*, 1951, ch. 2):

            w(r) = p integral_0^inf C(q) [c J1(qc) - b J1(qb)] J0(qr) dq,     b = inner, c = outer,

        with the nonlocal compliance C(q) of the stack (its local part acts only under the load).
        Simpson's rule at a sixteenth of the integrand's shortest period (the integrand is not
        even in q, so the trapezoid rule would keep an O(dq^2) error from q = 0), out to
        q = 40 / (thinnest layer), where the plate term has cut C(q) by orders of magnitude.
        """
        from scipy.integrate import simpson
        from scipy.special import j0, j1

        r = np.asarray(r, dtype=float)
        if np.any(r >= inner):
            raise ValueError(f"annulus_deflection is for points inside the annulus (r < {inner:g} m); got r up to {r.max():g} m")
        t_min = min(layer.thickness for layer in self.layers)
        dq = 0.125 * np.pi / (outer + float(np.max(r, initial=0.0)))
        q = np.arange(0.0, 40.0 / t_min + dq, dq)
        load = self.nonlocal_compliance(np.maximum(q, 1e-300)) * (outer * j1(q * outer) - inner * j1(q * inner))
        integrand = load[None, :] * j0(np.outer(r.ravel(), q))
        return pressure * simpson(integrand, x=q, axis=1).reshape(r.shape)

    def stiffness_quadratic(self) -> tuple[float, float]:
        """(k0, b): the quadratic k0 + b q^2 (Pa/m, Pa) through 1 / (nonlocal C(q)) at q = 0 and at q = 2 / coupling length.

        A sparse stand-in for the stack's stiffness (a Laplacian on the grid), the preconditioner
        of the coupled Newton system (:mod:`cmpsim.numerics.padgrid`), not a model of the pad: it is
        exact for long waves and, unlike the Winkler bed k0, stiff in the short ones. (With the
        plate's D q^4 added the preconditioned systems took 12 GMRES iterations instead of 15, but
        the biharmonic's fill made the solve 25 % slower on the graded default preset.)
        """
        k0 = 1.0 / float(self.nonlocal_compliance(np.array([0.0]))[0])
        q1 = 2.0 / self.coupling_length
        b = (1.0 / float(self.nonlocal_compliance(np.array([q1]))[0]) - k0) / q1**2
        return k0, max(b, 0.0)

    @property
    def coupling_length(self) -> float:
        """How far a load spreads: the stack thickness, or the plate length (D_1/k_2)^(1/4), m."""
        total = sum(layer.thickness for layer in self.layers)
        if len(self.layers) == 1:
            return total
        top, sub = self.layers
        d = plate_bending_stiffness(top.thickness, top.modulus, top.poisson)
        return max(total, (d * sub.compliance) ** 0.25)
