"""The guarded sparse LU (cmpsim.numerics.sparse): ordering kept, residual checked, partial pivoting as fall-back."""

import logging

import numpy as np
import scipy.sparse as sp

from cmpsim import Config
from cmpsim.solver.equilibrium import solve_equilibrium
from cmpsim.solver.model import build_problem, physical_setup
from cmpsim.numerics.sparse import BACKWARD_ERROR_LIMIT, FALLBACKS, GuardedFactor, backward_error, factorize


def _coupled_fills(config):
    """(largest fill, n) over the factorisations of one equilibrium of ``config``."""
    factors = []

    def recording(A):
        f = factorize(A)
        factors.append(f)
        return f

    problem = build_problem(config, physical_setup(config))
    problem.solver = recording
    solve_equilibrium(problem, tol=config.tolerance, max_iter=config.max_iterations)
    assert factors and all(f.pivoting == "diagonal" for f in factors)
    assert max(f.last_backward_error for f in factors) < 1e-13
    return max(f.fill for f in factors), problem.grid.size


def test_the_fill_of_the_300mm_coupled_system_stays_that_of_the_3_inch_one():
    """Partial pivoting filled 0.94 M for n = 1536 at 300 mm (16x the 3-inch 57 k); keeping the
    minimum-degree ordering, the fill per unknown is the same at both sizes (issue 23)."""
    small, n_small = _coupled_fills(Config.default().replace(grid="24x64"))
    large, n_large = _coupled_fills(Config.default().replace(grid="24x64", wafer_diameter=0.3, centre_distance=0.2))
    assert n_small == n_large == 1536
    assert large <= 1.5 * small, (small, large)
    assert large < 100_000  # 0.94 M with partial pivoting
    # and on the default (edge-graded) grids, per unknown
    small, n_small = _coupled_fills(Config.default())
    large, n_large = _coupled_fills(Config.default().replace(wafer_diameter=0.3, centre_distance=0.2))
    assert large / n_large <= 1.5 * small / n_small, (small / n_small, large / n_large)


def _needs_pivoting(n=200, tiny=1e-14):
    """Block-diagonal 2x2 [[tiny, 1], [1, tiny]]: without row swaps the elimination grows by 1/tiny."""
    blocks = [sp.csr_matrix([[tiny, 1.0], [1.0, tiny]]) for _ in range(n // 2)]
    return sp.block_diag(blocks, format="csc")


def test_a_matrix_that_needs_pivoting_falls_back_and_says_so(caplog):
    A = _needs_pivoting()
    b = np.arange(A.shape[0], dtype=float) + 1.0
    before = FALLBACKS["partial_pivoting"]
    f = GuardedFactor(A)
    assert f.pivoting == "diagonal"
    # what the unguarded diagonal-pivot solve would give: far above the limit
    assert backward_error(A, f._lu.solve(b), b) > 1e3 * BACKWARD_ERROR_LIMIT
    with caplog.at_level(logging.WARNING, logger="cmpsim.numerics.sparse"):
        x = f.solve(b)
    assert f.pivoting == "partial" and "backward error" in f.fallback_reason
    assert FALLBACKS["partial_pivoting"] == before + 1
    assert any("fell back to partial pivoting" in r.message for r in caplog.records)
    assert backward_error(A, x, b) < 1e-15
    np.testing.assert_allclose(A @ x, b, rtol=1e-12)


def test_a_zero_diagonal_falls_back_too():
    A = sp.csc_matrix(np.array([[0.0, 1.0, 0.0], [1.0, 0.0, 1.0], [0.0, 1.0, 1.0]]))
    b = np.array([1.0, 2.0, 3.0])
    x = GuardedFactor(A).solve(b)
    np.testing.assert_allclose(A @ x, b, rtol=1e-14)


def test_a_diagonally_dominant_system_keeps_its_ordering_and_takes_several_columns():
    rng = np.random.default_rng(1)
    n = 300
    A = sp.random(n, n, density=0.02, random_state=2, format="csc")
    A = (A + A.T + sp.diags(np.asarray(abs(A).sum(axis=1)).ravel() * 2 + 1.0)).tocsc()
    B = rng.standard_normal((n, 3))
    f = GuardedFactor(A)
    X = f.solve(B)
    assert f.pivoting == "diagonal" and f.fallback_reason is None
    assert f.last_backward_error < 1e-15
    np.testing.assert_allclose(A @ X, B, atol=1e-12)
