"""`cmpsim validate`: shipped data sets, the documented CSV format, honest verdicts, bad input."""

import math

import numpy as np
import pytest
from click.testing import CliRunner

import cmpsim
from cmpsim.cli import main
from cmpsim.validation import (
    QUANTITIES,
    DataError,
    _loo,
    fit_scale,
    load_dataset,
    load_datasets,
    shipped_dataset_paths,
    validate,
)

SHIPPED = {
    "mariscal2020_peteos_ceria",
    "us9499721_t18_2wt",
    "us9499721_t18_3wt",
    "us8142675_tP_platinum",
    "scarfo_convex_fluid_share",
    "sun2010_real_contact_area",
    "thakurta2001_model_prediction",
    "lai2001_no_hydroplaning",
    "lai2001_cu_alumina_size",
}
REMOVAL_SERIES = ("mariscal2020_peteos_ceria", "us9499721_t18_2wt", "us9499721_t18_3wt", "us8142675_tP_platinum")


@pytest.fixture(scope="module")
def shipped():
    """The default (predictive) model on every shipped data set."""
    return validate(grid="coarse")


@pytest.fixture(scope="module")
def shipped_paper():
    """The paper's model (the paper preset) on every shipped data set."""
    return validate(config=cmpsim.Config.paper(), grid="coarse")


def test_shipped_data_sets_carry_citation_and_provenance():
    paths = shipped_dataset_paths()
    names = set()
    for p in paths:
        ds = load_dataset(p)
        names.add(ds.name)
        assert ds.meta.get("citation") and ds.meta.get("provenance") and ds.meta.get("conditions"), p
        assert ds.kind in ("measurement", "model_prediction")
    assert names == SHIPPED
    # Lu et al. 2004 (the paper's own comparison) is not available and must not be invented
    assert not any("lu" in n.split("_")[0] for n in names)


def test_validate_without_arguments_runs_every_shipped_data_set(shipped):
    assert {d.name for d in shipped.datasets} == SHIPPED
    assert len(shipped.points) == sum(len(load_dataset(p).points) for p in shipped_dataset_paths())
    text = shipped.table()
    for name in SHIPPED:
        assert name in text
    assert all(p.status.startswith("ok") for p in shipped.points)


def test_the_paper_model_still_fails_the_scarfo_fluid_share(shipped_paper):
    """Kept on purpose: the paper's model carries far less load in the slurry than Scarfo et al. measured."""
    d = shipped_paper.dataset("scarfo_convex_fluid_share")
    assert d.failed
    (p,) = shipped_paper.points_of("scarfo_convex_fluid_share")
    assert p.model < 36.0 and p.agrees is False  # % of the load


def test_the_paper_model_still_fails_the_sun_contact_area(shipped_paper):
    d = shipped_paper.dataset("sun2010_real_contact_area")
    assert d.failed
    assert all(p.model > 3.16 * p.measured for p in shipped_paper.points_of("sun2010_real_contact_area"))


def test_the_paper_model_hydroplanes_at_3_9_m_s_against_lai(shipped_paper):
    d = shipped_paper.dataset("lai2001_no_hydroplaning")
    assert d.failed
    assert shipped_paper.points_of("lai2001_no_hydroplaning")[-1].model > 80.0


def test_the_paper_model_loses_to_preston_on_every_removal_series(shipped_paper):
    for name in REMOVAL_SERIES:
        d = shipped_paper.dataset(name)
        assert d.loo_rms_model > d.loo_rms_preston, name


def test_the_default_model_still_fails_the_scarfo_fluid_share(shipped):
    """Kept on purpose (docs/model.md, 13d): the compliant pad conforms and the slurry carries ~15 %, not 36-64 %."""
    d = shipped.dataset("scarfo_convex_fluid_share")
    assert d.failed
    (p,) = shipped.points_of("scarfo_convex_fluid_share")
    assert p.model < 36.0 and p.agrees is False


def test_the_default_model_meets_the_sun_contact_area_within_a_factor_3_and_rises_with_load(shipped):
    d = shipped.dataset("sun2010_real_contact_area")
    assert d.passed
    pts = shipped.points_of("sun2010_real_contact_area")
    assert all(p.measured / 3 < p.model < 3 * p.measured for p in pts)
    assert [p.model for p in pts] == sorted(p.model for p in pts)  # 2, 4, 6 psi


