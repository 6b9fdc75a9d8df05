"""`cmpsim reproduce`: ten figures with their CSVs, a generated trend table, REPORT.md/.html."""

import copy
import csv
import re

import pytest
from click.testing import CliRunner

from cmpsim.cli import main
from cmpsim.reproduction import CURVES, FIGURES, LOADS_PSI, SLIGHT, SPEEDS_RPM, STATEMENTS, evaluate_statements, reproduce


@pytest.fixture(scope="module")
def report(tmp_path_factory):
    out = tmp_path_factory.mktemp("repro_api")
    return reproduce(out=out, grid="coarse", progress=False)


@pytest.fixture(scope="module")
def cli_run(tmp_path_factory):
    out = tmp_path_factory.mktemp("repro_cli") / "figs"
    res = CliRunner().invoke(main, ["reproduce", "--out", str(out), "--grid", "coarse"])
    return res, out


def _trend_rows(md: str):
    rows = [line for line in md.splitlines() if re.match(r"^\| S\d\d \|", line)]
    return [[c.strip() for c in re.split(r"(?<!\\)\|", r)[1:-1]] for r in rows]


def test_cli_writes_ten_figures_csvs_and_both_reports(cli_run):
    res, out = cli_run
    assert res.exit_code == 0, res.output
    pngs = sorted(p.name for p in out.glob("fig*.png"))
    csvs = sorted(p.name for p in out.glob("fig*.csv"))
    assert len(pngs) == 10 and len(csvs) == 10
    assert [p[:5] for p in pngs] == [f"fig{n:02d}" for n in range(3, 13)]
    for p in out.glob("fig*.png"):
        assert p.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n" and p.stat().st_size > 10_000
    md = (out / "REPORT.md").read_text()
    html = (out / "REPORT.html").read_text()
    assert html.count("data:image/png;base64,") == 10  # figures inline
    rows = _trend_rows(md)
    assert len(rows) >= 18
    assert {r[4] for r in rows} <= {"yes", "no"}
    assert "Statements of the paper reproduced" in res.output


def test_report_states_parameters_and_criteria(cli_run):
    _, out = cli_run
    md = (out / "REPORT.md").read_text()
    assert "## Parameter set" in md and "| applied_pressure |" in md and "| asperity_density |" in md
    assert f"less than {SLIGHT:g} times the base-case value" in md  # the numeric meaning of 'slightly'
    assert "Lu et al." in md and "not available" in md
    for row in _trend_rows(md):
        if row[4] == "no":
            assert row[6], f"statement {row[0]} fails without a reason"
        else:
            assert row[6] == ""


def test_csv_holds_every_point_and_the_regularisation_flag(report):
    for f in report.figures:
        with open(f.csv) as fh:
            rows = list(csv.DictReader(line for line in fh if not line.startswith("#")))
        n = len(LOADS_PSI) if f.spec.sweep == "load" else len(SPEEDS_RPM)
        assert len(rows) == n * len(f.spec.curves)
        assert {"flow_factor_floored_fraction", "converged", "status", "film_thickness_center_um"} <= set(rows[0])
    rows3 = report.figure(3).rows
    hydro = [r for r in rows3 if r["model"] == "hydrodynamic"]
    lep = [r for r in rows3 if r["model"] == "lep"]
    # the hydrodynamic curves live where the flow factors had to be regularised: reported, not hidden
    assert all(r["flow_factor_floored_fraction"] > 0 for r in hydro if r["converged"] == "yes")
    assert all(r["flow_factor_floored_fraction"] == 0 for r in lep)
    assert any("regularised" in n for n in report.notes)


def test_relative_removal_rate_is_the_removal_rate_over_that_of_the_papers_reference_case(report):
    """Every point of Figs. 11-12 is divided by the removal rate of case (a) at 4 psi and 60 rpm,
    and that point is the reference case `cmpsim.solve` uses (LEP, 100 nm, 15 um, 4 psi, 60 rpm)."""
    import cmpsim
    from cmpsim.solver.model import REFERENCE_CASE

    rows = report.figure(11).rows + report.figure(12).rows
    (ref,) = {r["removal_rate_nm_per_min"] for r in rows if r["curve"] == "a" and r["applied_pressure_psi"] == pytest.approx(4.0) and r["rotation_speed_rpm"] == pytest.approx(60.0)}
    solved = cmpsim.solve(report.config.replace(model="lep", **REFERENCE_CASE), relative=False)
    assert ref == pytest.approx(solved.removal_rate_nm_per_min, rel=1e-7)  # Newton tolerance 1e-9 on the load
    assert len({r["curve"] for r in rows}) == 3 and len(rows) == 3 * (len(LOADS_PSI) + len(SPEEDS_RPM))
    for r in rows:
        assert r["removal_rate_relative"] == pytest.approx(r["removal_rate_nm_per_min"] / ref, rel=1e-12), (r["curve"], r["applied_pressure_psi"], r["rotation_speed_rpm"])


def test_identical_points_are_solved_once_and_their_pressure_solves_counted_once(report):
    from cmpsim.solver.points import config_key

    points = [p for pts in report.data.curves.values() for p in pts]
    distinct = {config_key(p.config): p for p in points}  # the reference case is one of them
    assert report.equilibria == len(distinct) < len(points)
    assert report.factorizations == sum(p.scalars["factorizations"] for p in distinct.values())


