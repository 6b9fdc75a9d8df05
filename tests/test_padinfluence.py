"""The layered pad's deflection operator on polar cells (cmpsim.physics.padinfluence, docs/model.md section 13c).

Claims: the cell integrals of the kernel reproduce the deflection of a uniformly loaded disc
(Hankel transform; mpmath at high precision in the slow test), converge at second order on
edge-graded rings for a smooth load with and without an angular mode, and reduce to the local
Winkler operator C(0) I when the coupling length is far below a cell.
"""

from __future__ import annotations

import numpy as np
import pytest
from scipy.special import jv

from cmpsim.inputs.config import Config
from cmpsim.numerics.grid import PolarGrid, graded_ring_faces
from cmpsim.numerics.padgrid import layer_deflection, layer_operator
from cmpsim.physics.padinfluence import angular_modes, apply_modes, radial_primitive, ring_influence
from cmpsim.physics.padstack import LayeredFoundation, PadLayer
from cmpsim.solver.setup import pad_foundation

R = 0.0381


@pytest.fixture(scope="module")
def stack():
    return pad_foundation(Config.default().replace(pad_compliance="layer"))  # IC1000 on Suba IV


def _hankel(stack, integrand, r, q_top=None):
    """∫_0^q_top C_nl(q) integrand(q, r) dq by Gauss-Legendre on panels of a quarter period (double precision)."""
    t_min = min(layer.thickness for layer in stack.layers)
    q_top = q_top or 60.0 / t_min
    x, wx = np.polynomial.legendre.leggauss(12)
    edges = np.linspace(0.0, q_top, int(q_top * 2 * R / np.pi * 4) + 1)
    half = 0.5 * np.diff(edges)
    q = ((0.5 * (edges[1:] + edges[:-1]))[:, None] + half[:, None] * x).ravel()
    wq = (half[:, None] * wx).ravel()
    return integrand(q[None, :], np.asarray(r)[:, None]) @ (stack.nonlocal_compliance(q) * wq)


def _graded(n_r, n_theta=32):
    return PolarGrid(R, n_r, n_theta, 5.0, 4e-3)


def test_a_uniformly_loaded_disc_deflects_as_its_hankel_transform(stack):
    # w(r) = p R ∫ C(q) J1(qR) J0(qr) dq: every cell integral summed, so only the quadrature errs
    g = _graded(24, 64)
    w = layer_operator(stack, g).apply(np.ones(g.size)).reshape(g.n_r, g.n_theta)
    ref = _hankel(stack, lambda q, r: R * jv(1, q * R) * jv(0, q * r), g.r[:, 0])
    assert np.ptp(w, axis=1).max() < 1e-12 * ref.max()  # the same in every sector
    assert np.max(np.abs(w[:, 0] - ref)) < 1e-7 * ref.max()  # 1.2e-8
    assert w[-1, 0] < 0.8 * w[0, 0]  # the unloaded pad outside holds the rim up


@pytest.mark.slow
def test_the_disc_deflection_agrees_with_an_mpmath_reference(stack):
    mp = pytest.importorskip("mpmath")
    mp.mp.dps = 20
    top, sub = stack.layers

    def layer(q, t, e, nu):
        e, nu, t = mp.mpf(e), mp.mpf(nu), mp.mpf(t)
        x, a = 2 * q * t, 3 - 4 * nu
        return e / (1 - nu**2) * q / 2 * (a * mp.cosh(x) + x * x / 2 + 5 - 12 * nu + 8 * nu**2) / (a * mp.sinh(x) - x)

    d = mp.mpf(top.modulus) * mp.mpf(top.thickness) ** 3 / (12 * (1 - mp.mpf(top.poisson) ** 2))
    rw = mp.mpf(R)
    q_top = 40 / mp.mpf(top.thickness)
    n = int(q_top * rw / mp.pi) + 1
    r_test = 0.5 * R  # a ring centre of the grid below
    g = PolarGrid(R, 24, 64)
    assert g.r[12, 0] == pytest.approx(0.5 * R + 0.5 * g.dr)
    r_test = g.r[12, 0]
    ref = rw * mp.quad(lambda q: mp.besselj(1, q * rw) * mp.besselj(0, q * r_test) / (d * q**4 + layer(q, sub.thickness, sub.modulus, sub.poisson)),
                       [k * q_top / n for k in range(n + 1)])
    w = layer_operator(stack, g).apply(np.ones(g.size)).reshape(g.n_r, g.n_theta)[12, 0]
    assert w == pytest.approx(float(ref), rel=1e-6)


