"""`cmpsim sweep` / `cmpsim.sweep`: file validation, equality with `cmpsim run`, dask clusters,
kill + resume, failures recorded, warm start, output files."""

from __future__ import annotations

import importlib.resources
import json
import os
import signal
import subprocess
import sys
import time
import tomllib
from pathlib import Path

import numpy as np
import pytest
import xarray as xr
from click.testing import CliRunner

import cmpsim
from cmpsim.cli import main
from cmpsim.inputs.config import PARAMETERS, Config, parse_value
from cmpsim.results import outputs
from cmpsim.results.result import SCALARS
from cmpsim.sweeps import SweepError, SweepSpec, sweep

CLI = [sys.executable, "-m", "cmpsim.cli"]
#: The command line with a gate on which sweep points may finish (tests/sweep_gate.py).
GATED = [sys.executable, str(Path(__file__).with_name("sweep_gate.py"))]

SMALL = """
[base]
grid = "coarse"

[axes]
applied_pressure = ["3psi", "5psi"]
rotation_speed = {start = "40rpm", stop = "80rpm", num = 2}
"""


def write(tmp_path: Path, text: str, name: str = "sweep.toml") -> Path:
    p = tmp_path / name
    p.write_text(text)
    return p


def open_nc(path) -> xr.Dataset:
    with xr.open_dataset(path, engine="scipy") as ds:
        return ds.load()


def point_settings(ds, status="ok"):
    """[(index dict, {setting: coordinate value})] of the points with the given status."""
    out = []
    for idx in zip(*np.nonzero(ds["status"].values == status)):
        sel = dict(zip(ds["status"].dims, idx))
        out.append((sel, {d: ds[d].values[i].item() for d, i in sel.items()}))
    return out


def run_json(settings: dict, extra=("grid=coarse",)) -> dict:
    args = ["run", "--json"]
    for a in extra:
        args += ["--set", a]
    for k, v in settings.items():
        args += ["--set", f"{k}={v}" if isinstance(v, str) else f"{k}={v!r} {PARAMETERS[k].unit}"]
    res = CliRunner().invoke(main, args)
    assert res.exit_code == 0, res.output
    data = json.loads(res.stdout)
    return {**data["values"], **data["solver"]}  # the scalars, as the sweep dataset holds them


# ---------------------------------------------------------------------------- equality with cmpsim run


def test_sweep_through_cli_and_api_equals_looping_cmpsim_run(tmp_path):
    path = write(tmp_path, SMALL)
    cold = sweep(path, workers=0, warm_start=False, progress=False)
    res = CliRunner().invoke(main, ["sweep", str(path), "--out", str(tmp_path / "cli.nc"), "--no-progress"])
    assert res.exit_code == 0, res.output
    cli = open_nc(tmp_path / "cli.nc")
    assert cold.sizes == cli.sizes == {"applied_pressure": 2, "rotation_speed": 2}
    np.testing.assert_array_equal(cold["applied_pressure"], [parse_value("applied_pressure", "3psi"), parse_value("applied_pressure", "5psi")])
    assert cli["rotation_speed"].attrs["units"] == "rad/s"
    pts = point_settings(cold)
    assert len(pts) == 4
    for sel, settings in pts:
        ref = run_json(settings)
        assert set(ref) <= set(cold.data_vars)
        for k, v in ref.items():
            # cold start: the very same computation as `cmpsim run`, so equal to the last bit
            assert cold[k].isel(sel).item() == v, k
            if k in ("iterations", "factorizations", "load_residual", "moment_residual"):
                continue  # depend on the start of Newton
            # the CLI sweep warm-starts along rotation_speed: equal to the solver tolerance
            got = cli[k].isel(sel).item()
            if isinstance(v, bool):
                assert bool(got) is v
            else:
                assert got == pytest.approx(v, rel=1e-6, abs=1e-12), k
        assert cold["status"].isel(sel).item() == cli["status"].isel(sel).item() == "ok"
        assert cold["error"].isel(sel).item() == ""
    assert (cli["start"].values == "warm").sum() == 2  # the second point of each chain


@pytest.mark.slow
def test_two_worker_local_cluster_equals_serial_run(tmp_path):
    text = SMALL.replace('num = 2', 'num = 3') + '\n[[points]]\napplied_pressure = "1000psi"\n'
    spec = SweepSpec.from_mapping(tomllib.loads(text))
    serial = sweep(spec, workers=0, progress=False)
    parallel = sweep(spec, workers=2, progress=False)
    xr.testing.assert_identical(parallel, serial)
    assert (serial["status"].values == "ok").sum() == 6
    assert (serial["start"].values == "warm").sum() == 4


