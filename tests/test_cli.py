"""The command line: `cmpsim run` on defaults, JSON contract, errors, outputs."""

import json
import subprocess
import sys

import pytest
from click.testing import CliRunner

from cmpsim.cli import main

REQUIRED_VALUES = {
    "film_thickness_center", "attack_angle", "contact_area_ratio_elastic", "contact_area_ratio_elastoplastic",
    "contact_area_ratio_plastic", "fluid_load_fraction", "removal_rate_mean", "within_wafer_nonuniformity",
}


def test_run_json_prints_exactly_one_object_with_the_contract_keys():
    res = CliRunner().invoke(main, ["run", "--json", "--set", "grid=coarse"])
    assert res.exit_code == 0, res.output
    data = json.loads(res.stdout)
    assert set(data) == {"schema", "cmpsim_version", "inputs", "values", "units", "solver", "profiles"}
    assert REQUIRED_VALUES <= set(data["values"]) and REQUIRED_VALUES <= set(data["units"])
    assert data["solver"]["converged"] is True and abs(data["solver"]["load_residual"]) < 1e-6


def test_run_json_equals_python_api():
    import cmpsim

    res = CliRunner().invoke(main, ["run", "--json", "--set", "applied_pressure=3psi", "--set", "grid=coarse"])
    api = cmpsim.solve(applied_pressure="3 psi", grid="coarse")
    assert json.loads(res.stdout) == json.loads(api.to_json())


def test_run_relative_asks_for_the_relative_removal_rate():
    """Issue 23: the default model gives removal_rate_relative (and solves its reference case) on request only."""
    plain = json.loads(CliRunner().invoke(main, ["run", "--json", "--set", "grid=coarse"]).stdout)
    asked = json.loads(CliRunner().invoke(main, ["run", "--json", "--relative", "--set", "grid=coarse"]).stdout)
    assert "removal_rate_relative" not in plain["values"] and asked["values"]["removal_rate_relative"] > 0
    assert asked["units"]["removal_rate_relative"] == "1"
    paper = json.loads(CliRunner().invoke(main, ["run", "--json", "--no-relative", "--preset", "paper", "--set", "grid=coarse"]).stdout)
    assert "removal_rate_relative" not in paper["values"]


def test_run_table_gives_every_output_its_unit_in_the_unit_column():
    import re

    import cmpsim

    res = CliRunner(env={"COLUMNS": "250"}).invoke(main, ["run", "--set", "grid=coarse"])
    assert res.exit_code == 0, res.output

    def cells(line):
        return [c.strip() for c in re.split(r"[│┃]", line)[1:-1]]

    lines = res.output.splitlines()
    column = cells(next(ln for ln in lines if ln.startswith("┃")))
    assert "unit" in column, column
    rows = {c[0]: c for c in map(cells, lines) if c and c[0]}
    expected = cmpsim.solve(grid="coarse").summary_rows()
    for name, _, unit, _ in expected:
        assert rows[name][column.index("unit")] == unit, name
    assert {"um", "nm/min", "urad", "%", "kPa"} <= {unit for _, _, unit, _ in expected}


@pytest.mark.parametrize(
    "args,message",
    [
        (["--set", "applied_pressure=-4psi"], "applied_pressure"),
        (["--set", "applied_pressure=0psi"], "valid range"),
        (["--set", "rotation_speed=60m"], "wrong dimension"),
        (["--set", "bogus=1"], "unknown parameter 'bogus'"),
        (["--set", "applied_pressure"], "NAME=VALUE"),
    ],
)
def test_bad_input_exits_nonzero_naming_the_parameter_and_writes_nothing(tmp_path, args, message):
    out = tmp_path / "out"
    res = CliRunner().invoke(main, ["run", *args, "--out", str(out)])
    assert res.exit_code == 2
    assert message in res.stderr
    assert not out.exists()


def test_malformed_toml_exits_nonzero(tmp_path):
    bad = tmp_path / "bad.toml"
    bad.write_text("[process\napplied_pressure = 1")
    res = CliRunner().invoke(main, ["run", str(bad)])
    assert res.exit_code == 2 and "not valid TOML" in res.stderr


def test_out_writes_netcdf_with_units_and_png(tmp_path):
    import xarray as xr

    res = CliRunner().invoke(main, ["run", "--set", "grid=coarse", "--out", str(tmp_path)])
    assert res.exit_code == 0, res.output
    ds = xr.open_dataset(tmp_path / "fields.nc")
    assert ds["film_thickness"].attrs["units"] == "m" and ds["x"].attrs["units"] == "m"
    assert ds["converged"].item() == 1 and ds.attrs["Conventions"] == "CF-1.11"
    assert (tmp_path / "maps.png").stat().st_size > 10_000
    assert json.loads((tmp_path / "result.json").read_text())["solver"]["converged"] is True
    assert (tmp_path / "profile.png").stat().st_size > 10_000
    ds.close()


def test_console_script_runs_on_defaults():
    proc = subprocess.run([sys.executable, "-m", "cmpsim.cli", "run", "--json"], capture_output=True, text=True, check=False)
    assert proc.returncode == 0, proc.stderr
    assert json.loads(proc.stdout)["solver"]["converged"] is True


def test_version_is_the_one_written_in_version_py():
    from cmpsim._version import __version__

    res = CliRunner().invoke(main, ["--version"])
    assert res.exit_code == 0 and res.output == f"cmpsim, version {__version__}\n"



