"""Film constants of a stack (issue 32): sources present, values consistent with cmpsim.physics.materials, thin-film optics checked."""

from __future__ import annotations

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from cmpsim.physics.films import (
    COPPER,
    FILM_CONSTANTS,
    OXIDE,
    SILICON_INDEX_650,
    TANTALUM,
    FilmConstants,
    film_reflectance,
    interface_reflectance,
)


def test_recipe_names_and_sources():
    assert {"copper", "barrier", "oxide"} <= set(FILM_CONSTANTS)
    for f in FILM_CONSTANTS.values():
        assert f.sources


def test_copper_and_oxide_repeat_cmpsim_materials():
    """The physics kernels import nothing of cmpsim; the test checks the repeated values agree."""
    from cmpsim.physics.materials import FILMS

    for ours, theirs in ((COPPER, FILMS["copper"]), (OXIDE, FILMS["oxide"]), (TANTALUM, FILMS["barrier"])):
        assert (ours.modulus, ours.poisson, ours.hardness) == (theirs.modulus, theirs.poisson, theirs.hardness)


def test_barrier_is_harder_and_chemically_less_activated_than_copper():
    assert TANTALUM.hardness > COPPER.hardness and TANTALUM.modulus > COPPER.modulus
    assert OXIDE.activation_energy < TANTALUM.activation_energy < COPPER.activation_energy
    # the reflectance step an end point sees when copper clears to the barrier
    assert COPPER.reflectance_650 - TANTALUM.reflectance_650 == pytest.approx(0.483)


def test_bad_constants_rejected():
    with pytest.raises(ValueError):
        FilmConstants("x", -1.0, 0.3, 1e9, None, None, None, None, None, None, "")
    with pytest.raises(ValueError):
        FilmConstants("x", 1e9, 0.3, 1e9, None, 1.2, None, None, None, None, "")


def test_film_reflectance_limits():
    # no film: the bare substrate under water
    assert film_reflectance(0.0) == pytest.approx(float(interface_reflectance(1.333, SILICON_INDEX_650)), rel=1e-12)
    # a half-wave film is absent optically; a film of the ambient's index is too
    half = 650e-9 / (2 * OXIDE.refractive_index_650)
    assert film_reflectance(half) == pytest.approx(float(film_reflectance(0.0)), rel=1e-12)
    assert film_reflectance(123e-9, film_index=1.333) == pytest.approx(float(film_reflectance(0.0)), rel=1e-12)
    # bare silicon in air: 0.345 (((n-1)^2 + k^2)/((n+1)^2 + k^2))
    assert float(interface_reflectance(1.0, SILICON_INDEX_650)) == pytest.approx(0.3453, abs=1e-4)
    # quarter-wave film on a lossless substrate: the closed form ((n0 n2 - n1^2)/(n0 n2 + n1^2))^2
    n0, n1, n2 = 1.0, 1.4565, 3.85
    q = 650e-9 / (4 * n1)
    assert film_reflectance(q, n1, n2, ambient_index=n0) == pytest.approx(((n0 * n2 - n1**2) / (n0 * n2 + n1**2)) ** 2, rel=1e-12)


@settings(max_examples=50, deadline=None)
@given(t=st.floats(0.0, 2e-6))
def test_film_reflectance_is_a_reflectance(t):
    r = float(film_reflectance(t))
    assert 0.0 <= r <= 1.0
