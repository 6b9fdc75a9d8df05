"""The sweep routes of ``cmpsim serve``: start a sweep in the background, follow it (state and
server-sent events), fetch its files, cancel it. The jobs themselves are :mod:`cmpsim.web.jobs`."""

from __future__ import annotations

import asyncio
import json
from typing import Any

from fastapi import APIRouter, Body, Request
from fastapi.responses import FileResponse, Response, StreamingResponse
from starlette.exceptions import HTTPException as StarletteHTTPException

from .jobs import SweepJobs
from .limits import JobSlots, LimitError, Limits
from .payloads import InputError, check_scalars, named_parameter, setting_names

__all__ = ["sweep_routes"]

_SWEEP_EXAMPLE = {
    "base": {"grid": "coarse"},
    "axes": {"applied_pressure": {"start": "2 psi", "stop": "6 psi", "num": 5}},
}


def sweep_routes(limits: Limits, slots: JobSlots, jobs: SweepJobs) -> APIRouter:
    """``/api/sweeps`` and ``/api/sweeps/{id}[/events|/result|/file]`` over the server's ``jobs``;
    a sweep takes one of the ``slots`` until it ends."""
    router = APIRouter()

    def _check_sweep_size(payload: dict) -> None:
        axes = payload.get("axes")
        if not isinstance(axes, dict):
            return
        for name, spec in axes.items():
            n = len(spec) if isinstance(spec, list) else (spec.get("num") if isinstance(spec, dict) else None)
            if isinstance(n, int) and not isinstance(n, bool) and n > limits.max_sweep_points:
                raise LimitError(
                    f"sweep [axes] {name}: {n} values, more than this server's largest sweep of "
                    f"{limits.max_sweep_points} points (--max-sweep-points)",
                    parameter=str(name),
                )

    @router.post(
        "/api/sweeps",
        status_code=202,
        summary="Start a sweep in the background",
        description=(
            "The body is the content of a sweep file as JSON: `base` (inputs), `axes` (name: list of values or "
            "{start, stop, num[, scale]}), `points` (explicit points). Answers at once with the sweep's `id` "
            "and layout; the sweep runs on the server's Dask cluster, as `cmpsim sweep` does."
        ),
    )
    def start_sweep(payload: dict[str, Any] = Body(..., openapi_examples={"pressure": {"value": _SWEEP_EXAMPLE}})):
        from ..sweeps import SweepSpec

        axes, points = payload.get("axes"), payload.get("points")
        names = [str(n) for n in axes] if isinstance(axes, dict) else []
        names += setting_names(payload.get("base"))
        for p in points if isinstance(points, list) else []:
            names += setting_names(p)
        _check_sweep_size(payload)
        if isinstance(payload.get("base"), dict):
            check_scalars(payload["base"], "sweep [base] ")
        try:
            spec = SweepSpec.from_mapping(payload, where="sweep")
            spec.check_size(limits.max_sweep_points)
        except LimitError:
            raise
        except ValueError as exc:
            raise InputError(str(exc), named_parameter(str(exc), names)) from None
        for grid in {spec.base.numerics.grid, *spec.coords.get("grid", ())}:
            try:
                limits.check_grid(grid)
            except LimitError:
                raise
            except ValueError:
                pass  # a malformed grid value: that point will be recorded as invalid
        slots.take()
        try:
            job = jobs.start(spec)
        except BaseException:
            slots.give_back()
            raise
        return {"id": job.id, "status": job.status, "total": job.total, "warnings": spec.invalid_values(), **job.layout()}

    def _job(job_id: str):
        job = jobs.get(job_id)
        if job is None:
            raise StarletteHTTPException(404, f"no sweep with id {job_id!r} on this server")
        return job

    @router.get("/api/sweeps", summary="The sweeps this server knows (without their points)")
    def list_sweeps():
        return [j.state(with_points=False) for j in list(jobs.jobs.values())]

    @router.get("/api/sweeps/{job_id}", summary="Status, done/total and the finished points of a sweep")
    def sweep_state(job_id: str):
        return _job(job_id).state()

    @router.get(
        "/api/sweeps/{job_id}/events",
        summary="Server-sent events: one `point` event per finished point, then `end`",
        response_class=StreamingResponse,
    )
    async def sweep_events(job_id: str, request: Request):
        job = _job(job_id)
        try:
            sent = max(0, int(request.headers.get("last-event-id", "0")))
        except ValueError:
            sent = 0

        async def stream():
            nonlocal sent
            yield "retry: 1000\n\n"
            while True:
                finished = job.finished_running
                while sent < job.done:
                    point = job.points[sent]
                    sent += 1
                    data = json.dumps({**point, "done": sent, "total": job.total}, allow_nan=False)
                    yield f"id: {sent}\nevent: point\ndata: {data}\n\n"
                if finished:
                    yield f"event: end\ndata: {json.dumps(job.state(with_points=False), allow_nan=False)}\n\n"
                    return
                if await request.is_disconnected():
                    return
                await asyncio.sleep(0.1)

        return StreamingResponse(stream(), media_type="text/event-stream", headers={"Cache-Control": "no-cache", "X-Accel-Buffering": "no"})

    @router.get("/api/sweeps/{job_id}/result", summary="The sweep's NetCDF file (once done)", response_class=FileResponse)
    def sweep_result(job_id: str):
        job = _job(job_id)
        if job.status != "done" or not job.out.is_file():
            raise StarletteHTTPException(409, f"the sweep is {job.status} ({job.done} of {job.total} points); its file is there once it is done")
        return FileResponse(job.out, media_type="application/x-netcdf", filename=f"cmpsim-sweep-{job.id}.nc")

    @router.get("/api/sweeps/{job_id}/file", summary="The sweep file (TOML) of a sweep, for `cmpsim sweep`")
    def sweep_file(job_id: str):
        job = _job(job_id)
        return Response(job.spec.to_toml(), media_type="application/toml", headers={"Content-Disposition": f'attachment; filename="cmpsim-sweep-{job.id}.toml"'})

    @router.delete("/api/sweeps/{job_id}", summary="Cancel a running sweep; forget a finished one")
    def delete_sweep(job_id: str):
        job = _job(job_id)
        if job.finished_running:
            jobs.remove(job_id)
            return {"id": job_id, "status": "deleted"}
        jobs.cancel(job_id)
        return {"id": job_id, "status": "cancelling"}

    return router
