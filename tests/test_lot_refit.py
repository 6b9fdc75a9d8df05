"""The lot controller that refits its own pad-life model from the lot's wafers (issue 38, control that
holds under drift; cmpsim.polisher.refit, docs/polisher.md eqs. C6-C8): the refit recovers the
constants that made the rates, keeps its constants when the rates do not identify them, holds a lot
whose model of the pad is wrong within 1 % where the fixed model does not, and resumes bit for bit."""

import json
import math
from dataclasses import replace
from importlib import resources

import numpy as np
import pytest
from click.testing import CliRunner

from cmpsim.cli import main
from cmpsim.physics.padlife import default_constants
from cmpsim.polisher.lot import run_lot
from cmpsim.polisher.pad import PadLife
from cmpsim.polisher.recipe import load_recipe
from cmpsim.polisher.refit import IDENTIFIED, MIN_RATES, RefitState, Seen, refit, refitted_model, walk

RECIPE_PATH = resources.files("cmpsim") / "data" / "recipe_oxide.toml"
RECIPE = RECIPE_PATH.read_text(encoding="utf-8")
COARSE = {"grid": "coarse"}
D = default_constants()
FAST = {"pad_wear_coefficient": 2 * D["pad_wear_coefficient"]}  # a fab pad that glazes twice as fast as the model's
FASTER = {"pad_wear_coefficient": 2 * D["pad_wear_coefficient"], "critical_glazed_area": 0.6 * D["critical_glazed_area"]}


def _history(true_constants, durations, level=3e-9):
    """A monitor wafer and lot wafers of the given one-step ``durations`` (s), their rates made by the pad-life
    model of ``true_constants`` (r_j = level f_j, eq. C6), and the controller's memory of the default model."""
    recipe = load_recipe(RECIPE)
    wafers = [Seen((float(d),)) for d in durations]
    ages, _ = walk(PadLife("none", constants=true_constants), recipe, COARSE, wafers, 1.0, 30.0)
    seen = [Seen(w.durations, None, level * a) for w, a in zip(wafers, ages)]
    model = PadLife("none", constants=D)
    start = RefitState.begin(model, recipe.step_config(recipe.steps[0], COARSE), seen[0].rate, seen[:1])
    return recipe, model, start, seen[1:]


@pytest.mark.parametrize("true_constants", [FAST, FASTER])
def test_the_refit_recovers_the_constants_that_made_the_rates(true_constants):
    """C6-C7 on rates the model itself makes: k_w alone from four rates, then k_w and G_c together, each to
    1e-4 of the constants that made them; the refitted model's pad ages are the rates' shape."""
    recipe, model, state, lot = _history(true_constants, [60, 90, 120, 150, 180, 240, 300, 360])
    for n, wafer in enumerate(lot, start=2):
        state = refit(state.seen(wafer), model, recipe, COARSE, 1.0, 30.0)
        if n < MIN_RATES:
            assert not state.last["refit"] and f"needs {MIN_RATES}" in state.last["why"]
        else:
            assert state.last["refit"], state.last
            assert state.last["fitted"] == ("k_w" if n == MIN_RATES else "k_w, G_c")
    truth = {**D, **true_constants}
    assert state.wear_coefficient == pytest.approx(truth["pad_wear_coefficient"], rel=1e-4)
    assert state.critical_glazed_area == pytest.approx(truth["critical_glazed_area"], rel=1e-4)
    assert all(h < IDENTIFIED for h in state.last["half_width"])
    ages, _ = walk(refitted_model(model, state), recipe, COARSE, state.wafers, 1.0, 30.0)
    rates = np.array([w.rate for w in state.wafers])
    assert np.std(np.log(rates) - np.log(ages)) < 1e-5


def test_the_refit_keeps_the_model_when_the_rates_do_not_identify_it():
    """Rates that scatter by 20 % around the model's shape do not give k_w within a factor 2: the constants
    stay, and the memory says why (C7)."""
    recipe, model, state, lot = _history(FAST, [60, 70, 80, 90])
    noise = np.random.default_rng(3).normal(0.0, 0.2, len(lot))
    for wafer, e in zip(lot, noise):
        state = refit(state.seen(Seen(wafer.durations, None, wafer.rate * math.exp(e))), model, recipe, COARSE, 1.0, 30.0)
    assert not state.moved and not state.last["refit"]
    assert "not identified" in state.last["why"] or "bound" in state.last["why"]


