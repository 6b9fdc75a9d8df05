"""Run-to-run control that learns (issue 38): the double EWMA follows a drift with no offset, the
zone feedback never takes a step it predicts raises the non-uniformity, a lot killed with -9
resumes bit for bit, and the issue's criteria on the shipped oxide recipe (slow)."""

import json
import os
import signal
import subprocess
import sys
import time
from importlib import resources
from pathlib import Path

import numpy as np
import pytest
from click.testing import CliRunner

from cmpsim.cli import main
from cmpsim.polisher.checkpoint import NAME, CheckpointMismatch, read_checkpoint
from cmpsim.polisher.control import DoubleEWMA, SingleEWMA, make_estimator
from cmpsim.polisher.lot import run_lot
from cmpsim.polisher.zones import PSI, ZoneFeedback, ZoneState, area_weights, nonuniformity, predicted_final

RECIPE_PATH = resources.files("cmpsim") / "data" / "recipe_oxide.toml"
RECIPE = RECIPE_PATH.read_text(encoding="utf-8")  # the oxide recipe, as shipped
COARSE = {"grid": "coarse"}


# --- the double EWMA on a synthetic process (eqs. C2-C4) -------------------------------------------

@pytest.mark.parametrize("ages", ["wafer", "irregular"])
def test_the_double_ewma_follows_a_linear_drift_with_no_steady_state_offset(ages):
    """r(A) = r0 + delta A: after the transient the prediction for the next wafer is exact (analytic:
    the fixed point a_k = r_k, D_k = delta of eqs. C2-C3 holds at any age spacing), while the single
    EWMA stays delta/lambda behind on unit spacing (it chases)."""
    rng = np.random.default_rng(7)
    r0, delta = 5e-9, -1e-11
    steps = np.ones(300) if ages == "wafer" else rng.uniform(0.2, 3.0, 300)
    age = np.concatenate([[0.0], np.cumsum(steps)])
    est = DoubleEWMA(level=r0, drift=0.0, age=0.0, clock="wafer")
    errors = []
    for k in range(1, age.size):
        errors.append(est.predict(age[k]) - (r0 + delta * age[k]))
        est = est.update(r0 + delta * age[k], age[k])
    errors = np.abs(np.array(errors)) / r0
    assert errors[0] > 1e-3  # it had to learn the drift
    assert np.max(errors[-20:]) < 1e-12, errors[-20:]
    assert est.drift == pytest.approx(delta, rel=1e-9)
    single = SingleEWMA(level=r0, weight=0.3)
    for k in range(1, 121):
        lag = single.predict() - (r0 + delta * k)
        single = single.update(r0 + delta * k)
    assert lag == pytest.approx(-delta / 0.3, rel=1e-6)


def test_the_model_drift_prior_is_exact_when_the_rate_follows_the_glazing_factor():
    """Eq. C5: on the glazing clock with the model's prior the first prediction of a rate r = c f(age) is exact."""
    c = 5.13e-9
    est = make_estimator("ewma", c * 0.93, clock="glazing", age=0.93, drift_prior="model")
    for f in (0.88, 0.8, 0.71, 0.6):
        assert est.predict(f) == pytest.approx(c * f, rel=1e-13)
        est = est.update(c * f, f)
    assert make_estimator("ewma", c, clock="glazing", age=0.93, drift_prior="none").drift == 0.0


# --- the zone feedback (eqs. Z1-Z5) ---------------------------------------------------------------

def _head(rng, zones=5, rings=30):
    r = np.linspace(0.005, 0.149, rings)
    centres = np.linspace(0.02, 0.145, zones)
    width = rng.uniform(0.01, 0.05)
    response = np.exp(-(((r[:, None] - centres[None, :]) / width) ** 2)) * rng.uniform(0.2, 1.5, zones) * 1e-13
    response += rng.normal(0, 0.1e-13, response.shape)  # coupling and noise: the predicted step may be poor
    w = area_weights(r)
    return r, w, response


