"""The Python API: import hygiene, Config round trip, Result contents and exports."""

import json
import math
import subprocess
import sys

import numpy as np
import pytest

import cmpsim


def test_import_cmpsim_loads_no_plotting_dask_or_xarray_and_writes_nothing(tmp_path):
    code = (
        "import sys, os; before = set(os.listdir('.')); import cmpsim; "
        "heavy = [m for m in ('matplotlib', 'matplotlib.pyplot', 'dask', 'distributed', 'xarray', 'pint', 'scipy') if m in sys.modules]; "
        "print(heavy); print(set(os.listdir('.')) - before)"
    )
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, cwd=tmp_path, check=True).stdout
    assert out.splitlines() == ["[]", "set()"]


def test_solve_returns_every_json_scalar_as_si_attribute():
    r = cmpsim.solve(grid="coarse")
    data = json.loads(r.to_json())
    scalars = {**data["values"], **data["solver"]}
    for key, value in scalars.items():
        assert getattr(r, key) == value or (value is None and not math.isfinite(getattr(r, key)))
    assert scalars == r.scalars


def test_solve_accepts_strings_quantities_and_si_floats_alike():
    import pint

    ureg = pint.UnitRegistry()
    a = cmpsim.solve(grid="coarse", applied_pressure="3 psi", relative=False)
    b = cmpsim.solve(grid="coarse", applied_pressure=3 * ureg.psi, relative=False)
    c = cmpsim.solve(grid="coarse", applied_pressure=3 * 6894.757293168361, relative=False)
    assert a.film_thickness_center == b.film_thickness_center == pytest.approx(c.film_thickness_center, rel=1e-12)


def test_api_and_cli_share_error_messages():
    from click.testing import CliRunner

    from cmpsim.cli import main

    with pytest.raises(ValueError) as exc:
        cmpsim.Config.default().replace(particle_diameter="-5 nm")
    res = CliRunner().invoke(main, ["run", "--set", "particle_diameter=-5nm"])
    assert str(exc.value) in res.stderr


def test_fields_are_on_the_wafer_with_units_and_nan_outside():
    r = cmpsim.solve(grid="coarse")
    ds = r.fields
    X, Y = np.meshgrid(ds.x.values, ds.y.values)
    outside = X**2 + Y**2 > (0.5 * r.config.wafer_diameter) ** 2 * (1 + 1e-9)
    for name in ("film_thickness", "slurry_pressure", "contact_pressure", "removal_rate",
                 "contact_area_ratio_elastic", "contact_area_ratio_elastoplastic", "contact_area_ratio_plastic"):
        v = ds[name].values
        assert np.all(np.isnan(v[outside])) and np.all(np.isfinite(v[~outside])), name
        assert "units" in ds[name].attrs
    assert ds.x.attrs["units"] == "m"
    # the map reproduces the analytic centre film thickness and the wafer-mean contact ratios
    n = len(ds.x) // 2
    assert ds.film_thickness.values[n, n] == pytest.approx(r.film_thickness_center, rel=1e-9)
    for kind in ("elastic", "elastoplastic"):  # pixel mean over the disk vs the area integral on the polar grid
        assert np.nanmean(ds[f"contact_area_ratio_{kind}"].values) == pytest.approx(r.scalars[f"contact_area_ratio_{kind}"], rel=1e-2), kind


def test_to_netcdf_round_trips_fields_and_scalars(tmp_path):
    import xarray as xr

    r = cmpsim.solve(grid="coarse")
    path = r.to_netcdf(tmp_path / "r.nc")
    ds = xr.open_dataset(path)
    np.testing.assert_allclose(ds.film_thickness.values, r.fields.film_thickness.values)
    assert ds["attack_angle"].item() == r.attack_angle and ds["attack_angle"].attrs["units"] == "rad"
    assert cmpsim.Config.from_mapping(__import__("tomllib").loads(ds.attrs["config_toml"])) == r.config
    ds.close()


def test_plot_returns_a_matplotlib_figure():
    import matplotlib

    matplotlib.use("Agg")
    from matplotlib.figure import Figure

    fig = cmpsim.solve(grid="coarse").plot()
    assert isinstance(fig, Figure) and len(fig.axes) >= 4


def test_provenance_names_model_version_and_every_parameter_with_its_source():
    r = cmpsim.solve(grid="coarse", model="elastic")
    prov = r.provenance
    assert prov["model"] == "elastic" and prov["version"] == cmpsim.__version__
    assert set(prov["parameters"]) == set(cmpsim.Config.default().to_dict())
    assert all(p["source"] for p in prov["parameters"].values())


def test_summary_lists_every_scalar_with_its_display_unit():
    from cmpsim.results.result import SCALARS

    r = cmpsim.solve(grid="coarse")
    # plain text: "name   value  unit" on one line, the meaning wrapped on the lines below the name
    rows = [ln.split() for ln in r.summary().splitlines()]
    for key in r.scalars:
        (row,) = [c for c in rows if c and c[0] == key]
        name, value, unit = row
        assert value and unit == (SCALARS[key][2] or "-"), key  # "-": a count or a flag, no unit


def test_field_maps_keep_the_solver_identities_up_to_the_rim():
    """total = slurry + contact and slurry = 0 on the rim, in the exported maps (a review found the
    rim values extrapolated a whole ring too far)."""
    r = cmpsim.solve(grid="coarse")
    ds = r.fields
    tot, slurry, contact = ds.total_pressure.values, ds.slurry_pressure.values, ds.contact_pressure.values
    ok = np.isfinite(tot)
    assert np.max(np.abs(tot[ok] - slurry[ok] - contact[ok])) < 1e-9 * np.nanmax(np.abs(tot))
    X, Y = np.meshgrid(ds.x.values, ds.y.values)
    rim = ok & (np.hypot(X, Y) > 0.5 * r.config.wafer_diameter * (1 - 1e-9))
    assert rim.any() and np.max(np.abs(slurry[rim])) < 1e-9 * np.nanmax(np.abs(slurry))
