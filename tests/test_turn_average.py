"""The removal profile is the removal averaged over the wafer's turn (issue 25, "kinematics of a real tool").

The equilibrium is solved in the frame of the carrier (:mod:`cmpsim.physics.kinematics`): origin at the
wafer centre, axes fixed, platen turning at Omega_p = ``rotation_speed`` about (0, e), head and
wafer at Omega_w = ``wafer_speed_ratio`` x Omega_p about the origin. The maps are stationary in
that frame, so a material point of the wafer at radius r, carried by the wafer's rotation,
sees every angle of the circle r once per turn: its time-averaged removal is the angular mean
of the map along the circle, which is how ``removal_rate_profile`` is defined (ring means,
docs/model.md, "Within-wafer uniformity"). These tests check that definition against a material
point followed in time, with head and platen at different speeds (90 / 100 rpm, the Mirra recipe
of Kim et al., J. Electrochem. Soc. 158 H635, 2011), where the map is not axisymmetric.
"""

from __future__ import annotations

import numpy as np
import pytest
from scipy.integrate import solve_ivp
from scipy.special import ellipe

import cmpsim
from cmpsim.physics.kinematics import Kinematics
from cmpsim.solver.model import physical_setup
from cmpsim.results.uniformity import ring_mean

PLATEN_HEAD = {"rotation_speed": "90 rpm", "wafer_speed_ratio": 100.0 / 90.0}


@pytest.fixture(scope="module")
def unequal():
    return cmpsim.solve(relative=False, grid="12x32", **PLATEN_HEAD)


