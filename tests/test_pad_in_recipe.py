"""The pad's life inside a recipe (issue 32): glazing and conditioning advanced at every time step
of the recipe engine (cmpsim.polisher.pad), verified against the pad-life kernel's exact solution
and for its order in the time step; the worn summits entering the solve when asked."""

from __future__ import annotations

import re
from importlib import resources

import numpy as np
import pytest

from cmpsim.inputs.config import Config
from cmpsim.physics.padlife import DEFAULT_PAD, PadLifeState, advance_pad_life, summit_constants
from cmpsim.polisher.engine import PadState, polish
from cmpsim.polisher.lot import run_lot
from cmpsim.polisher.pad import PadLife, fresh_pad, sliding_speed, worn_overrides

COARSE = {"grid": "coarse"}
OXIDE = resources.files("cmpsim").joinpath("data", "recipe_oxide.toml").read_text(encoding="utf-8")
TWO_STEPS = """
preset = "300mm"
[[film]]
material = "oxide"
thickness = "1.0 um"
[[step]]
name = "first"
time = "30 s"
applied_pressure = "3 psi"
[[step]]
name = "second"
time = "20 s"
applied_pressure = "2 psi"
"""


def test_the_fresh_pad_of_a_config_is_the_solvers_and_the_calibrated_pad_of_the_default():
    c = Config.preset("300mm")
    assert fresh_pad(c) == DEFAULT_PAD  # the preset's summits are the calibration's pad
    rough = Config.preset("300mm").replace(pad_roughness=10e-6)  # self-similar: R doubles, eta quarters
    p = fresh_pad(rough)
    assert p.sigma == 10e-6 and p.radius == pytest.approx(2 * c.asperity_radius, rel=1e-15)
    assert p.density == pytest.approx(c.asperity_density / 4, rel=1e-15)
    assert p.wear_coefficient == DEFAULT_PAD.wear_coefficient > 0


@pytest.mark.parametrize("conditioning", ["none", "in_situ"])
def test_the_recipe_wears_the_pad_as_the_kernel_does_over_its_steps(conditioning):
    """Advanced at every time step (1 s, the last shortened) the worn volume equals the kernel's exact
    solution over each step's pressure and speed (eq. L2 composes exactly)."""
    result = polish(TWO_STEPS, overrides=COARSE, pad_life=PadLife(conditioning), time_step=1.0)
    c = Config.preset("300mm")
    expected = advance_pad_life(PadLifeState(), 3 * 6894.757293168361, sliding_speed(c), 30.0, conditioning)
    expected = advance_pad_life(expected, 2 * 6894.757293168361, sliding_speed(c), 20.0, conditioning)
    assert float(result.pad_state.life.worn_volume) == pytest.approx(float(expected.worn_volume), rel=1e-12)
    assert result.pad_state.life.polish_time == pytest.approx(50.0, rel=1e-15)
    trace = result.steps[1].glazing
    assert trace["time"][0] == 30.0 and trace["time"][-1] == 50.0
    f = np.asarray(trace["rate_factor"])
    assert np.all(np.diff(f) < 0) if conditioning == "none" else np.all(np.abs(np.diff(f)) < 0.02)
    assert trace["rate_factor"][-1] == pytest.approx(float(summit_constants(expected).rate_factor), rel=1e-12)


def test_without_a_pad_life_the_recipe_is_unchanged_and_a_fresh_pad_life_starts_at_factor_one():
    plain = polish(OXIDE, overrides=COARSE)
    worn = polish(OXIDE, overrides=COARSE, pad_life=PadLife("none"))
    assert plain.steps[0].glazing is None and plain.pad_state.life is None
    assert worn.steps[0].glazing["rate_factor"][0] == 1.0
    assert plain.steps[0].removal_rate_profile == worn.steps[0].removal_rate_profile  # the step's start: fresh
    assert worn.steps[0].removed_volume < plain.steps[0].removed_volume  # the pad glazes during the step


@pytest.mark.parametrize("worn_for, order", [(0.0, 5.0 / 3.0), (120.0, 2.0)])
def test_the_glazed_removal_converges_at_the_order_of_the_midpoint_rule(worn_for, order):
    """The rate of a time step is the rate of the step's solve times the glazing factor at mid-step:
    the midpoint rule, second order in the time step for a smooth factor (a pad already worn for
    120 s). From a fresh pad the factor is not smooth at t = 0: the front leaves the cutoff c as
    t^(1/3) (the cap volume J2 ~ (c - zeta)^3 there) and the flat area as t^(2/3), so the first time
    step's error is O(dt^(5/3)) and the observed order is 5/3. No conditioning: the factor falls fastest."""
    c = Config.preset("300mm")
    start = PadState(life=advance_pad_life(PadLifeState(), c.applied_pressure, sliding_speed(c), worn_for, "none"))
    steps = (20.0, 10.0, 5.0, 0.3125)
    removed = {dt: polish(OXIDE, overrides=COARSE, pad_state=start, pad_life=PadLife("none"), time_step=dt).steps[0].removed_volume for dt in steps}
    errors = np.array([abs(removed[dt] - removed[steps[-1]]) for dt in steps[:-1]])
    observed = np.log2(errors[:-1] / errors[1:])
    assert np.all(np.abs(observed - order) < 0.06), (errors, observed)


