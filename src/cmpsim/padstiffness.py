"""A sparse stand-in for the layered pad's stiffness on the polar grid, and the Newton matrix it makes.

The layered pad's compliance C = c_loc + C_nl (``docs/model.md``, section 13c) is dense on the
grid (:mod:`cmpsim.padinfluence`); its coupled Newton system with the film is solved by GMRES
(:mod:`cmpsim.compliance`). The preconditioner is the same system with 1/C_nl(q) replaced by
the quadratic k0 + b q^2 (:meth:`cmpsim.padstack.LayeredFoundation.stiffness_quadratic`), on the
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

__all__ = ["pad_laplacian", "layer_newton_matrix"]

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
