"""cmpsim polish (issue 32): recipes through time, verified.

Cost: the copper recipe runs once on the default grid (the coarse grid's membrane bending does
not converge at 1.5 psi on the 300mm preset); every other solve uses the coarse grid.
"""

from __future__ import annotations

import json
from importlib import resources

import numpy as np
import pytest

import cmpsim
from cmpsim.inputs.config import Config
from cmpsim.polisher.endpoint import EndpointDetector, reflectance_signal, ring_reflectance
from cmpsim.polisher.engine import PadState, polish
from cmpsim.polisher.recipe import RecipeError, parse_recipe
from cmpsim.polisher.stack import FilmStack, remove

COARSE = {"grid": "coarse"}


def _data(name: str) -> str:
    return resources.files("cmpsim").joinpath("data", name).read_text(encoding="utf-8")


@pytest.fixture(scope="module")
def copper():
    return polish(_data("recipe_copper.toml"))


@pytest.fixture(scope="module")
def oxide():
    return polish(_data("recipe_oxide.toml"), overrides=COARSE)


# ---------------------------------------------------------------------------- the issue's recipes


def test_the_two_recipes_in_the_docs_are_the_issues_exactly():
    """The docs page includes the shipped files; the files are the issue's text (kept here verbatim)."""
    copper = '''# Copper damascene on the 300 mm head: bulk copper, soft landing to the end point, barrier.
preset = "300mm"
[[film]]
material = "copper"
thickness = "1.2 um"
[[film]]
material = "barrier"
thickness = "25 nm"
[[film]]
material = "oxide"
thickness = "500 nm"
[[step]]
name = "bulk"
time = "30 s"
applied_pressure = "3 psi"
[[step]]
name = "landing"
until = "endpoint"
max_time = "240 s"
applied_pressure = "1.5 psi"
[[step]]
name = "barrier"
time = "30 s"
applied_pressure = "2 psi"
'''
    oxide = '''# Oxide polish on the 300 mm head to a remaining-thickness target, for a lot of wafers.
preset = "300mm"
[[film]]
material = "oxide"
thickness = "1.0 um"
[target]
remaining = "500 nm"
[[step]]
name = "oxide"
time = "60 s"
'''
    assert _data("recipe_copper.toml") == copper
    assert _data("recipe_oxide.toml") == oxide
    from pathlib import Path

    page = (Path(__file__).parent.parent / "docs" / "examples" / "polish_recipe.py").read_text()
    assert "recipe_copper.toml" in page and "recipe_oxide.toml" in page


def test_json_keys_of_the_issue(oxide):
    d = json.loads(oxide.to_json())
    step = d["steps"][0]
    for key in ("name", "duration", "end", "removal_rate_mean", "pad_temperature", "thickness"):
        assert key in step
    assert set(step["pad_temperature"]) == {"time", "value"}
    assert set(step["thickness"]) == {"radius", "oxide"}
    assert step["end"] == "time" and step["duration"] == pytest.approx(60.0)
    assert d["target"]["remaining"] == pytest.approx(500e-9)


# ---------------------------------------------------------------------------- verification


def test_one_timed_step_equals_tune_zones_remaining_thickness():
    """Same inputs, same remaining thickness as tune_zones(incoming, polish_time) at the start's pressures."""
    from cmpsim.head.tuning import tune_zones

    res = polish(_data("recipe_oxide.toml"), overrides=COARSE)
    cfg = Config.preset("300mm").replace(grid="coarse", film="oxide")
    r = np.linspace(0.0, 0.15, 31)
    tz = tune_zones(cfg, incoming=(r, np.full_like(r, 1.0e-6)), polish_time="60 s", max_steps=0)
    ours = np.array(res.steps[0].thickness["oxide"])
    theirs = np.asarray(tz.before["remaining_thickness"]["thickness"])
    assert np.allclose(ours, theirs, rtol=0, atol=1e-15)


