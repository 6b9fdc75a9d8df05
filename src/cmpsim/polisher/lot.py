"""A lot: the wafers of a recipe in sequence on one pad, under run-to-run control (issue 32).

Each wafer is polished by :func:`cmpsim.polisher.engine.polish` with the pad carried from the
last one: its temperature (the wafer cools it between wafers, :func:`~cmpsim.polisher.engine.idle`)
and its life (the summit caps worn flat while polishing and cut back by the conditioning disk,
:mod:`cmpsim.physics.padlife`: ``conditioning`` "none", "ex_situ" between wafers, or "in_situ"
during the polish), advanced by the recipe engine at every time step (:mod:`cmpsim.polisher.pad`).
The glazing enters the removal rate through the pad-life kernel's glazed-area factor (eq. L4 of
docs/polisher.md; calibrated to Jeong et al. 2024, compared with Lawing 2004); with
``worn_summits`` the worn summit std enters each step's wafer solve as well.

Before the lot, ``qualification`` monitor wafers (1 by default) run the recipe as written on the
same pad, at the nominal incoming thickness: a fab commonly measures a blanket monitor's removal
rate when a lot starts on a tool (practice, not sourced here), and that measurement seeds the
EWMA's rate estimate. The pad they polished (warmed, worn, conditioned) is the pad the lot starts on. With ``qualification =
0`` the lot starts on the fresh pad and the controller is seeded by the model's prediction for it.

The incoming thickness of the top film varies from wafer to wafer
(:func:`cmpsim.polisher.incoming.incoming_profiles`, reproducible with ``seed``), or is given.
With ``control = "ewma"`` (the double EWMA) or ``"single_ewma"`` the run-to-run controller sets each
wafer's polish time of the recipe's last timed step from the rate its estimator
(:mod:`cmpsim.polisher.control`) predicts for the wafer's pad age and the incoming thickness
measured before the wafer (feed-forward, eq. C0), and, on a zoned membrane head, its zone
pressures through the head's zone response, computed once for the lot at its starting pressures,
taking only steps predicted to lower the non-uniformity (:mod:`cmpsim.polisher.zones`).

With ``checkpoint`` the lot's state is written atomically after its set-up and after every wafer
(:mod:`cmpsim.polisher.checkpoint`); ``resume`` goes on from it with results identical to the
uninterrupted lot. The lot always continues from the checkpoint's numbers, resumed or not.
"""

from __future__ import annotations

import math
import time as _time
from dataclasses import replace

import numpy as np

from ..results.uniformity import weighted_std_over_mean
from ..physics.padlife import ConditionerDisk, FreshPad, PadLifeState
from .checkpoint import (LotCheckpoint, digest, life_from_dict, life_to_dict, pad_state_from_dict, pad_state_to_dict, read_checkpoint,
                         write_checkpoint)
from .control import CONTROL, DRIFT_WEIGHT, WEIGHT, estimator_from_dict, feed_forward_time, make_estimator
from .engine import PadState, idle, polish
from .incoming import incoming_profiles, measurement_errors
from .pad import GlazingClock, PadLife, mean_factor, sliding_speed, time_mean, wear_through
from .recipe import RecipeError, load_recipe
from .refit import History, RefitState, Seen, refit, refitted_model, replay
from .lotresult import LotResult, WaferRecord, lot_csv, write_lot
from .zones import ZoneFeedback, ZoneState

__all__ = ["CONTROL", "WaferRecord", "LotResult", "run_lot", "lot_csv", "write_lot"]

#: Fixed-point iterations of a wafer's polish time and its pad age on the glazing clock (at most).
AGE_ITERATIONS = 30

def _controlled_step(recipe) -> int:
    timed = [k for k, s in enumerate(recipe.steps) if s.until == "time"]
    if not timed:
        raise RecipeError(f"{recipe.source}: a controlled lot needs a timed step (time = ...) whose polish time the controller sets; every step ends at an end point")
    return timed[-1]


def _inputs(recipe, wafers, conditioning, control, seed, overrides, incoming, idle_time, disk, pad, weight, drift_weight, zone_weight,
            zone_feedback, time_step, qualification, worn_summits) -> dict:
    """Every input that decides a lot's numbers, as JSON-able values (the checkpoint's ``inputs``)."""
    given = None
    if incoming is not None:
        given = [digest(incoming[0]), digest(incoming[1])]
    return {
        "recipe": repr(recipe), "wafers": int(wafers), "conditioning": conditioning, "control": control, "seed": seed,
        "overrides": repr(sorted((k, repr(v)) for k, v in (overrides or {}).items())), "incoming": given, "idle_time": float(idle_time),
        "disk": repr(disk), "pad": repr(pad), "weight": float(weight), "drift_weight": float(drift_weight), "zone_weight": float(zone_weight),
        "zone_feedback": bool(zone_feedback), "time_step": float(time_step), "qualification": int(qualification),
        "worn_summits": bool(worn_summits),
    }