def test_the_refit_needs_the_double_ewma_on_the_glazing_clock():
    for kw in ({"control": "none"}, {"control": "single_ewma"}, {"control": "ewma", "clock": "wafer"}):
        with pytest.raises(ValueError, match="refit_model .* needs control 'ewma' with clock 'glazing'"):
            run_lot(RECIPE, 2, refit_model=True, **kw)
    res = CliRunner().invoke(main, ["lot", str(RECIPE_PATH), "--wafers", "2", "--refit-model"])
    assert res.exit_code == 2 and "refit_model" in res.output
    two_steps = RECIPE + '[[step]]\nname = "buff"\ntime = "10 s"\napplied_pressure = "1 psi"\n'
    with pytest.raises(ValueError, match="refit_model needs a one-step recipe; .* has 2 steps"):
        run_lot(two_steps, 2, control="ewma", refit_model=True)


def test_the_refits_intervals_hold_their_95_percent_on_noisy_rates():
    """C7 with Student's t: rates with 2 % of scatter about the model of a pad glazing twice as fast, a monitor
    and four lot wafers, 40 draws: the true k_w lies inside the interval of at least 85 % of the refits taken
    (95 % nominal), and at most two of them are off by more than a factor 2 (the review found 10 of 94 with
    the normal quantile and three rates)."""
    recipe, model, start, lot = _history(FAST, [60, 90, 120, 150, 180])
    rng = np.random.default_rng(0)
    true = math.log(FAST["pad_wear_coefficient"])
    taken = inside = far = 0
    for _ in range(40):
        state = start
        for w in lot:
            state = state.seen(Seen(w.durations, None, w.rate * math.exp(0.02 * rng.standard_normal())))
        first = Seen(start.wafers[0].durations, None, start.wafers[0].rate * math.exp(0.02 * rng.standard_normal()))
        state = refit(replace(state, wafers=(first,) + state.wafers[1:]), model, recipe, COARSE, 1.0, 30.0)
        if state.last["refit"]:
            taken += 1
            err = abs(math.log(state.wear_coefficient) - true)
            inside += err <= state.last["half_width"][0]
            far += err > math.log(2.0)
    assert taken >= 20 and inside >= 0.85 * taken and far <= 2


def test_a_rate_not_above_zero_is_kept_but_not_fitted():
    """A wafer measured to remove nothing (or less than nothing, under metrology noise) does not stop later
    refits: its rate is left out of C6, the others refit as without it."""
    recipe, model, state, lot = _history(FAST, [60, 90, 120, 150, 180])
    clean = state
    for w in lot:
        clean = clean.seen(w)
    for bad in (0.0, -1e-10, float("nan")):
        odd = state.seen(Seen((20.0,), None, bad))
        for w in lot:
            odd = odd.seen(w)
        with np.errstate(all="raise"):
            odd = refit(odd, model, recipe, COARSE, 1.0, 30.0)
        assert odd.last["refit"] and odd.last["rates"] == len(lot) + 1
    assert refit(clean, model, recipe, COARSE, 1.0, 30.0).last["refit"]


def test_a_refit_stays_inside_the_constants_valid_range():
    """G_c at the top of its valid range (1): the refit's search ends there, and the refitted model is one
    the pad-life kernel takes (the review's rates of G_c = 1 made it accept 1.009 and the lot fail)."""
    recipe, model, state, lot = _history({"critical_glazed_area": 1.0}, [60, 90, 120, 150, 180, 210, 240])
    for w in lot:
        state = refit(state.seen(w), model, recipe, COARSE, 1.0, 30.0)
        assert state.critical_glazed_area <= 1.0
        refitted_model(model, state).at(recipe.step_config(recipe.steps[0], COARSE))  # the kernel's own range check


def test_the_history_walks_as_the_controller_and_its_replay_is_the_filter_from_the_start():
    """History (each wafer walked once at the starting constants, scaled) gives the ages the pad-life model
    gives wafer by wafer (wear_through, then the idle), and C8's replay is the double EWMA run from the seed
    over those ages."""
    from dataclasses import replace as _replace

    from cmpsim.physics.padlife import PadLifeState
    from cmpsim.polisher.control import make_estimator
    from cmpsim.polisher.pad import wear_through
    from cmpsim.polisher.refit import History, replay, starting_model

    recipe, model, state, lot = _history(FASTER, [60, 90, 120, 150, 180])
    for w in lot:
        state = state.seen(w)
    state = _replace(state, wear_coefficient=2 * state.start, critical_glazed_area=0.6 * state.start_glazed_area)
    history = History().extend(starting_model(model, state), recipe, COARSE, state.wafers, 1.0, 30.0)
    new, estimator, life = replay(state, history, model, "ewma", 0.3, 0.3, "glazing", "model")
    config = recipe.step_config(recipe.steps[0], COARSE)
    ages, walked = [], PadLifeState()
    for w in state.wafers:
        age, walked = wear_through(new, [(config, w.durations[0])], walked, 1.0)
        walked = new.idle(walked, 30.0)
        ages.append(age)
    assert history.ages(2.0, 0.6 * state.start_glazed_area) == pytest.approx(ages, rel=1e-12)
    assert float(life.worn_volume) == pytest.approx(float(walked.worn_volume), rel=1e-12)
    filt = make_estimator("ewma", state.seed_rate, 0.3, 0.3, "glazing", ages[0], "model")
    for w, a in zip(state.wafers[1:], ages[1:]):
        filt = filt.update(w.rate, a)
    assert (estimator.level, estimator.drift, estimator.age) == pytest.approx((filt.level, filt.drift, filt.age), rel=1e-12)


