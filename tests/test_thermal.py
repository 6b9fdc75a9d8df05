"""The pad's heat balance (issue 32): closed forms, convergence order, energy conservation, limits."""

from __future__ import annotations

import math

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st
from scipy.integrate import quad

from cmpsim.physics.thermal import (
    THERMAL,
    Layer,
    effusivity,
    lumped_rise,
    mean_wafer_duty,
    pad_column,
    partition_coefficient,
    polisher_column,
    semi_infinite_rise,
    semi_infinite_rise_convective,
    slab_rise,
    wafer_duty,
)

K, RC = THERMAL.pad_conductivity, THERMAL.pad_volumetric_heat_capacity
PSI = 6894.757
T0 = 293.15


def semi_infinite_column(cells=300, grading=1.025, depth=0.03, **kw):
    """A pad deep enough (30 mm against sqrt(alpha t) = 0.5 mm at 60 s) to be semi-infinite."""
    args = dict(duty=1.0, surface_coefficient=0.0, platen_coefficient=0.0, wafer_heat_capacity=0.0, slurry_temperature=T0)
    args.update(kw)
    return pad_column([Layer(depth, K, RC, cells=cells, grading=grading)], **args)


def test_constants_are_the_documented_values():
    assert THERMAL.pad_porosity == pytest.approx(0.3712, abs=1e-4)
    assert THERMAL.pad_conductivity == pytest.approx(0.1576, abs=1e-4)
    assert THERMAL.pad_wet_conductivity == pytest.approx(0.3693, abs=1e-4)
    assert THERMAL.pad_volumetric_heat_capacity == pytest.approx(9.02e5, rel=1e-3)
    assert THERMAL.wafer_heat_capacity == pytest.approx(1285.7, rel=1e-4)
    # Maxwell–Eucken limits: no pores -> matrix; pores of matrix conductivity -> matrix
    from cmpsim.physics.thermal import maxwell_eucken
    assert maxwell_eucken(0.27, 0.6, 0.0) == pytest.approx(0.27)
    assert maxwell_eucken(0.27, 0.27, 0.4) == pytest.approx(0.27)


@pytest.mark.parametrize("t", [1.0, 10.0, 60.0])
def test_semi_infinite_body_under_constant_flux(t):
    col = semi_infinite_column()
    q = 2000.0
    got = col.advance(col.initial_state(T0), q, t).surface - T0
    want = semi_infinite_rise(q, t, K, 1.0, RC)
    assert got == pytest.approx(want, rel=2e-4)


def test_spatial_convergence_is_second_order_against_the_slab_series():
    """Slab, flux on top, adiabatic bottom: the exact series of Carslaw & Jaeger 3.3. Uniform cells."""
    L, q, t = 1.27e-3, 5000.0, 2.0
    exact = slab_rise(q, t, L, K, 1.0, RC, terms=4000)
    errs = []
    for n in (8, 16, 32, 64):
        col = pad_column([Layer(L, K, RC, cells=n)], duty=1.0, surface_coefficient=0.0, platen_coefficient=0.0, wafer_heat_capacity=0.0)
        errs.append(abs(col.advance(col.initial_state(0.0), q, t).surface - exact))
    orders = np.log2(np.array(errs[:-1]) / np.array(errs[1:]))
    assert np.all((orders > 1.9) & (orders < 2.1)), orders
    assert errs[-1] / exact < 1e-4


def test_semi_infinite_with_surface_loss_and_its_steady_state():
    h, q = 60.0, 2000.0
    col = semi_infinite_column(surface_coefficient=h, depth=0.2, cells=400, grading=1.02)
    for t in (5.0, 60.0, 600.0):
        got = col.advance(col.initial_state(T0), q, t).surface - T0
        assert got == pytest.approx(semi_infinite_rise_convective(q, h, t, K, 1.0, RC), rel=5e-4)
    # closed form: h -> 0 gives the adiabatic semi-infinite rise, t -> inf gives q/h
    assert semi_infinite_rise_convective(q, 1e-9, 30.0, K, 1.0, RC) == pytest.approx(semi_infinite_rise(q, 30.0, K, 1.0, RC), rel=1e-6)
    assert semi_infinite_rise_convective(q, h, 1e14, K, 1.0, RC) == pytest.approx(q / h, rel=1e-5)


def test_long_time_steady_state_is_q_over_h():
    """Adiabatic platen side, loss only to the slurry: the pad settles at f q / h_s above T_slurry."""
    h, q, f = 40.0, 8000.0, 0.2
    col = pad_column([Layer(1.27e-3, K, RC, cells=20)], duty=f, surface_coefficient=h, platen_coefficient=0.0)
    late = col.advance(col.initial_state(T0), q, 50 * col.time_constant)
    assert late.surface - T0 == pytest.approx(f * q / h, rel=1e-10)
    np.testing.assert_allclose(late.temperature, col.steady_state(q).temperature, rtol=0, atol=1e-9)