def run_lot(
    recipe,
    wafers: int = 25,
    *,
    conditioning: str | None = None,
    control: str = "none",
    seed: int | None = None,
    overrides: dict | None = None,
    incoming=None,
    idle_time: float = 30.0,
    disk: ConditionerDisk | None = None,
    pad: FreshPad | None = None,
    weight: float = WEIGHT,
    drift_weight: float = DRIFT_WEIGHT,
    zone_weight: float = 0.5,
    zone_feedback: bool = True,
    clock: str = "glazing",
    drift_prior: str = "model",
    time_step: float = 1.0,
    qualification: int = 1,
    worn_summits: bool = False,
    checkpoint=None,
    resume: bool = False,
    after_wafer=None,
    pad_constants: dict | None = None,
    cache: dict | None = None,
    model_pad_constants: dict | None = None,
    polish_times=None,
    polish_zone_pressures=None,
    refit_model: bool = False,
    metrology_noise: float = 0.0,
) -> LotResult:
    """Polish ``wafers`` wafers of ``recipe`` in sequence on one pad (``cmpsim lot``).

    Parameters
    ----------
    recipe : Recipe, path or TOML text
        The recipe (:mod:`cmpsim.polisher.recipe`); with control it needs a ``[target] remaining``
        and a timed step.
    wafers : int
        Number of wafers, >= 1.
    conditioning : "none" | "ex_situ" | "in_situ", optional
        The conditioning disk: never, between wafers (for ``idle_time``), or while polishing; default
        the recipe's ``conditioning``, else "in_situ".
    control : "none" | "ewma" | "single_ewma"
        Without control every wafer runs the recipe as written; otherwise the rate estimator of that
        name (:data:`cmpsim.polisher.control.ESTIMATORS`: "ewma" the double EWMA, eqs. C2-C4; "single_ewma"
        issue 32's, eq. C1) sets each wafer's polish time (eq. C0) and, on a zoned head with
        ``zone_feedback``, the zone feedback (:mod:`cmpsim.polisher.zones`) its zone pressures.
    seed : int, optional
        Seed of the incoming thickness draw (reproducible lots).
    overrides : dict, optional
        Inputs for every step unless a step sets them (``--set``).
    incoming : array (wafers, radii) with radii, optional
        Given incoming profiles of the top film as ``(radius, thickness)`` (m, m); default drawn.
    idle_time : float
        Seconds between two wafers (the pad cools; ex-situ conditioning works then).
    disk, pad : optional
        The conditioning disk (default the recipe's ``[conditioner]``, else the calibrated disk) and the
        fresh pad (default each step's own, :func:`cmpsim.polisher.pad.fresh_pad`).
    weight, drift_weight, zone_weight : float
        The EWMA weights in (0, 1]: lambda_1 of the rate's level (C1/C2), lambda_2 of its drift (C3)
        and lambda_z of the profile's shape (Z5).
    clock : "glazing" | "wafer"
        The double EWMA's pad-age clock (:data:`cmpsim.polisher.control.CLOCKS`): the drift per unit of
        the pad-life model's rate factor over the wafer (eq. L4), or per wafer.
    zone_feedback : bool
        With control on a zoned head, the zone feedback sets the zone pressures (else they stay the recipe's).
    time_step : float
        The recipes' time step, s.
    qualification : int
        Monitor wafers polished with the recipe as written (nominal incoming films) on the lot's pad
        before the lot, >= 0: the last one's measured mean rate seeds the EWMA, and the lot starts on
        the pad they leave. 0: the lot starts on a fresh pad, the EWMA seeded by the model's rate for it.
    worn_summits : bool
        The worn pad's summit std enters every step's wafer solve (:class:`cmpsim.polisher.pad.PadLife`).
    pad_constants : dict, optional
        The glazing and conditioning constants ({name: SI}: ``pad_wear_coefficient``,
        ``critical_glazed_area``, ``conditioner_rate_constant``) of a calibrated process file
        (:func:`cmpsim.calibration.padlife.calibrate_padlife`); default the constants calibrated to
        Jeong et al. (2024) (:data:`cmpsim.physics.padlife.CALIBRATION`).
    cache : dict, optional
        The step solves of earlier lots of the same recipe and inputs, reused (a calibration runs
        the lot many times with other glazing constants, which do not change a wafer's solve).
    checkpoint : path, optional
        A file the lot's state is written to, atomically, after its set-up and after every wafer
        (:mod:`cmpsim.polisher.checkpoint`).
    resume : bool
        Go on from ``checkpoint`` if it exists (refused, naming them, if its inputs differ); the
        result is identical to the lot run without interruption.
    model_pad_constants : dict, optional
        The controller's model of the pad's life ({name: SI} as ``pad_constants``; default the
        pad's own). The controller never reads the simulated pad's state: it follows its own model
        of the pad's life through the polish times and pressures it commanded (its glazing clock
        and drift prior, eqs. C4-C5). A model other than the pad (another pad's calibration, or a
        deliberate error) shows how the control holds when its model is wrong (docs/polisher.md).
    polish_times : sequence of float, optional
        Replay a logged lot: wafer k's timed step (the last one that ends at a time) is polished for
        ``polish_times[k]`` s (one per wafer, > 0), as a fab's own run-to-run control commanded it; the
        recipe's other steps and pressures as written. Needs ``control = "none"``.
    polish_zone_pressures : sequence of tuples, optional
        With ``polish_times``: each wafer's zone pressures (Pa) as logged, for every step.
    refit_model : bool
        With ``control = "ewma"`` on the glazing clock and a one-step recipe: after each wafer the
        controller refits its model's wear coefficient k_w, and its critical glazed area G_c when the
        rates separate them, to the rates measured so far (when they identify them) and replays its
        filter on the refitted clock (:mod:`cmpsim.polisher.refit`, eqs. C6-C8). Off: the model keeps
        its constants.
    metrology_noise : float
        m, one sigma: the controller measures each radius of every wafer's incoming and post-polish
        profile with an independent normal error of this size (:func:`cmpsim.polisher.incoming.measurement_errors`,
        from ``seed``); 0: it measures them exactly. The lot's records keep the true thicknesses.
    after_wafer : callable, optional
        Called with the wafer's :class:`WaferRecord` after each wafer (and its checkpoint).
    """
    t0 = _time.perf_counter()
    recipe = load_recipe(recipe)
    if conditioning is None:
        conditioning = recipe.conditioning or "in_situ"
    if disk is None:
        disk = recipe.conditioner
    if not (isinstance(wafers, (int, np.integer)) and wafers >= 1):
        raise ValueError(f"wafers must be a whole number >= 1; got {wafers!r}")
    life_model = PadLife(conditioning, disk, pad, worn_summits, pad_constants)  # checks the conditioning
    # the controller's model of the pad's life (its glazing clock): the pad's own unless told otherwise
    model = life_model if model_pad_constants is None else PadLife(conditioning, disk, pad, worn_summits, model_pad_constants)
    if control not in CONTROL:
        raise ValueError(f"control must be one of {CONTROL}; got {control!r}")
    if not (math.isfinite(idle_time) and idle_time >= 0):
        raise ValueError(f"idle_time must be >= 0 s; got {idle_time!r}")
    if not (isinstance(qualification, (int, np.integer)) and qualification >= 0):
        raise ValueError(f"qualification must be a whole number of monitor wafers >= 0; got {qualification!r}")
    make_estimator("ewma", 1.0, weight, drift_weight, clock, 1.0, drift_prior)  # the weights and the clock checked before any solve
    if not 0 < zone_weight <= 1:
        raise ValueError(f"zone_weight (the EWMA weight of the profile) must be in (0, 1]; got {zone_weight!r}")
    if refit_model and not (control == "ewma" and clock == "glazing"):
        raise ValueError(f"refit_model refits the pad-life model of the glazing clock: it needs control 'ewma' with clock 'glazing'; "
                         f"got control {control!r}, clock {clock!r}")
    if isinstance(metrology_noise, bool) or not (isinstance(metrology_noise, (int, float, np.integer, np.floating))
                                                 and math.isfinite(metrology_noise) and metrology_noise >= 0):
        raise ValueError(f"metrology_noise must be a standard deviation >= 0 m; got {metrology_noise!r}")
    if refit_model and len(recipe.steps) > 1:
        raise ValueError(f"refit_model needs a one-step recipe; {recipe.source} has {len(recipe.steps)} steps: the lot's measured rate "
                         "is the mean over the steps, whose mix changes with the controlled step's time, and the refit would read that "
                         "change as glazing")
    if resume and checkpoint is None:
        raise ValueError("resume needs the checkpoint to resume from (cmpsim lot --resume needs --out DIR)")
    target = recipe.target.remaining
    controlled = control != "none"
    if polish_times is not None:
        polish_times = [float(t) for t in polish_times]
        if controlled:
            raise ValueError(f"polish_times replays the times a lot was polished at; control must be 'none', got {control!r}")
        if len(polish_times) < wafers or not all(math.isfinite(t) and t > 0 for t in polish_times[:wafers]):
            raise ValueError(f"polish_times needs a time > 0 s for each of the {wafers} wafers; got {len(polish_times)}")
        polish_times = polish_times[:wafers]
        replay_k = _controlled_step(recipe)  # the step whose time the lot logged
    if polish_zone_pressures is not None:
        if polish_times is None:
            raise ValueError("polish_zone_pressures replays a logged lot: give its polish_times too")
        polish_zone_pressures = [tuple(float(p) for p in z) for z in polish_zone_pressures]
        if len(polish_zone_pressures) < wafers:
            raise ValueError(f"polish_zone_pressures needs the zone pressures of each of the {wafers} wafers; got {len(polish_zone_pressures)}")
        polish_zone_pressures = polish_zone_pressures[:wafers]
    if controlled and target is None:
        raise RecipeError(f"{recipe.source}: control {control!r} needs the recipe's [target] remaining thickness")
    overrides = dict(overrides or {})
    step_k = _controlled_step(recipe) if controlled else None
    base = recipe.step_config(recipe.steps[step_k if step_k is not None else 0], overrides)
    inputs = _inputs(recipe, wafers, conditioning, control, seed, overrides, incoming, idle_time, disk, pad, weight, drift_weight,
                     zone_weight, zone_feedback, time_step, qualification, worn_summits) | {"clock": clock, "drift_prior": drift_prior}
    if pad_constants:  # a calibrated pad life decides the numbers too (absent otherwise: earlier checkpoints still resume)
        inputs["pad_constants"] = repr(sorted((k, float(v)) for k, v in pad_constants.items()))
    if model_pad_constants is not None:
        inputs["model_pad_constants"] = repr(sorted((k, float(v)) for k, v in model_pad_constants.items()))
    if polish_times is not None:
        inputs["polish_times"] = repr(polish_times)
    if polish_zone_pressures is not None:
        inputs["polish_zone_pressures"] = repr(polish_zone_pressures)
    if refit_model:
        inputs["refit_model"] = True
    if metrology_noise:
        inputs["metrology_noise"] = float(metrology_noise)

    def between_wafers(result):  # idle: the pad cools; ex situ, the disk conditions it
        cooled = idle(result.pad_state, idle_time, base)
        return PadState(cooled.thermal, life_model.idle(result.pad_state.life, idle_time), cooled.time)

    cache = {} if cache is None else cache  # the step solves of the last wafer: a wafer with the same inputs is not solved again
    preston = _preston_weights(recipe, step_k, overrides) if controlled else {}  # C0': the other steps' removal, in controlled-step seconds
    saved = read_checkpoint(checkpoint, inputs) if resume else None
    if saved is None:
        setup, pad_state, estimator, zones, feedback, solves, model_life = _set_up(
            recipe, wafers, step_k, preston, control, seed, overrides, incoming, base, time_step, qualification, life_model, between_wafers, cache,
            weight, drift_weight, zone_weight, zone_feedback, clock, drift_prior, model, idle_time)
        refit_state = None
        if refit_model:  # the controller's memory for its refits: the monitor wafers, the last one's rate its seed
            rated = estimator.level if setup["qualification"] else None
            monitors = tuple(Seen(tuple(d), None, rated if j == len(setup["monitor_durations"]) - 1 else None)
                             for j, d in enumerate(setup["monitor_durations"]))
            refit_state = RefitState.begin(model, base, estimator.level, monitors)
        if metrology_noise:  # the metrology's errors on every wafer, drawn once (kept in the checkpoint: a lot without a seed resumes too)
            errors = measurement_errors(wafers, len(setup["radius"]), float(metrology_noise), seed)
            setup["metrology"] = {"incoming": errors[0].tolist(), "final": errors[1].tolist()}
        saved = LotCheckpoint(inputs, 0, setup, pad_state_to_dict(pad_state), _dict(estimator), _dict(zones), [], solves,
                              life_to_dict(model_life), _dict(refit_state))
        if checkpoint is not None:
            write_checkpoint(checkpoint, saved)
    # the lot always goes on from the checkpoint's numbers, resumed or not, so that both run the same
    # arithmetic on the same arrays (a matrix product's last bit can depend on its operands' layout)
    setup, start, solves = saved.setup, saved.next_wafer, saved.solves
    pad_state, estimator, zones = _restore(saved)
    model_life = life_from_dict(saved.model_life)
    refit_state = None if saved.refit is None else RefitState.from_dict(saved.refit)
    history = History()  # the refit's samples of the controller's model, walked as the wafers come (in memory only)
    if refit_state is not None and refit_state.moved:
        model = refitted_model(model, refit_state)
    feedback = None if setup["feedback"] is None else _feedback_from_dict(setup["feedback"])
    records = [WaferRecord.from_dict(r) for r in saved.records]

    radius = np.asarray(setup["radius"], dtype=float)
    weights = np.asarray(setup["weights"], dtype=float)
    profiles = np.asarray(setup["profiles"], dtype=float)
    errors = None if "metrology" not in setup else (np.asarray(setup["metrology"]["incoming"], dtype=float),
                                                    np.asarray(setup["metrology"]["final"], dtype=float))
    others = [np.full(radius.shape, f.thickness) for f in recipe.films[1:]]
    start_pressures = tuple(setup["start_pressures"])

    for k in range(start, wafers):
        inc = profiles[k]
        inc_mean = float(np.sum(weights * inc))
        seen_in, seen_in_mean = inc, inc_mean  # the incoming profile as the metrology measures it
        if errors is not None:
            seen_in = inc + errors[0][k]
            seen_in_mean = float(np.sum(weights * seen_in))
        wafer_recipe, ov, zoned = recipe, dict(overrides), None
        plan, predicted = None, None
        if polish_times is not None:  # a logged lot, replayed
            wafer_recipe = recipe.with_step_time(replay_k, polish_times[k])
            if polish_zone_pressures is not None:
                zoned = ov["zone_pressures"] = polish_zone_pressures[k]
        if controlled:
            pressures, zoned_recipe = start_pressures, recipe
            if feedback is not None:  # the zone pressures of the controlled step (the other steps keep their own pressures)
                plan = feedback.plan(zones, seen_in, float(target))
                pressures = zoned = plan.pressures
                zoned_recipe = recipe.with_step_zones(step_k, pressures)
            factor = feedback.pressure_factor(pressures) if feedback is not None else 1.0
            before = records[-1].step_times if records and records[-1].step_times else setup.get("first_durations")
            other = _other_time(recipe, preston, before)
            predicted, t, wafer_recipe = _next_wafer(zoned_recipe, step_k, ov, estimator, factor, seen_in_mean, float(target), k + 1,
                                                     model_life, model, time_step, other)
        result = polish(wafer_recipe, overrides=ov, pad_state=pad_state, incoming=(radius, [inc, *others]), time_step=time_step,
                        pad_life=life_model, cache=cache)
        solves += result.solves
        total_time = sum(s.duration for s in result.steps)
        final = np.asarray(result.final.thickness[0], dtype=float)
        seen_out = final if errors is None else final + errors[1][k]  # the post-polish profile as measured
        removed = seen_in_mean - float(np.sum(weights * seen_out))  # the removal the controller sees
        pressures = tuple(zoned) if zoned is not None else start_pressures
        record = WaferRecord(
            index=k + 1,
            polish_time=float(total_time),
            removal_rate_mean=float(sum(s.removed_volume for s in result.steps) / result.final.wafer_area / total_time) if total_time > 0 else 0.0,
            final_thickness_mean=float(np.sum(weights * final)),
            final_thickness_nonuniformity=weighted_std_over_mean(final, weights),
            zone_pressures=tuple(float(p) for p in pressures),
            incoming_mean=inc_mean,
            pad_temperature_end=result.pad_state.surface_temperature,
            rate_factor=_mean_factor(result),
            summit_sigma=float(result.steps[0].glazing["summit_sigma"]),
            radius=radius,
            final_thickness=final,
            predicted_rate=predicted,
            predicted_nonuniformity=None if plan is None else plan.nu_after,
            zone_step=None if plan is None else plan.decision,
            step_times=tuple(float(r.duration) for r in result.steps),
        )
        records.append(record)
        pad_state = between_wafers(result)  # worn while polishing (conditioned in situ); idle: cooled, conditioned ex situ
        if controlled:  # the controller's model of the pad follows the wafer's steps as they ran (their logged times)
            model_age, model_life = _model_through(model, wafer_recipe, ov, result, model_life, time_step, idle_time)
        rate = None  # the rate the controller reads off the wafer (m/s)
        if controlled and total_time > 0:
            factor = feedback.pressure_factor(pressures) if feedback is not None else 1.0
            age = model_age if estimator.clock == "glazing" else float(k + 1)
            if preston:  # C0': the removal over the controlled step's time at its zone factor and the others' Preston-weighted times
                rate = removed / _removal_time(recipe, step_k, preston, record.step_times, factor)
            else:
                rate = removed / total_time / factor
            estimator = estimator.update(rate, age)
            if feedback is not None:
                zones = feedback.learn(zones, pressures, (seen_in - seen_out) / total_time)
        if refit_state is not None:  # C6-C8: the controller refits its model's k_w to the rates it measured
            seen = Seen(record.step_times, zoned, rate)
            before = (refit_state.wear_coefficient, refit_state.critical_glazed_area)
            refit_state = refit(refit_state.seen(seen), model, recipe, overrides, time_step, idle_time, history)
            if (refit_state.wear_coefficient, refit_state.critical_glazed_area) != before:
                model, estimator, model_life = replay(refit_state, history, model, control, weight, drift_weight, clock, drift_prior)
            record = records[-1] = replace(record, model_wear_coefficient=refit_state.wear_coefficient,
                                           model_critical_glazed_area=refit_state.critical_glazed_area)
        saved = LotCheckpoint(inputs, k + 1, setup, pad_state_to_dict(pad_state), _dict(estimator), _dict(zones),
                              [r.to_record() for r in records], solves, life_to_dict(model_life), _dict(refit_state))
        if checkpoint is not None:
            write_checkpoint(checkpoint, saved)
        pad_state, estimator, zones = _restore(saved)
        if after_wafer is not None:
            after_wafer(record)
    return LotResult(recipe, records, control, conditioning, seed, None if target is None else float(target), float(idle_time), solves,
                     _time.perf_counter() - t0, setup["qualification"],
                     {"weight": float(weight), "drift_weight": float(drift_weight), "zone_weight": float(zone_weight), "clock": clock,
                      "estimator": estimator.name, "zone_feedback": bool(feedback is not None), "refit_model": bool(refit_model)}
                     if controlled else None)


