"""cmpsim.die: the chip-scale density / step-height model, its verification and its physics checks."""

import json

import numpy as np
import pytest

import cmpsim
from cmpsim import die
from cmpsim.die.density import GaussianWeighting, effective_density
from cmpsim.die.evolution import DieEvolution
from cmpsim.die.layout import Layout
from cmpsim.die.pad import bending_length, pad_stack
from cmpsim.die.process import DieProcess
from cmpsim.die.stepheight import advance, rates

K = 2e-9  # m/s
R_ASP = 7e-6


def _uniform(rho, n=8, cell=250e-6, width=None):
    return Layout(np.full((n, n), rho), cell, None if width is None else np.full((n, n), width), "uniform")


def _stine_smith_step(t, rho, h0, hc, k):
    """Stine et al. (1998) eq. 3 while the step exceeds the contact height, then the exponential
    decay of the step-height model (Lee, Boning & Economikos 2001, eq. 5): written independently."""
    t1 = rho * (h0 - hc) / k
    return np.where(t < t1, h0 - k * t / rho, hc * np.exp(-(t - t1) * k / (rho * hc)))


# ---------------------------------------------------------------------------- verification
def test_uniform_density_die_follows_the_closed_form_step_height_decay_to_round_off():
    rho, h0, hc = 0.3, 1e-6, 1e-7
    lay = _uniform(rho)
    eff = effective_density(lay.density, lay.cell_size, GaussianWeighting(3e-3))
    assert np.max(np.abs(eff - rho)) < 1e-15
    proc = DieProcess(step_height=h0, contact_height=hc)
    ev = DieEvolution(lay, proc, eff, K, R_ASP)
    assert np.all(ev.h == hc)  # no line widths: wide spaces, the pad's contact height
    times = np.linspace(0.0, 400.0, 37)
    for t in times[1:]:
        ev.advance_to(t)
        ref = _stine_smith_step(t, rho, h0, hc, K)
        assert np.max(np.abs(ev.step_height - ref)) < 1e-14 * h0, t
        # the pad carries P on the whole cell: uniform removal at the blanket rate
        assert np.max(np.abs(ev.removed_thickness() - K * t)) < 1e-14 * h0
    t_planar = rho * (h0 - hc) / K + rho * hc / K * np.log(hc / proc.planarity)
    assert np.max(np.abs(ev.t_planar - t_planar)) < 1e-9 * t_planar


def test_the_step_height_integrator_is_exact_whatever_the_steps():
    s0 = np.array([1e-6, 5e-8, -3e-7, 0.0])
    f, h = np.array([0.2, 0.5, 0.7, 0.4]), 1e-7
    ka, kb = np.array([1e-9, 2e-10, 3e-9, 1e-8]), np.array([1e-9, 5e-9, 1e-9, 2e-10])
    once = advance(np.zeros(4), -s0, f, h, ka, kb, 600.0)
    za, zb = np.zeros(4), -s0
    for _ in range(60):
        za, zb = advance(za, zb, f, h, ka, kb, 10.0)
    assert np.allclose(za, once[0], rtol=0, atol=1e-18) and np.allclose(zb, once[1], rtol=0, atol=1e-18)


