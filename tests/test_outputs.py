"""The output registry and what is generated from it: names, JSON (schema 2 and 1), JSON Schema,
CF NetCDF, tables at 80 columns, and the within-wafer uniformity (profiles, WIWNU, range)."""

from __future__ import annotations

import json
import math
import re
import warnings
from pathlib import Path

import numpy as np
import pytest
from click.testing import CliRunner

import cmpsim
from cmpsim.results import outputs
from cmpsim.cli import main
from cmpsim.numerics.grid import PolarGrid
from cmpsim.results.result import JSON_SCHEMA_PATH
from cmpsim.results.uniformity import ring_areas_inside, ring_edges, ring_mean, uniformity, weighted_range, weighted_std_over_mean

DATA = Path(__file__).parent / "data"
TOP_KEYS = {"schema", "cmpsim_version", "inputs", "values", "units", "solver", "profiles"}
#: The contract of issue 14.
VALUES = [
    "film_thickness_center", "film_thickness_min", "film_thickness_mean", "h0", "attack_angle", "cross_tilt",
    "fluid_load_fraction", "contact_load_fraction", "contact_area_ratio", "contact_area_ratio_elastic",
    "contact_area_ratio_elastoplastic", "contact_area_ratio_plastic", "normal_stress_mean", "shear_stress_mean",
    "removal_rate_mean", "removal_rate_relative", "ambient_pressure", "sliding_speed", "within_wafer_nonuniformity",
    "removal_rate_range",
]
SOLVER = ["converged", "iterations", "factorizations", "load_residual", "moment_residual", "flow_factor_floored_fraction"]
FIELDS = [
    "film_thickness", "slurry_pressure", "granular_pressure", "contact_pressure", "total_pressure",
    "contact_area_ratio_elastic", "contact_area_ratio_elastoplastic", "contact_area_ratio_plastic",
    "normal_stress", "shear_stress", "removal_rate", "pad_deflection", "wafer_bending",
]
OPTIONAL_FIELDS = ["fill_fraction"]
#: The paper's model (cmpsim 0.1): the 0.1 object and the base-case profile below are its results.
PAPER = cmpsim.Config.paper()
#: CF / UDUNITS-2 spellings used by cmpsim.
CF_UNITS = {"m", "Pa", "m s-1", "1", "rad"}


@pytest.fixture(scope="module")
def base():
    return cmpsim.solve(PAPER, grid="coarse")


# ------------------------------------------------------------------------------------- names
def test_registry_holds_exactly_the_contract_names_in_si_without_units_in_names():
    assert outputs.value_names() == VALUES
    assert outputs.diagnostic_names() == SOLVER + ["moment_roots_found"]
    assert outputs.field_names() == FIELDS + OPTIONAL_FIELDS
    assert outputs.profile_names() == ["removal_rate_profile", "film_thickness_profile", "wafer_bending_profile"]
    for o in outputs.OUTPUTS.values():
        assert o.unit in CF_UNITS, o.name
        assert not re.search(r"_(m|rad|pa|um|nm|m_s|nm_per_min|per_min|kpa|psi)$", o.name), o.name
        assert o.long_name and o.display_unit is not None


def test_the_output_table_of_the_model_document_is_the_registry():
    doc = (Path(__file__).parents[1] / "docs" / "model.md").read_text(encoding="utf-8")
    assert outputs.output_table_markdown() in doc, "regenerate section 16 (Outputs) from cmpsim.results.outputs.output_table_markdown()"


def test_display_factors_are_the_unit_conversions():
    import pint

    ureg = pint.UnitRegistry()
    spell = {"m s-1": "m/s", "1": "dimensionless", "%": "percent", "": "dimensionless", "-": "dimensionless"}
    for o in outputs.OUTPUTS.values():
        if o.dtype != "float":
            continue
        want = ureg.Quantity(1.0, spell.get(o.unit, o.unit)).to(spell.get(o.display_unit, o.display_unit)).magnitude
        assert o.display_factor == pytest.approx(want, rel=1e-12), o.name


