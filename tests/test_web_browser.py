"""The page of `cmpsim serve` in a real Chromium: it loads, solves, shows errors and sweeps.

The browser is the system Chromium driven by Playwright (never a downloaded browser: see
docs/make_screenshots.py for the flags). Every request the page makes is routed through a
guard that fails the test if it leaves 127.0.0.1, and any JavaScript error fails it too.
In CI (the CI environment variable set) a missing Playwright or Chromium is a failure; on a
developer's machine these tests are skipped with the reason.
"""

from __future__ import annotations

import importlib.util
import json
import os
from pathlib import Path
from urllib.parse import urlsplit

import pytest

import cmpsim
from cmpsim.inputs.config import Config

pytestmark = [pytest.mark.slow, pytest.mark.filterwarnings("ignore::DeprecationWarning")]

ROOT = Path(__file__).resolve().parents[1]
IN_CI = bool(os.environ.get("CI"))


def _require(ok: bool, reason: str) -> None:
    if ok:
        return
    if IN_CI:
        pytest.fail(f"{reason}; CI must run the browser tests (.ci/run installs Debian's chromium and the playwright package)")
    pytest.skip(reason)


def _shots_module():
    spec = importlib.util.spec_from_file_location("make_screenshots", ROOT / "docs" / "make_screenshots.py")
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


SHOTS = _shots_module()


@pytest.fixture(scope="module")
def server():
    try:
        from cmpsim.web.app import create_app
        from cmpsim.web.server import start_in_background
    except ImportError as exc:
        _require(False, f'the web extra is not installed ({exc.name}): pip install "cmpsim[web]"')
    with start_in_background(create_app(workers=1)) as srv:
        yield srv


@pytest.fixture(scope="module")
def browser():
    try:
        from playwright.sync_api import sync_playwright
    except ImportError:
        _require(False, "the playwright package is not installed (pip install playwright; no `playwright install`)")
    executable = SHOTS.find_chromium()
    _require(executable is not None, "no system Chromium (Debian: apt-get install chromium; or set CMPSIM_CHROMIUM)")
    with sync_playwright() as pw:
        b = SHOTS.launch(pw, executable)
        yield b
        b.close()


@pytest.fixture
def page(browser, server):
    """A fresh page whose every request must go to 127.0.0.1, and which must raise no JS error."""
    context = browser.new_context(viewport=SHOTS.VIEWPORT, accept_downloads=True)
    outside, js_errors = [], []

    def guard(route):
        url = route.request.url
        scheme, host = urlsplit(url).scheme, urlsplit(url).hostname
        if scheme in ("data", "blob") or host == "127.0.0.1":
            route.continue_()
        else:
            outside.append(url)
            route.abort()

    context.route("**/*", guard)
    p = context.new_page()
    p.on("pageerror", lambda exc: js_errors.append(str(exc)))
    p.set_default_timeout(60_000)
    yield p
    context.close()
    assert not outside, f"the page made requests that leave 127.0.0.1: {outside}"
    assert not js_errors, f"JavaScript errors on the page: {js_errors}"


def _open(page, server):
    SHOTS.wait_ready(page, server.url)
    page.fill('#inputs [name="grid"]', "coarse")


def test_the_page_loads_with_every_input_of_api_params(page, server):
    SHOTS.wait_ready(page, server.url)
    params = page.evaluate("fetch('/api/params').then(r => r.json())")["parameters"]
    shown = page.evaluate(
        """() => Object.fromEntries([...document.querySelectorAll('#inputs [name]')].map(el => [el.name, {
            value: el.value,
            section: el.closest('fieldset').dataset.section,
            unit: el.parentElement.querySelector('.unit').textContent}]))"""
    )
    assert list(shown) == [p["name"] for p in params]
    for p in params:
        assert shown[p["name"]] == {"value": p["default_display"], "section": p["section"], "unit": p["display_unit"]}, p["name"]


