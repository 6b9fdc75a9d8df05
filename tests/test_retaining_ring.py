"""The retaining ring's load on the laterally coupled pad (issue 25)."""

import numpy as np
import pytest

import cmpsim
from cmpsim.inputs.config import Config
from cmpsim.numerics.grid import PolarGrid
from cmpsim.numerics.padgrid import layer_deflection, layer_operator
from cmpsim.solver.setup import pad_foundation

PSI = 6894.757293168361


@pytest.fixture(scope="module")
def stack():
    return pad_foundation(Config.default().replace(pad_compliance="layer"))  # IC1000 on Suba IV as layers


def test_the_rings_pad_deflection_agrees_with_the_fft_operator_of_the_pad(stack):
    """Two independent evaluations of the same C(q): the Hankel integral of the annulus and the
    Cartesian FFT operator that carries the wafer's own pressure, on a polar grid covering the ring."""
    radius, inner, outer = 0.0381, 0.0391, 0.0591
    r = np.linspace(0.0, 0.035, 8)
    w = stack.annulus_deflection(r, inner, outer, 5 * PSI)
    g = PolarGrid(outer, 120, 128)
    rr = g.r * np.ones_like(g.theta)
    p = np.where((rr > inner) & (rr < outer), 5 * PSI, 0.0)
    fft = np.interp(r, g.r[:, 0], layer_operator(stack, g).apply(p).reshape(rr.shape).mean(axis=1))
    scale = stack.annulus_deflection(np.array([radius]), inner, outer, 5 * PSI)[0]  # at the wafer edge, ~7 um
    assert scale > 1e-6
    assert np.max(np.abs(w - fft)) < 0.05 * scale  # 3.5 %: the cells straddling the ring's edges (0.8 % on 240 rings)


def test_far_from_the_ring_the_pad_does_not_move_and_a_wide_disk_sinks_it_like_a_winkler_bed(stack):
    assert abs(stack.annulus_deflection(np.array([0.0]), 0.0391, 0.0591, 5 * PSI)[0]) < 1e-3 * 5 * PSI / stack.stiffness
    # a load on 0 < r < 1 m: the centre sinks by p / k, the long-wavelength limit C(0) = 1/k (minus the local part)
    centre = stack.annulus_deflection(np.array([0.0]), 1e-9, 1.0, 5 * PSI)[0]
    assert centre == pytest.approx(5 * PSI * (1.0 / stack.stiffness - stack.local_compliance), rel=1e-3)
    # docs/model.md, section 13f: 2.7 um at the wafer edge per 2 psi of ring pressure (1 mm gap, 20 mm width)
    assert stack.annulus_deflection(np.array([0.0381]), 0.0391, 0.0591, 2 * PSI)[0] == pytest.approx(2.70e-6, abs=0.01e-6)
    with pytest.raises(ValueError, match="annulus_deflection is for points inside the annulus"):
        stack.annulus_deflection(np.array([0.05]), 0.0391, 0.0591, 1.0)


def test_raising_the_ring_pressure_lowers_the_edge_rate_monotonically():
    base = Config.default().replace(pad_compliance="layer")
    edge, centre, wiwnu = [], [], []
    for pressure in (0.0, 2 * PSI, 4 * PSI, 6 * PSI):
        r = cmpsim.solve(base.replace(retaining_ring_pressure=pressure), relative=False)
        profile = np.asarray(r.profiles["removal_rate_profile"])
        edge.append(profile[-1] / profile.mean())
        centre.append(profile[0] / profile.mean())
        wiwnu.append(r.scalars["within_wafer_nonuniformity"])
        assert np.max(np.abs(r.solution.state.residual)) < 1e-9
    assert all(b < a for a, b in zip(edge, edge[1:])), edge
    assert edge[0] > 1.3 and edge[-1] < 0.9  # the fast edge band of the layered pad, then a slow one
    # docs/model.md, section 13f: the non-uniformity has a minimum near 4 psi (0.084, 0.088 at 0 and 2 psi
    # with eq. 8 floored alone, before it was continued below 0.4: docs/model.md, section 5)
    assert wiwnu == pytest.approx([0.067, 0.051, 0.0125, 0.038], abs=0.002)


def test_the_rings_table_is_the_hankel_integral_to_a_millionth_under_the_whole_wafer():
    """The cached cubic spline of :func:`ring_table` (128 radii graded to the edge) against the
    integral itself at radii off its nodes, on the 300mm preset's pad and ring."""
    from cmpsim.models.carriers import ring_of, ring_table

    cfg = Config.preset("300mm")
    foundation, ring, radius = pad_foundation(cfg), ring_of(cfg), 0.5 * cfg.wafer_diameter
    r = np.concatenate([np.linspace(0.0, radius, 37)[1:-1], radius - np.geomspace(1e-5, 1e-2, 23)])
    exact = foundation.annulus_deflection(r, *ring)
    assert np.max(np.abs(exact)) > 1e-6  # the ring lowers the pad under the edge by microns
    assert np.max(np.abs(ring_table(foundation, radius, ring)(r) - exact)) < 1e-6 * np.max(np.abs(exact))
    assert ring_table(foundation, radius, ring) is ring_table(foundation, radius, ring)  # one table per pad, wafer, ring