def _next_wafer(recipe, step_k, overrides, estimator, factor, inc_mean, target, index, life, life_model, time_step, other=0.0):
    """The controlled wafer: its predicted rate (m/s; eq. C4 at its pad age, times Z6), polish time
    (s; eq. C0, less the ``other`` steps' removal in controlled-step seconds, C0') and recipe. On the
    glazing clock the wafer's age depends on its own polish time: the fixed point
    t = (incoming - target) / (rate at the age of a wafer of t), iterated to 1e-9 s."""
    def with_time(t):
        return recipe.with_step_time(step_k, t)

    def time_for(predicted):
        return max(feed_forward_time(predicted, inc_mean, target) - other / factor, time_step)

    if estimator.clock != "glazing":
        predicted = _prediction(estimator, float(index), factor, index)
        t = time_for(predicted)
        return predicted, t, with_time(t)
    configs = [recipe.step_config(s, overrides) for s in recipe.steps]
    if len(configs) == 1:  # the pad's states along the step computed once for all trial times
        clock = GlazingClock(life_model, configs[0], life, time_step)
    else:
        def clock(t):
            return mean_factor(life_model, list(zip(configs, [t if j == step_k else s.limit for j, s in enumerate(recipe.steps)])), life,
                               time_step)
    t = time_for(_prediction(estimator, estimator.age, factor, index))
    for _ in range(AGE_ITERATIONS):
        age = clock(t)
        predicted = _prediction(estimator, age, factor, index)
        new = time_for(predicted)
        done = abs(new - t) <= 1e-9
        t = new
        if done:
            break
    return predicted, t, with_time(t)