def test_a_value_with_a_unit_solves_and_the_results_table_and_the_map_appear(page, server):
    _open(page, server)
    page.fill('#inputs [name="applied_pressure"]', "3 psi")
    page.click("#solve")
    cell = page.wait_for_selector('#results td[data-key="film_thickness_center"]')
    page.wait_for_selector("#map-removal_rate .main-svg")
    data = json.loads(cmpsim.solve(applied_pressure="3 psi", grid="coarse").to_json())
    expected = {**data["values"], **data["solver"]}  # schema 2: the table shows values and solver diagnostics
    assert float(cell.get_attribute("title")) == expected["film_thickness_center"]  # the SI value
    # shown in the display unit of the outputs registry: um for the film, % for the load shares
    unit_of = lambda key: page.eval_on_selector(f'#results td[data-key="{key}"]', "c => c.nextElementSibling.textContent")  # noqa: E731
    assert float(cell.text_content()) == pytest.approx(expected["film_thickness_center"] * 1e6, rel=1e-4)
    assert unit_of("film_thickness_center") == "\u00b5m"
    fluid = page.text_content('#results td[data-key="fluid_load_fraction"]')
    assert float(fluid) == pytest.approx(expected["fluid_load_fraction"] * 100.0, rel=1e-4, abs=1e-9)
    assert unit_of("fluid_load_fraction") == "%"
    keys = page.eval_on_selector_all("#results td[data-key]", "cells => cells.map(c => c.dataset.key)")
    assert set(keys) == set(expected)
    for map_id in ("map-removal_rate", "map-film_thickness", "map-pressure"):
        assert page.evaluate(f"document.getElementById('{map_id}').data[0].type") == "heatmap"
    # a bare number is read in the display unit: 3 (psi) gives the same answer
    page.fill('#inputs [name="applied_pressure"]', "3")
    page.click("#solve")
    page.wait_for_function("document.getElementById('status').textContent.startsWith('Solved')")
    assert float(page.get_attribute('#results td[data-key="film_thickness_center"]', "title")) == expected["film_thickness_center"]


def test_a_bad_value_shows_cmpsims_message_beside_its_input(page, server):
    _open(page, server)
    for value in ("-3 psi", "3 kg"):  # out of range, wrong dimension
        with pytest.raises(ValueError) as info:
            Config.default().replace(applied_pressure=value)
        page.fill('#inputs [name="applied_pressure"]', value)
        page.click("#solve")
        page.wait_for_function(
            "text => document.querySelector('[data-error-for=\"applied_pressure\"]').textContent === text", arg=str(info.value)
        )
        # beside its input: in the same row of the form, and the input is marked
        row = page.locator('#inputs [name="applied_pressure"]').locator("xpath=..")
        assert row.locator(".error").text_content() == str(info.value)
        assert page.get_attribute('#inputs [name="applied_pressure"]', "aria-invalid") == "true"
    assert page.locator(".error:not(:empty)").count() == 1  # nothing else is blamed


def test_a_three_point_sweep_shows_progress_and_draws_its_curve(page, server):
    _open(page, server)
    page.evaluate(
        """() => { window.progressSeen = [];
        new MutationObserver(() => window.progressSeen.push(document.getElementById('sweep-progress').value))
          .observe(document.getElementById('sweep-status'), {childList: true, characterData: true, subtree: true}); }"""
    )
    page.select_option("#sweep-param-1", "applied_pressure")
    page.fill("#sweep-start-1", "2")
    page.fill("#sweep-stop-1", "4")
    page.fill("#sweep-num-1", "3")
    page.click("#run-sweep")
    page.wait_for_selector("#sweep-status[data-state=done]")
    assert page.text_content("#sweep-status") == "done: 3 of 3 points"
    assert page.evaluate("[document.getElementById('sweep-progress').value, document.getElementById('sweep-progress').max]") == [3, 3]
    seen = page.evaluate("window.progressSeen")
    assert {1, 2, 3} <= set(seen), seen  # the bar moved with each point's event
    curve = page.evaluate("document.getElementById('sweep-plot').data[0]")
    assert curve["x"] == [2, 3, 4] and len(curve["y"]) == 3 and all(isinstance(y, float) for y in curve["y"])
    assert page.is_visible("#download-sweep-file") and page.is_visible("#download-sweep-netcdf")


