"""The fast assemblies of the coupled pad Newton system against their definitions (issue 23, 3-inch speed).

``own_face_fluxes`` replaces four parity-masked operator assemblies, ``coupled_newton_matrices``
two sparse triple products and a sparse sum; the abrasive law's bisections run on the points
that need them only. Each must give what the definition gives.
"""

import numpy as np
import pytest
import scipy.sparse as sp

from cmpsim.physics.abrasion import interference, pad_gap
from cmpsim.numerics.grid import PolarGrid, face_operators
from cmpsim.operators.coupling import coupled_newton_matrices
from cmpsim.operators.reynolds import FaceCoefficients, assemble_operator, flux_divergence, own_face_fluxes


def _random_coefficients(grid, rng):
    shape = (grid.n_r, grid.n_theta)

    def five():
        return tuple(rng.uniform(0.5, 2.0, shape) * s for s in (1.0, 0.1, 1.0, 0.3, 0.3))

    return FaceCoefficients(five(), five())


@pytest.mark.parametrize("n_r, n_theta", [(3, 8), (8, 24), (11, 34)])
def test_own_face_fluxes_are_the_parity_masked_assemblies(n_r, n_theta):
    grid = PolarGrid(0.0381, n_r, n_theta)
    ops = face_operators(grid)
    rng = np.random.default_rng(n_r * n_theta)
    coeffs = _random_coefficients(grid, rng)
    phi = rng.standard_normal(grid.size)
    zero = tuple(np.zeros((n_r, n_theta)) for _ in range(5))
    want_r, want_a = np.empty(grid.size), np.empty(grid.size)
    for parity in (0, 1):  # a cell's row sees only its own face when its neighbours' faces are masked
        mask = ops.ring_parity == parity
        dc = FaceCoefficients(tuple(a * mask for a in coeffs.radial), zero)
        want_r[mask.ravel()] = (assemble_operator(grid, dc) @ phi + flux_divergence(grid, dc))[mask.ravel()]
        mask = ops.sector_parity == parity
        dc = FaceCoefficients(zero, tuple(a * mask for a in coeffs.angular))
        want_a[mask.ravel()] = (assemble_operator(grid, dc) @ phi + flux_divergence(grid, dc))[mask.ravel()]
    got_r, got_a = own_face_fluxes(grid, coeffs, phi)
    np.testing.assert_allclose(got_r, want_r, rtol=1e-12, atol=1e-14 * np.abs(want_r).max())
    np.testing.assert_allclose(got_a, want_a, rtol=1e-12, atol=1e-14 * np.abs(want_a).max())


@pytest.mark.parametrize("n_r, n_theta", [(3, 8), (8, 24), (11, 34)])
def test_coupled_newton_matrices_are_the_sparse_products(n_r, n_theta):
    grid = PolarGrid(0.0381, n_r, n_theta)
    ops = face_operators(grid)
    rng = np.random.default_rng(7 + n_r)
    A = assemble_operator(grid, _random_coefficients(grid, rng))
    s_rad, s_ang, v = rng.standard_normal((3, grid.size))
    R_w, S = coupled_newton_matrices(grid, A, s_rad, s_ang, v)
    want_R = ops.div_radial @ sp.diags(s_rad) @ ops.interp_radial + ops.div_angular @ sp.diags(s_ang) @ ops.interp_angular
    want_S = (A + want_R @ sp.diags(v)).tocsr()
    assert abs(R_w - want_R).max() <= 1e-14 * abs(want_R).max()
    assert abs(S - want_S).max() <= 1e-14 * abs(want_S).max()
    assert S.nnz == want_S.nnz  # the zero entries dropped as the sparse sum drops them
    # a matrix on another pattern takes the general route and gives the same
    B = sp.random(grid.size, grid.size, density=0.01, random_state=1, format="csr") + sp.eye(grid.size, format="csr")
    assert abs(coupled_newton_matrices(grid, B, s_rad, s_ang, v)[1] - (B + want_R @ sp.diags(v))).max() <= 1e-14 * abs(want_S).max()


def test_the_bisections_on_a_subset_give_each_point_its_own_answer():
    rng = np.random.default_rng(3)
    loads = 10 ** rng.uniform(-13, -3, 400)
    loads[:5] = 0.0
    radius = 10 ** rng.uniform(-8, -6, 400)
    together = interference(loads, radius, 1e11, 1e10, 0.6)
    alone = np.array([interference(f, r, 1e11, 1e10, 0.6) for f, r in zip(loads, radius)])
    # (a scalar and a vector exp or power may differ in the last bit)
    np.testing.assert_allclose(together, alone, rtol=1e-14, atol=0)
    pressures = 10 ** rng.uniform(2, 9, 300)
    x, n = np.array([5e-8, 1e-7, 2e-7]), np.array([1e13, 1e12, 1e11])
    together = pad_gap(pressures, x, n, 5e7)
    alone = np.array([pad_gap(p, x, n, 5e7) for p in pressures])
    np.testing.assert_allclose(together, alone, rtol=1e-14, atol=0)
    assert np.any(together > 0) and np.any(together == 0)  # both branches met