def _model_through(model: PadLife, recipe, overrides, result, life, time_step: float, idle_time: float):
    """The controller's model of the pad through a polished wafer (its steps at their logged durations) and
    the idle after it: (the wafer's mean rate factor, its pad-age on the glazing clock; the model's state)."""
    done = [(recipe.step_config(s, overrides), r.duration) for s, r in zip(recipe.steps, result.steps)]
    age, life = wear_through(model, done, life, time_step)
    return age, model.idle(life, idle_time)


def _preston_weights(recipe, step_k: int, overrides) -> dict:
    """C0': each other step's P U over the controlled step's (nominal pressures, the pad's speed under the
    wafer centre), {step index: weight}: the removal of a second of it in seconds of the controlled step."""
    pu = [float(c.applied_pressure) * sliding_speed(c) for c in (recipe.step_config(s, overrides) for s in recipe.steps)]
    return {j: pu[j] / pu[step_k] for j in range(len(pu)) if j != step_k}


def _removal_time(recipe, step_k: int, weights: dict, durations, factor: float = 1.0) -> float:
    """C0': a polished wafer's time in seconds of its controlled step (``durations`` its steps' times, s):
    the controlled step's at its zone ``factor`` (Z6) plus the other steps' Preston-weighted times."""
    return factor * durations[step_k] + _other_time(recipe, weights, durations, done=True)