def test_a_failed_sweep_point_is_shown_with_its_message(page, server):
    _open(page, server)
    page.fill("#sweep-start-1", "1000")
    page.fill("#sweep-stop-1", "2000")
    page.fill("#sweep-num-1", "2")
    page.click("#run-sweep")
    page.wait_for_selector("#sweep-status[data-state=done]")
    failures = page.locator("#sweep-failures li").all_text_contents()
    assert len(failures) == 2 and all("no equilibrium" in f and "applied_pressure = " in f for f in failures)


def _membrane(page, server):
    _open(page, server)
    assert page.is_disabled("#tune-zones")  # the rigid head has no zones to tune
    page.select_option('#inputs [name="carrier"]', "membrane")
    page.fill('#inputs [name="zone_radii"]', "20,38.1")
    assert page.is_enabled("#tune-zones")


def test_a_membrane_solve_marks_the_zone_boundaries_in_the_profile(page, server):
    _membrane(page, server)
    page.click("#solve")
    page.wait_for_selector("#profile .main-svg")
    shapes = page.evaluate("document.getElementById('profile').layout.shapes")
    assert [(s["x0"], s["x1"], s["line"]["dash"]) for s in shapes] == [(20.0, 20.0, "dash"), (38.1, 38.1, "dash")]
    labels = page.evaluate("document.getElementById('profile').layout.annotations.map(a => a.text)")
    assert labels == ["zone 1 | 20 mm", "zone 2 | 38.1 mm"]
    # back on the rigid head: no boundaries, and nothing to tune
    page.select_option('#inputs [name="carrier"]', "rigid")
    page.fill('#inputs [name="zone_radii"]', "")
    assert page.is_disabled("#tune-zones")
    page.click("#solve")
    page.wait_for_function("(document.getElementById('profile').layout.shapes || []).length === 0")


def test_tune_zones_fills_the_zone_pressures_and_flattens_the_profile(page, server):
    _membrane(page, server)
    page.fill('#inputs [name="zone_pressures"]', "3,5")  # a start away from the flat profile
    page.click("#tune-zones")
    page.wait_for_selector("#tune-profile .main-svg")
    before = float(page.get_attribute("#tune-summary", "data-before"))
    after = float(page.get_attribute("#tune-summary", "data-after"))
    assert after < before
    expected = cmpsim.tune_zones(Config.default().replace(grid="coarse", carrier="membrane", zone_radii="20,38.1 mm", zone_pressures="3,5 psi"))
    assert after == pytest.approx(expected.within_wafer_nonuniformity, rel=1e-9)
    filled = page.input_value('#inputs [name="zone_pressures"]')
    psi = 6894.757293168361
    assert [float(v) for v in filled.split(",")] == pytest.approx([p / psi for p in expected.zone_pressures], rel=1e-5)
    rows = page.eval_on_selector_all("#tune-table tbody tr", "rows => rows.map(r => [...r.cells].map(c => c.textContent))")
    assert [float(r[4]) for r in rows] == pytest.approx(list(expected.zone_pressures), rel=1e-5)
    traces = page.evaluate("document.getElementById('tune-profile').data.map(t => t.name)")
    assert traces == ["before", "tuned"]
    assert len(page.evaluate("document.getElementById('tune-profile').layout.shapes")) == 2
    # the tuned pressures in the form solve as they are
    page.click("#solve")
    page.wait_for_function("document.getElementById('status').textContent.startsWith('Solved')")
    assert page.is_hidden("#message")


