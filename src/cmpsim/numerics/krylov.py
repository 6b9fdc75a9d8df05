"""Unrestarted GMRES for the layered pad's coupled Newton steps (a pure numerical kernel).

Kept hand-written, not ``scipy.sparse.linalg.gmres``, because the benchmark
``benchmarks/bench_house.py`` measured scipy's 1.16-1.24x slower on this problem (docstring below).
Moved out of :mod:`cmpsim.operators.compliance`, which calls it as ``_gmres``.
"""

from __future__ import annotations

import numpy as np
from scipy.linalg import solve_triangular

__all__ = ["gmres"]


def gmres(matvec, b, x0, rtol: float, max_iter: int) -> np.ndarray:
    """Solve M x = b by GMRES without restart (classical Gram-Schmidt applied twice, Givens rotations).

    Kept hand-written because the library's is slower on this problem:
    ``scipy.sparse.linalg.gmres(restart=max_iter, maxiter=1)`` (the same algorithm, scipy 1.17)
    took 1.16-1.24x the time of this function on the Newton systems of the layered pad
    (``benchmarks/bench_house.py``, 21 systems of one equilibrium at the paper's base case,
    default grid, best of 5-7, three runs; the steps agree to 5e-15): its Givens rotations index
    the Hessenberg matrix with fancy indexing at every inner step, which costs more than the
    preconditioned mat-vecs of these well-clustered systems (30-100 iterations).
    Raises ValueError if the relative residual is not below ``rtol`` after ``max_iter``.
    """
    r = b - matvec(x0)
    beta = np.linalg.norm(r)
    target = rtol * np.linalg.norm(b)
    if beta <= target:
        return x0
    V = np.empty((max_iter + 1, b.size))
    H = np.zeros((max_iter + 1, max_iter))
    cs, sn = np.zeros(max_iter), np.zeros(max_iter)
    g = np.zeros(max_iter + 1)
    g[0] = beta
    V[0] = r / beta
    for j in range(max_iter):
        w = matvec(V[j])
        # classical Gram-Schmidt twice (BLAS-2 products; as accurate as modified Gram-Schmidt)
        h = V[: j + 1] @ w
        w -= h @ V[: j + 1]
        h2 = V[: j + 1] @ w
        w -= h2 @ V[: j + 1]
        H[: j + 1, j] = h + h2
        H[j + 1, j] = np.linalg.norm(w)
        breakdown = H[j + 1, j] == 0.0  # the Krylov space is invariant: the solution is in it
        if not breakdown:
            V[j + 1] = w / H[j + 1, j]
        for i in range(j):  # apply the earlier rotations to the new column
            a, c = H[i, j], H[i + 1, j]
            H[i, j], H[i + 1, j] = cs[i] * a + sn[i] * c, -sn[i] * a + cs[i] * c
        rho = np.hypot(H[j, j], H[j + 1, j])
        cs[j], sn[j] = H[j, j] / rho, H[j + 1, j] / rho
        H[j, j], H[j + 1, j] = rho, 0.0
        g[j + 1] = -sn[j] * g[j]
        g[j] = cs[j] * g[j]
        if abs(g[j + 1]) <= target or breakdown:
            break
    else:
        if abs(g[max_iter]) > 1e-6 * beta:
            raise ValueError(f"GMRES on the layered pad did not converge (relative residual {abs(g[max_iter]) / beta:.2g})")
    m = j + 1
    y = solve_triangular(H[:m, :m], g[:m])
    return x0 + y @ V[:m]
