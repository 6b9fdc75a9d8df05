"""The layered pad on the polar grid: its deflection operator, and a sparse stand-in for its stiffness.

The layered pad's compliance C = c_loc + C_nl (``docs/model.md``, section 13c) is dense on the
grid: :class:`LayerOperator` applies it exactly on the polar cells (the cell integrals of
:mod:`cmpsim.physics.padinfluence`), built once per stack and grid (:func:`layer_operator`,
:func:`layer_deflection`). Its coupled Newton system with the film is solved by GMRES
(:mod:`cmpsim.operators.compliance`). The preconditioner is the same system with 1/C_nl(q) replaced by
the quadratic k0 + b q^2 (:meth:`cmpsim.physics.padstack.LayeredFoundation.stiffness_quadratic`), on the
grid the sparse operator K = k0 I - b L with the finite-volume Laplacian L of the polar cells. Unlike the Winkler bed (K = k0 I), it is stiff in the short waves, as the pad is,
which keeps the preconditioned spectrum clustered where the film is stiff as well (docs/performance.md).

With v the nonlocal deflection (K v = p), w = c_loc p + v and p = P_phi dphi + P_h dw, the
deflection w is eliminated cell by cell (g = 1 / (1 - c_loc P_h)) and the Newton system in
(dphi, v) is sparse:

    [ A + R_w diag(c_loc g P_phi)    R_w diag(g)      ] [dphi]
    [ -diag(g P_phi)                 K - diag(g P_h)  ] [ v  ]
"""

from __future__ import annotations

import numpy as np
import scipy.sparse as sp

from .grid import PolarGrid, face_operators
from ..physics.padinfluence import angular_modes, apply_modes, radial_primitive, ring_influence
from ..physics.padstack import LayeredFoundation

__all__ = ["LayerOperator", "layer_operator", "layer_deflection", "pad_laplacian", "layer_newton_matrix"]

_LAYER_OPERATORS: dict = {}


def layer_operator(foundation: LayeredFoundation, grid: PolarGrid) -> "LayerOperator":
    """The deflection operator of the nonlocal part of ``foundation`` on ``grid`` (built once, cached)."""
    key = (foundation, grid)
    op = _LAYER_OPERATORS.get(key)
    if op is None:
        if len(_LAYER_OPERATORS) > 8:
            _LAYER_OPERATORS.clear()
        op = _LAYER_OPERATORS[key] = LayerOperator(foundation, grid)
    return op


def layer_deflection(foundation: LayeredFoundation, pressure, grid: PolarGrid) -> np.ndarray:
    """Deflection (m) at the cell centres of ``grid`` under a cell pressure field (Pa): local plus nonlocal part."""
    p = np.asarray(pressure, dtype=float)
    return (foundation.local_compliance * p.ravel() + layer_operator(foundation, grid).apply(p)).reshape(p.shape)



_LAPLACIANS: dict = {}


def pad_laplacian(grid: PolarGrid, outside: float) -> sp.csr_matrix:
    """Finite-volume Laplacian (1/m^2) of a cell field on the polar grid, the field decaying to zero
    ``outside`` (m) beyond the wafer edge (a plate on a foundation continues past the rim); cached."""
    key = (grid, outside)
    L = _LAPLACIANS.get(key)
    if L is not None:
        return L
    ops = face_operators(grid)
    r = grid.r[:, 0]
    faces = grid.ring_faces[1:]
    dist = np.append(np.diff(r), grid.radius - r[-1] + outside)
    c_r = np.repeat(faces * grid.dtheta / dist, grid.n_theta)
    c_a = np.repeat(grid.widths[:, 0] / (r * grid.dtheta), grid.n_theta)
    flux = -(ops.div_radial @ sp.diags(c_r) @ ops.div_radial.T) - (ops.div_angular @ sp.diags(c_a) @ ops.div_angular.T)
    L = (sp.diags(1.0 / grid.area.ravel()) @ flux).tocsr()
    if len(_LAPLACIANS) > 8:
        _LAPLACIANS.clear()
    _LAPLACIANS[key] = L
    return L


def layer_newton_matrix(A, R_w, P_phi, P_h, local_compliance: float, quadratic, laplacian) -> tuple[sp.csc_matrix, np.ndarray]:
    """The sparse (dphi, v) Newton matrix of the module docstring (2 N x 2 N, CSC), and g.

    ``A``: dR/dphi; ``R_w``: dR/dw; ``P_phi``, ``P_h``: the pad pressure's derivatives (flat);
    ``local_compliance``: c_loc (m/Pa); ``quadratic``: (k0, b); ``laplacian``: :func:`pad_laplacian`.
    """
    k0, b = quadratic
    n = P_phi.size
    g = 1.0 / (1.0 - local_compliance * P_h)
    K = sp.identity(n, format="csr") * k0 - b * laplacian
    top = sp.hstack([A + R_w @ sp.diags(local_compliance * g * P_phi), R_w @ sp.diags(g)])
    bottom = sp.hstack([sp.diags(-g * P_phi), K - sp.diags(g * P_h)])
    return sp.vstack([top, bottom]).tocsc(), g


class LayerOperator:
    """Deflection of the nonlocal compliance at the polar cell centres: exact cell integrals of its kernel.

    The pressure is uniform in each cell; the deflection at the centre of cell i is
    Σ_j K_ij p_j with K_ij the integral over cell j of the radial kernel G(|x_i - x'|) of
    C(q) (:mod:`cmpsim.physics.padinfluence`: boundary integrals of the kernel's radial primitive,
    tabulated once from C(q) by quadrature in q). The rings may be equal or edge-graded: every
    cell is integrated on its own extent, so the rim rings of a graded grid are resolved as
    they are. K is block-circulant over the sectors, applied by a real FFT over them and one
    n_r x n_r matrix per angular mode. The pad outside the wafer carries no load (the
    retaining ring's load is added by the carrier, :meth:`~cmpsim.physics.padstack.LayeredFoundation.annulus_deflection`).
    """

    #: C(q) is integrated to q = _Q_TOP / (thinnest layer), where the plate term has cut it by
    #: about 10^7 (two layers) or where a single layer is a half space to round-off (its 2/(E* q)
    #: tail is added in closed form); the kernel's near field is tabulated to _REACH coupling
    #: lengths, where it has decayed below 10^-9 of C(0) (docs/model.md, section 13c).
    _Q_TOP = 40.0
    _REACH = 40.0

    def __init__(self, foundation: LayeredFoundation, grid: PolarGrid):
        layers = foundation.layers
        t_min = min(layer.thickness for layer in layers)
        tail = 0.0
        if len(layers) == 1:  # C = 1 / K(q) -> 2 / (E* q): a half space beyond qt = 40
            tail = 2.0 * (1.0 - layers[0].poisson ** 2) / layers[0].modulus
        length = foundation.coupling_length
        self.shape = (grid.n_r, grid.n_theta)
        near, self.reach = radial_primitive(
            foundation.nonlocal_compliance, self._Q_TOP / t_min, min(2.0 * grid.radius, self._REACH * length), length, tail=tail
        )
        c0 = float(foundation.nonlocal_compliance(np.array([0.0]))[0])
        self.modes = angular_modes(ring_influence(near, self.reach, c0, grid.ring_faces, grid.n_theta))

    def apply(self, pressure) -> np.ndarray:
        """Nonlocal deflection (m, flat, cell order) of a polar cell pressure field (Pa)."""
        return apply_modes(self.modes, np.asarray(pressure, dtype=float).reshape(self.shape)).ravel()
