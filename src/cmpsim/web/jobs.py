"""Sweeps in the background: :func:`cmpsim.sweeps.sweep` on a Dask cluster, one thread a job.

Each job calls :func:`cmpsim.sweeps.sweep` exactly as ``cmpsim sweep`` does, with an output
path in the server's temporary folder and ``scheduler=`` a Dask client of its own on the
server's cluster (a ``LocalCluster`` started at the first sweep by
:func:`cmpsim.sweeps.local_cluster`, or an existing one given by address). The finished
points are read from the state folder that :func:`~cmpsim.sweeps.sweep` keeps beside its
output (``OUT.parts/<key>.json``, one file per point, written atomically as each point
arrives; see the :mod:`cmpsim.sweeps` docstring), which is what feeds the progress bar and
the server-sent events; the points that finish after the last look are read from the final
dataset. Cancelling cancels the job's Dask futures; :func:`~cmpsim.sweeps.sweep` then
returns and the job is marked ``cancelled``.
"""

from __future__ import annotations

import json
import logging
import shutil
import tempfile
import threading
import time
import uuid
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any, Callable

from .payloads import finite

__all__ = ["SweepJob", "SweepJobs", "STATES"]

log = logging.getLogger("cmpsim.web")

#: Job states: queued (waiting for the cluster), running, done, failed (the sweep raised),
#: cancelled (DELETE before the end).
STATES = ("queued", "running", "done", "failed", "cancelled")
_POLL_S = 0.1
_KEEP_FINISHED = 50


def _plain(v):
    """numpy scalars -> Python (NaN -> None), for JSON."""
    if hasattr(v, "item"):
        v = v.item()
    if isinstance(v, bytes):
        v = v.decode()
    return finite(v)


def point_values(scalars: dict) -> dict:
    """The SI values of a point record: the ``values`` of a schema-2 object, else the flat object."""
    if isinstance(scalars, dict) and isinstance(scalars.get("values"), dict):
        return {k: finite(v) for k, v in scalars["values"].items()}
    return {k: finite(v) for k, v in (scalars or {}).items() if not isinstance(v, (dict, list))}