def test_result_scalars_are_the_registry_scalars(base):
    assert list(base.scalars) == VALUES + SOLVER
    d = base.to_dict()
    assert list(d["values"]) == VALUES and list(d["solver"]) == SOLVER
    roots = cmpsim.solve(PAPER, grid="coarse", relative=False, check_roots=True)
    assert "moment_roots_found" in roots.to_dict()["solver"] and "removal_rate_relative" not in roots.to_dict()["values"]


def test_derived_scalars_follow_from_the_fields(base):
    s, g = base.scalars, base.grid
    area = math.pi * g.radius**2
    assert s["contact_area_ratio"] == s["contact_area_ratio_elastic"] + s["contact_area_ratio_elastoplastic"] + s["contact_area_ratio_plastic"]
    assert s["film_thickness_mean"] == pytest.approx(g.integrate(base.polar["film_thickness"]) / area, rel=1e-14)
    assert s["film_thickness_min"] <= s["film_thickness_mean"]
    # the normal stress of the removal law includes the ambient granular pressure: above the applied load
    assert s["normal_stress_mean"] > base.config.applied_pressure
    assert "ambient" in outputs.scalar("normal_stress_mean").long_name


def test_old_names_still_read_with_a_deprecation_warning(base):
    with pytest.warns(DeprecationWarning):
        assert base.film_thickness_center_m == base.film_thickness_center
    with pytest.warns(DeprecationWarning):
        assert base.removal_rate_nm_per_min == base.removal_rate_mean * 1e9 * 60.0
    with pytest.warns(DeprecationWarning):
        assert base.removal_rate == base.removal_rate_mean
    with pytest.warns(DeprecationWarning):
        assert base.scalars["mean_normal_stress_pa"] == base.normal_stress_mean
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        assert base.attack_angle == base.scalars["attack_angle"]
    with pytest.raises(AttributeError):
        base.no_such_output


# ------------------------------------------------------------------------------------- JSON
def test_to_dict_is_the_schema_2_object(base):
    d = base.to_dict()
    assert set(d) == TOP_KEYS and d["schema"] == 2 and d["cmpsim_version"] == cmpsim.__version__
    assert d["inputs"] == base.config.to_dict()
    assert set(d["units"]) == set(d["values"]) | set(d["solver"]) | {"radius", "removal_rate", "film_thickness", "wafer_bending"}
    assert d["units"]["removal_rate_mean"] == "m s-1" and d["units"]["attack_angle"] == "rad" and d["units"]["radius"] == "m"
    assert set(d["profiles"]) == {"radius", "removal_rate", "film_thickness", "wafer_bending"}
    assert len(d["profiles"]["radius"]) == base.grid.n_r == len(d["profiles"]["removal_rate"])
    assert json.loads(base.to_json()) == json.loads(json.dumps(d))


def _check(instance, schema, where="$"):
    """A hand check of the JSON Schema keywords cmpsim's schema uses (no jsonschema dependency)."""
    types = {"object": dict, "array": list, "string": str, "boolean": bool, "null": type(None)}
    if "const" in schema:
        assert instance == schema["const"], where
    if "type" in schema:
        allowed = schema["type"] if isinstance(schema["type"], list) else [schema["type"]]
        ok = False
        for t in allowed:
            if t == "number":
                ok |= isinstance(instance, (int, float)) and not isinstance(instance, bool)
            elif t == "integer":
                ok |= isinstance(instance, int) and not isinstance(instance, bool)
            else:
                ok |= isinstance(instance, types[t])
        assert ok, f"{where}: {instance!r} is not {allowed}"
    if isinstance(instance, dict):
        for k in schema.get("required", []):
            assert k in instance, f"{where}: missing {k}"
        props = schema.get("properties", {})
        if schema.get("additionalProperties") is False:
            assert set(instance) <= set(props), f"{where}: unexpected {set(instance) - set(props)}"
        for k, v in instance.items():
            if k in props:
                _check(v, props[k], f"{where}.{k}")
    if isinstance(instance, list) and "items" in schema:
        for i, v in enumerate(instance):
            _check(v, schema["items"], f"{where}[{i}]")


