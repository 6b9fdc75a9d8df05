"""Running the points: the task of one point (on a worker) and the serial and Dask executors.

The executors call the point function as ``cmpsim.sweeps._run_point``, looked up at call
time, so that a test can replace it.
"""

from __future__ import annotations

import contextlib
import json
import logging
import os
import time
import uuid
from functools import lru_cache

from ..inputs.config import Config
from ..solver.points import predict_start
from .plan import _PlanPoint
from .spec import SweepError

__all__ = ["local_cluster"]


@lru_cache(maxsize=8)
def _base_config(base_json: str) -> Config:
    return Config.from_mapping(json.loads(base_json))


def _run_point(task: dict, prev=None, prev2=None) -> dict:
    """Solve one point; never raises (failures are returned as records)."""
    from ..solver.model import build_problem
    from ..solver.points import solve_point

    t0 = time.perf_counter()
    rec = {
        "key": task["key"],
        "index": list(task["index"]),
        "settings": task["settings"],
        "x": task["x"],
        "status": "ok",
        "error": "",
        "start": "",
        "scalars": {},
        "u": None,
        "cold_base": None,
    }
    try:
        cfg = _base_config(task["base"]).replace(**task["settings"])
        problem = build_problem(cfg)
    except Exception as exc:  # ValueError: the user's input; anything else a bug: keep the sweep going, say what
        rec.update(status="invalid", error=str(exc) if isinstance(exc, ValueError) else f"{type(exc).__name__}: {exc}")
        rec["elapsed_s"] = time.perf_counter() - t0
        return rec
    start = None
    if task["warm_start"]:
        start, cold = predict_start(cfg, problem, task["x"], prev, prev2)
        rec["cold_base"] = None if cold is None else [float(v) for v in cold]
    out = solve_point(cfg, start=start, relative=True, problem=problem)  # the problem built above, not again
    rec["start"] = out.start
    if out.ok:
        rec["scalars"] = dict(out.result.scalars)  # values and diagnostics, registry names (cmpsim.results.outputs)
        rec["u"] = [float(v) for v in out.result.solution.state.u]
    else:
        rec.update(status="failed", error=out.error)
    rec["elapsed_s"] = time.perf_counter() - t0
    return rec


def _point_function():
    """``cmpsim.sweeps._run_point`` as it is now (tests replace it by attribute)."""
    from .. import sweeps

    return sweeps._run_point


def _payload(p: _PlanPoint, base_json: str, warm_start: bool) -> dict:
    return {"key": p.key, "index": list(p.index), "settings": p.settings, "x": p.x, "base": base_json, "warm_start": warm_start}


def _run_serial(chains, done, base_json, warm_start, on_result):
    for chain in chains:
        prev = prev2 = None
        for p in chain:
            rec = done.get(p.key)
            if rec is None:
                rec = _point_function()(_payload(p, base_json, warm_start), prev, prev2)
                on_result(p, rec, True)
            prev2, prev = prev, rec


def _local_workers(requested: int | None, chains, done) -> int:
    busy = sum(1 for c in chains if any(p.key not in done for p in c))
    if requested is not None:
        return max(1, requested)
    try:
        cores = len(os.sched_getaffinity(0))
    except AttributeError:  # pragma: no cover - macOS / Windows
        cores = os.cpu_count() or 1
    return max(1, min(cores, busy))


def _run_dask(chains, done, base_json, warm_start, on_result, client):
    """Run the chains on a Dask cluster, one task a point.

    The next point of a chain is submitted when the previous one has come back, with the
    records of the two previous points as plain arguments (not as futures): a dependency on
    a future would make the scheduler place the whole chain on the worker that holds it, and
    with more chains than workers (5 chains of 8 points on 2 workers) one worker would end
    with a chain more than the other. Without it every ready point goes to the least busy
    worker. ``priority=-depth`` keeps the chains advancing together.
    """
    from distributed import as_completed

    tag = uuid.uuid4().hex[:10]
    run_point = _point_function()
    futures = {}
    running = as_completed(with_results=True, raise_errors=False)

    def submit_next(chain, pos, prev, prev2):
        while pos < len(chain) and chain[pos].key in done:  # resumed: finished points feed the prediction
            prev2, prev = prev, done[chain[pos].key]
            pos += 1
        if pos < len(chain):
            p = chain[pos]
            flat = "-".join(map(str, p.index))
            fut = client.submit(
                run_point, _payload(p, base_json, warm_start), prev, prev2, key=f"cmpsim-point-{tag}-{flat}", retries=0, priority=-pos
            )
            futures[fut] = (chain, pos, prev)
            running.add(fut)

    for chain in chains:
        submit_next(chain, 0, None, None)
    try:
        for fut, result in running:
            chain, pos, prev = futures.pop(fut)
            p = chain[pos]
            if fut.status == "finished":
                rec = result
                on_result(p, rec, True)
            else:  # the worker died or the task broke: report the point, do not persist it
                try:
                    exc = fut.exception()
                except Exception as e:  # pragma: no cover
                    exc = e
                rec = {
                    "key": p.key, "index": list(p.index), "settings": p.settings, "x": p.x, "status": "failed",
                    "error": f"not computed: the dask task failed ({type(exc).__name__}: {exc}); run again with --resume",
                    "start": "", "scalars": {}, "u": None, "cold_base": None,
                }
                on_result(p, rec, False)
            submit_next(chain, pos + 1, rec, prev)
    finally:
        pending = [f for f in futures if f.status == "pending"]
        if pending:
            client.cancel(pending)
        futures.clear()


