"""cmpsim.numerics.roots.brentq is scipy.optimize.brentq: the same root to the last bit, the same
number of function calls, the same errors (it replaces scipy's on the solver's import chain:
issue 31)."""

import math

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st
from scipy.optimize import brentq as scipy_brentq

from cmpsim.numerics.roots import RTOL_MIN, brentq

FUNCTIONS = [
    lambda x, c: x**3 - c[0] * x - 1.0 + c[1],
    lambda x, c: math.tanh(3.0 * (x - c[0])) + 0.1 * c[1],
    lambda x, c: math.exp(x) - 2.0 - c[0] ** 2,
    lambda x, c: (x - c[0]) * abs(x - c[0]) ** 0.3,
    lambda x, c: math.sin(5.0 * x) + 0.5 * x - c[0],
    lambda x, c: 1.0 if x > c[0] else -1.0,  # a step: bisection all the way
]


def _counted(f):
    calls = []

    def g(x):
        calls.append(x)
        return f(x)

    return g, calls


@settings(max_examples=300, deadline=None)
@given(
    kind=st.integers(0, len(FUNCTIONS) - 1),
    c=st.lists(st.floats(-3.0, 3.0), min_size=2, max_size=2),
    xtol=st.floats(1e-15, 1e-2),
    rtol=st.floats(RTOL_MIN, 1e-6),
    maxiter=st.integers(1, 200),
)
def test_the_same_steps_and_root_as_scipy(kind, c, xtol, rtol, maxiter):
    f = FUNCTIONS[kind]
    mine, mine_calls = _counted(lambda x: f(x, c))
    ref, ref_calls = _counted(lambda x: f(x, c))
    try:
        expected = scipy_brentq(ref, -10.0, 10.0, xtol=xtol, rtol=rtol, maxiter=maxiter)
    except (ValueError, RuntimeError) as error:
        with pytest.raises(type(error)):
            brentq(mine, -10.0, 10.0, xtol=xtol, rtol=rtol, maxiter=maxiter)
    else:
        assert brentq(mine, -10.0, 10.0, xtol=xtol, rtol=rtol, maxiter=maxiter) == expected
    assert mine_calls == ref_calls  # every trial point, bit for bit


def test_converges_to_the_tolerance_and_refuses_bad_input():
    root = brentq(lambda x: x * x - 2.0, 0.0, 2.0, xtol=1e-15, rtol=RTOL_MIN)
    assert abs(root - math.sqrt(2.0)) <= 1e-15 + RTOL_MIN * math.sqrt(2.0)
    with pytest.raises(ValueError, match="different signs"):
        brentq(lambda x: x * x + 1.0, -1.0, 1.0)
    with pytest.raises(ValueError, match="xtol too small"):
        brentq(lambda x: x, -1.0, 1.0, xtol=0.0)
    with pytest.raises(ValueError, match="rtol too small"):
        brentq(lambda x: x, -1.0, 1.0, rtol=1e-17)
    with pytest.raises(ValueError, match="is NaN"):
        brentq(lambda x: np.nan if x > 0.3 else x - 0.5, -1.0, 1.0)
    with pytest.raises(RuntimeError, match="Failed to converge after 3 iterations"):
        brentq(lambda x: 1.0 if x > 1.0 / 3.0 else -1.0, -1.0, 1.0, xtol=1e-15, maxiter=3)
