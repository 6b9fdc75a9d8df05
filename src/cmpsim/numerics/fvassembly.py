"""Finite-volume assembly of the Reynolds operator on the polar wafer grid (:mod:`cmpsim.operators.reynolds`).

Conservative cell-centred finite volumes on :class:`cmpsim.numerics.grid.PolarGrid`: two-point normal
gradients, cross-gradient (off-diagonal tensor) terms from averaged central differences, the
Dirichlet edge at half a cell from the last centres (``docs/model.md``, "Reynolds equation").
The operator's entries, the face fluxes and their divergence are linear maps of the face
coefficients (:class:`FaceCoefficients`, computed by :func:`cmpsim.operators.reynolds.lubrication_coefficients`),
precomputed once per grid; a grooved pad's venting sink (``docs/model.md``, "Grooved pad") is one
more such map onto the diagonal. Split from :mod:`cmpsim.operators.reynolds`, which keeps the coefficients
and the solve and re-exports the public names of this module.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import scipy.sparse as sp

from .grid import PolarGrid

__all__ = [
    "FaceCoefficients",
    "assemble_operator",
    "face_fluxes",
    "flux_divergence",
    "own_face_fluxes",
    "assembly_map",
    "venting_map",
    "venting_film_matrices",
]


@dataclass
class FaceCoefficients:
    """Diffusion tensor (D_xx, D_xy, D_yy; m^3/s) and flux vector (q_x, q_y; m^2/s) on faces.

    ``radial`` and ``angular`` hold 5-tuples (dxx, dxy, dyy, qx, qy) of arrays shaped like
    the grid; ``floored`` counts faces whose flow-factor tensor was regularised. ``venting``
    (kappa^2, 1/m^2; 0 = ungrooved pad) adds the grooves' sink g kappa^2 phi of each cell to the
    operator (:func:`assemble_operator`), g the cell's conductance (:func:`venting_map`).
    """

    radial: tuple
    angular: tuple
    floored: int = 0
    n_faces: int = 0
    venting: float = 0.0


def _polar_components(dxx, dxy, dyy, theta_n):
    """Components of D in the (n, t) frame with normal at angle theta_n: (D_nn, D_nt)."""
    c, s = np.cos(theta_n), np.sin(theta_n)
    d_nn = c * c * dxx + 2.0 * s * c * dxy + s * s * dyy
    # t = e_theta = (-s, c)
    d_nt = -s * c * dxx + (c * c - s * s) * dxy + s * c * dyy
    return d_nn, d_nt


def _operator_entries(grid: PolarGrid):
    """The operator's entries as linear functions of the polar tensor components on the faces.

    Returns ``(rows, cols, src, weight)``: entry k adds ``weight[k] * c[src[k]]`` to
    ``A[rows[k], cols[k]]``, where ``c`` stacks, each flattened like the grid, D_rr and D_rt
    on the radial faces and D_tt and D_tr on the angular ones (4 N values). Geometry only.
    """
    n_r, n_t, dth, N = grid.n_r, grid.n_theta, grid.dtheta, grid.size
    gap = np.broadcast_to(grid.spacings, (n_r, n_t))  # centre to next centre (last: to the rim)
    rows, cols, src, wts = [], [], [], []
    i = np.arange(n_r)[:, None] * np.ones((1, n_t), dtype=int)
    j = np.arange(n_t)[None, :] * np.ones((n_r, 1), dtype=int)
    P = grid.index(i, j)

    def add(p, n, col, s, w):
        # +w c[s] in row p, -w c[s] in row n (the flux leaves p and enters n), column col
        for row, sign in ((p, 1.0), (n, -1.0)):
            if row is None:
                continue
            rows.append(row.ravel())
            cols.append(col.ravel())
            src.append(s.ravel())
            wts.append(sign * np.broadcast_to(w, row.shape).ravel())

    # ---- radial faces (outer face of each cell): c[0:N] = D_rr, c[N:2N] = D_rt
    _, _, length = grid.radial_faces
    rf = np.broadcast_to(grid.ring_faces[1:, None], (n_r, n_t))
    interior = i < n_r - 1
    Pi, Ni = P[interior], grid.index(i[interior] + 1, j[interior])
    Li = length[interior]
    add(Pi, Ni, Ni, Pi, -Li / gap[interior])
    add(Pi, Ni, Pi, Pi, Li / gap[interior])
    ii, jj = i[interior], j[interior]
    wt = -Li / (4.0 * dth * rf[interior])
    for di in (0, 1):
        add(Pi, Ni, grid.index(ii + di, jj + 1), Pi + N, wt)
        add(Pi, Ni, grid.index(ii + di, jj - 1), Pi + N, -wt)
    edge = ~interior
    Pe = P[edge]
    add(Pe, None, Pe, Pe, length[edge] / gap[edge])

    # ---- angular faces (counter-clockwise face of each cell): c[2N:3N] = D_tt, c[3N:4N] = D_tr
    La = np.broadcast_to(grid.widths, P.shape)
    Nb = grid.index(i, j + 1)
    r_c = np.broadcast_to(grid.r, P.shape)
    add(P, Nb, Nb, P + 2 * N, -La / (r_c * dth))
    add(P, Nb, P, P + 2 * N, La / (r_c * dth))
    for jj_shift in (0, 1):
        sel = np.roll(np.arange(n_t), -jj_shift)  # cell (i, j + shift)
        for c_arr, w_arr in grid.radial_derivative_stencil:
            add(P, Nb, c_arr[:, sel], P + 3 * N, -0.5 * w_arr[:, sel] * La)
    return (np.concatenate(rows), np.concatenate(cols), np.concatenate(src), np.concatenate(wts))


@dataclass(frozen=True)
class _AssemblyMap:
    """Precomputed map from the stacked polar components (4 N) to the CSR data of the operator."""

    to_data: sp.csr_matrix  # (nnz, 4 N)
    indices: np.ndarray
    indptr: np.ndarray
    cos_r: np.ndarray  # direction cosines of the radial-face normals (theta_j)
    sin_r: np.ndarray
    cos_a: np.ndarray  # of the angular-face normals (theta_{j+1/2} + pi/2)
    sin_a: np.ndarray


_MAPS: dict = {}


def assembly_map(grid: PolarGrid) -> _AssemblyMap:
    """The :class:`_AssemblyMap` of a grid (built once per grid, vectorised, and cached)."""
    amap = _MAPS.get(grid)
    if amap is not None:
        return amap
    N = grid.size
    rows, cols, src, wts = _operator_entries(grid)
    keys, inverse = np.unique(rows.astype(np.int64) * N + cols, return_inverse=True)
    indptr = np.searchsorted(keys // N, np.arange(N + 1)).astype(np.int32)
    to_data = sp.csr_matrix((wts, (inverse.ravel(), src)), shape=(len(keys), 4 * N))
    to_data.sum_duplicates()
    theta = np.broadcast_to(grid.theta, (grid.n_r, grid.n_theta))
    theta_f = np.broadcast_to((np.arange(grid.n_theta) + 1.0)[None, :] * grid.dtheta + 0.5 * np.pi, theta.shape)
    amap = _AssemblyMap(
        to_data, (keys % N).astype(np.int32), indptr, np.cos(theta), np.sin(theta), np.cos(theta_f), np.sin(theta_f)
    )
    if len(_MAPS) > 16:
        _MAPS.clear()
    _MAPS[grid] = amap
    return amap


@dataclass(frozen=True)
class _VentingMap:
    """The cell conductance of the grooves' sink as a linear map of the stacked face components."""

    to_cells: sp.csr_matrix  # (N, 4 N): area_P g_P, m^2 x (m^3/s or m^4/(Pa s))
    diagonal: np.ndarray  # position of each diagonal entry A[P, P] in the CSR data of the operator