def test_worn_summits_enter_the_solve_only_when_asked():
    c = Config.preset("300mm")
    assert worn_overrides(c, PadLifeState()) == {}  # a fresh pad changes nothing
    worn = advance_pad_life(PadLifeState(), c.applied_pressure, sliding_speed(c), 120.0, "none")
    over = worn_overrides(c, worn)
    ratio = float(summit_constants(worn).sigma)
    assert over == {"pad_roughness": pytest.approx(5e-6 * ratio, rel=1e-15), "asperity_radius": c.asperity_radius,
                    "asperity_density": c.asperity_density, "roughness_scaling": "fixed_summits"}
    start = PadState(life=worn)
    kept = polish(OXIDE, overrides=COARSE, pad_state=start, pad_life=PadLife("none"))
    entered = polish(OXIDE, overrides=COARSE, pad_state=start, pad_life=PadLife("none", worn_summits=True))
    assert kept.steps[0].glazing["summit_sigma"] == entered.steps[0].glazing["summit_sigma"] == pytest.approx(ratio)
    assert entered.steps[0].removed_volume != kept.steps[0].removed_volume  # the worn std changed the equilibrium


def test_a_lot_on_a_fresh_pad_shows_the_first_wafer_effect_within_2_percent():
    """qualification = 0: the lot starts on a fresh pad; in situ the pad reaches its balance within
    the first wafer (time constant 1/r_c = 20 s), so the first wafer is faster by about 1 %, not by
    the 3.4 % the balance's own factor differs from fresh (measured 0.95 %)."""
    lot = run_lot(OXIDE, 3, conditioning="in_situ", seed=1, overrides=COARSE, qualification=0)
    rates = np.array([w.removal_rate_mean for w in lot.wafers])
    first_effect = rates[0] / rates[1] - 1.0
    assert 0.0 < first_effect < 0.02, first_effect
    assert lot.qualification is None


def test_a_qualified_lot_starts_on_the_monitor_wafers_pad_and_reports_it():
    lot = run_lot(OXIDE, 1, conditioning="none", seed=1, overrides=COARSE, qualification=2)
    assert lot.qualification["wafers"] == 2 and lot.qualification["polish_time"] == 60.0
    assert lot.to_dict()["qualification"]["removal_rate_mean"] > lot.wafers[0].removal_rate_mean  # the pad glazed on
    assert lot.wafers[0].summit_sigma < 1.0
    with pytest.raises(ValueError, match="qualification"):
        run_lot(OXIDE, 1, overrides=COARSE, qualification=-1)


def test_a_recipe_can_carry_its_conditioning_and_disk_and_bad_ones_are_refused():
    from cmpsim.polisher.recipe import RecipeError, parse_recipe

    text = 'conditioning = "none"\n' + OXIDE + '[conditioner]\ndown_force = "5 lbf"\nsweep_duty = 0.5\n'
    recipe = parse_recipe(text)
    assert recipe.conditioning == "none"
    assert recipe.conditioner.down_force == pytest.approx(22.241108, rel=1e-6) and recipe.conditioner.sweep_duty == 0.5
    own = polish(recipe, overrides=COARSE)  # the recipe's pad life, without pad_life=
    given = polish(OXIDE, overrides=COARSE, pad_life=PadLife("none"))
    assert own.steps[0].glazing["rate_factor"] == given.steps[0].glazing["rate_factor"]
    lot = run_lot(recipe, 1, overrides=COARSE, qualification=0)
    assert lot.conditioning == "none"  # the lot takes the recipe's conditioning unless told
    assert run_lot(recipe, 1, overrides=COARSE, qualification=0, conditioning="in_situ").conditioning == "in_situ"
    for top, table, words in [
        ('conditioning = "sometimes"\n', "", "conditioning (line 1) must be one of"),
        ("", '[conditioner]\ndown_force = "1 N"\n', "needs conditioning"),
        ('conditioning = "in_situ"\n', "[conditioner]\nforce = 1\n", "unknown key 'force'"),
        ('conditioning = "in_situ"\n', '[conditioner]\ndown_force = "3 m"\n', "down_force"),
        ('conditioning = "in_situ"\n', "[conditioner]\nsweep_duty = 2\n", "sweep_duty"),
    ]:
        with pytest.raises(RecipeError, match=re.escape(words)):
            parse_recipe(top + OXIDE + table)


def test_a_lot_solves_a_wafer_whose_inputs_repeat_once_and_the_reuse_changes_nothing():
    """Without control every wafer has the monitor's inputs: one solve serves the lot (polish's cache),
    and a recipe polished from that cache equals one polished alone, bit for bit."""
    lot = run_lot(OXIDE, 3, conditioning="in_situ", seed=1, overrides=COARSE)
    assert lot.solves == 1
    cache: dict = {}
    first = polish(OXIDE, overrides=COARSE, cache=cache)
    again = polish(OXIDE, overrides=COARSE, cache=cache)
    alone = polish(OXIDE, overrides=COARSE)
    assert (first.solves, again.solves, alone.solves) == (1, 0, 1)
    assert again.steps[0].thickness == alone.steps[0].thickness and again.steps[0].removed_volume == alone.steps[0].removed_volume
    assert len(cache) == 1
    polish(TWO_STEPS, overrides=COARSE, cache=cache)
    assert len(cache) == 2  # the cache holds the last call's solves only