def test_the_shipped_json_schema_is_generated_from_the_registry_and_the_output_validates(base):
    shipped = JSON_SCHEMA_PATH.read_text(encoding="utf-8")
    assert shipped == outputs.json_schema_text(), "regenerate with `python -m cmpsim.results.outputs`"
    schema = json.loads(shipped)
    assert set(schema["required"]) == TOP_KEYS and schema["additionalProperties"] is False
    assert set(schema["properties"]["values"]["properties"]) == set(VALUES)
    assert set(schema["properties"]["solver"]["properties"]) == set(SOLVER) | {"moment_roots_found"}
    _check(json.loads(base.to_json()), schema)
    _check(json.loads(cmpsim.solve(grid="coarse", relative=False, check_roots=True).to_json()), schema)  # the default model too
    bad = json.loads(base.to_json())
    bad["values"]["film_thickness_center_m"] = 1.0
    with pytest.raises(AssertionError):
        _check(bad, schema)


def test_schema_1_is_the_0_1_object_unchanged():
    # cmpsim 0.1 printed the reference file on its defaults, i.e. the paper's model: the paper
    # preset must give the very same object (names, key order, types and numbers). The solver's
    # cost (iterations, LU factorisations) and its round-off residuals are not results: the
    # speed work of issue 15 solves the same discrete problem with fewer of them.
    ref = json.loads((DATA / "schema1_coarse_v0_1.json").read_text())
    paper = cmpsim.Config.paper().replace(grid="coarse")
    for got, want in ((cmpsim.solve(paper).to_schema1(), ref["plain"]), (cmpsim.solve(paper, check_roots=True).to_schema1(), ref["check_roots"])):
        assert list(got) == list(want)
        for k, v in want.items():
            assert type(got[k]) is type(v), k
            if k not in ("load_residual", "moment_residual", "iterations", "factorizations"):
                assert got[k] == pytest.approx(v, rel=1e-8, abs=1e-8 * abs(want["attack_angle_rad"]) if k == "cross_tilt_rad" else 0.0), k


def test_cli_schema_1_prints_the_0_1_object_and_a_deprecation_on_stderr(base):
    res = CliRunner().invoke(main, ["run", "--preset", "paper", "--json", "--schema", "1", "--set", "grid=coarse"])
    assert res.exit_code == 0, res.output
    assert json.loads(res.stdout) == json.loads(base.to_json(schema=1))
    assert "deprecated" in res.stderr
    res2 = CliRunner().invoke(main, ["run", "--json", "--set", "grid=coarse"])
    assert json.loads(res2.stdout)["schema"] == 2 and "deprecated" not in res2.stderr


# ------------------------------------------------------------------------------------- NetCDF
def test_netcdf_is_cf_with_scalars_as_0d_variables(base, tmp_path):
    import xarray as xr

    path = base.to_netcdf(tmp_path / "r.nc")
    with xr.open_dataset(path, mask_and_scale=False) as ds:
        assert ds.attrs["Conventions"] == "CF-1.11"
        for key in ("source", "history", "references", "title"):
            assert ds.attrs[key]
        for name in VALUES + SOLVER:
            o = outputs.scalar(name)
            v = ds[o.netcdf_name]
            assert v.ndim == 0 and v.attrs["long_name"] == o.long_name, name
            if o.dtype == "bool":
                assert list(v.attrs["flag_values"]) == [0, 1] and v.attrs["flag_meanings"] == "not_converged converged"
                assert int(v) == int(base.scalars[name])
            else:
                assert v.attrs["units"] in CF_UNITS and float(v) == pytest.approx(base.scalars[name], rel=1e-15), name
        for name in FIELDS:
            assert ds[name].dims == ("y", "x") and ds[name].attrs["units"] in CF_UNITS
        # a wafer mean whose map has the same name is NAME_mean, and says so
        assert ds["contact_area_ratio_elastic_mean"].attrs["cmpsim_name"] == "contact_area_ratio_elastic"
        assert ds["contact_area_ratio_elastic_mean"].attrs["cell_methods"] == "area: mean"
        assert ds["radius"].attrs["units"] == "m" and ds["radius"].attrs["bounds"] == "radius_bounds"
        np.testing.assert_allclose(ds["removal_rate_profile"].values, base.removal_rate_profile, rtol=1e-15)
        np.testing.assert_allclose(ds["radius_bounds"].values[:, 1] - ds["radius_bounds"].values[:, 0], base.grid.dr)
        assert not any(k in ds.attrs for k in ("attack_angle", "attack_angle_rad"))