def test_the_operator_converges_at_second_order_on_graded_rings(stack):
    # paraboloid p = 1 - (r/R)^2 (mode 0) and p = (r/R) cos(theta) (mode 1), exact by Hankel transforms
    cases = (
        (lambda r, t: 1.0 - (r / R) ** 2, lambda q, r: 2.0 * jv(2, q * R) * jv(0, q * r) / q, lambda t: 1.0),
        (lambda r, t: (r / R) * np.cos(t), lambda q, r: R * jv(2, q * R) * jv(1, q * r), np.cos),
    )
    for load, kernel, angular in cases:
        errors = []
        for n_r in (12, 24, 48):
            g = _graded(n_r, 4 * n_r)
            w = layer_operator(stack, g).apply(np.broadcast_to(load(g.r, g.theta), (g.n_r, g.n_theta))).reshape(g.n_r, g.n_theta)
            ref = _hankel(stack, kernel, g.r[:, 0])[:, None] * angular(g.theta)
            errors.append(np.max(np.abs(w - ref)) / np.max(np.abs(ref)))
        order = np.log2(np.array(errors[:-1]) / np.array(errors[1:]))
        assert errors[-1] < 2e-3 and np.all(order > 1.7), (errors, order)


def test_a_kernel_far_narrower_than_the_cells_is_the_winkler_bed():
    # every length and modulus x s: the same k, coupling length 25 um (s = 0.01) and 7.6 um (0.003)
    # against rim rings of 0.3 mm on the edge-graded default preset; a smooth load
    c = Config.default()
    g = c.polar_grid()
    x, y = g.centres
    p = 1.0 + 0.5 * x / R + 0.3 * (y / R) ** 2
    errors = []
    for s in (0.01, 0.003):
        thin = LayeredFoundation(tuple(PadLayer(t * s, e * s, nu) for t, e, nu in (
            (c.pad_thickness, c.pad_bulk_modulus, c.pad_poisson), (c.subpad_thickness, c.subpad_modulus, c.subpad_poisson))))
        errors.append(np.abs(layer_deflection(thin, p, g) * thin.stiffness - p))
    # s = 0.01: the rim ring (its centre 6 coupling lengths from the unloaded pad) within 1e-3, the rest 1e-5
    assert errors[0][-1].max() < 1e-3 * p.max() and errors[0][:-1].max() < 1e-5 * p.max()
    assert errors[1].max() < 0.01 * errors[0].max()  # and it vanishes with the coupling length


def test_the_influence_is_symmetric_in_the_sector_offset_and_applies_by_modes():
    stack = pad_foundation(Config.default().replace(pad_compliance="layer"))
    faces = graded_ring_faces(R, 10, 3.0, 5e-3)
    near, reach = radial_primitive(stack.nonlocal_compliance, 40 / 1.27e-3, 2 * R, stack.coupling_length)
    K = ring_influence(near, reach, float(stack.nonlocal_compliance(np.array([0.0]))[0]), faces, 16)
    assert np.allclose(K[:, :, 1:], K[:, :, :0:-1], rtol=0, atol=1e-14 * K.max())
    p = np.random.default_rng(1).normal(size=(10, 16))
    direct = np.einsum("ikd,kjd->ij", K, np.stack([np.roll(p, -d, axis=1) for d in range(16)], axis=2))
    assert np.allclose(apply_modes(angular_modes(K), p), direct, rtol=0, atol=1e-12 * np.abs(direct).max())