@pytest.mark.slow
def test_dask_scheduler_address_runs_the_same_sweep(tmp_path):
    from distributed import LocalCluster

    spec = SweepSpec.from_mapping(tomllib.loads(SMALL))
    with LocalCluster(n_workers=1, threads_per_worker=1, processes=False, dashboard_address=None) as cluster:
        remote = sweep(spec, scheduler=cluster.scheduler_address, progress=False)
    xr.testing.assert_identical(remote, sweep(spec, workers=0, progress=False))


@pytest.mark.slow
def test_a_broken_dask_task_is_reported_and_its_chain_goes_on_from_the_cold_start(monkeypatch):
    # a task that raises on the worker (not a failed solve: those come back as records) is
    # reported as not computed; the next point of its chain is still solved, from its cold start
    from distributed import LocalCluster

    import cmpsim.sweeps as sweeps_module

    spec = SweepSpec.from_mapping(tomllib.loads(SMALL.replace("num = 2", "num = 3")))
    real = sweeps_module._run_point

    def broken_first_point(task, prev=None, prev2=None):
        if task["index"] == [0, 0]:
            raise RuntimeError("worker lost")
        return real(task, prev, prev2)

    monkeypatch.setattr(sweeps_module, "_run_point", broken_first_point)
    with LocalCluster(n_workers=2, threads_per_worker=1, processes=False, dashboard_address=None) as cluster:
        ds = sweep(spec, scheduler=cluster.scheduler_address, progress=False)
    status, start = ds["status"].values, ds["start"].values
    assert status[0, 0] == "failed" and "the dask task failed (RuntimeError: worker lost)" in ds["error"].values[0, 0]
    assert (status == "ok").sum() == 5
    assert start[0, 1] == "cold" and start[0, 2] == "warm"  # the chain restarts after the broken point
    monkeypatch.setattr(sweeps_module, "_run_point", real)
    serial = sweep(spec, workers=0, progress=False)
    for name in ("film_thickness_center", "attack_angle"):
        np.testing.assert_allclose(ds[name].values[0, 1:], serial[name].values[0, 1:], rtol=1e-6)
        np.testing.assert_array_equal(ds[name].values[1], serial[name].values[1])


# ---------------------------------------------------------------------------- kill and resume


KILL = """
[base]
grid = "default"

[axes]
applied_pressure = {start = "3psi", stop = "5psi", num = 4}
rotation_speed = {start = "40rpm", stop = "80rpm", num = 6}
"""


def n_parts(parts: Path) -> int:
    try:
        return sum(1 for p in parts.iterdir() if p.suffix == ".json" and p.name != "manifest.json" and not p.name.startswith("."))
    except FileNotFoundError:
        return 0


def wait_for_parts(parts: Path, k: int, proc, timeout: float = 300.0) -> None:
    """Wait until k points are saved; the gated run can save no more, so nothing races."""
    deadline = time.monotonic() + timeout
    while n_parts(parts) < k:
        assert proc.poll() is None, f"the sweep ended before saving {k} points: {proc.communicate()}"
        assert time.monotonic() < deadline, f"no {k} saved points after {timeout} s"
        time.sleep(0.05)