def _other_time(recipe, weights: dict, durations, done: bool = False) -> float:
    """C0': the other steps' Preston-weighted time (s of the controlled step): their ``durations`` as run
    (``done``), or before the wafer their set times, an end-pointed step the last wafer's (else its limit)."""
    total = 0.0
    for j, w in weights.items():
        s = recipe.steps[j]
        d = durations[j] if (done or s.until != "time") and durations else s.limit
        total += w * float(d)
    return total


def _prediction(estimator, age: float, factor: float, index: int) -> float:
    """The controller's rate (m/s) for wafer ``index`` at pad ``age`` (eq. C4 times Z6); ValueError saying
    why when its drift carries the rate to zero or below (no polish time can be commanded then)."""
    rate = estimator.predict(age) * factor
    if not (math.isfinite(rate) and rate > 0.0):
        state = f"level {estimator.level * 6e10:.4g} nm/min" + (f", drift {estimator.drift * 6e10:.4g} nm/min per unit of age from age "
                                                                  f"{estimator.age:.4g} to {age:.4g}" if hasattr(estimator, "drift") else "")
        raise ValueError(f"wafer {index}: the {estimator.name} controller predicts a removal rate of {rate * 6e10:.4g} nm/min ({state}): "
                         "its linear drift does not describe this pad's decay, and no polish time follows; use the glazing clock with a "
                         "pad-life model calibrated to this pad (--drift-clock glazing, cmpsim calibrate LOT.csv --recipe), or a smaller "
                         "--drift-weight")
    return rate