LOT = dict(control="ewma", conditioning="none", seed=1, overrides=COARSE, zone_feedback=False, pad_constants=FAST, model_pad_constants=D)


@pytest.fixture(scope="module")
def refitted():
    return run_lot(RECIPE, 6, refit_model=True, **LOT)


def test_a_lot_whose_model_of_the_pad_is_wrong_holds_1_percent_once_the_model_is_refitted(refitted):
    """The fab's pad glazes twice as fast as the controller's model: with the model fixed the lot misses by
    up to 7.7 % on wafers 3-6 (measured); refitted after each wafer (from the fourth rate on) within 0.05 % on
    wafers 4-6, its k_w
    within 1 % of the pad's."""
    fixed = run_lot(RECIPE, 6, **LOT)
    miss = [abs(w.final_thickness_mean / refitted.target - 1) for w in fixed.wafers]
    assert max(miss[2:]) > 0.05
    miss = [abs(w.final_thickness_mean / refitted.target - 1) for w in refitted.wafers]
    assert max(miss[3:]) < 5e-4
    assert refitted.wafers[-1].model_wear_coefficient == pytest.approx(FAST["pad_wear_coefficient"], rel=0.01)
    assert refitted.controller["refit_model"] is True and fixed.wafers[-1].model_wear_coefficient is None


def test_a_refitting_lot_interrupted_resumes_bit_for_bit(refitted, tmp_path):
    class Stop(Exception):
        pass

    def stop_after_3(record):
        if record.index == 3:
            raise Stop

    path = tmp_path / "lot.checkpoint.json"
    with pytest.raises(Stop):
        run_lot(RECIPE, 6, refit_model=True, checkpoint=path, after_wafer=stop_after_3, **LOT)
    assert json.loads(path.read_text())["refit"]["wafers"]  # the controller's memory is in the checkpoint
    resumed = run_lot(RECIPE, 6, refit_model=True, checkpoint=path, resume=True, **LOT)
    assert [w.to_record() for w in resumed.wafers] == [w.to_record() for w in refitted.wafers]


def test_the_command_line_refits_and_reports_the_models_constants_per_wafer():
    res = CliRunner().invoke(main, ["lot", str(RECIPE_PATH), "--wafers", "3", "--control", "ewma", "--refit-model", "--conditioning", "none",
                                    "--no-zone-feedback", "--seed", "1", "--set", "grid=coarse", "--json"])
    assert res.exit_code == 0, res.output
    out = json.loads(res.output)
    assert out["controller"]["refit_model"] is True
    assert out["units"]["model_wear_coefficient"].startswith("1/Pa")
    assert all(w["model_wear_coefficient"] > 0 and w["model_critical_glazed_area"] > 0 for w in out["wafers"])


@pytest.mark.parametrize("conditioning, qualification", [("ex_situ", 0), ("in_situ", 2)])
def test_the_refit_follows_the_pad_on_a_fresh_pad_and_under_conditioning(conditioning, qualification):
    """Without monitor wafers (the EWMA seeded by the model, the fit on the lot's own rates only) and with
    two, conditioned between wafers or while polishing: the refitted k_w comes within 5 % of the pad's
    (measured 5.532e-15 and 5.531e-15 against 5.533e-15), and the last wafers hold 0.1 % (measured
    0.001 % and 0; the fresh pad's first four wafers, before the first refit, miss by 2.6-5.2 %)."""
    lot = run_lot(RECIPE, 6, refit_model=True, **{**LOT, "conditioning": conditioning, "qualification": qualification})
    assert lot.wafers[-1].model_wear_coefficient == pytest.approx(FAST["pad_wear_coefficient"], rel=0.05)
    assert all(abs(w.final_thickness_mean / lot.target - 1) < 1e-3 for w in lot.wafers[-2:])