def test_removal_profile_is_the_time_average_of_a_material_point_over_one_turn(unequal):
    r = unequal
    g = r.grid
    rate = r.polar["removal_rate"]
    # the map is not axisymmetric at unequal speeds: the average over the turn matters
    spread = np.ptp(rate, axis=1) / rate.mean(axis=1)
    assert spread.max() > 0.01
    kin = physical_setup(r.config).kinematics
    period = 2 * np.pi / kin.wafer_speed

    def wafer_velocity(t, x):  # the material point moves with the wafer surface
        _, _, uwx, uwy = kin.velocities(x[0], x[1])
        return [float(uwx), float(uwy)]

    n_samples = 4 * g.n_theta  # equal time steps through the cell centres: exact on the interpolant
    times = np.arange(n_samples) * period / n_samples
    for i in (0, g.n_r // 2, g.n_r - 1):
        ri, t0 = g.r[i, 0], g.theta[0, 0]
        path = solve_ivp(wafer_velocity, (0.0, period), [ri * np.cos(t0), ri * np.sin(t0)], t_eval=np.append(times, period), rtol=1e-12, atol=1e-15 * ri)
        x, y = path.y
        # one turn of the head brings the point back: it circles the wafer centre at radius r_i
        assert np.hypot(x, y) == pytest.approx(ri, rel=1e-9)
        assert (x[-1], y[-1]) == pytest.approx((x[0], y[0]), abs=1e-8 * ri)
        seen = g.interpolate(rate, x[:-1], y[:-1])
        assert seen.mean() == pytest.approx(r.removal_rate_profile[i], rel=1e-7)
    # and the profile's area mean is the wafer-mean rate
    assert np.sum(r.removal_rate_profile * g.area[:, 0] * g.n_theta) / np.sum(g.area) == pytest.approx(r.removal_rate_mean, rel=1e-12)


def test_turn_averaged_sliding_speed_is_the_mean_distance_to_a_circle():
    # |u_pad - u_wafer| at (r, theta) = |Omega_p e - (Omega_p - Omega_w) r e_theta|: its turn average
    # is the mean distance from a point to a circle, (2/pi)(a + b r) E(k), k^2 = 4abr/(a + br)^2
    c = cmpsim.Config.default().replace(grid="24x64", **PLATEN_HEAD)
    setup = physical_setup(c)
    kin, g = setup.kinematics, setup.grid
    _, _, dux, duy = kin.mean_and_relative(*g.centres)
    turn = ring_mean(np.hypot(dux, duy))
    a, b, r = kin.pad_speed * kin.centre_distance, abs(kin.pad_speed - kin.wafer_speed), g.r[:, 0]
    exact = 2 / np.pi * (a + b * r) * ellipe(4 * a * b * r / (a + b * r) ** 2)
    assert turn == pytest.approx(exact, rel=1e-13)
    # equal speeds: every point slides at Omega e at every instant
    equal = Kinematics(kin.pad_speed, kin.pad_speed, kin.centre_distance)
    _, _, dux, duy = equal.mean_and_relative(*g.centres)
    assert np.hypot(dux, duy) == pytest.approx(a, rel=1e-14)


# ---------------------------------------------------------------------------------- the head's sweep
def test_head_sweep_quadrature_is_the_time_average_of_the_oscillation():
    from scipy.integrate import quad

    from cmpsim.physics.kinematics import head_sweep_nodes

    e0, amp = 0.1, 0.03
    for n in (1, 2, 4):
        e, w = head_sweep_nodes(e0, amp, n)
        assert w.sum() == pytest.approx(1.0, rel=1e-15) and np.all(np.abs(e - e0) < amp)
        for degree in range(2 * n):  # exact below degree 2n
            f = lambda x: ((x - 0.08) / 0.05) ** degree  # noqa: E731
            time_mean = quad(lambda t: f(e0 + amp * np.sin(2 * np.pi * t)), 0.0, 1.0, epsabs=1e-14, epsrel=1e-13)[0]
            assert np.dot(w, f(e)) == pytest.approx(time_mean, rel=1e-12, abs=1e-14)
    # a smooth, non-polynomial quantity (a speed-like e^1.5): 4 nodes to 1e-7
    e, w = head_sweep_nodes(e0, amp, 4)
    time_mean = quad(lambda t: (e0 + amp * np.sin(2 * np.pi * t)) ** 1.5, 0.0, 1.0, epsrel=1e-13)[0]
    assert np.dot(w, e**1.5) == pytest.approx(time_mean, rel=1e-7)
    with pytest.raises(ValueError, match="amplitude"):
        head_sweep_nodes(e0, e0, 4)
    with pytest.raises(ValueError, match="nodes"):
        head_sweep_nodes(e0, amp, 0)


def test_head_sweep_average_of_the_default_model():
    from cmpsim.head.head_sweep import sweep_average

    config = cmpsim.Config.default().replace(grid="12x32")
    still = cmpsim.solve(config, relative=False)
    zero = sweep_average(config, amplitude=0.0, nodes=2)
    # no sweep: the still head's profile (the second node is solved from the first: to round-off)
    np.testing.assert_allclose(zero.removal_rate_profile, still.removal_rate_profile, rtol=1e-12)
    assert zero.within_wafer_nonuniformity == pytest.approx(still.within_wafer_nonuniformity, rel=1e-9)
    two, four = (sweep_average(config, amplitude="30 mm", nodes=n) for n in (2, 4))
    # the average is the weighted mean of the nodes' turn-averaged profiles
    np.testing.assert_allclose(four.removal_rate_profile, np.mean([r.removal_rate_profile for r in four.results], axis=0), rtol=1e-14)
    assert [r.config.centre_distance for r in four.results] == pytest.approx(list(four.centre_distances), rel=1e-15)
    # the rate is nearly proportional to the sliding speed Omega e, whose cycle average is Omega e_0:
    # the swept mean stays within 0.5 % of the still one, while the profile's shape changes
    assert four.removal_rate_mean == pytest.approx(still.removal_rate_mean, rel=5e-3)
    assert four.within_wafer_nonuniformity != pytest.approx(still.within_wafer_nonuniformity, rel=0.05)
    # and 2 nodes already give the 4-node average closely
    assert two.removal_rate_mean == pytest.approx(four.removal_rate_mean, rel=5e-4)
    assert two.within_wafer_nonuniformity == pytest.approx(four.within_wafer_nonuniformity, rel=0.05)
    print(f"\nmean rate still {still.removal_rate_mean * 6e10:.3f}, swept (2 / 4 nodes) {two.removal_rate_mean * 6e10:.3f} / {four.removal_rate_mean * 6e10:.3f} nm/min; "
          f"WIWNU still {100 * still.within_wafer_nonuniformity:.3f} %, swept {100 * four.within_wafer_nonuniformity:.3f} %")