def test_tune_zones_with_the_ring_tunes_the_ring_at_the_kept_rate_like_the_command(page, server):
    """The page's "with the ring" is ``cmpsim tune-zones --ring`` (issue 32): the same numbers, the ring as one
    more row, the mean removal rate before and after (kept), and the tuned ring pressure written into its input."""
    _membrane(page, server)
    page.select_option('#inputs [name="pad_compliance"]', "layer")
    page.fill('#inputs [name="retaining_ring_pressure"]', "4")
    page.check("#tune-ring")
    page.click("#tune-zones")
    page.wait_for_selector("#tune-profile .main-svg")
    cfg = Config.default().replace(grid="coarse", carrier="membrane", zone_radii="20,38.1 mm", pad_compliance="layer", retaining_ring_pressure="4 psi")
    expected = cmpsim.tune_zones(cfg, ring=True)
    assert expected.keep == "rate"
    after = float(page.get_attribute("#tune-summary", "data-after"))
    assert after == pytest.approx(expected.within_wafer_nonuniformity, rel=1e-9)
    rate_before = float(page.get_attribute("#tune-summary", "data-rate-before"))
    rate_after = float(page.get_attribute("#tune-summary", "data-rate-after"))
    assert rate_after == pytest.approx(rate_before, rel=1e-3) and "(kept)" in page.text_content("#tune-summary")
    rows = page.eval_on_selector_all("#tune-table tbody tr", "rows => rows.map(r => [...r.cells].map(c => c.textContent))")
    assert [r[0] for r in rows] == ["1", "2", "ring"]
    assert float(rows[2][4]) == pytest.approx(expected.ring_pressure, rel=1e-5)
    psi = 6894.757293168361
    assert float(page.input_value('#inputs [name="retaining_ring_pressure"]')) == pytest.approx(expected.ring_pressure / psi, rel=1e-5)


def test_a_failed_tuning_shows_the_apis_message(page, server):
    _membrane(page, server)
    page.fill('#inputs [name="zone_pressures"]', "3,5,6")  # three pressures for two zones
    page.click("#tune-zones")
    page.wait_for_selector("#message:not([hidden])")
    with pytest.raises(ValueError) as info:
        Config.default().replace(carrier="membrane", zone_radii="20,38.1 mm", zone_pressures="3,5,6 psi")
    assert str(info.value) in page.text_content("#message") + page.text_content(".error:not(:empty)")
    assert page.is_hidden("#tune")


def test_the_api_reference_page_is_served_by_cmpsim_itself(page, server):
    page.goto(server.url + "/api/docs")
    page.wait_for_selector(".route h2")
    titles = page.locator(".route h2").all_text_contents()
    assert "POST /api/solve" in titles and "POST /api/sweeps" in titles


def test_the_docs_screenshot_script_makes_both_pictures(page, server, tmp_path):
    made = SHOTS.take_screenshots(page, server.url, tmp_path, grid="coarse", sweep_points=3)
    assert [p.name for p in made] == ["solved.png", "sweep.png"]
    for p in made:
        assert p.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n" and p.stat().st_size > 10_000
    committed = ROOT / "docs" / "web"
    assert {p.name for p in made} <= {p.name for p in committed.glob("*.png")}, "run python docs/make_screenshots.py"


# ---------------------------------------------------------------------------- the die view


def _chip(path: Path) -> Path:
    """A 400 um chip built here with gdstk: 200 um blocks of 8 um lines at 10 um pitch (80 %) and of
    2 um lines (20 %) in a checkerboard, on layer 1/0."""
    import gdstk

    lib = gdstk.Library(unit=1e-6, precision=1e-9)

    def lines(name, width):
        cell = gdstk.Cell(name)
        for i in range(20):
            cell.add(gdstk.rectangle((i * 10.0, 0), (i * 10.0 + width, 200.0), layer=1))
        return cell

    dense, sparse = lines("DENSE", 8.0), lines("SPARSE", 2.0)
    top = gdstk.Cell("CHIP")
    top.add(gdstk.Reference(dense, (0, 0)), gdstk.Reference(sparse, (200, 0)), gdstk.Reference(sparse, (0, 200)), gdstk.Reference(dense, (200, 200)))
    lib.add(dense, sparse, top)
    lib.write_gds(str(path))
    return path