@pytest.mark.slow
def test_sweep_killed_with_sigkill_resumes_to_the_uninterrupted_result(tmp_path):
    path = write(tmp_path, KILL)
    out = tmp_path / "killed.nc"
    parts = Path(str(out) + ".parts")
    # exactly two points can finish (the first two to start); the others block, so the run cannot end before the kill
    proc = subprocess.Popen(GATED + ["2", str(tmp_path / "tokens"), "sweep", str(path), "--out", str(out)], stdout=subprocess.PIPE, stderr=subprocess.PIPE, start_new_session=True)
    try:
        wait_for_parts(parts, 2, proc)
        os.killpg(proc.pid, signal.SIGKILL)  # the sweep and its dask workers, no clean-up
    finally:
        proc.wait(timeout=30)
    saved = n_parts(parts)
    assert proc.returncode == -signal.SIGKILL
    assert not out.exists(), "killed before the end: no final file"
    assert saved == 2
    assert not [p for p in tmp_path.iterdir() if p.name.startswith(".killed.nc")], "no half-written output"
    # tamper with one saved point: if resume recomputed it, the mark would disappear
    victim = next(p for p in parts.iterdir() if p.name != "manifest.json" and p.suffix == ".json")
    rec = json.loads(victim.read_text())
    rec["scalars"]["removal_rate_mean"] = -123.0
    victim.write_text(json.dumps(rec))

    res = subprocess.run(CLI + ["sweep", str(path), "--out", str(out), "--resume", "--no-progress"], capture_output=True, text=True, timeout=180)
    assert res.returncode == 0, res.stderr
    line = next(ln for ln in res.stdout.splitlines() if ln.startswith("resumed:"))
    k, n = int(line.split()[1]), int(line.split()[3])
    assert line == f"resumed: {k} of {n} points already done" and n == 24 and 0 < k < n and k >= saved
    assert not parts.exists()

    resumed = open_nc(out)
    sel = dict(zip(resumed["status"].dims, rec["index"]))
    assert resumed["removal_rate_mean"].isel(sel).item() == -123.0  # reused, not recomputed
    reference = sweep(path, out=tmp_path / "reference.nc", workers=0, progress=False)
    resumed["removal_rate_mean"][sel] = reference["removal_rate_mean"].isel(sel).item()
    xr.testing.assert_identical(resumed, open_nc(tmp_path / "reference.nc"))
    assert (resumed["status"].values == "ok").all() and resumed["status"].size == 24


#: Seconds a Ctrl-C'd sweep may take to end: the bounded close of client and cluster
#: (2 x cmpsim.sweeps.executors.INTERRUPT_CLOSE_SECONDS) and the kill, with room for a loaded machine.
CTRL_C_BOUND = 45.0


@pytest.mark.slow
def test_ctrl_c_saves_the_finished_points_and_exits_130_without_worker_tracebacks(tmp_path):
    path = write(tmp_path, KILL)
    out = tmp_path / "int.nc"
    parts = Path(str(out) + ".parts")
    # exactly one point can finish (the first to start); the others block, so the run cannot end before the Ctrl-C
    proc = subprocess.Popen(
        GATED + ["1", str(tmp_path / "tokens"), "sweep", str(path), "--out", str(out), "--no-progress"],
        stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True, start_new_session=True,
    )
    try:
        wait_for_parts(parts, 1, proc)
        os.killpg(proc.pid, signal.SIGINT)  # what Ctrl-C in a terminal does: the whole process group
        t0 = time.monotonic()
        try:
            # hard bound: the clean-up is bounded by 2 x INTERRUPT_CLOSE_SECONDS, then the workers are killed
            stdout, stderr = proc.communicate(timeout=CTRL_C_BOUND)
        except subprocess.TimeoutExpired:
            os.killpg(proc.pid, signal.SIGKILL)
            out_, err_ = proc.communicate()
            pytest.fail(f"the sweep was still running {CTRL_C_BOUND} s after Ctrl-C; stdout={out_!r} stderr={err_!r}")
        waited = time.monotonic() - t0
    finally:
        if proc.poll() is None:
            os.killpg(proc.pid, signal.SIGKILL)
            proc.wait()
    assert proc.returncode == 130, stderr
    line = next(ln for ln in stdout.splitlines() if ln.startswith("interrupted:"))
    assert f"points saved in {parts}" in line and "--resume" in line
    k = int(line.split()[1])
    assert k == 1 and n_parts(parts) == 1
    assert "Traceback" not in stderr and not out.exists()
    assert waited < CTRL_C_BOUND


def test_interrupted_serial_sweep_keeps_exactly_the_finished_points_and_resumes_to_the_same_dataset(tmp_path, monkeypatch):
    """The state logic in-process: an interrupt after three points saves three, resume ends equal."""
    import cmpsim.sweeps as sweeps_module

    real, calls = sweeps_module._run_point, []

    def interrupt_after_three(task, prev=None, prev2=None):
        if len(calls) == 3:
            raise KeyboardInterrupt
        calls.append(task["key"])
        return real(task, prev, prev2)

    path, out = write(tmp_path, SMALL), tmp_path / "s.nc"
    messages = []
    monkeypatch.setattr(sweeps_module, "_run_point", interrupt_after_three)
    with pytest.raises(KeyboardInterrupt):
        sweep(path, out=out, workers=0, progress=False, log=messages.append)
    parts = Path(str(out) + ".parts")
    assert n_parts(parts) == 3 and not out.exists()
    assert messages == [f"interrupted: 3 of 4 points saved in {parts}; run again with --resume to finish"]
    monkeypatch.setattr(sweeps_module, "_run_point", real)
    resumed = sweep(path, out=out, workers=0, progress=False, resume=True, log=messages.append)
    assert messages[-1] == "resumed: 3 of 4 points already done" and not parts.exists()
    xr.testing.assert_identical(resumed, sweep(path, workers=0, progress=False))