# ------------------------------------------------------------------------------------- tables
def _lines_ok(text: str, names, width: int):
    lines = text.splitlines()
    assert max(len(ln) for ln in lines) <= width
    for n in names:
        assert any(re.search(rf"(^|[\s│|]){re.escape(n)}([\s│|]|$)", ln) for ln in lines), f"{n} cut or missing"


@pytest.mark.parametrize("width", [80, 132])
def test_run_table_is_legible_without_cutting_names(base, width):
    _lines_ok(base.summary(width), VALUES + SOLVER, width)
    assert "%" in base.summary(width) and "nm/min" in base.summary(width)


@pytest.mark.parametrize("width", [80, 132])
def test_params_table_is_legible_with_ranges_in_display_units(width):
    from cmpsim.inputs.config import PARAMETERS

    res = CliRunner().invoke(main, ["params"], env={"COLUMNS": str(width)})
    assert res.exit_code == 0
    _lines_ok(res.output, list(PARAMETERS), width)
    assert "(0, inf) psi" in res.output and "(0, 2000] nm" in res.output


# ------------------------------------------------------------------------------------- uniformity kernels
def test_ring_mean_of_a_manufactured_map_is_its_exact_rotation_average():
    g = PolarGrid(0.05, 12, 32)
    x, y = g.centres
    r = np.hypot(x, y)
    a, b, c, d = 2.0, 3.0e2, 40.0, 7.0
    # a + b r^2 + c r cos(theta) + d r^2 sin(2 theta): only a + b r^2 survives the rotation
    f = a + b * r**2 + c * x + d * 2.0 * x * y
    np.testing.assert_allclose(ring_mean(f), a + b * g.r[:, 0] ** 2, rtol=1e-14)
    # the profile, piecewise constant on the rings, integrates to the map's integral
    areas = ring_areas_inside(ring_edges(g.radius, g.n_r), g.radius)
    np.testing.assert_allclose(areas, g.area.sum(axis=1), rtol=1e-13)
    assert np.sum(ring_mean(f) * areas) == pytest.approx(g.integrate(f), rel=1e-14)


def test_wiwnu_and_range_of_a_known_profile_with_edge_exclusion():
    radius, n = 0.04, 8  # rings 5 mm wide
    p = np.arange(1.0, n + 1.0)  # 1, 2, ..., 8
    edges = ring_edges(radius, n)
    # a 7.5 mm exclusion keeps rings 0-5 and half (by radius) of ring 6
    w = np.pi * (np.minimum(edges[1:], 0.0325) ** 2 - np.minimum(edges[:-1], 0.0325) ** 2)
    mean = np.sum(w * p) / w.sum()
    want = math.sqrt(np.sum(w * (p - mean) ** 2) / w.sum()) / mean
    wiwnu, rng = uniformity(p, radius, 0.0075)
    assert wiwnu == pytest.approx(want, rel=1e-14) and rng == 6.0
    assert uniformity(np.full(n, 3.3), radius, 0.003) == (pytest.approx(0.0, abs=1e-15), 0.0)
    assert uniformity(p, radius, 0.0)[1] == 7.0
    for bad in (-1e-3, radius, 0.05):
        with pytest.raises(ValueError, match="edge_exclusion"):
            uniformity(p, radius, bad)
    assert math.isnan(weighted_std_over_mean([1.0, -1.0], [1.0, 1.0]))
    assert weighted_range([5.0, 1.0, 9.0], [1.0, 1.0, 0.0]) == 4.0