def test_effective_density_of_a_density_step_equals_direct_convolution():
    n, cell, length = 32, 250e-6, 2e-3
    rho = np.where(np.arange(n)[None, :] < n // 2, 0.2, 0.8) * np.ones((n, 1))
    rho[3:9, 20:27] = 0.5  # and a block, so that the test is 2-D
    w = GaussianWeighting(length)
    fft = effective_density(rho, cell, w)
    x = np.arange(n) * cell
    direct = np.zeros_like(rho)
    period = n * cell
    for iy in range(n):
        for ix in range(n):
            dx = (x[ix] - x[None, :] + period / 2) % period - period / 2
            dy = (x[iy] - x[:, None] + period / 2) % period - period / 2
            r2 = dx**2 + dy**2
            direct[iy, ix] = np.sum(rho * w.weight(np.sqrt(r2))) * cell**2
    # the next periodic images weigh up to exp(-pi (period / 2 L)^2) ~ 1e-7: add them too
    images = np.zeros_like(rho)
    for my in (-1, 0, 1):
        for mx in (-1, 0, 1):
            if (mx, my) == (0, 0):
                continue
            for iy in range(n):
                for ix in range(n):
                    dx = (x[ix] - x[None, :] + period / 2) % period - period / 2 + mx * period
                    dy = (x[iy] - x[:, None] + period / 2) % period - period / 2 + my * period
                    images[iy, ix] += np.sum(rho * w.weight(np.hypot(dx, dy))) * cell**2
    assert np.max(np.abs(fft - (direct + images))) < 1e-12
    assert fft.min() >= 0.2 - 1e-12 and fft.max() <= 0.8 + 1e-12  # a positive weighting stays inside the extremes


def test_removed_volume_equals_the_time_integral_of_the_local_rates():
    lay = Layout(np.array([[0.1, 0.5], [0.9, 0.0]]).repeat(4, 0).repeat(4, 1), 250e-6, np.full((8, 8), 20e-6), "four")
    eff = effective_density(lay.density, lay.cell_size, GaussianWeighting(1e-3))
    proc = DieProcess(kind="copper", copper_thickness=3e-7, trench_depth=3e-7, barrier_thickness=3e-8, barrier_selectivity=0.3, oxide_selectivity=0.1)
    ev = DieEvolution(lay, proc, eff, 5e-9, R_ASP)
    times = np.linspace(0.0, 200.0, 20001)
    r = [ev.removal_rate()]
    for t in times[1:]:
        ev.advance_to(t)
        r.append(ev.removal_rate())
    r = np.array(r)
    assert np.all(np.isfinite(ev.t_clear))  # the run went through every stage
    integral = np.trapezoid(r, times, axis=0)
    removed = ev.removed_thickness()
    assert np.max(np.abs(integral - removed)) < 2e-4 * removed.max()
    # and the die total (the removed volume) agrees
    assert abs(integral.sum() - removed.sum()) < 1e-4 * removed.sum()


# ---------------------------------------------------------------------------- physics checks
def _blocks(values, widths=None, block=8, cell=250e-6):
    rho = np.kron(np.asarray(values, dtype=float), np.ones((block, block)))
    w = None if widths is None else np.kron(np.asarray(widths, dtype=float), np.ones((block, block)))
    return Layout(rho, cell, w, "blocks")


def test_step_height_falls_faster_in_low_density_regions():
    lay = _blocks([[0.2, 0.5, 0.8]])
    res = die.simulate(lay, 200.0, blanket_rate=K, planarization_length=0.5e-3, step_height=1e-6)
    by = {r["density"]: r for r in res.to_dict()["regions"]}
    assert by[0.2]["step_height"] < by[0.5]["step_height"] < by[0.8]["step_height"]
    res = die.simulate(lay, 800.0, blanket_rate=K, planarization_length=0.5e-3, step_height=1e-6)
    by = {r["density"]: r for r in res.to_dict()["regions"]}
    assert by[0.2]["time_to_planarize"] < by[0.5]["time_to_planarize"] < by[0.8]["time_to_planarize"]
    # Stine's density model: the time to planarize scales with the effective density
    for r in by.values():
        ref = r["effective_density"] * (1e-6 - 1e-7) / K + r["effective_density"] * 1e-7 / K * np.log(1e-7 / 1e-8)
        assert abs(r["time_to_planarize"] - ref) < 1e-6 * ref


def _copper(lay, time=None, **kw):
    return die.simulate(lay, time, blanket_rate=5e-9, planarization_length=0.5e-3, process="copper", **kw).to_dict()["regions"]


def test_dishing_grows_with_line_width_during_over_polish():
    widths = [0.25e-6, 1e-6, 2e-6, 5e-6, 20e-6, 100e-6]
    regs = _copper(_blocks([[0.5] * 6], [widths]), 600.0)
    dish = [r["dishing"] for r in sorted(regs, key=lambda r: r["line_width"])]
    assert all(d > 0 for d in dish)
    assert all(b >= a for a, b in zip(dish, dish[1:])) and dish[-1] > 20 * dish[0]


def test_erosion_grows_with_array_density_during_over_polish():
    dens = [0.1, 0.3, 0.5, 0.7, 0.9]
    regs = _copper(_blocks([dens], [[2e-6] * 5]), 600.0)
    ero = [r["erosion"] for r in sorted(regs, key=lambda r: r["density"])]
    assert all(e > 0 for e in ero)
    assert all(b > a for a, b in zip(ero, ero[1:]))


def test_narrow_trenches_start_flat_and_wide_ones_print_the_trench_depth():
    lay = _blocks([[0.5, 0.5]], [[1e-6, 50e-6]])
    ev = die.simulate(lay, 0.0, blanket_rate=5e-9, process="copper", planarization_length=0.5e-3).evolution
    assert ev.step_height[0, 0] == 0.0 and ev.step_height[0, -1] == pytest.approx(DieProcess().trench_depth)


def test_derived_planarization_length_rises_with_pad_stack_stiffness():
    c = cmpsim.Config.default()
    mod = [die.planarization_length_from_pad(c.replace(pad_bulk_modulus=f"{e} MPa")) for e in (100, 200, 300, 600, 1000)]
    thick = [die.planarization_length_from_pad(c.replace(pad_thickness=f"{t} mm")) for t in (0.8, 1.27, 2.0)]
    assert all(b > a for a, b in zip(mod, mod[1:])) and all(b > a for a, b in zip(thick, thick[1:]))
    # a plate on a soft layer: L = sqrt(4 pi ln 2) (D1/k2)^(1/4) to within the layer's finite-depth stiffening
    ratio = die.planarization_length_from_pad(c) / bending_length(pad_stack(c))
    assert 2.9 < ratio < 3.0


def test_derived_planarization_length_of_ic1000_suba_iv_exceeds_the_published_ones():
    """Kept failing on purpose (docs/validation.md): the bending argument gives 6.9 mm for the
    default IC1000/Suba IV-like stack, the published lengths of such stacks are 2.7-4.5 mm (Ouma
    et al. 1997; Ouma 1998). The test fails when the model comes into that range, so that the
    validation page is revised with it."""
    derived = die.planarization_length_from_pad(cmpsim.Config.default())
    published = [3.00e-3, 2.72e-3, 3.75e-3, 4.50e-3, 3.60e-3, 2.90e-3]
    assert derived > max(published)
    assert 1.5 < derived / np.mean(published) < 2.5


# ---------------------------------------------------------------------------- the wafer
@pytest.fixture(scope="module")
def wafer_result():
    """A 200 mm wafer polishing copper (the film of the copper process)."""
    return cmpsim.solve(cmpsim.Config.default().replace(wafer_diameter="200 mm", grid="coarse", film="copper"), relative=False)


@pytest.fixture(scope="module")
def oxide_wafer_result():
    return cmpsim.solve(cmpsim.Config.default().replace(wafer_diameter="200 mm", grid="coarse", film="oxide"), relative=False)


def test_each_die_of_the_wafer_is_the_die_polished_at_its_own_blanket_rate(wafer_result):
    lay = die.builtin_layout("lines", 1e-3)
    w = die.simulate_wafer(lay, 900.0, result=wafer_result, process="copper")
    assert len(w.x) > 20
    k = die.blanket_rates(wafer_result, w.x, w.y)
    assert np.array_equal(k, w.blanket_rate) and k.max() > k.min()
    for i in (int(np.argmin(k)), int(np.argmax(k))):
        one = die.simulate(lay, 900.0, config=wafer_result.config, blanket_rate=float(k[i]), process="copper")
        d = one.to_dict()
        assert w.dishing_max[i] == pytest.approx(d["dishing_max"], rel=1e-9)
        assert w.erosion_max[i] == pytest.approx(d["erosion_max"], rel=1e-9, abs=1e-18)
        assert w.time_to_clear[i] == pytest.approx(d["time_to_clear"], rel=1e-9)


def test_dies_lie_inside_the_edge_exclusion():
    x, y = die.die_sites((20e-3, 20e-3), 0.3, 3e-3)
    assert np.all(np.hypot(np.abs(x) + 10e-3, np.abs(y) + 10e-3) <= 0.147 + 1e-12)
    assert len(x) == 148


def test_blanket_rate_is_the_rotation_averaged_profile(wafer_result):
    r = wafer_result.radius
    assert np.allclose(die.blanket_rates(wafer_result, r, 0 * r), wafer_result.removal_rate_profile, rtol=1e-15)


# ---------------------------------------------------------------------------- layouts and inputs
def test_layout_csv_round_trip(tmp_path):
    lay = die.builtin_layout("lines", 500e-6)
    back = die.read_layout(lay.to_csv(tmp_path / "lines.csv"))
    assert np.array_equal(back.density, lay.density) and np.allclose(back.line_width, lay.line_width, rtol=1e-12)
    assert back.cell_size == pytest.approx(lay.cell_size) and len(back.regions()) == len(lay.regions())


def test_pitch_grid_gives_the_line_width(tmp_path):
    p = tmp_path / "p.csv"
    p.write_text("# cell_size = 1 mm\n# [density]\n0.5,0.25\n# [pitch um]\n4,8\n")
    lay = die.read_layout(p)
    assert np.allclose(lay.line_width, [[2e-6, 2e-6]])


@pytest.mark.parametrize(
    "text, message",
    [
        ("# [density]\n0.5\n", "cell_size"),
        ("# cell_size = 1 mm\n# [density]\n0.5,1.5\n", "[0, 1]"),
        ("# cell_size = 1 mm\n# [density]\n0.5,0.5\n0.5\n", "different lengths"),
        ("# cell_size = 1 mm\n# [density]\n0.5,x\n", "not a number"),
        ("# cell_size = 1 kg\n# [density]\n0.5\n", "cell_size"),
        ("# cell_size = 1 mm\n# [line_width um]\n1\n", "no [density]"),
    ],
)
def test_bad_layout_files_are_refused_with_the_reason(tmp_path, text, message):
    p = tmp_path / "bad.csv"
    p.write_text(text)
    with pytest.raises(ValueError, match=message.replace("[", r"\[").replace("]", r"\]")):
        die.read_layout(p)


def test_die_inputs_take_units_and_refuse_out_of_range_values():
    assert DieProcess.from_values("copper", trench_depth="0.3 um").trench_depth == pytest.approx(3e-7)
    with pytest.raises(ValueError, match="contact_height"):
        DieProcess(contact_height=0.0)
    with pytest.raises(ValueError, match="process must be"):
        DieProcess(kind="tungsten")


# ---------------------------------------------------------------------------- the command
def test_die_command_json_contract(tmp_path):
    from click.testing import CliRunner

    from cmpsim.cli import main

    res = CliRunner().invoke(main, ["die", "lines", "--process", "copper", "--wafer", "--json", "--cell-size", "500um",
                                    "--set", "grid=coarse", "--set", "wafer_diameter=150mm", "--out", str(tmp_path)])
    assert res.exit_code == 0, res.output
    data = json.loads(res.stdout)
    assert {"planarization_length", "time_to_planarize", "regions", "dies"} <= set(data)
    assert all({"density", "line_width", "step_height", "dishing", "erosion"} <= set(r) for r in data["regions"])
    assert all({"x", "y", "blanket_rate", "time_to_clear", "dishing_max", "erosion_max"} <= set(d) for d in data["dies"])
    import xarray as xr

    with xr.open_dataset(tmp_path / "die.nc") as ds:
        assert ds["dishing"].attrs["units"] == "m" and ds["x"].attrs["units"] == "m"
    with xr.open_dataset(tmp_path / "wafer.nc") as ds:
        assert ds["time_to_clear"].attrs["units"] == "s" and ds.sizes["die"] == len(data["dies"])
    assert (tmp_path / "die.png").stat().st_size > 0 and (tmp_path / "wafer.png").stat().st_size > 0


def test_die_command_lists_the_built_in_dies_and_refuses_bad_input():
    from click.testing import CliRunner

    from cmpsim.cli import main

    res = CliRunner().invoke(main, ["die", "--list"])
    assert res.exit_code == 0 and all(n in res.output for n in die.BUILTIN_LAYOUTS)
    bad = CliRunner().invoke(main, ["die", "nonexistent.csv"])
    assert bad.exit_code == 2 and "built-in die" in bad.output and "Traceback" not in bad.output
    bad = CliRunner().invoke(main, ["die", "uniform", "--time", "-3 s", "--blanket-rate", "100nm/min"])
    assert bad.exit_code == 2 and "time must be >= 0" in bad.output


def test_pad_weighting_keeps_the_mean_density_and_smooths_a_step():
    c = cmpsim.Config.default()
    lay = die.builtin_layout("step", 100e-6)
    res = die.simulate(lay, 0.0, config=c, blanket_rate=K, weighting="pad")
    eff = res.effective_density
    assert abs(eff.mean() - lay.density.mean()) < 1e-12
    assert eff[:, :50].mean() > 0.2 and eff[:, 50:].mean() < 0.8  # the pad averages across the step
    assert res.planarization_length == pytest.approx(die.planarization_length_from_pad(c))
    with pytest.raises(ValueError, match="weighting"):
        die.simulate(lay, 0.0, config=c, blanket_rate=K, weighting="square")


def test_a_user_planarization_length_replaces_the_derived_one_and_both_are_reported():
    from click.testing import CliRunner

    from cmpsim.cli import main

    res = CliRunner().invoke(main, ["die", "uniform", "--json", "--time", "1 min", "--blanket-rate", "100 nm/min", "--planarization-length", "3 mm"])
    assert res.exit_code == 0, res.output
    data = json.loads(res.stdout)
    assert data["planarization_length"] == pytest.approx(3e-3)
    assert data["planarization_length_from_pad"] == pytest.approx(die.planarization_length_from_pad(cmpsim.Config.default()))
    assert data["time"] == pytest.approx(60.0) and data["blanket_rate"] == pytest.approx(100e-9 / 60)


def test_an_oxide_wafer_reports_planarization_and_no_dishing(oxide_wafer_result):
    w = die.simulate_wafer(die.builtin_layout("density", 1e-3), result=oxide_wafer_result)
    d = w.to_dict()
    assert all(x["dishing_max"] is None and x["erosion_max"] is None for x in d["dies"])
    assert np.allclose(w.time_to_clear, w.time_to_planarize) and np.all(w.time_to_planarize < w.time)
    # the slowest site sets the default time: its die planarizes last, at time / (1 + over_polish)
    assert w.time_to_planarize.max() * (1 + DieProcess().over_polish) == pytest.approx(w.time, rel=1e-12)


def test_the_wafer_solve_polishes_the_film_of_the_process(wafer_result):
    lay = die.builtin_layout("uniform", 500e-6)
    assert die.simulate(lay, 10.0, blanket_rate=K, process="copper").to_dict()["film"] == "copper"
    with pytest.raises(ValueError, match="film = 'oxide'"):
        die.simulate_wafer(lay, 10.0, result=wafer_result, process="oxide")


def test_a_cell_snapped_onto_the_contact_height_keeps_polishing():
    """Regression: after the snap onto |s| = h, zA - (zA - h) may exceed h by an ulp; the cell
    then bounced between the two regimes and `cmpsim die lines` failed ("left time unpolished")."""
    from cmpsim.die.stepheight import advance

    k = 1.958870281687486e-09
    za, zb = advance(0.0, -1e-06, 0.2692705992352215, 9.795319242856495e-08, k, k, 127.6245815443355)
    removed = 0.2692705992352215 * (0.0 - za) + (1 - 0.2692705992352215) * (-1e-06 - zb)
    assert abs(removed - k * 127.6245815443355) < 1e-12 * 1e-6  # mass balance: the cell removes K t on average
    assert 0.0 <= za - zb < 9.795319242856495e-08


def test_a_contact_height_below_the_ulp_of_the_heights_is_integrated():
    """Found on an odd layout (circles at a pitch 1 dbu off their size): a contact height of 1.2 pm under
    heights of about 1 um. After the snap onto |s| = h the step exceeds h by an ulp of the heights, far
    more than 1e-12 h, and the integration bounced between its regimes until it gave up. Now it goes on,
    and the cell's mean removal is the blanket rate times the time (the pad's load balance)."""
    za0, zb0, f, h, k, dt = -6.033274519004813e-07, -1e-06, 0.4143686802456941, 1.2179956180421813e-12, 200e-9 / 60, 90.0
    za, zb = advance(za0, zb0, f, h, k, k, dt)
    assert f * (za - za0) + (1 - f) * (zb - zb0) == pytest.approx(-k * dt, rel=1e-9)
    assert abs(za - zb) <= h * (1 + 1e-9) + 1e-21  # the step ends inside the contact height