def test_removal_conserves_volume_with_the_rate_integral():
    """Carry-over at a clearing: removed volume = time integral of the rate over the wafer area, exactly."""
    faces = np.array([0.0, 0.01, 0.02, 0.03])
    radius = 0.5 * (faces[1:] + faces[:-1])
    areas = np.pi * np.diff(faces**2)
    stack = FilmStack(("copper", "barrier", "oxide"), ("copper", "barrier", "oxide"), radius, areas,
                      np.array([[10e-9, 30e-9, 100e-9], [5e-9, 5e-9, 5e-9], [100e-9, 100e-9, 100e-9]]))
    rates = np.array([[2e-9, 2e-9, 2e-9], [1e-9, 1e-9, 1e-9], [0.5e-9, 0.5e-9, 0.5e-9]])  # m/s
    dt = 10.0
    new, rem = remove(stack, rates, dt)
    # ring 0: copper clears at 5 s, barrier clears at 10 s exactly; ring 1: copper clears at 15 s > dt
    expected = np.array([10e-9 + 5e-9, 20e-9, 20e-9])
    assert np.allclose(stack.thickness.sum(0) - new.thickness.sum(0), expected, rtol=1e-12)
    integral = np.sum(areas * np.sum(rates * rem.exposure, axis=0))
    assert stack.volume().sum() - new.volume().sum() == pytest.approx(integral, rel=1e-12)
    assert rem.volume(areas) == pytest.approx(integral, rel=1e-12)
    assert np.all(rem.exposure.sum(0) + rem.idle == pytest.approx(dt))


def test_the_recipe_conserves_volume(copper):
    removed = sum(s.removed_volume for s in copper.steps)
    assert copper.initial.volume().sum() - copper.final.volume().sum() == pytest.approx(removed, rel=1e-12)
    for s in copper.steps:
        assert s.removal_rate_mean * s.duration * copper.final.wafer_area == pytest.approx(s.removed_volume, rel=1e-12)


def test_one_solve_gives_every_films_rate():
    """The equilibrium does not depend on the film: the rate re-evaluated on it equals a solve with that film."""
    from cmpsim.polisher.engine import StepSolve

    cfg = Config.preset("300mm").replace(grid="coarse")
    step = StepSolve(cfg)
    for film in ("copper", "barrier"):
        direct = cmpsim.solve(cfg.replace(film=film)).profiles["removal_rate_profile"]
        assert np.allclose(step.rate_profile(film, 300.0), direct, rtol=1e-12, atol=0)


def test_pad_warms_over_a_step_and_more_at_a_faster_platen(oxide):
    slow = polish(_data("recipe_oxide.toml"), overrides={**COARSE, "rotation_speed": "60 rpm", "wafer_speed_ratio": 56.0 / 60.0})
    rise = oxide.steps[0].pad_temperature["value"][-1] - oxide.steps[0].pad_temperature["value"][0]
    rise_slow = slow.steps[0].pad_temperature["value"][-1] - slow.steps[0].pad_temperature["value"][0]
    assert rise > rise_slow > 0
    assert np.all(np.diff(oxide.steps[0].pad_temperature["value"]) > 0)


def test_the_warmer_pad_raises_the_rate_with_the_chemical_step():
    """two_step kinetics: the rate follows the pad's temperature; with the default (mechanical) it does not."""
    two = polish(_data("recipe_oxide.toml"), overrides={**COARSE, "removal_kinetics": "two_step"})
    d = two.steps[0]
    from cmpsim.polisher.engine import StepSolve

    cfg = Config.preset("300mm").replace(grid="coarse", removal_kinetics="two_step")
    s = StepSolve(cfg)
    cold, warm = s.rate_profile("oxide", 298.15), s.rate_profile("oxide", 298.15 + 10)
    assert np.all(warm > cold)
    mech = StepSolve(Config.preset("300mm").replace(grid="coarse"))
    assert np.array_equal(mech.rate_profile("oxide", 298.15), mech.rate_profile("oxide", 350.0))
    # the rate integrated through the warming exceeds the cold pad's rate
    cold_mean = float(np.sum(cold * two.final.areas) / two.final.wafer_area)
    assert d.removal_rate_mean > cold_mean