def _restore(saved: LotCheckpoint):
    """The pad, the rate estimator and the zone state of a checkpoint."""
    estimator = None if saved.estimator is None else estimator_from_dict(saved.estimator)
    zones = None if saved.zones is None else ZoneState.from_dict(saved.zones)
    return pad_state_from_dict(saved.pad_state), estimator, zones


def _dict(state):
    return None if state is None else state.to_dict()


def _set_up(recipe, wafers, step_k, preston, control, seed, overrides, incoming, base, time_step, qualification, life_model, between_wafers,
            cache, weight, drift_weight, zone_weight, zone_feedback, clock, drift_prior, model, idle_time):
    """The lot before its first wafer: the monitor wafers (or the fresh pad's prediction), the rings,
    the incoming profiles, the first rate estimate, the zone response and the first shape; and the
    controller's ``model`` of the pad's life through the monitor wafers (its state after them). ``step_k``:
    the controlled step (None: no control); ``preston``: the other steps' weights of C0'."""
    controlled = step_k is not None
    pad_state = PadState(life=PadLifeState())
    model_life, model_age = PadLifeState(), 1.0
    monitors = []  # each monitor wafer's step durations (s)
    if qualification:
        solves = 0
        for _ in range(qualification):
            first = polish(recipe, overrides=overrides, time_step=time_step, pad_state=pad_state, pad_life=life_model, cache=cache)
            monitors.append([float(s.duration) for s in first.steps])
            solves += first.solves
            pad_state = between_wafers(first)
            model_age, model_life = _model_through(model, recipe, overrides, first, model_life, time_step, idle_time)
    else:
        first = polish(recipe, overrides=overrides, time_step=time_step, cache=cache)
        solves = first.solves
    first_time = sum(s.duration for s in first.steps)
    first_durations = [float(s.duration) for s in first.steps]  # an end-pointed step's first expected time (C0')
    first_removed = first.initial.mean_thickness(0) - first.final.mean_thickness(0)
    qualified = None if not qualification else {
        "wafers": int(qualification), "polish_time": float(first_time),
        "removal_rate_mean": float(first_removed / first_time) if first_time > 0 else 0.0,
    }
    radius = np.asarray(first.initial.radius, dtype=float)
    weights = np.asarray(first.initial.areas, dtype=float) / float(np.sum(first.initial.areas))  # the wafer-area mean of the stack
    top = recipe.films[0]
    if incoming is None:
        profiles = incoming_profiles(wafers, radius, top.thickness, seed=seed)
    else:
        given_r, given_t = incoming
        given_t = np.atleast_2d(np.asarray(given_t, dtype=float))
        if given_t.shape[0] < wafers:
            raise ValueError(f"incoming holds {given_t.shape[0]} profiles for {wafers} wafers")
        profiles = np.array([np.interp(radius, np.asarray(given_r, dtype=float), t) for t in given_t[:wafers]])

    zoned = len(base.zone_radii) > 0
    edges = np.concatenate(([0.0], np.asarray(base.zone_radii, dtype=float)))
    start_pressures = tuple(base.zone_pressures) if base.zone_pressures else ((base.applied_pressure,) * len(base.zone_radii) if zoned else ())
    estimator = feedback = zones = None
    if controlled:
        age = model_age if clock == "glazing" else 0.0  # the monitor wafer's age in the controller's model (a fresh pad: 1)
        # C0': the monitor's removal over its time in controlled-step seconds, as the lot's wafers are read (one step: its time)
        seen = _removal_time(recipe, step_k, preston, first_durations) if preston else first_time
        estimator = make_estimator(control, first_removed / seen, weight, drift_weight, clock, age, drift_prior)
        if zoned and zone_feedback:
            from ..head.zone_response import ZoneSolver, profile_of, response_matrix

            run = ZoneSolver(base)
            r0 = run(start_pressures)
            run.adopt(r0)
            rate0 = np.interp(radius, profile_of(r0)["radius"], profile_of(r0)["rate"])
            response = response_matrix(run, start_pressures, profile_of(r0)["rate"])
            response = np.array([np.interp(radius, profile_of(r0)["radius"], column) for column in np.asarray(response).T]).T
            solves += run.solves
            feedback = ZoneFeedback(response=response, start_pressures=tuple(float(p) for p in start_pressures),
                                    mean_rate=float(weights @ rate0), weights=weights, zone_areas=np.pi * np.diff(edges**2),
                                    zone_weight=zone_weight)
            measured = (np.asarray(first.initial.thickness[0], dtype=float) - np.asarray(first.final.thickness[0], dtype=float)) / first_time
            zones = ZoneState(feedback.start_pressures, measured / float(weights @ measured))  # the first shape: the monitor wafer's
    setup = {"radius": radius.tolist(), "weights": weights.tolist(), "profiles": profiles.tolist(), "qualification": qualified,
             "start_pressures": [float(p) for p in start_pressures], "feedback": None if feedback is None else _feedback_to_dict(feedback),
             "monitor_durations": monitors, "first_durations": first_durations}
    return setup, pad_state, estimator, zones, feedback, solves, (model_life if controlled else None)