@dataclass
class SweepJob:
    """One sweep: its spec, state, and the points finished so far (in the order they finished)."""

    id: str
    spec: Any  # cmpsim.sweeps.SweepSpec
    out: Path
    status: str = "queued"
    error: str | None = None
    points: list = field(default_factory=list)
    summary: list = field(default_factory=list)
    created: float = field(default_factory=time.time)
    finished: float | None = None
    cancel_requested: bool = False
    _seen: set = field(default_factory=set)
    _lock: threading.Lock = field(default_factory=threading.Lock)
    _client: Any = None
    _thread: threading.Thread | None = None

    @property
    def total(self) -> int:
        return self.spec.n_points

    @property
    def done(self) -> int:
        return len(self.points)

    @property
    def finished_running(self) -> bool:
        return self.status in ("done", "failed", "cancelled")

    def layout(self) -> dict:
        """Dimensions, SI coordinates and units of the sweep (what a client needs to draw it)."""
        from ..inputs.config import PARAMETERS, to_display

        coords = {d: [_plain(v) for v in self.spec.coords[d]] for d in self.spec.dims}
        units = {d: (PARAMETERS[d].unit if PARAMETERS[d].unit not in ("choice", "grid") else "") for d in self.spec.dims}

        def shown(d, v):
            try:
                shown = _plain(to_display(d, v))
                return float(f"{shown:.12g}") if isinstance(shown, float) else shown  # 2 psi, not 2.0000000000000004
            except Exception:  # a value pint cannot convert (recorded as invalid): show it as given
                return v

        display = {
            d: {"unit": PARAMETERS[d].display if units[d] else "", "values": [shown(d, v) for v in coords[d]]} for d in self.spec.dims
        }
        return {"dims": list(self.spec.dims), "coords": coords, "units": units, "display": display}

    def state(self, with_points: bool = True) -> dict:
        with self._lock:
            points = list(self.points)
        out = {
            "id": self.id,
            "status": self.status,
            "done": len(points),
            "total": self.total,
            "failed": sum(1 for p in points if p["status"] != "ok"),
            "error": self.error,
            "summary": list(self.summary),
            **self.layout(),
        }
        if with_points:
            out["points"] = points
        return out

    # ------------------------------------------------------------------ points
    def _add(self, rec: dict) -> None:
        key = tuple(rec["index"])
        with self._lock:
            if key in self._seen:
                return
            self._seen.add(key)
            point = {
                "index": list(rec["index"]),
                "settings": {k: _plain(v) for k, v in rec.get("settings", {}).items()},
                "status": rec["status"],
                "error": rec.get("error", ""),
                "values": point_values(rec.get("scalars", {})),
            }
            self.points.append(point)

    def collect_parts(self) -> None:
        """Read the points :func:`cmpsim.sweeps.sweep` saved so far (``OUT.parts/*.json``)."""
        parts = Path(str(self.out) + ".parts")
        try:
            files = sorted(parts.glob("*.json"), key=lambda p: p.stat().st_mtime)
        except OSError:
            return
        for p in files:
            if p.name == "manifest.json" or p.name.startswith("."):
                continue
            try:
                rec = json.loads(p.read_text(encoding="utf-8"))
            except (OSError, ValueError):
                continue  # removed under us (the sweep ended): the dataset has it
            if isinstance(rec, dict) and "index" in rec and "status" in rec:
                self._add(rec)

    def collect_dataset(self, ds) -> None:
        """Add the requested points the state folder no longer showed, from the final dataset."""
        skip = {"status", "error", "start"}
        for idx in self.spec.requested():
            if tuple(idx) in self._seen:
                continue
            status = str(_plain(ds["status"].values[idx]))
            values = {k: _plain(ds[k].values[idx]) for k in ds.data_vars if k not in skip and ds[k].dims == ds["status"].dims}
            if status != "ok":
                values = {}
            self._add(
                {
                    "index": list(idx),
                    "settings": self.spec.settings(idx),
                    "status": status,
                    "error": str(_plain(ds["error"].values[idx]) or ""),
                    "scalars": values,
                }
            )