def test_pad_state_is_carried_from_wafer_to_wafer(oxide):
    """A lot calls polish wafer after wafer: the pad state comes out and goes in."""
    from cmpsim.polisher.engine import idle

    cfg = Config.preset("300mm")
    after = idle(oxide.pad_state, 20.0, cfg)
    assert oxide.pad_state.surface_temperature > after.surface_temperature > 298.15
    second = polish(_data("recipe_oxide.toml"), overrides=COARSE, pad_state=after)
    assert second.steps[0].pad_temperature["value"][0] == pytest.approx(after.surface_temperature)
    assert second.pad_state.surface_temperature > oxide.pad_state.surface_temperature
    assert second.pad_state.time == pytest.approx(oxide.pad_state.time + 20.0 + 60.0)


# ---------------------------------------------------------------------------- the copper recipe (issue's criteria)


def test_copper_bulk_step_leaves_copper_everywhere(copper):
    bulk = copper.steps[0]
    assert bulk.end == "time" and bulk.duration == pytest.approx(30.0)
    assert min(bulk.thickness["copper"]) > 0


def test_copper_pad_warms_over_each_step(copper):
    bulk = copper.steps[0]
    rise = bulk.pad_temperature["value"][-1] - bulk.pad_temperature["value"][0]
    assert rise > 1.0  # measured: 43.2 K in 30 s at 3 psi (docs/polisher.md compares it with White 2003 and Shin 2025)


@pytest.mark.xfail(strict=True, reason="measured on the ungrooved 300mm preset: the landing step at 1.5 psi removes 33 nm/min "
                   "(the slurry carries most of the load), copper is cleared nowhere at max_time = 240 s (0 % of the area); "
                   "the end point is not reached. Not tuned: docs/polisher.md")
def test_copper_landing_ends_at_the_end_point_with_copper_cleared_on_95_percent(copper):
    landing = copper.steps[1]
    assert landing.end == "endpoint" and landing.duration < 240.0
    assert landing.endpoint["cleared_fraction"] >= 0.95


@pytest.mark.xfail(strict=True, reason="follows from the landing step: copper was never cleared, so the barrier step polishes copper (docs/polisher.md)")
def test_copper_barrier_step_removes_the_barrier_where_copper_cleared(copper):
    landing, barrier = copper.steps[1], copper.steps[2]
    cleared = np.array(landing.thickness["copper"]) <= 0
    assert cleared.mean() >= 0.95
    assert np.all(np.array(barrier.thickness["barrier"])[cleared] < 25e-9)


@pytest.mark.xfail(strict=True, reason="measured: the solved shear field gives an effective friction of 0.56 (summits 0.4 plus the slurry), "
                   "q = 22.6 kW/m2 at 3 psi and 1.95 m/s: the pad rises 43 K in the 30 s bulk step, not 'a few kelvin' "
                   "(White 2003: 9.1 K at 6 psi, 0.96 m/s; Shin 2025: 15 K in 90 s at 2 psi). Not tuned: docs/polisher.md")
def test_copper_pad_warms_by_a_few_kelvin_like_the_measurements(copper):
    bulk = copper.steps[0]
    rise = bulk.pad_temperature["value"][-1] - bulk.pad_temperature["value"][0]
    assert rise < 20.0


def test_end_point_detector_on_a_clearing_copper_film():
    """The signal settles at the barrier's level as copper clears; the cleared fraction is reported."""
    faces = np.linspace(0.0, 0.15, 31)
    radius = 0.5 * (faces[1:] + faces[:-1])
    areas = np.pi * np.diff(faces**2)
    t = np.array([np.linspace(20e-9, 400e-9, 30), np.full(30, 25e-9), np.full(30, 500e-9)])
    stack = FilmStack(("copper", "barrier", "oxide"), ("copper", "barrier", "oxide"), radius, areas, t)
    from cmpsim.polisher.endpoint import cleared_level

    det = EndpointDetector(0.943, cleared_level(stack, 0), 0.95)
    rates = np.array([np.full(30, 5e-9), np.full(30, 1e-9), np.full(30, 1e-9)])
    for step in range(200):
        stack, _ = remove(stack, rates, 1.0)
        if det.reached(reflectance_signal(stack)):
            break
    signal = reflectance_signal(stack)
    assert det.reached(signal) and det.progress(signal) >= 0.95
    # the signal runs ahead of the cleared area: copper thinner than its opacity (40 nm) already
    # shows the barrier. Measured: cleared on 75.1 % of the area, the rest under 11-50 nm of copper
    assert stack.cleared_fraction(0) == pytest.approx(0.7511, abs=1e-3)
    assert stack.thickness[0].max() == pytest.approx(50e-9, rel=1e-6)
    assert ring_reflectance(stack).min() >= 0.0