def _feedback_to_dict(f: ZoneFeedback) -> dict:
    return {"response": np.asarray(f.response).tolist(), "start_pressures": list(f.start_pressures), "mean_rate": f.mean_rate,
            "weights": np.asarray(f.weights).tolist(), "zone_areas": np.asarray(f.zone_areas).tolist(), "zone_weight": f.zone_weight,
            "bounds": list(f.bounds), "regularisation": f.regularisation, "halvings": f.halvings}


def _feedback_from_dict(d: dict) -> ZoneFeedback:
    return ZoneFeedback(response=np.asarray(d["response"], dtype=float), start_pressures=tuple(d["start_pressures"]),
                        mean_rate=float(d["mean_rate"]), weights=np.asarray(d["weights"], dtype=float),
                        zone_areas=np.asarray(d["zone_areas"], dtype=float), zone_weight=float(d["zone_weight"]), bounds=tuple(d["bounds"]),
                        regularisation=float(d["regularisation"]), halvings=int(d["halvings"]))


def _mean_factor(result) -> float:
    """The glazed pad's rate factor averaged over a wafer's polish time (trapezoid over the time steps), 1."""
    return time_mean(np.concatenate([np.asarray(s.glazing["time"], dtype=float) for s in result.steps]),
                     np.concatenate([np.asarray(s.glazing["rate_factor"], dtype=float) for s in result.steps]))