def test_the_default_model_does_not_hydroplane_up_to_3_9_m_s(shipped):
    d = shipped.dataset("lai2001_no_hydroplaning")
    assert d.passed
    assert all(p.model < 80.0 for p in shipped.points_of("lai2001_no_hydroplaning"))


def test_the_default_model_beats_the_mean_on_all_four_removal_series(shipped):
    for name in REMOVAL_SERIES:
        d = shipped.dataset(name)
        assert d.loo_rms_model < d.loo_rms_mean and d.passed, name


def test_the_default_model_is_flat_in_particle_size_and_fails_lais_size_series(shipped):
    """Kept failing on purpose (docs/model.md, 13e.1 step 2b, 13e.6 and 13e.8): the particles are
    counted summit by summit, but the summit contacts (radius ~4.8 um at 48 kPa) are far larger than
    the particles and the pad's flow pressure caps each particle's load at p_pad pi r^2, so 50, 300
    and 1000 nm alumina on copper remove alike; Lai measured 51 / 112 / 133 nm/min. Predicting the
    mean does as well: no pass. The film's indentation size effect (film_size_length) would give a
    size effect, but no measurement of it exists at particle radii, so it is off by default."""
    d = shipped.dataset("lai2001_cu_alumina_size")
    pts = shipped.points_of("lai2001_cu_alumina_size")
    assert [p.measured for p in pts] == [51.0, 112.0, 133.0]
    assert all(p.status.startswith("ok") for p in pts)  # 1 um particles are valid in the default model
    raw = [p.model_raw for p in pts]
    assert max(raw) == pytest.approx(min(raw), rel=1e-9)  # does not rise with size
    assert 20.0 < raw[0] < 1000.0  # nm/min: the right order with no fitted constant
    assert d.failed and not d.loo_rms_model < d.loo_rms_mean * (1 - 1e-9)


def _lai_with(**updates):
    path = [p for p in shipped_dataset_paths() if "cu_alumina_size" in str(p)]
    rep = validate(path, config=cmpsim.Config.default().replace(**updates), grid="coarse")
    return rep.datasets[0], [p.model_raw for p in rep.points_of("lai2001_cu_alumina_size")]


def test_lai_with_the_indentation_size_effect_of_bulk_copper_an_exploration_not_the_default():
    """docs/model.md 13e.8, reported, not adopted (decided before this run, for the reasons given
    there: bulk annealed copper is not Lai's sputtered film, the Berkovich h* is converted to a
    sphere under an assumption, and the particles' contacts are 2-3 decades below the depths h*
    was measured at). With Nix & Gao's fit for annealed copper (H_0 = 0.58 GPa, h* = 1.6 um, so
    R* = 2 h* / (3 tan^2 19.7 deg) = 8.32 um for a sphere) the rate rises with size, 0.438 / 0.745 / 1
    against the measured 0.383 / 0.842 / 1, and the leave-one-out error is 11.5 nm/min against the
    mean's 52.2; with the film's 1.5 GPa and the Taylor R* = 27 alpha^2 mu^2 b / H_0^2 = 1.77 um
    it is 19.8. The 50 nm point is the elastic limit in both (copper at ~10 GPa does not yield)."""
    tan2 = math.tan(math.radians(90 - 70.3)) ** 2
    bulk, raw = _lai_with(film_hardness="0.58 GPa", film_size_length=2 * 1.6e-6 / (3 * tan2))
    assert raw[0] < raw[1] < raw[2]
    assert [round(r / raw[-1], 3) for r in raw] == [0.438, 0.745, 1.0]
    assert bulk.loo_rms_model == pytest.approx(11.5, abs=0.1) and bulk.loo_rms_mean == pytest.approx(52.17, abs=0.01)
    taylor, raw_t = _lai_with(film_size_length=27 * 0.25 * 48e9**2 * 0.2556e-9 / 1.5e9**2)
    assert raw_t[0] < raw_t[1] < raw_t[2] and taylor.loo_rms_model == pytest.approx(19.8, abs=0.1)
    assert raw_t[0] == pytest.approx(raw[0], rel=1e-9)  # the elastic limit: no hardness in it