_VENT_MAPS: dict = {}


def venting_map(grid: PolarGrid) -> _VentingMap:
    """The map c -> area_P g_P of a grid (built once per grid, cached), with the operator's diagonal positions.

    g_P, the cell's isotropic conductance, is the mean of the radial conductance D_rr on its
    radial faces (the outer one, and the inner one off the centre) and of the angular one D_tt
    on its two angular faces, averaged: (D_rr + D_tt) / 2 = trace(D) / 2 at second order.
    """
    vm = _VENT_MAPS.get(grid)
    if vm is not None:
        return vm
    N = grid.size
    i, j = (a.ravel() for a in np.indices((grid.n_r, grid.n_theta)))
    P = np.arange(N)  # = grid.index(i, j)
    area = grid.area.ravel()
    n_radial = np.where(i > 0, 2.0, 1.0)  # the centre's cells have no inner face
    rows = [P, P[i > 0], P, P]
    src = [P, grid.index(i[i > 0] - 1, j[i > 0]), 2 * N + P, 2 * N + grid.index(i, j - 1)]
    wts = [0.5 * area / n_radial, 0.5 * area[i > 0] / 2.0, 0.25 * area, 0.25 * area]
    to_cells = sp.csr_matrix((np.concatenate(wts), (np.concatenate(rows), np.concatenate(src))), shape=(N, 4 * N))
    amap = assembly_map(grid)
    rows_a = np.repeat(np.arange(N), np.diff(amap.indptr))
    diagonal = np.flatnonzero(rows_a == amap.indices)
    if diagonal.size != N:
        raise RuntimeError("the Reynolds operator's pattern lacks diagonal entries")  # pragma: no cover (geometry)
    vm = _VentingMap(to_cells, diagonal)
    if len(_VENT_MAPS) > 16:
        _VENT_MAPS.clear()
    _VENT_MAPS[grid] = vm
    return vm


