"""The Newton matrix of the pad-coupled film solve on a polar grid (discretisation floor).

The coupled solve of a compliant pad (:mod:`cmpsim.operators.compliance`) linearises the Reynolds residual
in the slurry unknown and the pad deflection w: S = A + R_w diag(P_phi / K), with
R_w = D_r diag(s_r) I_r + D_a diag(s_a) I_a (the face divergences D and film interpolations I of
:func:`cmpsim.numerics.grid.face_operators`, the face-flux slopes s of the slurry model). This module
fills R_w and S through a map built once per grid instead of sparse triple products; moved out
of :mod:`cmpsim.operators.reynolds`, which keeps the Reynolds operator itself.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import scipy.sparse as sp

from ..numerics.grid import PolarGrid, face_operators
from .reynolds import assembly_map

__all__ = ["coupled_newton_matrices"]

_COUPLING_MAPS: dict = {}

@dataclass(frozen=True)
class _CouplingMap:
    """Fixed sparsity of the coupled Newton matrix on one grid (built once per grid, cached).

    R_w = D_r diag(s_r) I_r + D_a diag(s_a) I_a is linear in the face slopes s = (s_r, s_a):
    its CSR data is ``to_rw @ s``. S = A + R_w diag(v) lives on the union of the patterns of
    the Reynolds operator A (:func:`assembly_map`) and of R_w, at the
    positions ``a_pos`` and ``rw_pos``. Assembling by these maps replaces two sparse triple
    products, a sparse sum and a format conversion per linearisation by one mat-vec and two
    scatters (the same entries, summed in another order).
    """

    to_rw: sp.csr_matrix  # (nnz(R_w), 2 N)
    rw_indices: np.ndarray
    rw_indptr: np.ndarray
    rw_cols: np.ndarray  # column of each R_w entry
    a_indices: np.ndarray  # the pattern of A the map was built for (checked at every use)
    a_indptr: np.ndarray
    a_pos: np.ndarray
    rw_pos: np.ndarray
    s_indices: np.ndarray
    s_indptr: np.ndarray


_COUPLING_MAPS: dict = {}


def _triple_entries(div, interp, offset: int):
    """(row, col, face + offset, weight) of every product D_ik I_kj of div @ diag(s) @ interp."""
    d = div.tocsc()
    d_rows, d_faces = d.indices, np.repeat(np.arange(d.shape[1]), np.diff(d.indptr))
    d_vals = d.data
    it = interp.tocsr()
    count = np.diff(it.indptr)[d_faces]
    start = np.repeat(it.indptr[d_faces], count) + (np.arange(count.sum()) - np.repeat(np.cumsum(count) - count, count))
    return (np.repeat(d_rows, count), it.indices[start], np.repeat(d_faces, count) + offset, np.repeat(d_vals, count) * it.data[start])


def _coupling_map(grid: PolarGrid) -> _CouplingMap:
    cm = _COUPLING_MAPS.get(grid)
    if cm is not None:
        return cm
    ops = face_operators(grid)
    n = grid.size
    parts = [_triple_entries(ops.div_radial, ops.interp_radial, 0), _triple_entries(ops.div_angular, ops.interp_angular, n)]
    rows, cols, faces, wts = (np.concatenate(x) for x in zip(*parts))
    keys, inverse = np.unique(rows.astype(np.int64) * n + cols, return_inverse=True)
    to_rw = sp.csr_matrix((wts, (inverse.ravel(), faces)), shape=(len(keys), 2 * n))
    to_rw.sum_duplicates()
    amap = assembly_map(grid)
    a_keys = np.repeat(np.arange(n, dtype=np.int64), np.diff(amap.indptr)) * n + amap.indices
    s_keys = np.union1d(a_keys, keys)
    cm = _CouplingMap(
        to_rw, (keys % n).astype(np.int32), np.searchsorted(keys // n, np.arange(n + 1)).astype(np.int32),
        (keys % n).astype(np.int64), amap.indices, amap.indptr, np.searchsorted(s_keys, a_keys), np.searchsorted(s_keys, keys),
        (s_keys % n).astype(np.int32), np.searchsorted(s_keys // n, np.arange(n + 1)).astype(np.int32),
    )
    if len(_COUPLING_MAPS) > 16:
        _COUPLING_MAPS.clear()
    _COUPLING_MAPS[grid] = cm
    return cm


def coupled_newton_matrices(grid: PolarGrid, A, s_rad, s_ang, v):
    """(R_w, S = A + R_w diag(v)) of the pad-coupled Newton system, CSR (units of A).

    R_w = D_r diag(s_rad) I_r + D_a diag(s_ang) I_a (:func:`cmpsim.numerics.grid.face_operators`: the
    face divergences D and the film interpolations I; ``s_*`` the face-flux slopes of
    :func:`own_face_fluxes`), A the Reynolds operator of :func:`assemble_operator` and ``v``
    the flat diagonal (P_phi / K in :func:`cmpsim.operators.compliance._linearise`). Assembled through a
    per-grid map; exact zeros are dropped as the sparse sum drops them.
    """
    cm = _coupling_map(grid)
    n = grid.size
    rw_data = cm.to_rw @ np.concatenate([s_rad, s_ang])
    R_w = sp.csr_matrix((rw_data, cm.rw_indices, cm.rw_indptr), shape=(n, n))
    same = np.array_equal(A.indptr, cm.a_indptr) and np.array_equal(A.indices, cm.a_indices)
    if not same:  # not the assembled pattern: the general way
        return R_w, (A + R_w @ sp.diags(v)).tocsr()
    data = np.zeros(cm.s_indices.size)
    data[cm.a_pos] = A.data
    data[cm.rw_pos] += rw_data * v[cm.rw_cols]
    # drop the exact zeros as the sparse sum does (the zero cross-term entries of A would only add fill)
    keep = data != 0.0
    indptr = np.concatenate([[0], np.cumsum(keep)])[cm.s_indptr].astype(np.int32)
    return R_w, sp.csr_matrix((data[keep], cm.s_indices[keep], indptr), shape=(n, n))