def test_python_m_cmpsim_is_the_command_line():
    """``python -m cmpsim`` runs the same command line (a user without the script on PATH), under the same name."""
    import subprocess
    import sys

    from cmpsim._version import __version__

    proc = subprocess.run([sys.executable, "-m", "cmpsim", "--version"], capture_output=True, text=True, timeout=120)
    assert proc.returncode == 0 and proc.stdout == f"cmpsim, version {__version__}\n"
    bad = subprocess.run([sys.executable, "-m", "cmpsim", "die", "--window", "0um", "lines"], capture_output=True, text=True, timeout=120)
    assert bad.returncode == 2 and "Traceback" not in bad.stderr


#: The one line the command line prints for the warning of a reference case that removes nothing
#: (a rigid pad with the measured 5 um summits hydroplanes there).
NAN_WARNING = (
    "cmpsim: warning: removal_rate_relative is undefined (NaN, null in JSON): the reference case "
    "(LEP, 4 psi, 60 rpm, d = 100 nm, sigma = reference_roughness) removes nothing\n"
)


def test_console_script_prints_cmpsims_warning_as_one_line_without_the_source_echo():
    proc = subprocess.run(
        [sys.executable, "-m", "cmpsim.cli", "run", "--json", "--relative", "--set", "pad_compliance=rigid", "--grid", "coarse"],
        capture_output=True, text=True, check=False,
    )
    assert proc.returncode == 0, proc.stderr
    assert proc.stderr == NAN_WARNING  # not "cli.py:NNN: RuntimeWarning: ...\n  result = solve(cfg, ...)"
    assert json.loads(proc.stdout)["values"]["removal_rate_relative"] is None


def test_the_warning_display_is_the_commands_own_and_restored_after_it():
    import warnings

    import cmpsim.cli

    before = warnings.showwarning
    res = CliRunner().invoke(main, ["run", "--json", "--relative", "--set", "pad_compliance=rigid", "--grid", "coarse"])
    assert res.exit_code == 0, res.output
    assert res.stderr == NAN_WARNING
    assert warnings.showwarning is before  # importing or running the CLI leaves the library's warnings alone
    # another package's warning keeps Python's format (its source says where it comes from)
    seen = []
    cmpsim.cli.show_warning("not ours", UserWarning, "/elsewhere/pkg/mod.py", 7, other=lambda *a: seen.append(a))
    assert seen == [("not ours", UserWarning, "/elsewhere/pkg/mod.py", 7, None, None)]


def test_the_run_tables_warnings_are_one_line_each_on_stderr():
    """The hydrodynamic variant of the paper's model equilibrates outside the flow factors' validity
    (docs/limitations.md): the table goes to stdout, the warning to stderr in the one format."""
    res = CliRunner().invoke(main, ["run", "--preset", "paper", "--set", "model=hydrodynamic", "--grid", "coarse"])
    assert res.exit_code == 0, res.output
    lines = res.stderr.splitlines()
    assert len(lines) == 1 and lines[0].startswith("cmpsim: warning: the flow-factor tensor was regularised on "), res.stderr
    assert "warning" not in res.stdout.replace("regularised", "")


def test_every_solving_command_takes_its_inputs_the_same_way(tmp_path, monkeypatch):
    """--config, --preset, --set and --grid on run, reproduce, validate and calibrate; `run FILE` is `run --config FILE`."""
    import cmpsim

    cfg_file = tmp_path / "in.toml"
    cmpsim.Config.default().replace(applied_pressure="3 psi").to_toml(cfg_file)
    positional = CliRunner().invoke(main, ["run", str(cfg_file), "--json", "--grid", "coarse"])
    option = CliRunner().invoke(main, ["run", "--config", str(cfg_file), "--json", "--set", "grid=coarse"])
    assert positional.exit_code == option.exit_code == 0, positional.output + option.output
    assert json.loads(positional.stdout) == json.loads(option.stdout)
    both = CliRunner().invoke(main, ["run", str(cfg_file), "--config", str(cfg_file)])
    assert both.exit_code == 2 and "give the configuration once" in both.stderr

    seen = {}

    def capture(name):
        def fake(*args, config=None, **kw):
            seen[name] = config
            raise ValueError("stop here")

        return fake

    monkeypatch.setattr("cmpsim.reproduction.reproduce", capture("reproduce"))
    monkeypatch.setattr("cmpsim.validation.validate", capture("validate"))
    monkeypatch.setattr("cmpsim.calibration.calibrate", capture("calibrate"))
    inputs = ["--config", str(cfg_file), "--preset", "paper", "--set", "particle_diameter=150nm", "--grid", "12x32"]
    data = tmp_path / "rates.csv"  # calibrate reads its data before it fits (rows of every scale: docs/calibrate.md)
    data.write_text("dataset,quantity,value,unit,applied_pressure\nr,removal_rate_mean,100,nm/min,3 psi\nr,removal_rate_mean,200,nm/min,6 psi\n")
    for command in (["reproduce", "--out", str(tmp_path / "r")], ["validate", "--out", str(tmp_path / "v")], ["calibrate", str(data), "--free", "pad_modulus"]):
        res = CliRunner().invoke(main, command + inputs)
        assert res.exit_code == 2 and "stop here" in res.stderr, res.output
        cfg = seen[command[0]]
        assert (cfg.grid_shape, cfg.particle_diameter) == ((12, 32), pytest.approx(150e-9)), command[0]
        assert cfg.applied_pressure == pytest.approx(cmpsim.Config.default().replace(applied_pressure="3 psi").applied_pressure)
        bad = CliRunner().invoke(main, command + ["--grid", "3x3"])
        assert bad.exit_code == 2 and "grid must be" in bad.stderr, command[0]
