"""The removal laws: the paper's Runnels–Eyman law and the shear-power law."""

from __future__ import annotations

import numpy as np
import pytest

import cmpsim
from cmpsim.physics.removal import shear_power_removal_rate


def test_shear_power_law_is_prestons_law_in_full_contact():
    p, u, k_s, mu = 27.6e3, 0.63, 2.5e-13, 0.4
    rr = shear_power_removal_rate(np.full(5, p), np.zeros(5), np.full(5, u), k_s, mu, 0.7)
    np.testing.assert_allclose(rr, k_s * mu * p * u, rtol=1e-15)


def test_shear_power_law_adds_the_weighted_fluid_shear_power():
    rr = shear_power_removal_rate(0.0, (np.array([3.0]), np.array([4.0])), 2.0, 1e-12, 0.4, 0.5)
    np.testing.assert_allclose(rr, 1e-12 * 0.5 * 5.0 * 2.0, rtol=1e-15)


def test_wafer_mean_shear_power_rate_tends_to_preston_when_the_pad_carries_the_whole_load():
    # the paper's model (granular slurry, rigid pad) with the shear-power law: at 1 rpm the slurry
    # carries almost nothing: RR -> k_s mu P U over the wafer
    r = cmpsim.solve(cmpsim.Config.paper(), removal_law="shear_power", rotation_speed="1 rpm", grid="coarse", relative=False)
    c = r.config
    preston = c.shear_power_coefficient * c.friction_coefficient * c.applied_pressure * r.sliding_speed
    assert r.contact_load_fraction > 0.999
    assert r.removal_rate_mean == pytest.approx(preston * r.contact_load_fraction, rel=1e-9)  # uniform |du|: exact


def test_relative_removal_rate_is_nan_with_a_warning_when_the_reference_case_removes_nothing():
    # a rigid pad with the measured 5 um summits hydroplanes at the reference case: no contact, no removal
    with pytest.warns(RuntimeWarning, match="removal_rate_relative is undefined"):
        r = cmpsim.solve(pad_compliance="rigid", grid="coarse", relative=True)
    assert np.isnan(r.scalars["removal_rate_relative"])
    assert '"removal_rate_relative": null' in r.to_json()


def test_shear_power_removal_of_the_default_model_is_the_shear_power_of_the_contact_load():
    """The default model with the shear-power law (its removal law before issue 24) and no fluid
    shear (fluid_shear_weight 0): under uniform sliding speed (equal platen and carrier speeds) its
    wafer mean is k_s mu U times the mean contact pressure exactly, whatever share the Newtonian slurry carries."""
    r = cmpsim.solve(removal_law="shear_power", rotation_speed="1 rpm", grid="coarse", relative=False)
    c = r.config
    assert (c.removal_law, c.fluid_shear_weight) == ("shear_power", 0.0)
    preston = c.shear_power_coefficient * c.friction_coefficient * c.applied_pressure * r.sliding_speed
    assert 0 < r.fluid_load_fraction < 0.05
    assert r.removal_rate_mean == pytest.approx(preston * r.contact_load_fraction, rel=1e-9)


def test_the_reference_case_is_solved_only_when_its_ratio_is_wanted(monkeypatch):
    """Issue 23: removal_rate_relative (and its reference solve) comes by default with the paper's
    removal law only; the predictive default gives it when asked, and its JSON omits it otherwise."""
    import cmpsim.solver.model as model

    solved = []
    monkeypatch.setattr(model, "_REFERENCE_CACHE", {})
    real = model._reference_removal_rate
    monkeypatch.setattr(model, "_reference_removal_rate", lambda ref: solved.append(ref) or real(ref))
    d = cmpsim.solve(grid="coarse")
    assert not solved and "removal_rate_relative" not in d.scalars and "removal_rate_relative" not in d.to_json()
    p = cmpsim.solve(cmpsim.Config.paper(), grid="coarse", applied_pressure="3 psi")
    assert len(solved) == 1 and p.scalars["removal_rate_relative"] > 0
    asked = cmpsim.solve(grid="coarse", relative=True)
    assert len(solved) == 2 and asked.scalars["removal_rate_relative"] == pytest.approx(asked.scalars["removal_rate_mean"] / model._REFERENCE_CACHE[tuple(sorted(solved[-1].to_dict().items()))])
