"""The bent wafer in equilibrium (cmpsim.operators.membrane; issue 25)."""

from types import SimpleNamespace

import numpy as np
import pytest

from cmpsim.numerics.grid import PolarGrid
from cmpsim.operators.membrane import solve_bending
from cmpsim.numerics.plate import KirchhoffPlate, PlateOperator

WAFER = KirchhoffPlate(381e-6, 130e9, 0.28)
A = 0.0381
K = 1.8e9  # Pa/m, the default pad stack
P = 27579.0


def _rigid_part(g, f):
    x, y = g.centres
    a = g.area
    return np.sum(f * a) / np.sum(a) + np.sum(f * x * a) / np.sum(x * x * a) * x + np.sum(f * y * a) / np.sum(y * y * a) * y


def _winkler_equilibrium(g, face):
    """A wafer of face shape ``face`` (m, towards the pad) on a Winkler bed, its rigid position
    in force and moment balance with the uniform load P: p = k (face - w - rigid) with the rigid
    part chosen so that the load is P and the moments zero."""

    def equilibrium(w):
        p = K * (face - w)
        return SimpleNamespace(p_total=p - _rigid_part(g, p) + P)

    return equilibrium


def _winkler_response(g):
    """The linear change of that pressure under a change dw of the bending (the rigid position re-balanced)."""

    def response(w, dw):
        dp = -K * dw
        return dp - _rigid_part(g, dp)

    return response


def _bend(g, face, **options):
    return solve_bending(_winkler_equilibrium(g, face), WAFER, g, np.full(face.shape, P), K, 1e-14, _winkler_response(g), **options)


def test_bending_on_a_winkler_bed_is_the_plate_on_foundation_solution():
    g = PolarGrid(A, 24, 32)
    x, y = g.centres
    face = 5e-6 * (1 - (x * x + y * y) / A**2) + 1e-6 * np.cos(3 * g.theta) * (g.r / A) ** 3
    sol = _bend(g, face)
    # D del^4 w = k (face - w) - rigid part  ->  (K + k) w = k (face - rigid part of face)
    exact = PlateOperator(WAFER, g, K).deflection(K * (face - _rigid_part(g, face)))
    assert np.max(np.abs(sol.deflection - exact)) < 1e-8 * np.max(np.abs(exact))
    # the pressure is linear in the bending here: each Newton step gains the Krylov tolerance (1e-4),
    # so three steps (four solves) land on it from flat, without continuation
    assert sol.stages == [1.0] and sol.solves <= 4 and sol.krylov > 0


def test_a_flat_wafer_on_a_winkler_bed_under_uniform_zones_stays_flat_and_presses_uniformly():
    g = PolarGrid(A, 16, 16)
    sol = _bend(g, np.zeros((16, 16)))
    assert np.max(np.abs(sol.deflection)) == 0.0
    assert np.max(np.abs(sol.state.p_total - P)) < 1e-12 * P
    assert sol.solves <= 3


def test_a_warm_start_at_the_solution_takes_one_iteration():
    g = PolarGrid(A, 16, 16)
    x, y = g.centres
    face = 5e-6 * (1 - (x * x + y * y) / A**2)
    cold = _bend(g, face)
    warm = _bend(g, face, start=cold.deflection)
    assert warm.solves == 1
    assert warm.stages == [1.0]
    assert np.max(np.abs(warm.deflection - cold.deflection)) < 1e-9 * np.max(np.abs(cold.deflection))


def test_a_bending_out_of_newtons_reach_from_flat_is_found_by_continuation_in_stiffness():
    """An equilibrium solver that cannot follow a change of the bending larger than 5 % of the answer
    (as a real one fails far from its start): Newton from the flat wafer fails even with halved steps,
    and the continuation from a stiff wafer down to the plate's stiffness reaches the same bending."""
    g = PolarGrid(A, 16, 16)
    x, y = g.centres
    face = 5e-6 * (1 - (x * x + y * y) / A**2)
    exact = PlateOperator(WAFER, g, K).deflection(K * (face - _rigid_part(g, face)))
    reach = 0.05 * np.max(np.abs(exact))
    solvable = _winkler_equilibrium(g, face)
    last = {"w": np.zeros(face.shape)}

    def equilibrium(w):
        if np.max(np.abs(w - last["w"])) > reach:
            raise RuntimeError("no equilibrium this far from the last one")
        last["w"] = np.array(w, copy=True)
        return solvable(w)

    sol = solve_bending(equilibrium, WAFER, g, np.full(face.shape, P), K, 1e-14, _winkler_response(g))
    assert len(sol.stages) > 1 and sol.stages[-1] == 1.0
    assert np.max(np.abs(sol.deflection - exact)) < 1e-8 * np.max(np.abs(exact))