def test_the_default_model_overstates_the_3_to_2_wt_percent_ratio_of_us9499721(shipped):
    """US 9,499,721 Table 18: 3 wt% removes 6-11 % more than 2 wt% at 1.5, 3 and 5 psi; the model's
    particle count follows the loading, so its ratio is the volume-fraction ratio 1.51 (+36 to +42 %;
    docs/model.md, 13e.6)."""
    two = {p.conditions.split(",")[0]: p for p in shipped.points_of("us9499721_t18_2wt")}
    three = {p.conditions.split(",")[0]: p for p in shipped.points_of("us9499721_t18_3wt")}
    assert set(three) == {"applied_pressure=1.5 psi", "applied_pressure=3 psi", "applied_pressure=5 psi"}
    phi = [(w / 2200) / (w / 2200 + (1 - w) / 1000) for w in (0.02, 0.03)]
    for key, p3 in three.items():
        measured = p3.measured / two[key].measured
        model = p3.model_raw / two[key].model_raw
        assert 1.05 < measured < 1.12
        assert model == pytest.approx(phi[1] / phi[0], rel=0.01)
        assert 0.30 < model / measured - 1 < 0.45, key


def test_the_two_step_kinetics_with_its_unsourced_defaults_barely_moves_the_loading_ratio():
    """docs/model.md 13e.6: no sourced two-step constants exist for silica on TEOS (Mariscal et al.
    fitted ceria on PETEOS, and their constants were not available); with the order-of-magnitude
    defaults the chemical step is slow only at 5 psi and the 3 / 2 wt% ratio stays 1.45-1.48 (+31 to
    +40 %). The measured ratio rises with the pressure (1.06 -> 1.11), as a chemical step that
    speeds up with the friction power would make it."""
    paths = [p for p in shipped_dataset_paths() if "t18" in str(p)]
    rep = validate(paths, config=cmpsim.Config.default().replace(removal_kinetics="two_step"), grid="coarse")
    two = {p.conditions.split(",")[0]: p for p in rep.points_of("us9499721_t18_2wt")}
    ratios = [p.model_raw / two[k].model_raw for k, p in ((p.conditions.split(",")[0], p) for p in rep.points_of("us9499721_t18_3wt"))]
    assert all(1.43 < r < 1.49 for r in ratios) and ratios == sorted(ratios, reverse=True)


def test_the_default_model_beats_preston_only_on_the_platinum_series(shipped):
    """Kept on purpose: the target is Preston beaten on two series; the default beats it on one."""
    beaten = {name for name in REMOVAL_SERIES if shipped.dataset(name).loo_rms_model < shipped.dataset(name).loo_rms_preston}
    assert beaten == {"us8142675_tP_platinum"}


def test_the_default_models_film_stays_far_below_thakurtas_peer_model(shipped):
    """Kept on purpose: the compliant pad gives a mean film of ~10 um against the peer model's 48 um."""
    (mean,) = [p for p in shipped.points_of("thakurta2001_model_prediction") if p.quantity == "film_thickness_mean"]
    assert mean.model < 0.75 * mean.measured


def test_thakurta_is_a_labelled_model_to_model_comparison(shipped):
    d = shipped.dataset("thakurta2001_model_prediction")
    assert d.kind == "model_prediction" and d.verdict == "n/a"
    assert "model-to-model" in " ".join(" ".join(r) for r in shipped.dataset_rows())
    assert all(p.agrees is None for p in shipped.points_of("thakurta2001_model_prediction"))


def test_shape_data_sets_report_loo_errors_beside_the_mean_baseline(shipped):
    for name in ("mariscal2020_peteos_ceria", "us9499721_t18_2wt", "us9499721_t18_3wt", "us8142675_tP_platinum"):
        d = shipped.dataset(name)
        assert d.comparison == "shape"
        assert d.scale > 0 and math.isfinite(d.loo_rms_model) and math.isfinite(d.loo_rms_mean) and math.isfinite(d.loo_rms_preston)
        assert d.verdict == ("pass" if d.loo_rms_model < d.loo_rms_mean else "fail")


def test_parity_plot_and_csv(shipped, tmp_path):
    shipped.parity_plot(tmp_path / "parity.png")
    shipped.to_csv(tmp_path / "points.csv")
    shipped.summary_csv(tmp_path / "datasets.csv")
    assert (tmp_path / "parity.png").read_bytes()[:4] == b"\x89PNG"
    assert "mariscal2020_peteos_ceria" in (tmp_path / "points.csv").read_text()
    assert "loo_rms_mean" in (tmp_path / "datasets.csv").read_text()


def test_cli_validate_without_arguments_prints_the_table(tmp_path):
    res = CliRunner().invoke(main, ["validate", "--grid", "coarse", "--out", str(tmp_path / "v"), "--markdown"])
    assert res.exit_code == 0, res.output
    assert "scarfo_convex_fluid_share" in res.output and "| fail |" in res.output
    assert (tmp_path / "v" / "parity.png").exists()