class SweepJobs:
    """The server's sweeps: start, look up, cancel; owns the Dask cluster and the temporary folder.

    Parameters
    ----------
    workers : int, optional
        Worker processes of the local Dask cluster (default: the machine's cores, as ``cmpsim sweep``).
    scheduler : str, optional
        Address of an existing Dask scheduler to use instead of a local cluster.
    max_points : int
        Passed to :func:`cmpsim.sweeps.sweep` (it refuses larger sweeps before any work).
    on_finish : callable, optional
        Called with the job when it stops running (the server gives back its job slot there).
    """

    def __init__(self, workers: int | None = None, scheduler: str | None = None, max_points: int = 1000, on_finish: Callable | None = None):
        self.workers = workers
        self.scheduler = scheduler
        self.max_points = max_points
        self.on_finish = on_finish
        self.jobs: dict[str, SweepJob] = {}
        self._lock = threading.Lock()
        self._cluster = None
        self._cluster_lock = threading.Lock()
        self._dir: Path | None = None
        self._closed = False

    # ------------------------------------------------------------------ resources
    def _folder(self) -> Path:
        with self._lock:
            if self._dir is None:
                self._dir = Path(tempfile.mkdtemp(prefix="cmpsim-serve-"))
            return self._dir

    def _address(self) -> str:
        if self.scheduler:
            return self.scheduler
        with self._cluster_lock:
            if self._cluster is None:
                import os

                from ..sweeps import local_cluster

                n = self.workers
                if n is None:
                    try:
                        n = len(os.sched_getaffinity(0))
                    except AttributeError:  # pragma: no cover - macOS / Windows
                        n = os.cpu_count() or 1
                self._cluster = local_cluster(max(1, n))
            return self._cluster.scheduler_address

    def close(self) -> None:
        """Cancel running sweeps, wait for them, close the cluster and delete the files."""
        self._closed = True
        for job in list(self.jobs.values()):
            self.cancel(job.id)
        for job in list(self.jobs.values()):
            if job._thread is not None:
                job._thread.join(timeout=30)
        with self._cluster_lock:
            if self._cluster is not None:
                try:
                    self._cluster.close()
                except Exception:  # pragma: no cover - best effort at shutdown
                    log.exception("closing the Dask cluster")
                self._cluster = None
        if self._dir is not None:
            shutil.rmtree(self._dir, ignore_errors=True)

    # ------------------------------------------------------------------ jobs
    def start(self, spec) -> SweepJob:
        """Start a validated :class:`~cmpsim.sweeps.SweepSpec` in the background; returns at once."""
        job_id = uuid.uuid4().hex[:12]
        folder = self._folder() / job_id
        folder.mkdir()
        job = SweepJob(id=job_id, spec=spec, out=folder / "sweep.nc")
        with self._lock:
            self.jobs[job_id] = job
            self._forget_old()
        job._thread = threading.Thread(target=self._run, args=(job,), name=f"cmpsim-sweep-{job_id}", daemon=True)
        job._thread.start()
        return job

    def get(self, job_id: str) -> SweepJob | None:
        return self.jobs.get(job_id)

    def cancel(self, job_id: str) -> SweepJob | None:
        job = self.jobs.get(job_id)
        if job is None:
            return None
        job.cancel_requested = True
        self._cancel_futures(job)
        return job

    def remove(self, job_id: str) -> None:
        with self._lock:
            job = self.jobs.pop(job_id, None)
        if job is not None:
            shutil.rmtree(job.out.parent, ignore_errors=True)

    def _forget_old(self) -> None:
        finished = sorted((j for j in self.jobs.values() if j.finished_running), key=lambda j: j.finished or 0)
        for job in finished[: max(0, len(finished) - _KEEP_FINISHED)]:
            self.jobs.pop(job.id, None)
            shutil.rmtree(job.out.parent, ignore_errors=True)

    @staticmethod
    def _cancel_futures(job: SweepJob) -> None:
        client = job._client
        if client is None:
            return
        try:
            from distributed import Future

            keys = list(client.futures)
            if keys:
                client.cancel([Future(k, client) for k in keys])
        except Exception:  # the client may be closing: the sweep ends anyway
            log.debug("cancelling the futures of sweep %s", job.id, exc_info=True)

    def _watch(self, job: SweepJob, stop: threading.Event) -> None:
        while not stop.wait(_POLL_S):
            job.collect_parts()
            if job.cancel_requested:
                self._cancel_futures(job)

    def _run(self, job: SweepJob) -> None:
        from ..sweeps import SweepError, summary_lines, sweep

        stop = threading.Event()
        watcher = threading.Thread(target=self._watch, args=(job, stop), name=f"cmpsim-sweep-watch-{job.id}", daemon=True)
        messages: list[str] = []
        final = "cancelled"
        try:
            if job.cancel_requested or self._closed:
                return
            from distributed import Client

            address = self._address()
            job._client = Client(address, timeout="20s")
            job.status = "running"
            watcher.start()
            ds = sweep(
                job.spec,
                out=job.out,
                scheduler=job._client,
                progress=False,
                max_points=self.max_points,
                log=messages.append,
            )
            stop.set()
            watcher.join()
            job.collect_parts()
            if not job.cancel_requested:
                job.collect_dataset(ds)
                job.summary = summary_lines(ds)
                final = "done"
        except SweepError as exc:
            job.error, final = str(exc), "failed"
        except BaseException as exc:  # noqa: BLE001 - a cancelled future, a lost cluster, a bug: report it
            if not job.cancel_requested:
                log.exception("sweep %s failed", job.id)
                job.error, final = f"the sweep stopped: {type(exc).__name__}: {exc}", "failed"
        finally:
            stop.set()
            if watcher.is_alive():
                watcher.join()
            if job._client is not None:
                try:
                    job._client.close()
                except Exception:  # pragma: no cover
                    log.debug("closing the client of sweep %s", job.id, exc_info=True)
                job._client = None
            job.finished = time.time()
            if self.on_finish is not None:
                self.on_finish(job)  # gives back the job slot before anyone sees the job end
            job.status = final
