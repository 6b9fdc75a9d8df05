"""The lot controller that refits its own pad-life model from the lot's wafers (issue 38, control that
holds under drift; cmpsim.polisher.refit, docs/polisher.md eqs. C6-C8): the refit recovers the
constants that made the rates, keeps its constants when the rates do not identify them, holds a lot
whose model of the pad is wrong within 1 % where the fixed model does not, and resumes bit for bit."""

import json
import math
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
    """C6-C7 on rates the model itself makes: k_w alone from three rates, then k_w and G_c together, each to
    1e-4 of the constants that made them; the refitted model's pad ages are the rates' shape."""
    recipe, model, state, lot = _history(true_constants, [60, 90, 120, 150, 180, 240, 300, 360])
    for n, wafer in enumerate(lot, start=2):
        state = refit(state.seen(wafer), model, recipe, COARSE, 1.0, 30.0)
        if n < MIN_RATES:
            assert not state.last["refit"] and "needs 3" in state.last["why"]
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


LOT = dict(control="ewma", conditioning="none", seed=1, overrides=COARSE, zone_feedback=False, pad_constants=FAST, model_pad_constants=D)


@pytest.fixture(scope="module")
def refitted():
    return run_lot(RECIPE, 6, refit_model=True, **LOT)


def test_a_lot_whose_model_of_the_pad_is_wrong_holds_1_percent_once_the_model_is_refitted(refitted):
    """The fab's pad glazes twice as fast as the controller's model: with the model fixed the lot misses by
    up to 7.7 % on wafers 3-6 (measured); refitted after each wafer (from the third rate on) within 0.05 %, its k_w
    within 1 % of the pad's."""
    fixed = run_lot(RECIPE, 6, **LOT)
    miss = [abs(w.final_thickness_mean / refitted.target - 1) for w in fixed.wafers]
    assert max(miss[2:]) > 0.05
    miss = [abs(w.final_thickness_mean / refitted.target - 1) for w in refitted.wafers]
    assert max(miss[2:]) < 5e-4
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