def test_the_zone_feedback_never_takes_a_step_it_predicts_raises_the_nonuniformity():
    """Eq. Z4 on 300 random heads, shapes, incoming profiles, pressures near the bounds and weights:
    the predicted non-uniformity at the chosen pressures is never above the current pressures'; some
    steps are refused or halved (the check is not vacuous)."""
    rng = np.random.default_rng(38)
    decisions = []
    for _ in range(300):
        r, w, response = _head(rng)
        zones = response.shape[1]
        shape = 1.0 + rng.normal(0, 0.03, r.size) + rng.uniform(-0.05, 0.05) * (r / r[-1]) ** 4
        shape /= w @ shape
        fb = ZoneFeedback(response=response, start_pressures=(3 * PSI,) * zones, mean_rate=4e-9, weights=w,
                          zone_areas=np.full(zones, 1.0), regularisation=10 ** rng.uniform(-6, 0), keep_load=bool(rng.integers(2)),
                          bounds=(rng.uniform(0.5, 2.9) * PSI, rng.uniform(3.1, 8) * PSI), halvings=int(rng.integers(0, 4)))
        state = ZoneState(tuple(rng.uniform(fb.bounds[0], fb.bounds[1], zones)), shape)
        incoming = 1e-6 * (1 + rng.normal(0, 0.01) * (r / r[-1] - 2 / 3) + rng.normal(0, 0.002, r.size))
        plan = fb.plan(state, incoming, 5e-7)
        assert plan.nu_after <= plan.nu_before
        step = np.array(plan.pressures) - np.array(state.pressures)
        assert plan.nu_after == pytest.approx(fb.predicted_nonuniformity(state, step, incoming, 5e-7), rel=1e-12)
        assert np.all(np.array(plan.pressures) >= fb.bounds[0]) and np.all(np.array(plan.pressures) <= fb.bounds[1])
        if plan.decision == "refused":
            assert plan.pressures == state.pressures
        decisions.append(plan.decision.split()[0])
    assert {"accepted", "halved", "refused"} <= set(decisions), set(decisions)


def test_the_zone_feedback_flattens_a_linear_plant_and_its_prediction_is_the_plant():
    """A plant whose rate is exactly linear in the zone pressures: the predicted final profile
    (eq. Z2) equals the polished one, and the feedback removes the shape the zones can reach."""
    r = np.linspace(0.0, 0.15, 61)
    w = area_weights(r)
    centres = np.array([0.0, 0.05, 0.1, 0.14])
    response = np.exp(-(((r[:, None] - centres[None, :]) / 0.03) ** 2)) * 1e-13  # m/s/Pa, overlapping
    p0 = np.full(4, 3 * PSI)
    base = 4e-9 + response @ np.array([-0.1, 0.05, -0.35, 0.4]) * PSI  # a shape the zones can undo
    fb = ZoneFeedback(response=response, start_pressures=tuple(p0), mean_rate=float(w @ base), weights=w, zone_areas=np.ones(4),
                      zone_weight=1.0, regularisation=1e-9)
    state = ZoneState(tuple(p0), base / (w @ base))
    incoming = np.full(r.size, 1e-6)
    spreads = []
    for _ in range(4):
        plan = fb.plan(state, incoming, 5e-7)
        rate = base + response @ (np.array(plan.pressures) - p0)
        time = (w @ incoming - 5e-7) / (w @ rate)
        final = incoming - rate * time
        np.testing.assert_allclose(final, predicted_final(incoming, 5e-7, fb.shape_after(state, np.array(plan.pressures) - state.pressures), w),
                                   rtol=0, atol=1e-18)
        spreads.append(nonuniformity(final, w))
        state = fb.learn(state, plan.pressures, rate)
    assert spreads[-1] < 1e-6 and nonuniformity(incoming - base * (w @ incoming - 5e-7) / (w @ base), w) > 1e-2, spreads


# --- the checkpoint --------------------------------------------------------------------------------

def test_a_checkpoint_of_other_inputs_is_refused_naming_them(tmp_path):
    path = tmp_path / NAME
    lot = run_lot(RECIPE, 1, control="ewma", seed=1, overrides=COARSE, conditioning="none", checkpoint=path)
    assert json.loads(path.read_text())["next_wafer"] == 1 and len(lot.wafers) == 1
    with pytest.raises(CheckpointMismatch, match=r"seed: checkpoint 1, now 2"):
        run_lot(RECIPE, 1, control="ewma", seed=2, overrides=COARSE, conditioning="none", checkpoint=path, resume=True)
    saved = json.loads(path.read_text())
    with pytest.raises(CheckpointMismatch, match="drift_weight"):
        read_checkpoint(path, saved["inputs"] | {"drift_weight": 0.5})
    path.write_text("{not json")
    with pytest.raises(CheckpointMismatch, match="not a lot checkpoint"):
        read_checkpoint(path, saved["inputs"])
    assert read_checkpoint(tmp_path / "absent.json", saved["inputs"]) is None