def test_the_die_view_uploads_a_layout_and_shows_the_three_maps_and_the_hotspots(page, server, tmp_path):
    from click.testing import CliRunner

    from cmpsim.cli import main
    from cmpsim.layout import PDK_LAYER_MAPS

    path = _chip(tmp_path / "chip.gds")
    _open(page, server)
    assert page.is_disabled("#run-die")  # nothing to run before a file is chosen
    page.set_input_files("#die-file", str(path))
    # a PDK lists its named layers once chosen
    page.select_option("#die-pdk", "gf180mcu")
    names = page.eval_on_selector_all('#die-pdk-layers input[name="die-pdk-layer"]', "cbs => cbs.map(c => c.value)")
    assert names == list(PDK_LAYER_MAPS["gf180mcu"])
    page.select_option("#die-pdk", "sky130")
    names = page.eval_on_selector_all('#die-pdk-layers input[name="die-pdk-layer"]', "cbs => cbs.map(c => c.value)")
    assert names == list(PDK_LAYER_MAPS["sky130"])
    # a named layer the chip lacks: cmpsim's message, the layers control marked
    page.check('#die-pdk-layers input[value="met2"]')
    page.click("#run-die")
    page.wait_for_selector("#die-message:not([hidden])")
    assert "--layer 'met2' (69/20, 41/28) is not in chip.gds; its layers are: 1/0" in page.text_content("#die-message")
    assert page.get_attribute("#die-layers", "aria-invalid") == "true"
    # the chip's own layer, copper, two limits
    page.uncheck('#die-pdk-layers input[value="met2"]')
    page.fill("#die-layers", "1/0")
    page.select_option("#die-process", "copper")
    page.fill("#die-spec-thickness", "30")
    page.fill("#die-spec-dishing", "50")
    page.click("#run-die")
    page.wait_for_selector("#die-hotspots .main-svg")
    assert page.is_hidden("#die-message")
    res = CliRunner().invoke(main, ["die", str(path), "--layer", "1/0", "--process", "copper", "--spec", "thickness=30nm",
                                    "--spec", "dishing=50nm", "--grid", "coarse", "--json"])
    assert res.exit_code == 0, res.output
    cli = json.loads(res.stdout)
    assert cli["hotspot_count"] > 0
    assert page.text_content("#die-count") == str(cli["hotspot_count"])
    # the three maps: density (in %), the final surface with the hotspots as markers, the hotspot map
    density = page.evaluate("document.getElementById('die-density').data[0]")
    assert density["type"] == "heatmap" and len(density["z"]) == 20 and density["z"][0][0] == pytest.approx(80.0, abs=1e-3)
    height = page.evaluate("document.getElementById('die-height').data.map(t => [t.type, t.x.length])")
    assert height[0] == ["heatmap", 20] and height[1] == ["scatter", min(cli["hotspot_count"], 5000)]
    assert page.evaluate("document.getElementById('die-hotspots').data[0].type") == "heatmap"
    # the scalars of the JSON of a single-level run, each with its SI value on hover
    for key in ("hotspot_count", "thickness_range", "dishing_max", "time"):
        assert float(page.get_attribute(f'#die-results td[data-key="{key}"]', "title")) == pytest.approx(cli[key], rel=1e-12), key
    assert page.is_visible("#download-die-json")


def test_the_docs_screenshot_script_makes_the_die_picture(page, server, tmp_path):
    shot = SHOTS.take_die_screenshot(page, server.url, SHOTS.demo_layout(tmp_path / "demo.gds"), tmp_path, grid="coarse")
    assert shot.name == "die.png" and shot.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n" and shot.stat().st_size > 10_000
    assert (ROOT / "docs" / "web" / "die.png").is_file(), "run python docs/make_screenshots.py"