def test_partition_between_pad_and_carrier_follows_the_effusivities():
    """Two semi-infinite bodies, the carrier side heated all the time, the pad a share f (eq. P3)."""
    f, q, t = 0.25, 5000.0, 20.0
    kc, rcc = 0.2, 1.6e6  # a rubber-like carrier
    carrier = Layer(0.03, kc, rcc, cells=300, grading=1.025)
    col = semi_infinite_column(duty=f, carrier_layers=[carrier])
    state, energy = col.advance(col.initial_state(T0), q, t, with_energy=True)
    ep, ec = effusivity(K, 1.0, RC), effusivity(kc, 1.0, rcc)
    want = 2 * f * q * math.sqrt(t / math.pi) / (ep + f * ec)
    assert state.surface - T0 == pytest.approx(want, rel=5e-4)
    share = float(partition_coefficient(ep, ec, f))
    # the pad's heat = its semi-infinite content for the interface history T_s ~ sqrt(t): e_p T_s sqrt(pi t) / 2 ... = share f q t
    assert share * f * q * t == pytest.approx(ep * want * math.sqrt(math.pi * t) / 2, rel=1e-12)
    assert energy.residual == pytest.approx(0.0, abs=1e-8 * energy.supplied)


def test_energy_is_conserved_over_steps_and_cooling():
    col = polisher_column(0.15, 0.2, platen="sink")
    state = col.initial_state(T0)
    total = dict(supplied=0.0, stored=0.0, out=0.0)
    for q, dt in ((8000.0, 30.0), (12000.0, 45.0), (0.0, 20.0), (5000.0, 60.0), (0.0, 120.0)):
        state, e = col.advance(state, q, dt, with_energy=True)
        assert abs(e.residual) <= 1e-9 * max(e.supplied, abs(e.stored), 1.0)
        total["supplied"] += e.supplied
        total["stored"] += e.stored
        total["out"] += e.to_slurry + e.to_platen + e.to_carrier
    stored = np.sum(col.capacity * (state.temperature - T0))
    assert total["stored"] == pytest.approx(stored, abs=1e-10 * total["supplied"])
    assert total["supplied"] - total["out"] == pytest.approx(stored, abs=1e-10 * total["supplied"])


def test_zero_flux_gives_no_warming_and_cooling_relaxes_to_the_slurry():
    col = polisher_column(0.15, 0.2)
    state = col.advance(col.initial_state(T0), 0.0, 100.0)
    np.testing.assert_allclose(state.temperature, T0, rtol=0, atol=1e-10)
    hot = col.advance(col.initial_state(T0), 10000.0, 60.0)
    cooled = [col.advance(hot, 0.0, t).surface for t in (5.0, 20.0, 60.0, 600.0)]
    assert hot.surface > cooled[0] > cooled[1] > cooled[2] > cooled[3] >= T0 - 1e-12
    assert cooled[3] - T0 < 1e-6 * (hot.surface - T0)


def test_advance_is_exact_in_time():
    """One step of 60 s equals 60 steps of 1 s (the modal solution has no time-step error)."""
    col = polisher_column(0.15, 0.2)
    one = col.advance(col.initial_state(T0), 9000.0, 60.0)
    many = col.initial_state(T0)
    for _ in range(60):
        many = col.advance(many, 9000.0, 1.0)
    np.testing.assert_allclose(one.temperature, many.temperature, rtol=0, atol=1e-10)
    assert many.time == pytest.approx(60.0)


def test_coupled_stepping_orders():
    """q rising with the surface temperature (friction, Arrhenius): the explicit coupling of a
    recipe (q from the state at the step's start) is first order in the step; Heun's
    predictor-corrector (mid-step flux) is second order."""
    col = polisher_column(0.15, 0.2)
    q0, gamma, T_end = 8000.0, 0.02, 60.0

    def flux(state):
        return q0 * (1.0 + gamma * (state.surface - T0))

    def run(n, heun):
        s, dt = col.initial_state(T0), T_end / n
        for _ in range(n):
            if heun:
                pred = col.advance(s, flux(s), dt)
                s = col.advance(s, 0.5 * (flux(s) + flux(pred)), dt)
            else:
                s = col.advance(s, flux(s), dt)
        return s.surface

    ref = run(4096, True)
    e_expl = [abs(run(n, False) - ref) for n in (16, 32, 64, 128)]
    e_heun = [abs(run(n, True) - ref) for n in (16, 32, 64, 128)]
    o_expl = np.log2(np.array(e_expl[:-1]) / e_expl[1:])
    o_heun = np.log2(np.array(e_heun[:-1]) / e_heun[1:])
    assert np.all(np.abs(o_expl - 1.0) < 0.15), o_expl
    assert np.all(np.abs(o_heun - 2.0) < 0.25), o_heun