# ---------------------------------------------------------------------------- bad input


GOOD = '''preset = "300mm"
[[film]]
material = "copper"
thickness = "1 um"
[[film]]
material = "oxide"
thickness = "500 nm"
[[step]]
name = "bulk"
time = "30 s"
'''


@pytest.mark.parametrize(
    "text, words",
    [
        ('preset = "300mm"\n[[film]]\nmaterial = "oxide"\nthickness = "1 um"\n', ["no [[step]]"]),
        (GOOD + '[[step]]\nname = "x"\ntime = "10 s"\nfoo = 3\n', ["step 2", "'x'", "unknown input 'foo'", "line 14"]),
        (GOOD.replace('material = "oxide"', 'material = "gold"'), ["film 2", "'gold'", "line 5", "unknown film material"]),
        ('preset = "300mm"\n[[film]]\nmaterial = "oxide"\nthickness = "1 um"\n[[step]]\nname = "ep"\nuntil = "endpoint"\nmax_time = "60 s"\n', ["step 1", "'ep'", "line 5", "nothing" if False else "no film left"]),
        (GOOD.replace('time = "30 s"', 'time = "-30 s"'), ["step 1", "'bulk'", "line 10", "> 0"]),
        (GOOD + '[[step]]\nname = "land"\nuntil = "endpoint"\n', ["step 2", "'land'", "needs max_time"]),
        (GOOD + '[[step\nname = "x"\n', ["not valid TOML", "line"]),
        (GOOD + '[[step]]\nname = "p"\ntime = "5 s"\napplied_pressure = "-3 psi"\n', ["step 2", "'p'", "applied_pressure"]),
    ],
)
def test_bad_recipes_are_refused_naming_the_step_and_line(text, words):
    with pytest.raises(RecipeError) as info:
        parse_recipe(text)
    for w in words:
        assert w in str(info.value), (w, str(info.value))


def test_cli_exits_2_and_writes_nothing_on_a_bad_recipe(tmp_path):
    from click.testing import CliRunner

    from cmpsim.cli import main

    bad = tmp_path / "bad.toml"
    bad.write_text(GOOD + '[[step]]\nname = "x"\ntime = "10 s"\nfoo = 3\n')
    out = tmp_path / "out"
    r = CliRunner().invoke(main, ["polish", str(bad), "--out", str(out)])
    assert r.exit_code == 2
    assert "step 2" in r.output and "foo" in r.output
    assert not out.exists()


def test_cli_json_and_out(tmp_path):
    from click.testing import CliRunner

    from cmpsim.cli import main

    recipe = tmp_path / "oxide.toml"
    recipe.write_text(_data("recipe_oxide.toml"))
    out = tmp_path / "out"
    r = CliRunner().invoke(main, ["polish", str(recipe), "--set", "grid=coarse", "--json", "--out", str(out)])
    assert r.exit_code == 0, r.output
    d = json.loads(r.output.strip().splitlines()[-1])
    assert d["steps"][0]["name"] == "oxide"
    from cmpsim.polisher.report import FILES

    assert sorted(p.name for p in out.iterdir()) == sorted(FILES)
    header = (out / "thickness.csv").read_text().splitlines()[0]
    assert header == "radius_m,oxide.oxide_m"


def test_set_applies_to_every_step_unless_the_step_sets_it():
    rec = parse_recipe(GOOD.replace('time = "30 s"', 'time = "30 s"\napplied_pressure = "2 psi"') + '[[step]]\nname = "b"\ntime = "5 s"\n')
    a = rec.step_config(rec.steps[0], {"applied_pressure": "4 psi"})
    b = rec.step_config(rec.steps[1], {"applied_pressure": "4 psi"})
    assert a.applied_pressure == pytest.approx(2 * 6894.757293168361)
    assert b.applied_pressure == pytest.approx(4 * 6894.757293168361)


def test_package_entrance():
    assert cmpsim.polish is polish
    assert PadState().surface_temperature is None
