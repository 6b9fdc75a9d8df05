"""Parameter sweeps: the outer product of setting axes, run on dask.distributed, resumable.

A sweep file (TOML, see docs/sweeps.md and ``cmpsim/data/example_sweep.toml``) holds

* ``[base]``: any ``cmpsim run`` setting (same names, values with units), flat or in the
  sections of a config file (``[base.process]``); ``preset = "paper"`` starts from that
  preset (:meth:`cmpsim.Config.from_mapping`);
* ``[axes]``: one key per swept setting, a list (``applied_pressure = ["2psi", "4psi"]``) or a
  range (``rotation_speed = {start = "30rpm", stop = "90rpm", num = 7}``, optional
  ``scale = "log"``); the sweep is their outer product;
* ``[[points]]``: optional explicit extra points (tables of settings).

The result is one :class:`xarray.Dataset` with one dimension per swept setting (named as the
setting, SI coordinates, ``units`` in the attributes), every scalar of ``cmpsim run --json``
as a variable, plus ``status`` (``ok`` / ``failed`` / ``invalid`` / ``not_requested``),
``error`` and ``start`` (``warm`` / ``cold`` / ``cold-retry``) per point.

Execution
---------
Each point is one dask task. Points are grouped into *chains* along the last numeric axis
(at most ``chain_length`` points, a fixed split that does not depend on the number of workers)
and each task of a chain is submitted when the previous point of its chain has come back, with
the converged records of the one or two previous points as plain arguments (not as dask
dependencies, which would pin a chain to one worker). The start of Newton is predicted from
them (see :func:`cmpsim.solver.points.predict_start`); if a predicted start fails, the point is solved again from the cold
start. The result of a point therefore depends only on the chain layout, never on how many
workers there are or on the order in which points finish.

Persistence and resume
----------------------
With an output path ``PATH`` every finished point is written atomically, by the client as it
arrives, to ``PATH.parts/<key>.json`` (key = hash of the sweep identity and the point's
settings); ``PATH.parts/manifest.json`` identifies the sweep. ``resume=True`` reloads those
records, feeds them to the chains as if they had just been computed (same warm starts) and
computes only the missing points, so the final dataset equals an uninterrupted run. The final
file is written to a temporary sibling and renamed; the state directory is removed once the
file is in place.

Rooms
-----
``spec`` (the sweep file and its layout), ``plan``
(identity, chains, warm-start prediction), ``executors`` (the task of one
point; serial and Dask execution), ``state`` (the ``PATH.parts/``
directory), ``dataset`` (the xarray result, its file and summary);
:func:`sweep` connects them.
"""

from __future__ import annotations

import json
import os
from pathlib import Path
from typing import Callable, Mapping

from .dataset import STATUS_MEANINGS, _build_dataset, _check_out, _write, summary_lines
from ..solver.points import Progress
from .executors import _run_dask, _run_serial, _with_client, local_cluster
# the per-point function; the executors look it up here at call time, so a test can replace it
from .executors import _run_point  # noqa: F401
from .plan import DEFAULT_CHAIN_LENGTH, _identity, _plan
from .spec import DEFAULT_MAX_POINTS, Axis, SweepError, SweepSpec
from .state import _State

__all__ = [
    "Axis",
    "SweepSpec",
    "SweepError",
    "sweep",
    "local_cluster",
    "summary_lines",
    "DEFAULT_MAX_POINTS",
    "DEFAULT_CHAIN_LENGTH",
    "STATUS_MEANINGS",
]


def _as_spec(spec_or_path) -> SweepSpec:
    if isinstance(spec_or_path, SweepSpec):
        return spec_or_path
    if isinstance(spec_or_path, Mapping):
        return SweepSpec.from_mapping(spec_or_path)
    if isinstance(spec_or_path, (str, os.PathLike)):
        return SweepSpec.from_toml(spec_or_path)
    raise SweepError(f"sweep: expected a SweepSpec, a mapping or the path of a sweep file; got {type(spec_or_path).__name__}")


