"""``cmpsim sweep``: a parameter sweep from a TOML file, on dask.distributed."""

from __future__ import annotations

import os
import sys
from pathlib import Path

import click

from .group import _fail, _warn, check_out, main


@main.command(name="sweep")
@click.argument("sweep_file", type=click.Path(dir_okay=False))
@click.option("--out", "out_path", type=click.Path(), help="Result file: NetCDF (default SWEEP_FILE stem + .nc in the current directory), or zarr for a .zarr path.")
@click.option("--workers", type=click.IntRange(min=0), default=None, help="Worker processes of the local Dask cluster (default: the machine's cores); 0 runs in this process without Dask.")
@click.option("--scheduler", metavar="ADDRESS", help="Run on an existing Dask cluster, e.g. tcp://host:8786 (its workers need cmpsim installed).")
@click.option("--resume", is_flag=True, help="Continue an interrupted sweep: reuse the points saved next to --out, compute only the missing ones.")
@click.option("--max-points", type=click.IntRange(min=1), default=None, help="Refuse sweeps with more points than this (default 10000).")
@click.option("--no-warm-start", is_flag=True, help="Start every point from the cold start instead of from its converged neighbours.")
@click.option("--no-progress", is_flag=True, help="No progress bar.")
def sweep_command(sweep_file, out_path, workers, scheduler, resume, max_points, no_warm_start, no_progress):
    """Run a parameter sweep (outer product of [axes] plus [[points]]) on dask.distributed.

    SWEEP_FILE is a TOML file with an optional [base] table of `cmpsim run` settings and an
    [axes] table (setting = list of values or {start, stop, num}); see docs/sweeps.md and
    the example shipped as cmpsim/data/example_sweep.toml. The result is one xarray Dataset
    (one dimension per axis, every `cmpsim run --json` scalar as a variable, status and
    error per point). Every finished point is saved in OUT.parts/ as it completes, so an
    interrupted sweep continues with --resume.
    """
    import time as _time

    from ..sweeps import DEFAULT_MAX_POINTS, SweepError, SweepSpec, summary_lines
    from ..sweeps import sweep as run_sweep

    try:
        spec = SweepSpec.from_toml(sweep_file)
        spec.check_size(max_points or DEFAULT_MAX_POINTS)
    except ValueError as exc:
        _fail(str(exc))
    out = Path(out_path) if out_path else Path.cwd() / (Path(sweep_file).stem + ".nc")
    try:
        check_out(out)
    except ValueError as exc:
        _fail(str(exc))
    where = f"Dask cluster at {scheduler}" if scheduler else ("this process (no Dask)" if workers == 0 else "a local Dask cluster")
    click.echo(f"sweep: {spec.n_points} points ({' x '.join(f'{d} {n}' for d, n in zip(spec.dims, spec.shape))}) on {where} -> {out}")
    for message in spec.invalid_values():
        _warn(f"{message}; the points with this value will be recorded as invalid")
    t0 = _time.perf_counter()
    try:
        ds = run_sweep(
            spec,
            out=out,
            workers=workers,
            scheduler=scheduler,
            resume=resume,
            progress=not no_progress,
            warm_start=not no_warm_start,
            max_points=max_points or DEFAULT_MAX_POINTS,
            log=click.echo,
        )
    except SweepError as exc:
        _fail(str(exc))
    except KeyboardInterrupt:
        # The finished points are saved and the cluster closed (or its workers killed) within a
        # bound by now; exit at once, so that no interpreter-exit hook (Dask closes clusters
        # at exit) can wait on a worker that is still busy.
        sys.stdout.flush()
        sys.stderr.flush()
        os._exit(130)
    elapsed = _time.perf_counter() - t0
    for line in summary_lines(ds):
        click.echo(line)
    click.echo(f"wrote {out} in {elapsed:.1f} s")