def venting_film_matrices(grid: PolarGrid, dcoeffs: FaceCoefficients, phi, venting: float):
    """(V_r, V_a): change of each cell's venting sink per unit change of the film on the radial / angular faces.

    The sink of cell P is kappa^2 area_P g_P phi_P (m^3/s; :func:`venting_map`), with g_P linear in
    its faces' conductances; ``dcoeffs`` holds their derivatives in the film on each face (per m),
    so V_r[P, f] = kappa^2 phi_P d(area_P g_P)/dh_f (m^3/s per m, sparse N x N each). The part of the
    pad-coupled Newton matrix the face-flux slopes (:func:`own_face_fluxes`) do not hold.
    """
    N = grid.size
    vm = venting_map(grid)
    dc = _stacked_components(assembly_map(grid), dcoeffs)
    scale = sp.diags(venting * np.asarray(phi, dtype=float).ravel())
    return (
        (scale @ vm.to_cells[:, :N] @ sp.diags(dc[:N])).tocsr(),
        (scale @ vm.to_cells[:, 2 * N : 3 * N] @ sp.diags(dc[2 * N : 3 * N])).tocsr(),
    )


def _stacked_components(amap: _AssemblyMap, coeffs: FaceCoefficients) -> np.ndarray:
    c, s = amap.cos_r, amap.sin_r
    dxx, dxy, dyy = coeffs.radial[:3]
    d_rr = c * c * dxx + 2.0 * s * c * dxy + s * s * dyy
    d_rt = -s * c * dxx + (c * c - s * s) * dxy + s * c * dyy
    c, s = amap.cos_a, amap.sin_a
    dxx, dxy, dyy = coeffs.angular[:3]
    d_tt = c * c * dxx + 2.0 * s * c * dxy + s * s * dyy
    # D_tr with n = e_theta, t = -e_r: the sign flip gives e_theta . D . e_r
    d_tr = -(-s * c * dxx + (c * c - s * s) * dxy + s * c * dyy)
    return np.concatenate([d_rr.ravel(), d_rt.ravel(), d_tt.ravel(), d_tr.ravel()])


def assemble_operator(grid: PolarGrid, coeffs: FaceCoefficients) -> sp.csr_matrix:
    """Matrix A with (A phi)_P = sum over faces of P of the outward flux -D grad(phi) . n L.

    For a symmetric positive-definite D it is an M-matrix (without cross terms), singular
    only without the Dirichlet edge. Units: m^3/s (flux per unit phi). The entries are a
    linear map of the face tensors, precomputed once per grid (:func:`assembly_map`): one
    sparse mat-vec per assembly. A grooved pad (``coeffs.venting`` = kappa^2 > 0) adds the
    sink kappa^2 area_P g_P to the diagonal (:func:`venting_map`; ``docs/model.md``, "Grooved
    pad"), still linear in the face tensors.
    """
    amap = assembly_map(grid)
    c = _stacked_components(amap, coeffs)
    data = amap.to_data @ c
    if coeffs.venting:
        vm = venting_map(grid)
        data[vm.diagonal] += coeffs.venting * (vm.to_cells @ c)
    N = grid.size
    return sp.csr_matrix((data, amap.indices, amap.indptr), shape=(N, N), copy=False)


