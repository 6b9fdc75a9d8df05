"""Verification of the polar finite-volume Reynolds solver: manufactured solutions and exact cases."""

import numpy as np
import pytest
import sympy

from cmpsim.numerics.grid import PolarGrid
from cmpsim.operators.reynolds import FaceCoefficients, ReynoldsSystem, assemble_operator
from cmpsim.testing.checks import manufactured_errors

R = 0.0381
X, Y = sympy.symbols("x y")


def _manufactured(anisotropy: float):
    """phi = 0 on r = R, variable SPD tensor D, source -div(D grad phi)."""
    phi = (1 - (X**2 + Y**2) / R**2) * sympy.exp(X / R) * (1 + sympy.Rational(1, 2) * sympy.sin(3 * Y / R))
    dxx = 1 + X / (2 * R) + (Y / R) ** 2 / 5
    dyy = 2 + 3 * Y / (10 * R)
    dxy = anisotropy * (sympy.Rational(3, 10) + X / (10 * R))
    fx = dxx * sympy.diff(phi, X) + dxy * sympy.diff(phi, Y)
    fy = dxy * sympy.diff(phi, X) + dyy * sympy.diff(phi, Y)
    src = -(sympy.diff(fx, X) + sympy.diff(fy, Y))
    return sympy.lambdify((X, Y), [dxx, dxy, dyy, src, phi], "numpy")


def _solve_mms(fun, n, edge_ratio=1.0):
    """Errors (max, L2) on n rings x 4n sectors; ``edge_ratio`` > 1: rings graded towards the edge (rim
    rings edge_ratio times narrower, widening over R/4), the same map at every n."""
    return manufactured_errors(fun, PolarGrid(R, n, 4 * n, edge_ratio, R / 4 if edge_ratio > 1 else 0.0))


@pytest.mark.parametrize(
    "anisotropy, edge_ratio",
    [(0.0, 1.0), (1.0, 1.0), (1.0, 6.0)],
    ids=["isotropic-variable-D", "full-tensor-with-cross-terms", "cross-terms-on-edge-graded-rings"],
)
def test_manufactured_solution_converges_at_second_order(anisotropy, edge_ratio):
    fun = _manufactured(anisotropy)
    errs = [_solve_mms(fun, n, edge_ratio) for n in (10, 20, 40)]
    emax = np.array([e[0] for e in errs])
    el2 = np.array([e[1] for e in errs])
    order_max = np.log2(emax[:-1] / emax[1:])
    order_l2 = np.log2(el2[:-1] / el2[1:])
    print(f"\nMMS anisotropy={anisotropy}, edge_ratio={edge_ratio}: max-norm errors {emax}, observed orders {order_max}; L2 orders {order_l2}")
    assert np.all(order_max > 1.8)
    assert np.all(order_l2 > 1.8)
    assert order_max[-1] < 2.3  # and not suspiciously better than the scheme allows


def test_uniform_flux_field_gives_exactly_ambient_pressure():
    """A divergence-free flux (uniform velocity over a uniform film) drives no pressure."""
    g = PolarGrid(R, 12, 32)
    ones = np.ones((g.n_r, g.n_theta))
    q = (ones, 0 * ones, 2 * ones, 0.3 * ones, -0.7 * ones)
    phi = ReynoldsSystem(g, FaceCoefficients(q, q)).solve()
    assert np.max(np.abs(phi)) < 1e-12


def test_operator_is_symmetric_positive_definite_for_isotropic_coefficients():
    g = PolarGrid(R, 10, 24)
    xr, yr, _ = g.radial_faces
    xa, ya, _ = g.angular_faces
    d = lambda x, y: 1.0 + 0.5 * x / R  # noqa: E731
    z = np.zeros_like(xr)
    c = FaceCoefficients((d(xr, yr), z, d(xr, yr), z, z), (d(xa, ya), z, d(xa, ya), z, z))
    A = assemble_operator(g, c).toarray()
    assert np.allclose(A, A.T, rtol=0, atol=1e-14 * np.abs(A).max())
    assert np.linalg.eigvalsh(0.5 * (A + A.T)).min() > 0


def test_axisymmetric_poisson_solution_converges_at_second_order():
    """div(grad phi) = -4 on the disk with phi = 0 at r = R has phi = R^2 - r^2."""
    errs = []
    for n in (8, 16, 32):
        g = PolarGrid(R, n, 16)
        ones = np.ones((g.n_r, g.n_theta))
        z = 0 * ones
        c = FaceCoefficients((ones, z, ones, z, z), (ones, z, ones, z, z))
        phi = ReynoldsSystem(g, c, source=4.0 * g.area).solve()
        errs.append(np.max(np.abs(phi - (R * R - g.r**2))))
    orders = np.log2(np.array(errs[:-1]) / np.array(errs[1:]))
    print(f"\naxisymmetric Poisson: errors {errs}, observed orders {orders}")
    assert errs[-1] < 1e-3 * R * R
    assert np.all(np.abs(orders - 2.0) < 0.2)