def _write(tmp_path, text, name="mine.csv"):
    p = tmp_path / name
    p.write_text(text)
    return p


def test_a_users_own_file_is_compared(tmp_path):
    r = cmpsim.solve(grid="coarse", applied_pressure="3 psi", relative=False)
    h = r.film_thickness_center * 1e6
    p = _write(
        tmp_path,
        "# citation: my lab notebook\n"
        "dataset,quantity,value,unit,uncertainty,comparison,applied_pressure,rotation_speed,source\n"
        f"lab,film_thickness,{h + 0.5:.6f},um,1,absolute,3 psi,60 rpm,run 1\n"
        f"lab,film_thickness,{h + 5:.6f},um,1,absolute,3 psi,60 rpm,run 2\n",
    )
    rep = validate(p, grid="coarse")
    pts = rep.points_of("lab")
    assert pts[0].agrees is True and pts[1].agrees is False
    assert pts[0].error == pytest.approx(-0.5, abs=1e-6)
    assert rep.dataset("lab").rms_error == pytest.approx(math.sqrt((0.25 + 25) / 2), rel=1e-6)
    assert rep.datasets[0].citation == "my lab notebook"


def test_sliding_speed_is_converted_with_the_centre_distance(tmp_path):
    p = _write(
        tmp_path,
        "dataset,quantity,value,unit,comparison,sliding_speed,centre_distance\n"
        "s,fluid_load_fraction,10,%,absolute,0.5 m/s,0.2 m\n",
    )
    (ds,) = load_datasets(p)
    from cmpsim.validation import point_config

    cfg = point_config(cmpsim.Config.default(), ds.points[0].conditions)
    assert cfg.rotation_speed == pytest.approx(0.5 / 0.2)


@pytest.mark.parametrize(
    "body, needle",
    [
        ("quantity,value,unit\nflim_thickness,30,um\n", "unknown quantity 'flim_thickness'"),
        ("quantity,value,unit\nfilm_thickness,30,psi\n", "not a unit of film_thickness"),
        ("quantity,value,unit\nfilm_thickness,thirty,um\n", "value 'thirty' is not a number"),
        ("quantity,value,unit\nfilm_thickness,30\n", "2 fields but the header has 3"),
        ("quantity,value\nfilm_thickness,30\n", "required column 'unit' is missing"),
        ("quantity,value,unit,pressure\nfilm_thickness,30,um,4 psi\n", "unknown column 'pressure'"),
        ("quantity,value,unit,comparison\nfilm_thickness,30,um,roughly\n", "unknown comparison 'roughly'"),
        ("quantity,value,unit,applied_pressure\nfilm_thickness,30,um,4 m\n", "applied_pressure"),
        ("quantity,value,unit,comparison\nfluid_load_fraction,50,%,range\n", "needs the half-width"),
        ("# only comments\n", "no header row"),
        ("quantity,value,unit\n", "no data rows"),
    ],
)
def test_malformed_files_are_errors_naming_the_problem(tmp_path, body, needle):
    p = _write(tmp_path, body)
    with pytest.raises(DataError, match=re_escape(needle)):
        load_datasets(p)
    res = CliRunner().invoke(main, ["validate", str(p), "--grid", "coarse", "--out", str(tmp_path / "o")])
    assert res.exit_code == 2
    assert needle in res.output and "mine.csv" in res.output


def re_escape(s):
    import re

    return re.escape(s)


def test_missing_file_is_an_error(tmp_path):
    res = CliRunner().invoke(main, ["validate", str(tmp_path / "nope.csv")])
    assert res.exit_code == 2 and "does not exist" in res.output


def test_scale_fit_and_leave_one_out():
    m = np.array([1.0, 2.0, 3.0])
    y = 2.0 * m
    assert fit_scale(m, y) == pytest.approx(2.0)
    assert np.allclose(_loo(m, y, np.ones(3)), 0.0)
    err_mean = _loo(None, y, np.ones(3))
    assert err_mean == pytest.approx([3.0, 0.0, -3.0])  # mean of the other two minus the point


def test_every_quantity_has_a_unit_and_an_extractor():
    r = cmpsim.solve(grid="coarse", relative=False)
    for q, (unit, disp, desc, fn) in QUANTITIES.items():
        v = fn(r)
        assert np.isfinite(v), q
    assert QUANTITIES["friction_coefficient"][3](r) == pytest.approx(r.shear_stress_mean / r.config.applied_pressure)