def test_statements_are_registered_once_and_cover_every_figure():
    ids = [s.id for s in STATEMENTS]
    assert len(ids) == len(set(ids)) >= 18
    covered = set()
    for s in STATEMENTS:
        lo, _, hi = s.figure.partition("-")
        covered |= set(range(int(lo), int(hi or lo) + 1))
    assert covered == set(range(3, 13))
    assert {f.number for f in FIGURES} == set(range(3, 13))
    assert {c for f in FIGURES for c in f.curves} <= set(CURVES)


def test_verdicts_are_computed_from_the_data(report):
    """Flip a curve in the data: the verdict follows (no verdict is written by hand)."""
    base = {r.id: r.reproduced for r in report.statements}
    assert base["S01"] is True  # film falls with load on the LEP curve (this model reproduces it)
    data = copy.deepcopy(report.data)
    for p in data.curve("lep_s15", "load"):
        p.scalars["film_thickness_center"] = 1e-6 * p.x  # now rising with load
    flipped = {r.id: r for r in evaluate_statements(data)}
    assert flipped["S01"].reproduced is False
    assert "rises between" in flipped["S01"].why_not
    # a missing equilibrium makes the statements that need it fail, with the reason
    data2 = copy.deepcopy(report.data)
    data2.curve("a", "speed")[3].scalars = None
    res2 = {r.id: r for r in evaluate_statements(data2)}
    assert res2["S28"].reproduced is False and "no equilibrium" in res2["S28"].why_not


def test_slight_criterion_uses_the_base_value(report):
    data = copy.deepcopy(report.data)
    for c in ("d100", "d200"):
        for sweep in ("load", "speed"):
            for p in data.curve(c, sweep):
                x = p.x if sweep == "load" else p.x / 15.0
                p.scalars["attack_angle"] = 1e-5 * (1.0 - 0.01 * x)  # falls by a few % only
    res = {r.id: r for r in evaluate_statements(data)}
    assert res["S11"].reproduced and res["S12"].reproduced
    assert not res["S15"].reproduced  # falling with speed, the paper says rising


def test_report_counts_match_table(report):
    md = report.report_md.read_text()
    rows = _trend_rows(md)
    assert sum(r[4] == "yes" for r in rows) == report.n_reproduced
    assert f"{report.n_reproduced} of {len(report.statements)}" in md
    # the run's cost as the report states it: the solving is part of the whole run
    assert 0 < report.solve_s <= report.elapsed_s
    assert f"{report.equilibria} equilibria solved ({report.factorizations} sparse LU factorisations) in {report.solve_s:.1f} s; whole run {report.elapsed_s:.1f} s" in md


def test_cmpsim_reproduce_is_the_function_even_after_importing_its_module():
    import cmpsim
    import cmpsim.reproduction  # noqa: F401

    assert cmpsim.reproduce is reproduce


FIGURE_PROCESS_SCRIPT = r"""
import dataclasses, os, sys, threading
from pathlib import Path
from cmpsim.reproduction import FIGURES, reproduce
from cmpsim.reproduction.report import FigureWriter

out = Path(sys.argv[1])
assert threading.active_count() == 1
rep = reproduce(out=out / "run", grid="coarse", progress=False)  # figures on the forked process
assert threading.active_count() == 1, "the sender thread outlived the run"
serial = FigureWriter(processes=1)
assert serial._child is None
for spec in FIGURES:
    serial.submit(spec, rep.data, out / "serial" / f"{spec.name}.png")
serial.finish()
same = all((out / "run" / f"{s.name}.png").read_bytes() == (out / "serial" / f"{s.name}.png").read_bytes() for s in FIGURES)
print("same:", same)
writer = FigureWriter()
print("forked:", writer._child is not None)
broken = dataclasses.replace(FIGURES[0], curves=("no-such-curve",))  # its data do not exist
writer.submit(broken, rep.data, out / "broken.png")
try:
    writer.finish()
    print("raised:", False)
except RuntimeError as exc:
    print("raised:", "no-such-curve" in str(exc))
finally:
    writer.close()
print("child alive:", writer._child is not None and writer._child.is_alive())
print("broken file:", (out / "broken.png").exists())
"""


def test_the_figure_process_draws_the_same_pngs_and_reports_its_failures(tmp_path):
    # run in a fresh interpreter: the figure process is forked only where no other thread runs
    # (this test process may hold Dask's or the web server's threads)
    import os
    import subprocess
    import sys

    proc = subprocess.run([sys.executable, "-c", FIGURE_PROCESS_SCRIPT, str(tmp_path)], capture_output=True, text=True, timeout=300)
    assert proc.returncode == 0, proc.stderr
    lines = dict(line.split(": ", 1) for line in proc.stdout.splitlines() if ": " in line)
    two_cores = len(os.sched_getaffinity(0)) >= 2
    assert lines["forked"] == str(two_cores)
    assert lines["same"] == "True"  # byte for byte, the 10 PNGs of the run against this process's
    assert lines["raised"] == "True"  # a figure failing in the child is raised here, with its error
    assert lines["child alive"] == "False"
    assert lines["broken file"] == "False"  # and leaves no file