def test_lumped_limit_of_a_thin_conductive_pad():
    h, q, cap = 50.0, 3000.0, 2000.0
    col = pad_column([Layer(1e-4, 1e3, cap / 1e-4, cells=4)], duty=1.0, surface_coefficient=h, platen_coefficient=0.0, wafer_heat_capacity=0.0)
    for t in (10.0, 40.0, 200.0):
        got = col.advance(col.initial_state(T0), q, t).surface - T0
        assert got == pytest.approx(lumped_rise(q, h, cap, t), rel=1e-5)
    assert col.time_constant == pytest.approx(cap / h, rel=1e-5)


def test_wafer_duty_averages_to_r_over_4d():
    R, d = 0.15, 0.2
    inner, outer = d - R, d + R
    mean = quad(lambda r: wafer_duty(r, R, d) * 2 * np.pi * r, inner, outer, limit=200)[0] / (np.pi * (outer**2 - inner**2))
    assert mean == pytest.approx(mean_wafer_duty(R, d), rel=1e-6)
    assert wafer_duty(0.0, R, 0.1) == pytest.approx(1.0)  # the platen centre under a wafer that covers it
    assert wafer_duty(d + R + 0.01, R, d) == 0.0


@settings(max_examples=30, deadline=None)
@given(q=st.floats(0.0, 5e4), scale=st.floats(0.1, 10.0), t=st.floats(0.0, 600.0))
def test_rise_is_linear_in_the_flux_and_never_negative(q, scale, t):
    col = polisher_column(0.1, 0.15)
    a = col.advance(col.initial_state(T0), q, t).temperature - T0
    b = col.advance(col.initial_state(T0), scale * q, t).temperature - T0
    np.testing.assert_allclose(b, scale * a, rtol=1e-9, atol=1e-9)
    assert np.all(a >= -1e-9)


@settings(max_examples=20, deadline=None)
@given(t1=st.floats(0.0, 200.0), t2=st.floats(0.0, 200.0))
def test_surface_rise_is_monotone_in_time_under_constant_flux(t1, t2):
    col = polisher_column(0.15, 0.2)
    s0 = col.initial_state(T0)
    a, b = sorted((t1, t2))
    assert col.advance(s0, 10000.0, a).surface <= col.advance(s0, 10000.0, b).surface + 1e-12


def test_batch_of_fluxes_advances_each_column_independently():
    col = polisher_column(0.15, 0.2)
    q = np.array([0.0, 5000.0, 10000.0])
    batch = col.advance(col.initial_state(np.full(3, T0)), q, 30.0)
    for i in range(3):
        single = col.advance(col.initial_state(T0), q[i], 30.0)
        np.testing.assert_allclose(batch.temperature[i], single.temperature, atol=1e-12)


# ----------------------------------------------------------------- published measurements

def published_cases():
    """(label, wafer radius, centre distance, pressure, sliding speed, friction, time, measured rise)."""
    v_shin = 2 * math.pi * 93 / 60 * 0.2
    return [
        ("White 2003, mu 0.18", 0.1, 0.15, 6 * PSI, 0.96, 0.18, 60.0, 9.1),
        ("White 2003, mu 0.25", 0.1, 0.15, 6 * PSI, 0.96, 0.25, 60.0, 9.1),
        ("Shin 2025, mu 0.3", 0.15, 0.2, 2 * PSI, v_shin, 0.3, 90.0, 15.0),
        ("Shin 2025, mu 0.4", 0.15, 0.2, 2 * PSI, v_shin, 0.4, 90.0, 15.0),
    ]


def test_published_pad_temperature_rises_are_bracketed():
    """The platen-sink and adiabatic-platen columns bracket the measured rises (9.1 K; 15 K), and
    the sink's rise is within a factor 1.6 of them (docs/polisher.md, comparison table)."""
    for label, R, d, P, v, mu, t, measured in published_cases():
        q = mu * P * v
        sink = polisher_column(R, d, platen="sink")
        adia = polisher_column(R, d, platen="adiabatic")
        lo = sink.advance(sink.initial_state(T0), q, t).surface - T0
        hi = adia.advance(adia.initial_state(T0), q, t).surface - T0
        assert lo <= hi
        assert measured / 1.6 < lo < 1.6 * measured, (label, lo, measured)
        assert hi > 0.9 * measured, (label, hi)