def face_fluxes(grid: PolarGrid, coeffs: FaceCoefficients) -> tuple[np.ndarray, np.ndarray]:
    """Integrated flux q . n L through each cell's faces, m^3/s, each of shape (n_r, n_theta).

    Returns ``(fr, fa)``: ``fr[i, j]`` through the outer radial face of cell (i, j) (outward
    from it; for the last ring, out of the wafer), ``fa[i, j]`` through its counter-clockwise
    angular face (towards cell (i, j + 1)).
    """
    n_t = grid.n_theta
    qx, qy = coeffs.radial[3:5]
    # integral of the outward normal over the arc r = r_f, |theta - theta_j| < dtheta/2 is
    # 2 r_f sin(dtheta/2) e_r(theta_j): with it the normals of a cell sum exactly to zero, so
    # a uniform flux field has exactly zero divergence (free-stream preservation)
    rf = grid.ring_faces[1:, None]
    lr = 2.0 * rf * np.sin(0.5 * grid.dtheta)
    c, s = np.cos(grid.theta), np.sin(grid.theta)
    fr = (qx * c + qy * s) * lr  # outward through the outer face of (i, j)
    qx, qy = coeffs.angular[3:5]
    tf = (np.arange(n_t) + 1.0)[None, :] * grid.dtheta
    fa = (-qx * np.sin(tf) + qy * np.cos(tf)) * grid.widths  # through the ccw face of (i, j)
    return fr, fa


def flux_divergence(grid: PolarGrid, coeffs: FaceCoefficients) -> np.ndarray:
    """Sum over the faces of each cell of the outward flux q . n L, m^3/s, shape (size,)."""
    fr, fa = face_fluxes(grid, coeffs)
    div = fr.copy()
    div[1:, :] -= fr[:-1, :]
    div += fa - np.roll(fa, 1, axis=1)
    return div.ravel()


_OWN_FACES: dict = {}


def _own_face_entries(grid: PolarGrid):
    """The entries of :func:`_operator_entries` that give a cell's flux through its own faces
    (row = the face's cell): (face, src, col, weight, radial?)."""
    own = _OWN_FACES.get(grid)
    if own is None:
        N = grid.size
        rows, cols, src, wts = _operator_entries(grid)
        keep = rows == src % N
        src = src[keep]
        own = (src % N, src, cols[keep], wts[keep], src < 2 * N)
        if len(_OWN_FACES) > 16:
            _OWN_FACES.clear()
        _OWN_FACES[grid] = own
    return own


def own_face_fluxes(grid: PolarGrid, coeffs: FaceCoefficients, phi) -> tuple[np.ndarray, np.ndarray]:
    """Outward flux (m^3/s) of the field ``phi`` through each cell's own faces, flat (size,) each.

    ``(radial, angular)``: through the outer radial face and the counter-clockwise angular face
    of each cell, -D grad(phi) . n L + q . n L with the face coefficients ``coeffs``: the terms
    of the cell's row of A phi + :func:`flux_divergence` that belong to those faces. With
    coefficient derivatives in ``coeffs`` these are the face-flux slopes of the coupled pad solve.
    """
    amap = assembly_map(grid)
    N = grid.size
    face, src, col, wts, radial = _own_face_entries(grid)
    terms = wts * _stacked_components(amap, coeffs)[src] * np.asarray(phi, dtype=float).ravel()[col]
    fr, fa = face_fluxes(grid, coeffs)
    rad = np.bincount(face[radial], terms[radial], minlength=N) + fr.ravel()
    ang = np.bincount(face[~radial], terms[~radial], minlength=N) + fa.ravel()
    return rad, ang
