"""Sparse direct solves that keep their fill-reducing ordering, guarded by the residual.

Every sparse factorisation of cmpsim goes through :func:`factorize` (``docs/model.md``,
section "Sparse factorisation"). SuperLU's default partial pivoting (``diag_pivot_thresh =
1``) swaps rows whenever a diagonal entry is smaller than the largest below it, and so throws
away the minimum-degree ordering of A^T + A as soon as the operator loses diagonal dominance:
the coupled pad system of a 300 mm wafer (min |a_ii| / sum_j |a_ij| = 0.001) filled 0.93 M
entries for n = 1536 (20x the 3-inch one) and took 90 ms a factorisation instead of 2 ms.

:func:`factorize` therefore factors in SuperLU's symmetric mode with diagonal pivots
(``diag_pivot_thresh = 0``, ``SymmetricMode``): the ordering is kept, the fill is that of the
symmetric pattern. Without pivoting the elimination may grow, so the solves are checked: the
normwise backward error ``|A x - b|_inf / (|A|_inf |x|_inf + |b|_inf)`` (Higham, *Accuracy and
Stability of Numerical Algorithms*, 2002, eq. 7.23) of the first solve with a factor must stay
below :data:`BACKWARD_ERROR_LIMIT` (the growth of an elimination is a property of the factors,
not of the right-hand side: one solve shows it, and checking every solve cost 6 % of a
coupled equilibrium). A solve that exceeds it (or a zero pivot) makes the factor
refactorise once with partial pivoting (scipy's default) and solve again; the fall-back is
logged (logger ``cmpsim.numerics.sparse``, level WARNING), counted in :data:`FALLBACKS` and kept on the
factor (``.pivoting``, ``.fallback_reason``), never silent.
"""

from __future__ import annotations

import logging

import numpy as np
import scipy.sparse as sp
import scipy.sparse.linalg as spla

__all__ = ["BACKWARD_ERROR_LIMIT", "FALLBACKS", "SUPERNODES", "GuardedFactor", "factorize", "backward_error"]

#: Largest normwise backward error accepted from a solve without row pivoting, about 1e6 x the
#: unit round-off: the coupled systems measure 1e-16 to 1e-14 without pivoting (``tests/test_sparse.py``).
BACKWARD_ERROR_LIMIT = 1e-10

#: ``FALLBACKS["partial_pivoting"]``: how many factorisations of this process fell back to partial pivoting.
FALLBACKS = {"partial_pivoting": 0}

#: The fill-reducing column ordering: the operators have a symmetric pattern, so a minimum
#: degree of A^T + A fills least (3x faster than the default COLAMD on the default grid).
ORDERING = "MMD_AT_PLUS_A"

#: SuperLU's supernode relaxation and panel size for the diagonal-pivot factorisation: small
#: panels suit the narrow supernodes of these 2-D five- and nine-point operators. Measured on the
#: coupled pad matrices (3 in, 24x64 and fine 64x124; 300 mm fine) and the paper preset's
#: Reynolds operator (24x64, 96x256): 12-25 % less time per factorisation than scipy's
#: defaults (SuperLU's ``sp_ienv``), the same ordering and fill (benchmarks/README.md, bench_scale).
SUPERNODES = {"relax": 1, "panel_size": 4}

_LOG = logging.getLogger(__name__)


def backward_error(matrix, x, b, matrix_norm: float | None = None) -> float:
    """Normwise backward error of ``x`` as a solution of ``matrix @ x = b`` (dimensionless).

    ``|A x - b|_inf / (|A|_inf |x|_inf + |b|_inf)``, the largest over the columns of ``b``
    (Higham 2002, eq. 7.23); ``matrix_norm`` is |A|_inf if already known. Zero for x = b = 0.
    """
    x = np.asarray(x, dtype=float)
    b = np.asarray(b, dtype=float)
    if matrix_norm is None:
        matrix_norm = float(abs(matrix).sum(axis=1).max())
    r = matrix @ x - b
    num = np.max(np.abs(r), axis=0)
    den = matrix_norm * np.max(np.abs(x), axis=0) + np.max(np.abs(b), axis=0)
    err = np.where(den > 0, num / np.where(den > 0, den, 1.0), np.where(num > 0, np.inf, 0.0))
    return float(np.max(err)) if np.all(np.isfinite(x)) else float("inf")


class GuardedFactor:
    """LU factorisation of a sparse square matrix with ``.solve(b)``, ordering kept, residual guarded.

    Parameters
    ----------
    matrix : scipy sparse matrix
        The system matrix (any unit); converted to CSC.
    limit : float
        Backward error above which a solve falls back to partial pivoting (default
        :data:`BACKWARD_ERROR_LIMIT`).

    Attributes
    ----------
    pivoting : str
        ``"diagonal"`` (ordering kept) or ``"partial"`` (after a fall-back).
    fallback_reason : str or None
        Why the factor fell back (backward error, or a zero pivot), None if it did not.
    last_backward_error : float
        Backward error of the first solve (NaN before it).
    """

    def __init__(self, matrix, limit: float = BACKWARD_ERROR_LIMIT):
        self.matrix = sp.csc_matrix(matrix)
        self.limit = float(limit)
        self.fallback_reason: str | None = None
        self.last_backward_error = float("nan")
        self._checked = False
        self._norm = float(abs(self.matrix).sum(axis=1).max()) if self.matrix.nnz else 0.0
        try:
            self._lu = spla.splu(
                self.matrix, permc_spec=ORDERING, diag_pivot_thresh=0.0, options={"SymmetricMode": True}, **SUPERNODES
            )
            self.pivoting = "diagonal"
        except RuntimeError as exc:  # a zero pivot on the diagonal
            self._fall_back(f"diagonal pivoting failed ({exc})")

    def _fall_back(self, reason: str) -> None:
        self._lu = spla.splu(self.matrix, permc_spec=ORDERING)
        self.pivoting = "partial"
        self.fallback_reason = reason
        FALLBACKS["partial_pivoting"] += 1
        _LOG.warning("sparse LU of an n = %d system fell back to partial pivoting: %s", self.matrix.shape[0], reason)

    @property
    def fill(self) -> int:
        """Entries of the factors, nnz(L) + nnz(U)."""
        return int(self._lu.L.nnz + self._lu.U.nnz)

    def solve(self, b) -> np.ndarray:
        """x with ``matrix @ x = b`` (b flat or with columns); the first solve is guarded by its backward error."""
        x = self._lu.solve(b)
        if self._checked:
            return x
        err = backward_error(self.matrix, x, b, self._norm)
        if self.pivoting == "diagonal" and not err <= self.limit:
            self._fall_back(f"backward error {err:.2e} > {self.limit:.0e} without row pivoting")
            x = self._lu.solve(b)
            err = backward_error(self.matrix, x, b, self._norm)
        self.last_backward_error = err
        self._checked = True
        return x


def factorize(matrix) -> GuardedFactor:
    """The sparse direct solver of cmpsim: :class:`GuardedFactor` of ``matrix`` (``.solve(b)``)."""
    return GuardedFactor(matrix)