def test_resume_without_saved_state_starts_from_zero_and_says_so(tmp_path):
    messages = []
    ds = sweep(write(tmp_path, SMALL), out=tmp_path / "r.nc", workers=0, resume=True, progress=False, log=messages.append)
    assert any("no saved state" in m and "starting from zero" in m for m in messages), messages
    assert (ds["status"].values == "ok").all()
    xr.testing.assert_identical(open_nc(tmp_path / "r.nc"), ds)


def test_saved_points_are_never_discarded_or_mixed_with_another_sweep(tmp_path):
    path = write(tmp_path, SMALL)
    out = tmp_path / "s.nc"
    parts = Path(str(out) + ".parts")
    parts.mkdir()
    (parts / "manifest.json").write_text(json.dumps({"identity": "another sweep"}))
    (parts / "0123.json").write_text("{}")
    with pytest.raises(SweepError, match="--resume"):
        sweep(path, out=out, workers=0, progress=False)
    with pytest.raises(SweepError, match="different sweep"):
        sweep(path, out=out, workers=0, progress=False, resume=True)
    assert (parts / "0123.json").exists() and not out.exists()


# ---------------------------------------------------------------------------- failures


def test_failed_and_invalid_points_are_recorded_with_their_error_not_fatal(tmp_path):
    text = """
[base]
grid = "coarse"
[axes]
applied_pressure = ["-1psi", "4psi", "1000psi"]
dome_height = ["5um", "50mm"]
"""
    path = write(tmp_path, text)
    # out of range alone (announced up front); 50 mm is invalid only against the wafer radius
    assert [m.split(" =")[0] for m in SweepSpec.from_toml(path).invalid_values()] == ["applied_pressure"]
    ds = sweep(path, out=tmp_path / "f.nc", workers=0, progress=False)
    status = ds["status"].values
    assert status.tolist() == [["invalid", "invalid"], ["ok", "invalid"], ["failed", "invalid"]]
    err = ds["error"].values
    assert "applied_pressure" in err[0, 0] and "valid range" in err[0, 0]
    assert "dome_height" in err[1, 1]
    # the same message `cmpsim run` prints for that point
    res = CliRunner().invoke(main, ["run", "--json", "--set", "grid=coarse", "--set", "applied_pressure=1000psi"])
    assert res.exit_code == 3
    assert err[2, 0] and err[2, 0] in res.stderr
    assert err[1, 0] == "" and np.isfinite(ds["film_thickness_center"].values[1, 0])
    assert np.isnan(ds["film_thickness_center"].values[2, 0]) and ds["iterations"].values[2, 0] == -1
    assert ds.attrs["points_failed"] == 1 and ds.attrs["points_invalid"] == 4
    xr.testing.assert_identical(open_nc(tmp_path / "f.nc"), ds)


# ---------------------------------------------------------------------------- bad sweep files


@pytest.mark.parametrize(
    "text, message",
    [
        ("[axes]\napplied_presure = ['2psi']\n", "unknown setting 'applied_presure'"),
        ("[base]\nspeed = '60rpm'\n[axes]\napplied_pressure = ['2psi']\n", "unknown setting 'speed'"),
        ("[axis]\napplied_pressure = ['2psi']\n", "unknown key"),
        ("[axes]\napplied_pressure = ['2 m', '3psi']\n", "wrong dimension"),
        ("[axes]\nrotation_speed = {start = '30rpm', stop = '2psi', num = 3}\n", "wrong dimension"),
        ("[axes]\napplied_pressure = []\n", "empty"),
        ("[axes]\napplied_pressure = {start = '2psi', stop = '6psi', num = 0}\n", "empty"),
        ("[axes]\napplied_pressure = {start = '2psi', stop = '6psi'}\n", "needs num"),
        ("[axes]\nmodel = {start = 'lep', stop = 'elastic', num = 2}\n", "numeric setting"),
        ("[axes]\napplied_pressure = ['4psi', '4 psi']\n", "appears twice"),
        ("[axes]\napplied_pressure = {start = '2psi', stop = '6psi', num = 30}\nrotation_speed = {start = '30rpm', stop = '90rpm', num = 30}\n", "more than the maximum of 500"),
        ("[base]\napplied_pressure = '-4psi'\n[axes]\nrotation_speed = ['60rpm']\n", "applied_pressure"),
        ("", "no points"),
        ("[base]\npreset = 'papr'\n[axes]\nrotation_speed = ['60rpm']\n", "preset must be one of 'default', 'paper'"),
        ("[base]\npreset = 1\n[axes]\nrotation_speed = ['60rpm']\n", "preset must be a preset name"),
    ],
)
def test_bad_sweep_files_fail_before_any_work_naming_the_problem(tmp_path, text, message):
    out = tmp_path / "bad.nc"
    with pytest.raises(SweepError, match=message):
        sweep(write(tmp_path, text), out=out, workers=0, progress=False, max_points=500)
    assert not out.exists() and not Path(str(out) + ".parts").exists()


