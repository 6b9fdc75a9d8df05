"""A layout riding along a recipe (``cmpsim polish --die``, issue 32): the die model at wafer sites through the steps.

The layout is made here with gdstk (two line arrays on layer 1/0, 400 um square, 20 um windows);
every wafer solve is on the coarse grid with the 300mm preset's pressure.
"""

from __future__ import annotations

import json

import gdstk
import numpy as np
import pytest
from click.testing import CliRunner

from cmpsim.cli import main
from cmpsim.die.chip import DieModel, layout_die
from cmpsim.die.process import DieProcess
from cmpsim.polisher.engine import polish
from cmpsim.polisher.recipe import load_recipe
from cmpsim.polisher.ride import SITE_KEYS, RidingDie, parse_sites

COARSE = {"grid": "coarse"}
FILMS = '''preset = "300mm"
[[film]]
material = "copper"
thickness = "300 nm"
[[film]]
material = "barrier"
thickness = "25 nm"
[[film]]
material = "oxide"
thickness = "500 nm"
'''
PROCESS = DieProcess.from_values("copper", copper_thickness="300 nm", barrier_thickness="25 nm")  # the recipe's films


def _steps(*steps):
    return FILMS + "".join(f'[[step]]\nname = "{name}"\n{body}\n' for name, body in steps)


@pytest.fixture(scope="module")
def chip(tmp_path_factory):
    """A 400 um die (um units): 10 um lines at 20 um pitch on its left half, 2 um lines at 20 um pitch on its right."""
    path = tmp_path_factory.mktemp("ride") / "chip.gds"
    lib = gdstk.Library(unit=1e-6, precision=1e-9)
    top = gdstk.Cell("CHIP")
    for i in range(20):
        width = 10.0 if i < 10 else 2.0
        top.add(gdstk.rectangle((20.0 * i, 0.0), (20.0 * i + width, 400.0), layer=1, datatype=0))
    lib.add(top)
    lib.write_gds(str(path))
    return path


def _riding(chip, **kw):
    return RidingDie(str(chip), layers=("1/0",), window=20e-6, **kw)


def _alone(chip, recipe, step, rate, time, spec=None):
    """The die model alone at a step's config, a blanket rate and a time (``cmpsim die``'s DieModel)."""
    cfg = recipe.step_config(recipe.steps[step], COARSE)
    return DieModel(cfg, PROCESS, blanket_rate=rate, spec=spec).run(layout_die(str(chip), ["1/0"], 20e-6), time)


def _same_die(a, b, rtol=1e-9):
    for name in ("upper_height", "lower_height", "mean_height", "dishing", "erosion", "step_height"):
        x, y = getattr(a.evolution, name), getattr(b.evolution, name)
        np.testing.assert_allclose(x, y, rtol=rtol, atol=1e-15, equal_nan=True, err_msg=name)


def test_one_step_equals_the_die_model_alone_at_the_sites_rate_and_time(chip):
    text = _steps(("polish", 'time = "90 s"'))
    res = polish(text, overrides=COARSE, die=_riding(chip, sites=(0.0, 0.1), spec={"dishing": "5 nm"}))
    step = res.steps[0]
    profile = step.removal_rate_profile
    for k, site in enumerate(step.die):
        rate = float(np.interp(site["radius"], profile["radius"], profile["copper"]))  # mechanical kinetics: the rate at the step's start
        assert site["blanket_rate"] == pytest.approx(rate, rel=1e-12)
        assert site["time"] == site["duration"] == 90.0
        alone = _alone(chip, load_recipe(text), 0, rate, 90.0, spec={"dishing": "5 nm"})
        _same_die(res.ride.dies[k], alone)
        d = alone.to_dict()
        for key in ("thickness_range", "step_height_max", "dishing_max", "erosion_max"):
            assert site[key] == pytest.approx(d[key], rel=1e-9, abs=1e-15), key
        assert site["hotspot_count"] == d["hotspot_count"] > 0  # counted as cmpsim die lists them
    assert step.die[0]["dishing_max"] > 1e-9  # the field copper cleared: the die dishes
    assert set(SITE_KEYS) <= set(step.die[0])


def test_two_timed_steps_equal_one_step_of_their_sum(chip):
    riding = _riding(chip, sites=(0.05,))
    two = polish(_steps(("first", 'time = "40 s"'), ("second", 'time = "50 s"')), overrides=COARSE, die=riding)
    one = polish(_steps(("both", 'time = "90 s"')), overrides=COARSE, die=riding)
    _same_die(two.ride.dies[0], one.ride.dies[0])
    assert two.steps[1].die[0]["time"] == pytest.approx(90.0)
    assert two.steps[1].die[0]["dishing_max"] == pytest.approx(one.steps[0].die[0]["dishing_max"], rel=1e-9)


def test_the_end_point_steps_duration_is_what_the_die_sees(chip):
    text = _steps(("landing", 'until = "endpoint"\nmax_time = "300 s"'))
    res = polish(text, overrides=COARSE, die=_riding(chip, sites=(0.02,)))
    step = res.steps[0]
    assert step.end == "endpoint" and 0 < step.duration < 300.0
    site = step.die[0]
    assert site["duration"] == site["time"] == step.duration
    alone = _alone(chip, load_recipe(text), 0, site["blanket_rate"], step.duration)
    _same_die(res.ride.dies[0], alone)