def sweep(
    spec_or_path,
    out=None,
    workers: int | None = None,
    scheduler=None,
    resume: bool = False,
    progress: bool = True,
    warm_start: bool = True,
    max_points: int = DEFAULT_MAX_POINTS,
    chain_length: int = DEFAULT_CHAIN_LENGTH,
    log: Callable[[str], None] | None = None,
):
    """Run a parameter sweep; returns an :class:`xarray.Dataset` (see the module docstring).

    Parameters
    ----------
    spec_or_path : SweepSpec, mapping or path
        The sweep (a sweep file, or its content as a mapping).
    out : path, optional
        Write the dataset there (NetCDF; zarr for a ``.zarr`` path) and keep the state of
        finished points in ``out + ".parts/"`` while running. Without it nothing is written
        and the sweep cannot be resumed.
    workers : int, optional
        Size of the local ``dask.distributed.LocalCluster`` (one single-threaded worker
        process each); default: the machine's cores (at most one per chain). ``0`` runs the
        points one after the other in this process, without dask.
    scheduler : str or distributed.Client, optional
        Address of an existing Dask scheduler (``tcp://host:8786``) or a connected Client;
        the points then run on that cluster (its workers need cmpsim installed).
    resume : bool
        Reuse the points saved in ``out + ".parts/"`` by an interrupted run of the same sweep.
    progress : bool
        Show a progress bar (rich) and messages on stderr.
    warm_start : bool
        Start Newton from a prediction made from converged neighbours (default) or always cold.
    max_points : int
        Refuse sweeps with more points than this (before any work).
    chain_length : int
        Longest run of points solved in sequence with warm starts (one cold start per run);
        a fixed layout, so results do not depend on the number of workers.
    log : callable, optional
        Receives the messages (resume status, interruption); default: stderr when
        ``progress`` is on, otherwise silent.

    Raises
    ------
    SweepError
        Bad sweep file or options, too many points, zarr missing, saved state of another
        sweep: always before any point is computed.
    """
    spec = _as_spec(spec_or_path)
    spec.check_size(max_points)
    if chain_length < 1:
        raise SweepError(f"chain_length must be >= 1; got {chain_length}")
    if workers is not None and workers < 0:
        raise SweepError(f"workers must be >= 0; got {workers}")
    if workers is not None and scheduler is not None:
        raise SweepError("give either workers (a local cluster) or scheduler (an existing cluster), not both")
    if log is None:
        if progress:
            import sys

            def log(msg):
                print(msg, file=sys.stderr, flush=True)
        else:

            def log(msg):
                pass

    identity = _identity(spec, warm_start, chain_length)
    chains = _plan(spec, identity, warm_start, chain_length)
    plan_points = [p for c in chains for p in c]
    n = len(plan_points)
    keys = {p.key for p in plan_points}
    state = None
    done: dict[str, dict] = {}
    if out is not None:
        out = Path(out)
        _check_out(out)
        state = _State(out)
        options = {"warm_start": bool(warm_start), "chain_length": int(chain_length)}
        if resume:
            if state.exists():
                man = state.read_manifest()
                if man is not None and man.get("identity") != identity:
                    raise SweepError(
                        f"the saved state in {state.dir} belongs to a different sweep (the sweep file, the cmpsim version "
                        "or the warm-start settings changed); delete that directory or choose another --out"
                    )
                done = state.load(keys)
                log(f"resumed: {len(done)} of {n} points already done")
            else:
                log(f"resume: no saved state in {state.dir}; starting from zero (0 of {n} points done)")
        elif state.part_files():
            raise SweepError(
                f"{state.dir} holds {len(state.part_files())} saved points of an interrupted sweep; "
                "run with --resume (resume=True) to finish it, or delete that directory to start over"
            )
        state.clean_temporaries()
        state.begin(identity, spec, n, options)
    elif resume:
        raise SweepError("resume needs an output path (out=...): the saved state lives next to it")

    records: dict[str, dict] = dict(done)
    base_json = json.dumps(spec.base.to_sections())
    n_failed = sum(1 for r in done.values() if r["status"] != "ok")
    all_persisted = True
    n_saved = len(done)
    bar = Progress(progress, n, "sweep", done=len(done), failed=n_failed)

    def on_result(p, rec, persist):
        nonlocal all_persisted, n_saved
        if persist and state is not None:
            state.save(rec)
            n_saved += 1
        elif not persist:
            all_persisted = False
        records[p.key] = rec
        bar.advance(rec["status"] == "ok")

    missing = n - len(done)
    try:
        with bar:
            if missing == 0:
                pass
            elif scheduler is None and workers == 0:
                _run_serial(chains, done, base_json, warm_start, on_result)
            else:
                _with_client(scheduler, workers, chains, done, lambda c: _run_dask(chains, done, base_json, warm_start, on_result, c))
    except KeyboardInterrupt:
        if state is not None:
            log(f"interrupted: {n_saved} of {n} points saved in {state.dir}; run again with --resume to finish")
        raise
    ds = _build_dataset(spec, chains, records, identity, warm_start, chain_length)
    if out is not None:
        _write(ds, out)
        if all_persisted:
            state.remove()
        else:
            log(f"some points were not computed (dask task failures); {state.dir} is kept: run again with --resume")
    return ds