def test_base_preset_starts_the_sweep_from_that_preset():
    """`[base] preset = "paper"` is the paper's model with the file's other settings on top,
    as `preset = "paper"` does in a config file (Config.from_mapping)."""
    text = "[base]\npreset = 'paper'\ngrid = 'coarse'\npad = {pad_modulus = '200MPa'}\n[axes]\nrotation_speed = ['40rpm', '80rpm']\n"
    spec = SweepSpec.from_mapping(tomllib.loads(text))
    assert spec.base == Config.paper().replace(grid="coarse", pad_modulus="200MPa")
    assert spec.base != Config.default().replace(grid="coarse", pad_modulus="200MPa")
    assert SweepSpec.from_mapping(tomllib.loads(text.replace("preset = 'paper'", "preset = 'default'"))).base == Config.default().replace(grid="coarse", pad_modulus="200MPa")


def test_cli_rejects_a_too_large_sweep_with_exit_status_2(tmp_path):
    res = CliRunner().invoke(main, ["sweep", str(write(tmp_path, SMALL)), "--out", str(tmp_path / "x.nc"), "--max-points", "3"])
    assert res.exit_code == 2
    assert "4 points" in res.stderr and "maximum of 3" in res.stderr
    assert not (tmp_path / "x.nc.parts").exists()


def test_zarr_path_writes_a_zarr_store_equal_to_the_netcdf_result(tmp_path):
    spec = write(tmp_path, SMALL)
    nc = sweep(spec, out=tmp_path / "x.nc", workers=0, progress=False)
    zr = sweep(spec, out=tmp_path / "x.zarr", workers=0, progress=False)
    stored = xr.open_zarr(tmp_path / "x.zarr").load()
    for name in ("film_thickness_center", "attack_angle", "status"):
        np.testing.assert_array_equal(stored[name].values, nc[name].values)
        np.testing.assert_array_equal(zr[name].values, nc[name].values)
    assert stored["applied_pressure"].attrs["units"] == nc["applied_pressure"].attrs["units"]
    assert not (tmp_path / "x.zarr.parts").exists()


# ---------------------------------------------------------------------------- layout and files


def test_string_axes_and_explicit_points_make_one_dimension_per_setting(tmp_path):
    text = """
[base]
grid = "coarse"
[axes]
model = ["lep", "elastic"]
applied_pressure = ["3psi", "5psi"]
[[points]]
applied_pressure = "4psi"
particle_diameter = "150nm"
[[points]]
model = "lep"
applied_pressure = "3psi"
"""
    spec = SweepSpec.from_mapping(tomllib.loads(text))
    assert spec.dims == ("model", "applied_pressure", "particle_diameter") and spec.n_points == 5
    ds = sweep(spec, workers=0, progress=False)
    assert ds["model"].values.tolist() == ["lep", "elastic"]
    assert ds["particle_diameter"].values.tolist() == [100e-9, pytest.approx(150e-9)]
    assert ds["particle_diameter"].attrs["units"] == "m" and ds["applied_pressure"].attrs["units"] == "Pa"
    assert (ds["status"].values == "ok").sum() == 5
    assert (ds["status"].values == "not_requested").sum() == 2 * 3 * 2 - 5
    extra = ds.sel(model="lep", particle_diameter=ds["particle_diameter"][1]).isel(applied_pressure=2)
    assert extra["status"].item() == "ok"
    ref = cmpsim.solve(grid="coarse", applied_pressure="4psi", particle_diameter="150nm")
    assert extra["film_thickness_center"].item() == pytest.approx(ref.film_thickness_center, rel=1e-6)