def test_a_warming_pad_drives_the_die_with_the_rate_the_stack_is_polished_with(chip):
    """two_step kinetics: the rate follows the pad's temperature through the step; the die's blanket depth
    (its mean rate times the duration) is the copper the wafer lost at the site."""
    res = polish(_steps(("polish", 'time = "20 s"')), overrides={**COARSE, "removal_kinetics": "two_step"}, die=_riding(chip, sites=(0.03, 0.12)))
    step = res.steps[0]
    assert step.pad_temperature["value"][-1] > step.pad_temperature["value"][0] + 1.0
    th = step.thickness
    for site in step.die:
        lost = 300e-9 - float(np.interp(site["radius"], th["radius"], th["copper"]))
        assert site["blanket_rate"] * site["duration"] == pytest.approx(lost, rel=1e-9)
        start = float(np.interp(site["radius"], step.removal_rate_profile["radius"], step.removal_rate_profile["copper"]))
        assert site["blanket_rate"] > start  # the warmer pad polishes faster than at the step's start


def test_a_glazing_pad_drives_the_die_with_the_rate_the_stack_is_polished_with(chip):
    """The pad's life through the step (no conditioning): the glazed rate falls through the step; the
    die's blanket depth is still the copper the wafer lost at the site."""
    from cmpsim.polisher.pad import PadLife

    res = polish(_steps(("polish", 'time = "20 s"')), overrides=COARSE, pad_life=PadLife("none"), die=_riding(chip, sites=(0.03, 0.12)))
    step = res.steps[0]
    assert step.glazing["rate_factor"][-1] < step.glazing["rate_factor"][0] == 1.0
    th = step.thickness
    for site in step.die:
        lost = 300e-9 - float(np.interp(site["radius"], th["radius"], th["copper"]))
        assert site["blanket_rate"] * site["duration"] == pytest.approx(lost, rel=1e-9)
        start = float(np.interp(site["radius"], step.removal_rate_profile["radius"], step.removal_rate_profile["copper"]))
        assert site["blanket_rate"] < start  # the glazing pad polishes slower than at the step's start


def test_resume_at_changing_rates_is_one_run_at_the_mean_rate(chip):
    """Every rate of the die model is the blanket rate times a pressure ratio: K1 t1 then K2 t2 is (K1 t1 + K2 t2) / T for T."""
    lay = layout_die(str(chip), ["1/0"], 20e-6)
    model = DieModel(None, PROCESS, blanket_rate=4e-9)
    start = model.start(lay)
    a = model.resume(start, 30.0, blanket_rate=6e-9)
    b = model.resume(a, 60.0, blanket_rate=3e-9)
    assert start.time == 0.0 and a.time == 30.0 and b.time == 90.0
    np.testing.assert_array_equal(start.evolution.za, start.evolution.za0)  # resume leaves its state as it was
    _same_die(b, DieModel(None, PROCESS, blanket_rate=(6e-9 * 30 + 3e-9 * 60) / 90).run(lay, 90.0))


def test_default_sites_and_parse_sites():
    assert parse_sites("0, 70 mm,0.14 m") == pytest.approx((0.0, 0.07, 0.14))
    assert parse_sites("75") == pytest.approx((0.075,))
    with pytest.raises(ValueError, match="--sites"):
        parse_sites("0,,1mm")


def test_cli_json_out_and_exit_2_on_bad_input(chip, tmp_path):
    recipe = tmp_path / "r.toml"
    recipe.write_text(_steps(("polish", 'time = "60 s"')))
    runner = CliRunner()
    out = tmp_path / "out"
    args = ["polish", str(recipe), "--set", "grid=coarse", "--die", str(chip), "--layer", "1/0", "--sites", "0,100mm", "--spec", "dishing=5nm"]
    res = runner.invoke(main, args + ["--json", "--out", str(out)])
    assert res.exit_code == 0, res.output
    data = json.loads(res.output)
    sites = data["steps"][0]["die"]
    assert [s["radius"] for s in sites] == pytest.approx([0.0, 0.1])
    assert {"radius", "duration", *SITE_KEYS} <= set(sites[0])
    assert data["ride"]["process"] == "copper" and data["ride"]["layers"] == ["1/0"] and data["ride"]["sites"] == pytest.approx([0.0, 0.1])
    for key in ("die.radius", "die.dishing_max", "die.blanket_rate", "die.hotspot_count"):
        assert key in data["units"]
    assert (out / "die.csv").read_text().startswith("step,radius_m,duration_s,time_s,blanket_rate_m_per_s")
    for folder in ("die_1_r0mm", "die_2_r100mm"):
        assert {"die.json", "die.nc", "die.png", "hotspots.csv", "hotspots.lyrdb"} <= {p.name for p in (out / folder).iterdir()}
    bad = [
        (["--die", str(tmp_path / "missing.gds"), "--layer", "1/0"], "missing.gds"),
        (["--die", str(chip), "--layer", "7/0"], "7/0"),
        (["--die", str(chip)], "--layer"),
        (["--die", str(chip), "--layer", "1/0", "--sites", "0,200mm"], "--sites"),
        (["--layer", "1/0"], "--die"),
        (["--die", str(chip), "--layer", "1/0", "--die-param", "trench_depth=1 kg"], "trench_depth"),
    ]
    for extra, word in bad:
        target = tmp_path / "nothing"
        res = runner.invoke(main, ["polish", str(recipe), "--set", "grid=coarse", "--out", str(target), *extra])
        assert res.exit_code == 2, (extra, res.output)
        assert word in res.output and "Traceback" not in res.output, res.output
        assert not target.exists()