def test_the_cli_refuses_resume_without_out_and_a_foreign_checkpoint(tmp_path):
    bad = CliRunner().invoke(main, ["lot", str(RECIPE_PATH), "--wafers", "1", "--resume"])
    assert bad.exit_code == 2 and "--out" in bad.output
    out = tmp_path / "lot"
    out.mkdir()
    (out / NAME).write_text(json.dumps({"format": "something else"}))
    bad = CliRunner().invoke(main, ["lot", str(RECIPE_PATH), "--wafers", "1", "--set", "grid=coarse", "--out", str(out), "--resume"])
    assert bad.exit_code == 2 and "not a lot checkpoint" in bad.output
    assert {p.name for p in out.iterdir()} == {NAME}  # nothing written
    bad = CliRunner().invoke(main, ["lot", str(RECIPE_PATH), "--drift-weight", "0"])
    assert bad.exit_code == 2 and "--drift-weight" in bad.output


def _lot_command(out, wafers):
    return [sys.executable, "-m", "cmpsim.cli", "lot", str(RECIPE_PATH), "--wafers", str(wafers), "--control", "ewma",
            "--conditioning", "none", "--seed", "1", "--set", "grid=coarse", "--json", "--out", str(out)]


@pytest.mark.slow
def test_a_lot_killed_with_sigkill_resumes_bit_for_bit(tmp_path):
    """A real process killed with SIGKILL after its second wafer, then run again with --resume,
    gives the same lot.json wafers, bit for bit, as the lot run without interruption."""
    env = dict(os.environ, PYTHONPATH=str(Path(__file__).resolve().parents[1] / "src"))
    wafers = 5
    whole = subprocess.run(_lot_command(tmp_path / "whole", wafers), env=env, capture_output=True, text=True, timeout=900)
    assert whole.returncode == 0, whole.stderr
    out = tmp_path / "killed"
    # the gate blocks the lot for good once wafer 2's checkpoint is written: the kill lands mid-lot, no race
    gate = [sys.executable, str(Path(__file__).with_name("lot_gate.py")), "2", *_lot_command(out, wafers)[3:]]
    proc = subprocess.Popen(gate, env=env, stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
    checkpoint = out / NAME
    deadline = time.monotonic() + 900
    try:
        while time.monotonic() < deadline:
            if checkpoint.exists() and json.loads(checkpoint.read_text())["next_wafer"] >= 2:
                break
            assert proc.poll() is None, "the lot ended before it could be killed"
            time.sleep(0.05)
        os.kill(proc.pid, signal.SIGKILL)
    finally:
        proc.wait(timeout=60)
    assert proc.returncode == -signal.SIGKILL
    done = json.loads(checkpoint.read_text())["next_wafer"]
    assert 2 <= done < wafers  # killed mid-lot
    assert not (out / "lot.json").exists()
    resumed = subprocess.run([*_lot_command(out, wafers), "--resume"], env=env, capture_output=True, text=True, timeout=900)
    assert resumed.returncode == 0, resumed.stderr
    a = json.loads((tmp_path / "whole" / "lot.json").read_text())
    b = json.loads((out / "lot.json").read_text())
    assert a["wafers"] == b["wafers"]  # every float equal: JSON writes repr, which round-trips
    assert {k: v for k, v in a.items() if k not in ("wall_time", "solves")} == {k: v for k, v in b.items() if k not in ("wall_time", "solves")}
    assert json.loads(resumed.stdout)["wafers"] == a["wafers"]


# --- the controller's own model of the pad ----------------------------------------------------------

def test_the_controller_follows_its_own_model_of_the_pad_not_the_simulated_pads_state(tmp_path):
    """The controller's glazing clock is its model of the pad's life run through the steps it commanded
    (model_pad_constants; default the pad's own). The same constants given explicitly give the lot bit
    for bit; a model that glazes twice as fast commands other times on the same pad, and the checkpoint
    carries the model's state."""
    from cmpsim.physics.padlife import default_constants

    kw = dict(control="ewma", conditioning="none", seed=1, overrides=COARSE, zone_feedback=False)
    own = run_lot(RECIPE, 3, **kw)
    explicit = run_lot(RECIPE, 3, model_pad_constants=default_constants(), **kw)
    assert [w.to_record() for w in own.wafers] == [w.to_record() for w in explicit.wafers]
    wrong = {"pad_wear_coefficient": 2 * default_constants()["pad_wear_coefficient"]}
    other = run_lot(RECIPE, 3, model_pad_constants=wrong, checkpoint=tmp_path / "c.json", **kw)
    assert all(a.polish_time != b.polish_time for a, b in zip(own.wafers, other.wafers))
    saved = json.loads((tmp_path / "c.json").read_text())
    assert saved["model_life"]["polish_time"] > 0 and "model_pad_constants" in saved["inputs"]
    # a model that glazes faster predicts a slower pad, so it polishes longer than the pad needs: the first wafers overshoot
    assert other.wafers[0].final_thickness_mean < own.wafers[0].final_thickness_mean


def test_the_cli_refuses_a_controller_config_it_cannot_use(tmp_path):
    ctl = tmp_path / "ctl.toml"
    ctl.write_text("[calibration.padlife.constants]\npad_wear_coefficient = 5.5e-15\n")
    res = CliRunner().invoke(main, ["lot", str(RECIPE_PATH), "--wafers", "2", "--controller-config", str(ctl)])
    assert res.exit_code == 2 and "needs --control ewma" in res.output
    res = CliRunner().invoke(main, ["lot", str(RECIPE_PATH), "--wafers", "2", "--control", "ewma", "--controller-config", str(RECIPE_PATH)])
    assert res.exit_code == 2 and "no [calibration.padlife] table" in res.output
    bad = tmp_path / "bad.toml"
    bad.write_text("[calibration.padlife.constants]\npad_wear_coefficient = -1.0\n")
    res = CliRunner().invoke(main, ["lot", str(RECIPE_PATH), "--wafers", "2", "--control", "ewma", "--controller-config", str(bad)])
    assert res.exit_code == 2 and "pad_wear_coefficient" in res.output


def test_a_drift_that_carries_the_rate_below_zero_stops_the_lot_saying_why():
    """A per-wafer drift learnt on a pad that glazes fast can extrapolate to a negative rate (measured: the
    model-free double EWMA on a pad glazing twice as fast, docs/polisher.md): no polish time follows, and the
    lot stops naming the wafer, the controller's state and what to do, not with a bare rate error."""
    from dataclasses import replace

    from cmpsim.polisher.lot import _prediction

    est = replace(make_estimator("ewma", 50e-9 / 60, 0.3, 0.3, "wafer", 8.0, "none"), drift=-20e-9 / 60)
    assert _prediction(est, 9.0, 1.0, 9) == pytest.approx(30e-9 / 60)
    with pytest.raises(ValueError, match=r"wafer 12: the ewma controller predicts a removal rate of -10 nm/min .*drift -20 nm/min.*--drift-clock glazing"):
        _prediction(est, 11.0, 1.0, 12)


# --- the criteria on the shipped oxide recipe (25 wafers, no conditioning) ------------------

@pytest.fixture(scope="module")
def lots():
    """The shipped oxide recipe, 25 wafers, seed 1, no conditioning, coarse grid (docs/polisher.md
    gives the default grid's numbers too)."""
    kw = dict(conditioning="none", seed=1, overrides=COARSE)
    return {
        "none": run_lot(RECIPE, 25, control="none", **kw),
        "ewma": run_lot(RECIPE, 25, control="ewma", **kw),
        "ewma, no zones": run_lot(RECIPE, 25, control="ewma", zone_feedback=False, **kw),
    }


def _miss(lot):
    return np.abs(np.array([w.final_thickness_mean for w in lot.wafers]) / lot.target - 1.0)


def _nu(lot):
    return np.array([w.final_thickness_nonuniformity for w in lot.wafers])


@pytest.mark.slow
def test_without_conditioning_the_rate_falls_to_about_half(lots):
    rates = np.array([w.removal_rate_mean for w in lots["none"].wafers])
    assert rates[-1] / rates[0] == pytest.approx(0.53, abs=0.01)


@pytest.mark.slow
def test_the_controlled_lot_holds_the_final_thickness_within_1_percent_on_wafers_5_to_25(lots):
    """Measured 0.0003 % (coarse grid): the drift prior and clock come from the pad-life model that
    also drives the simulated pad (docs/polisher.md says what that does and does not show)."""
    assert np.max(_miss(lots["ewma"])[4:]) <= 0.01, _miss(lots["ewma"])


@pytest.mark.slow
def test_with_zone_feedback_the_nonuniformity_is_no_worse_than_without(lots):
    with_zones, without = _nu(lots["ewma"]), _nu(lots["ewma, no zones"])
    assert np.mean(with_zones) <= np.mean(without), (with_zones, without)
    assert np.max(with_zones[4:]) <= np.max(without[4:])
    assert all(w.zone_step is not None for w in lots["ewma"].wafers)


@pytest.mark.slow
def test_the_zone_feedback_predicts_the_wafers_it_polishes(lots):
    """The predicted non-uniformity (eq. Z2) is the polished one within 0.1 points from wafer 2 on."""
    lot = lots["ewma"]
    predicted = np.array([w.predicted_nonuniformity for w in lot.wafers])
    assert np.max(np.abs(predicted - _nu(lot))[1:]) < 1e-3, (predicted, _nu(lot))


@pytest.mark.slow
@pytest.mark.xfail(strict=True, reason="learnt from scratch (per-wafer clock, no drift prior, lambda 0.3/0.3) the double EWMA misses by "
                   "up to 13.7 % on wafers 5-25 (coarse grid): the glazing's drift falls tenfold over the lot and the filter lags it "
                   "(docs/polisher.md)")
def test_the_model_free_double_ewma_holds_1_percent():
    lot = run_lot(RECIPE, 25, control="ewma", clock="wafer", drift_prior="none", conditioning="none", seed=1, overrides=COARSE,
                  zone_feedback=False)
    assert np.max(_miss(lot)[4:]) <= 0.01, _miss(lot)


#: The glazing factor over each wafer of the controlled lot without conditioning (coarse grid, seed 1; lot.json's rate_factor).
GLAZING = (0.8759, 0.8032, 0.7447, 0.6963, 0.6528, 0.6125, 0.5772, 0.5451, 0.5155, 0.4889, 0.4648, 0.4428, 0.423, 0.4052, 0.3888,
           0.3736, 0.3594, 0.3467, 0.3351, 0.3243, 0.3142, 0.3048, 0.2958, 0.2872, 0.2797)


@pytest.mark.parametrize("gamma, worst, settled", [(0.9, 0.0108, 6), (1.1, 0.0107, 6), (0.8, 0.0217, 7), (1.25, 0.0262, 18)])
def test_a_glazing_the_model_gets_wrong_is_learnt(gamma, worst, settled):
    """The default controller's clock and prior are the pad-life model's (eqs. C2-C5). A pad whose
    rate goes as f^gamma instead of f (the model's glazing off by 1 - gamma in the exponent) is
    learnt: the miss on wafers 5-25 peaks at ``worst`` and stays below 1 % from wafer ``settled``
    (measured; docs/polisher.md). With gamma = 1 it is exact."""
    true = lambda f: 5e-9 * f**gamma  # noqa: E731
    est = make_estimator("ewma", true(0.93), clock="glazing", age=0.93, drift_prior="model")
    miss = []
    for f in GLAZING:
        miss.append(abs(true(f) / est.predict(f) - 1))
        est = est.update(true(f), f)
    miss = np.array(miss)
    assert np.max(miss[4:]) == pytest.approx(worst, abs=5e-4)
    assert np.max(miss[settled - 1:]) < 0.01 <= miss[settled - 2]


# --- a recipe of several steps (C0') ----------------------------------------------------------------

TWO_STEPS = RECIPE.replace('[[step]]\nname = "oxide"\ntime = "60 s"',
                           '[[step]]\nname = "bulk"\ntime = "30 s"\napplied_pressure = "4 psi"\n[[step]]\nname = "finish"\ntime = "60 s"\napplied_pressure = "2 psi"')


@pytest.mark.parametrize("zone_feedback", [False, True])
def test_a_two_step_recipe_is_controlled_to_its_target(zone_feedback):
    """A bulk step of 30 s at 4 psi, then the controlled finish at 2 psi. The feed-forward counts the bulk
    step's removal (its time weighted by P U against the finish's, eq. C0'): within 0.5 % from the first
    wafer, where main missed by 11-17 % (the controlled step was given the whole removal). With zone
    feedback the zones set the finish's pressures only, and the bulk keeps its 4 psi (main: a RecipeError,
    the zone pressures set on every step)."""
    assert "bulk" in TWO_STEPS
    lot = run_lot(TWO_STEPS, 4, control="ewma", conditioning="none", seed=1, overrides=COARSE, zone_feedback=zone_feedback)
    assert max(abs(w.final_thickness_mean / lot.target - 1) for w in lot.wafers) < 5e-3
    assert all(w.step_times[0] == 30.0 and w.step_times[1] > 0 for w in lot.wafers)
    if zone_feedback:
        assert any(w.zone_step == "accepted" for w in lot.wafers) and len(set(lot.wafers[-1].zone_pressures)) > 1