def local_cluster(n_workers: int):
    """The ``distributed.LocalCluster`` a sweep uses: ``n_workers`` single-threaded processes.

    Two departures from the Dask defaults, both for the worker processes only:

    * they ignore SIGINT, so that a Ctrl-C in the terminal (sent to the whole process group)
      reaches only the calling process, which saves its state and closes the cluster cleanly
      instead of the workers dying with tracebacks;
    * they keep glibc's default malloc trimming. Dask sets ``MALLOC_TRIM_THRESHOLD_=65536``
      for its workers, which also switches off glibc's dynamic mmap threshold: every large
      numpy temporary of the solver is then mapped and unmapped again, and a point took
      20-30 % longer in a worker than in the calling process (measured on the fine grid).
      A value set by the user (environment or Dask configuration) is respected.
    """
    import dask
    from distributed import LocalCluster

    cfg = {}
    key = "distributed.nanny.pre-spawn-environ"
    if "MALLOC_TRIM_THRESHOLD_" not in os.environ and str((dask.config.get(key, {}) or {}).get("MALLOC_TRIM_THRESHOLD_")) == "65536":
        cfg[key + ".MALLOC_TRIM_THRESHOLD_"] = None
    with dask.config.set(cfg), _sigint_ignored():
        return LocalCluster(
            n_workers=n_workers,
            threads_per_worker=1,
            processes=True,
            dashboard_address=None,
            silence_logs=logging.ERROR,
        )


@contextlib.contextmanager
def _sigint_ignored():
    """Ignore SIGINT while worker processes are spawned (they keep ignoring it)."""
    import signal
    import threading

    if threading.current_thread() is not threading.main_thread():
        yield
        return
    old = signal.signal(signal.SIGINT, signal.SIG_IGN)
    try:
        yield
    finally:
        signal.signal(signal.SIGINT, old)


#: Seconds the clean-up after a Ctrl-C may take (closing the client, then the cluster) before
#: the worker processes are killed. A worker busy in a long point (a fine 300 mm solve) cannot
#: be stopped by Dask between two bytecodes, so the bound is what ends the run "within seconds".
INTERRUPT_CLOSE_SECONDS = 10.0


def _close_within(close, seconds: float) -> bool:
    """Call ``close()`` on a daemon thread and wait at most ``seconds``; True if it returned.

    A close that hangs (a scheduler waiting on a blocked task, an event loop stuck) is left
    behind on its daemon thread, which does not keep the interpreter alive.
    """
    import threading

    box: list[BaseException] = []

    def run():
        try:
            close()
        except BaseException as exc:  # reported below; a failed close is not a finished one
            box.append(exc)

    thread = threading.Thread(target=run, name="cmpsim-close", daemon=True)
    thread.start()
    thread.join(seconds)
    return not thread.is_alive() and not box


def _child_pids() -> set[int]:
    """The pids of every process this one started and that still runs."""
    import psutil  # a dependency of dask.distributed

    return {c.pid for c in psutil.Process().children(recursive=True)}


def _kill_new_child_processes(before: set[int]) -> int:
    """SIGKILL the processes this one started since ``before`` was taken (the local cluster's
    workers, restarted ones included); how many. Older children (a caller's own processes) and
    multiprocessing's resource tracker, which outlives the cluster, are left alone."""
    import psutil

    victims = []
    for child in psutil.Process().children(recursive=True):
        if child.pid in before:
            continue
        with contextlib.suppress(psutil.Error):
            if any("resource_tracker" in part for part in child.cmdline()):
                continue
            child.kill()
            victims.append(child)
    psutil.wait_procs(victims, timeout=5)
    return len(victims)


def _with_client(scheduler, workers, chains, done, fn):
    """Run ``fn(client)`` on the given scheduler or on a local cluster made for this sweep.

    On a Ctrl-C (KeyboardInterrupt) the client and the local cluster are closed with a bound
    of :data:`INTERRUPT_CLOSE_SECONDS` each; past it the cluster's worker processes are
    killed, so the run ends within seconds whatever the workers are doing (the points already
    finished are saved as they arrive, before this).
    """
    from distributed import Client

    if scheduler is not None and not isinstance(scheduler, str):
        return fn(scheduler)  # a connected Client: used as is, not closed
    if scheduler is not None:
        try:
            client = Client(scheduler, timeout="20s")
        except Exception as exc:
            raise SweepError(f"cannot connect to the Dask scheduler at {scheduler!r}: {exc}") from None
        try:
            return fn(client)
        except KeyboardInterrupt:
            _close_within(client.close, INTERRUPT_CLOSE_SECONDS)
            client = None
            raise
        finally:
            if client is not None:
                client.close()
    before = _child_pids()
    cluster = local_cluster(_local_workers(workers, chains, done))
    client = None
    try:
        client = Client(cluster)
        return fn(client)
    except KeyboardInterrupt:
        closed = client is None or _close_within(client.close, INTERRUPT_CLOSE_SECONDS)
        closed = _close_within(cluster.close, INTERRUPT_CLOSE_SECONDS) and closed
        if not closed:
            _kill_new_child_processes(before)
        client = cluster = None
        raise
    finally:
        if client is not None:
            client.close()
        if cluster is not None:
            cluster.close()