# ------------------------------------------------------------------------------------- uniformity of the model
def test_profiles_integrate_to_the_wafer_means(base):
    g = base.grid
    areas = ring_areas_inside(ring_edges(g.radius, g.n_r), g.radius)
    area = math.pi * g.radius**2
    assert np.sum(base.removal_rate_profile * areas) / area == pytest.approx(base.removal_rate_mean, rel=1e-13)
    assert np.sum(base.film_thickness_profile * areas) / area == pytest.approx(base.film_thickness_mean, rel=1e-13)
    np.testing.assert_allclose(base.radius, (np.arange(g.n_r) + 0.5) * g.dr)
    # with no edge exclusion the WIWNU is the area-weighted spread of the whole profile
    full = cmpsim.solve(PAPER, grid="coarse", edge_exclusion=0.0, relative=False)
    p = full.removal_rate_profile
    std = math.sqrt(np.sum(areas * (p - full.removal_rate_mean) ** 2) / area)
    assert full.within_wafer_nonuniformity == pytest.approx(std / full.removal_rate_mean, rel=1e-10)
    assert full.removal_rate_range == pytest.approx(np.ptp(p), rel=1e-14)


def test_a_flat_wafer_in_uniform_sliding_polishes_uniformly():
    """Uniform speed, flat wafer: the film is uniform, so the Couette flux is divergence free,
    the slurry gauge pressure vanishes and the pad carries the load uniformly: WIWNU = 0."""
    r = cmpsim.solve(PAPER, grid="coarse", kinematics="sliding", dome_height=0.0, relative=False)
    assert r.converged and r.attack_angle == pytest.approx(0.0, abs=1e-15)
    assert np.ptp(r.polar["contact_pressure"]) <= 1e-12 * r.config.applied_pressure
    assert r.within_wafer_nonuniformity < 1e-13
    assert r.removal_rate_range < 1e-13 * r.removal_rate_mean


def test_the_base_case_removal_profile_follows_the_dome(base):
    # the convex wafer presses hardest at its centre: the removal falls towards the edge
    p = base.removal_rate_profile
    assert p[0] > p[-1] and base.within_wafer_nonuniformity > 0.01
    assert base.film_thickness_profile[0] < base.film_thickness_profile[-1]


def test_edge_exclusion_is_an_input_refused_when_it_leaves_no_wafer():
    c = cmpsim.Config.default()
    assert c.edge_exclusion == 3e-3 and c.wafer.edge_exclusion == 3e-3
    assert c.replace(edge_exclusion="5 mm").edge_exclusion == pytest.approx(5e-3)
    with pytest.raises(ValueError, match="edge_exclusion.*leaves no wafer"):
        c.replace(edge_exclusion="40 mm")
    with pytest.raises(ValueError, match="edge_exclusion"):
        c.replace(wafer_diameter="5 mm")
    with pytest.raises(ValueError, match="edge_exclusion"):
        c.replace(edge_exclusion="-1 mm")
    res = CliRunner().invoke(main, ["run", "--set", "edge_exclusion=38.1mm"])
    assert res.exit_code == 2 and "edge_exclusion" in res.stderr


def test_run_out_writes_the_profile_plot_beside_the_maps(tmp_path):
    res = CliRunner().invoke(main, ["run", "--set", "grid=coarse", "--out", str(tmp_path)])
    assert res.exit_code == 0, res.output
    assert (tmp_path / "profile.png").stat().st_size > 10_000 and (tmp_path / "maps.png").exists()
    assert json.loads((tmp_path / "result.json").read_text())["schema"] == 2