def test_output_file_holds_config_version_and_sweep_and_appears_atomically(tmp_path):
    path = write(tmp_path, '# comment: 15 µm pad\n[base]\nparticle_diameter = "200nm"\n' + SMALL.replace("[base]\n", ""))
    out = tmp_path / "res" / "out.nc"
    ds = sweep(path, out=out, workers=0, progress=False)
    assert sorted(p.name for p in out.parent.iterdir()) == ["out.nc"]  # no temporaries, no state left
    disk = open_nc(out)
    xr.testing.assert_identical(disk, ds)
    assert disk.attrs["cmpsim_version"] == cmpsim.__version__
    assert disk.attrs["sweep_toml"] == path.read_text()
    assert Config.from_mapping(tomllib.loads(disk.attrs["config_toml"])) == Config.default().replace(particle_diameter="200nm", grid="coarse")
    assert disk.attrs["Conventions"] == "CF-1.11"
    for k in SCALARS:
        o = outputs.scalar(k)
        assert k in disk.data_vars and disk[k].attrs["long_name"] == o.long_name
        if o.dtype == "bool":  # a CF flag
            assert list(disk[k].attrs["flag_values"]) == [0, 1] and disk[k].attrs["flag_meanings"] == "not_converged converged"
        else:
            assert disk[k].attrs["units"] == SCALARS[k][0]


def test_shipped_example_sweep_file_is_valid():
    path = importlib.resources.files("cmpsim") / "data" / "example_sweep.toml"
    spec = SweepSpec.from_toml(path)
    assert spec.dims == ("applied_pressure", "rotation_speed") and spec.n_points == 35
    assert spec.chain_dim == "rotation_speed"


# ---------------------------------------------------------------------------- warm start


@pytest.mark.parametrize(
    "model, axis",
    [
        ("hydrodynamic", {"start": "40rpm", "stop": "80rpm", "num": 5}),
        ("lep", ["50MPa", "140MPa", "230MPa", "320MPa", "410MPa"]),
    ],
    ids=["hydrodynamic-speed", "lep-pad_modulus"],
)
def test_warm_start_agrees_with_cold_start_and_never_costs_more_solves(model, axis):
    name = "rotation_speed" if isinstance(axis, dict) else "pad_modulus"
    # the paper's model (rigid pad): the pure hydrodynamic variant has no pad contact, so the
    # default's compliant Winkler stack does not apply to it; `[base] preset = "paper"` in a file
    spec = SweepSpec.from_mapping({"base": {"preset": "paper", "grid": "coarse", "model": model}, "axes": {name: axis}})
    warm = sweep(spec, workers=0, progress=False)
    cold = sweep(spec, workers=0, progress=False, warm_start=False)
    assert (warm["status"].values == "ok").all() and (cold["status"].values == "ok").all()
    assert (warm["start"].values == "warm").sum() == 4
    for k in ("film_thickness_center", "film_thickness_min", "attack_angle", "fluid_load_fraction", "removal_rate_mean"):
        np.testing.assert_allclose(warm[k], cold[k], rtol=1e-6, err_msg=k)
    assert int(warm["factorizations"].sum()) <= int(cold["factorizations"].sum())
    assert int(warm["iterations"].sum()) <= int(cold["iterations"].sum())
    if model == "hydrodynamic":
        assert int(warm["factorizations"].sum()) < 0.6 * int(cold["factorizations"].sum())


def test_a_close_that_hangs_is_given_up_within_its_bound_and_a_failed_one_is_not_finished():
    import threading

    from cmpsim.sweeps.executors import _close_within

    never = threading.Event()
    t0 = time.monotonic()
    assert _close_within(never.wait, 0.3) is False
    assert time.monotonic() - t0 < 5.0
    assert _close_within(lambda: None, 5.0) is True

    def broken():
        raise RuntimeError("scheduler gone")

    assert _close_within(broken, 5.0) is False


def test_the_worker_processes_of_an_interrupted_run_are_killed_and_older_children_are_not():
    from cmpsim.sweeps.executors import _child_pids, _kill_new_child_processes

    sleep = [sys.executable, "-c", "import time; time.sleep(600)"]
    older = subprocess.Popen(sleep)
    try:
        before = _child_pids()
        worker = subprocess.Popen(sleep)  # started after the snapshot, like the cluster's workers
        try:
            t0 = time.monotonic()
            assert _kill_new_child_processes(before) == 1
            worker.wait(timeout=10)  # reaped already by the kill (its status is then unknown to Popen); it sleeps 600 s otherwise
            assert time.monotonic() - t0 < 10
            assert older.poll() is None, "a process started before the cluster was killed"
        finally:
            if worker.poll() is None:
                worker.kill()
    finally:
        older.kill()
        older.wait()
