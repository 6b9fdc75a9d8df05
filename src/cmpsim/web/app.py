"""The FastAPI application of ``cmpsim serve``: the JSON HTTP API and the page that uses it.

Every route ends in the Python API: ``/api/solve`` in :meth:`cmpsim.inputs.config.Config.from_mapping`,
:func:`cmpsim.solve` and :meth:`cmpsim.results.result.Result.to_json` (the object ``cmpsim run --json``
prints); ``/api/sweeps`` in :func:`cmpsim.sweeps.sweep` (see :mod:`cmpsim.web.jobs`);
``/api/validate`` in :func:`cmpsim.validation.validate`; ``/api/die`` (an uploaded layout) in
:func:`cmpsim.die.chip.layout_die` and :func:`cmpsim.die.simulate`, as ``cmpsim die LAYOUT`` (see
:mod:`cmpsim.web.die_routes`). Bad input gets HTTP 422 with cmpsim's
own message and the parameter it names (``{"detail": ..., "parameter": ...}``); nothing the
server does wrong shows a traceback to the client.

The application is put together here from rooms of its own: :mod:`~cmpsim.web.payloads`
(request bodies to a Config, answers to JSON, :class:`InputError`), :mod:`~cmpsim.web.page`
(the page's files), :mod:`~cmpsim.web.sweep_routes` (the sweep routes over
:mod:`~cmpsim.web.jobs`), :mod:`~cmpsim.web.die_routes` (a layout uploaded, the die model run on it)
and :mod:`~cmpsim.web.guard` (the token).
"""

from __future__ import annotations

import json
import logging
import tempfile
from contextlib import asynccontextmanager
from pathlib import Path
from typing import Any, Literal

from fastapi import Body, FastAPI, Query, Request
from fastapi.exceptions import RequestValidationError
from fastapi.responses import JSONResponse, Response
from starlette.concurrency import run_in_threadpool
from starlette.exceptions import HTTPException as StarletteHTTPException

from .. import __version__
from .die_routes import die_routes
from .guard import TOKEN_COOKIE, TokenGuard
from .jobs import SweepJobs
from .limits import BodySizeLimit, Busy, JobSlots, LimitError, Limits
from .page import STATIC_FILES, page_routes
from .payloads import (
    InputError,
    config_from_request,
    error_response,
    fields_payload,
    named_parameter,
    outputs_payload,
    params_payload,
    setting_names,
    validation_payload,
)
from .sweep_routes import sweep_routes

__all__ = ["create_app", "InputError", "TOKEN_COOKIE", "STATIC_FILES", "TokenGuard", "config_from_request"]

log = logging.getLogger("cmpsim.web")

_SOLVE_EXAMPLE = {"applied_pressure": "3 psi", "rotation_speed": "60 rpm", "grid": "coarse"}


def create_app(limits: Limits | None = None, token: str | None = None, workers: int | None = None, scheduler: str | None = None) -> FastAPI:
    """The application of ``cmpsim serve``.

    Parameters
    ----------
    limits : Limits, optional
        Largest grid, sweep, body, and the number of jobs running at once (default :class:`Limits`).
    token : str, optional
        If given, every route needs it (see :class:`TokenGuard`).
    workers, scheduler
        The Dask cluster of the sweeps: a local one with ``workers`` processes (default the
        machine's cores), or the existing one at ``scheduler``.
    """
    limits = limits or Limits()
    slots = JobSlots(limits.max_jobs)
    jobs = SweepJobs(workers=workers, scheduler=scheduler, max_points=limits.max_sweep_points, on_finish=lambda job: slots.give_back())

    @asynccontextmanager
    async def lifespan(app):
        yield
        await run_in_threadpool(jobs.close)

    app = FastAPI(
        title="cmpsim",
        version=__version__,
        summary="Wafer-scale CMP simulator: the HTTP API of `cmpsim serve`.",
        description=(
            "JSON in and out; inputs as strings with units (`\"3 psi\"`) or SI numbers, named as in "
            "`cmpsim params`. Bad input: HTTP 422 `{\"detail\": message, \"parameter\": name}`."
        ),
        docs_url=None,  # FastAPI's Swagger page loads its JS from a CDN; /api/docs is served locally
        redoc_url=None,
        openapi_url="/api/openapi.json",
        redirect_slashes=False,  # a path is served as written or not at all
        lifespan=lifespan,
    )
    app.state.limits = limits
    app.state.slots = slots
    app.state.jobs = jobs
    app.add_middleware(BodySizeLimit, max_bytes=limits.max_body_bytes, max_upload=limits.max_upload_bytes)
    if token:
        app.add_middleware(TokenGuard, token=token)

    # ------------------------------------------------------------------ errors
    async def _unprocessable(request, exc: InputError | LimitError):
        return error_response(422, str(exc), exc.parameter)

    app.add_exception_handler(InputError, _unprocessable)
    app.add_exception_handler(LimitError, _unprocessable)

    @app.exception_handler(Busy)
    async def _busy(request, exc: Busy):
        return error_response(429, str(exc), None, headers={"Retry-After": str(limits.retry_after_s)})

    @app.exception_handler(RequestValidationError)
    async def _validation(request, exc: RequestValidationError):
        errors = exc.errors()
        first = errors[0] if errors else {}
        loc = [str(x) for x in first.get("loc", ())]
        kind = first.get("type", "")
        if loc[:1] == ["body"]:
            if kind == "json_invalid":
                ctx = first.get("ctx", {}).get("error", "")
                return error_response(422, f"the request body is not valid JSON{': ' + str(ctx) if ctx else ''}")
            return error_response(422, 'the request body must be a JSON object, e.g. {"applied_pressure": "3 psi"}' + ("" if len(loc) == 1 else f" ({'.'.join(loc[1:])}: {first.get('msg', '')})"))
        name = loc[-1] if loc else None
        return error_response(422, f"{name}: {first.get('msg', 'invalid value')}" if name else "invalid request", name)

    @app.exception_handler(StarletteHTTPException)
    async def _http(request, exc: StarletteHTTPException):
        return error_response(exc.status_code, str(exc.detail), None, headers=getattr(exc, "headers", None))

    @app.exception_handler(Exception)
    async def _internal(request, exc: Exception):
        # the traceback goes to the server's log (uvicorn logs the re-raised exception), never to the client
        log.error("internal error on %s %s: %s", request.method, request.url.path, type(exc).__name__)
        return error_response(500, "internal server error; it was logged on the server (please report what you sent)")

    app.include_router(page_routes())

    # ------------------------------------------------------------------ API: inputs
    @app.get("/api/info", summary="Version, limits and jobs running")
    def info():
        return {
            "cmpsim_version": __version__,
            "limits": limits.as_dict(),
            "jobs_running": slots.used,
            "token_required": bool(token),
            "sweep_cluster": f"Dask scheduler at {scheduler}" if scheduler else ("local Dask cluster, one worker per core" if workers is None else f"local Dask cluster, {workers} worker(s)"),
        }

    @app.get("/api/params", summary="Every input: name, section, default, display unit, valid range, source, choices")
    def params():
        return params_payload()

    @app.get("/api/outputs", summary="Every scalar output: name, kind, SI unit, display unit and factor, description")
    def outputs_list():
        return outputs_payload()

    # ------------------------------------------------------------------ API: one operating point
    @app.post(
        "/api/solve",
        summary="Solve one operating point",
        description=(
            "The body is a JSON object of inputs (flat, or in the sections of a config file); missing inputs "
            "take their defaults. The answer is exactly the object `cmpsim run --json` prints for the same "
            "inputs; `?format=netcdf` answers the NetCDF file of `Result.to_netcdf`; `?include=fields` adds "
            "`fields` (the wafer maps on x, y; `&fields=a,b` chooses them) to that object. 422: bad input "
            "(names the parameter) or no equilibrium (the diagnosis). 429: every job slot taken."
        ),
        responses={200: {"content": {"application/json": {}, "application/x-netcdf": {}}}},
    )
    def solve_route(
        payload: dict[str, Any] | None = Body(None, openapi_examples={"3 psi": {"value": _SOLVE_EXAMPLE}}),
        format: Literal["json", "netcdf"] = Query("json", description="json (default) or netcdf"),
        include: Literal["fields"] | None = Query(None, description="fields: add the wafer maps"),
        fields: str | None = Query(None, description="comma-separated field names for include=fields (default all)"),
    ):
        from ..solver.equilibrium import EquilibriumError
        from ..solver.model import solve

        cfg = config_from_request(payload)
        limits.check_grid(cfg.numerics.grid)
        names = [f.strip() for f in fields.split(",") if f.strip()] if fields else None
        with slots:
            try:
                result = solve(cfg)
            except EquilibriumError as exc:
                raise InputError(f"no equilibrium: {exc}") from None
            except ValueError as exc:
                raise InputError(str(exc), named_parameter(str(exc), setting_names(payload))) from None
            if format == "netcdf":
                with tempfile.TemporaryDirectory(prefix="cmpsim-serve-") as tmp:
                    data = result.to_netcdf(Path(tmp) / "result.nc").read_bytes()
                return Response(data, media_type="application/x-netcdf", headers={"Content-Disposition": 'attachment; filename="cmpsim-result.nc"'})
            text = result.to_json()  # the object `cmpsim run --json` prints
            if include != "fields":
                return Response(text, media_type="application/json")
            obj = json.loads(text)
            obj["fields"] = fields_payload(result, names)
            return JSONResponse(obj)

    # ------------------------------------------------------------------ API: zone tuning
    @app.post(
        "/api/tune-zones",
        summary="Zone pressures of a membrane head that flatten the removal profile",
        description=(
            "The body is a JSON object of inputs, as for /api/solve, of a membrane head (`carrier`: "
            "`membrane`, `zone_radii`, optionally `zone_pressures` as the start). The answer is the object "
            "`cmpsim tune-zones --json` prints: `zone_pressures` (Pa), `within_wafer_nonuniformity` (fraction), "
            "`profile` (`radius`, `rate`), `mean_rate` (m/s), `before`; with `ring=true` also `ring_pressure` (Pa). "
            "The same call as the command line (`cmpsim.head.tuning.tune_zones_from_text`). "
            "422: bad input or no equilibrium. 429: every job slot taken."
        ),
    )
    def tune_zones_route(
        payload: dict[str, Any] | None = Body(None),
        bounds: str = Query("0.5,8 psi", description="bounds of every zone pressure: LOW,HIGH and one unit"),
        keep: Literal["none", "pressure", "rate"] | None = Query(None, description="also keep the zones' mean pressure or the mean rate, or nothing; default: rate with ring, none without"),
        ring: bool = Query(False, description="also tune the retaining ring's pressure (retaining_ring_pressure is the start; the layered pad)"),
        ring_bounds: str | None = Query(None, description="bounds of the ring pressure with ring=true: LOW,HIGH and one unit (default 1.5,9 psi)"),
    ):
        from ..solver.equilibrium import EquilibriumError
        from ..head.tuning import tune_zones_from_text

        cfg = config_from_request(payload)
        limits.check_grid(cfg.numerics.grid)
        with slots:
            try:
                return JSONResponse(tune_zones_from_text(cfg, bounds, keep=keep, ring=ring, ring_bounds=ring_bounds).to_dict())
            except EquilibriumError as exc:
                raise InputError(f"no equilibrium: {exc}") from None
            except ValueError as exc:
                raise InputError(str(exc), named_parameter(str(exc), setting_names(payload))) from None

    # ------------------------------------------------------------------ API: sweeps
    app.include_router(sweep_routes(limits, slots, jobs))

    # ------------------------------------------------------------------ API: the die on an uploaded layout
    app.include_router(die_routes(limits, slots))

    # ------------------------------------------------------------------ API: validation
    @app.post(
        "/api/validate",
        summary="Model vs measurements from a CSV in the format of `cmpsim validate`",
        description=(
            "The body is the CSV text (`Content-Type: text/csv`), or JSON `{\"csv\": text, \"base\": {inputs}}`. "
            "Answers the tables `cmpsim validate` prints (per point, per data set), plus each point's numbers."
        ),
        openapi_extra={"requestBody": {"content": {"text/csv": {"schema": {"type": "string"}}, "application/json": {"schema": {"type": "object"}}}}},
    )
    async def validate_route(request: Request, grid: str | None = Query(None, description="grid preset or NRxNT for every solve")):
        raw = await request.body()
        base: Any = {}
        ctype = request.headers.get("content-type", "").split(";")[0].strip().lower()
        if ctype == "application/json":
            try:
                obj = json.loads(raw)
            except ValueError as exc:
                raise InputError(f"the request body is not valid JSON: {exc}") from None
            if not isinstance(obj, dict) or not isinstance(obj.get("csv"), str):
                raise InputError('the JSON body must be {"csv": "<the CSV text>", "base": {inputs}}', "csv")
            text, base = obj["csv"], obj.get("base") or {}
        else:
            try:
                text = raw.decode("utf-8")
            except UnicodeDecodeError:
                raise InputError("the CSV must be UTF-8 text") from None
        if grid is not None:
            if not isinstance(base, dict):
                raise InputError('"base" must be an object of inputs', "base")
            base = dict(base, grid=grid)
        return await run_in_threadpool(_validate, text, base)

    def _validate(text: str, base: Any) -> dict:
        from ..validation import load_datasets, validate

        cfg = config_from_request(base)
        limits.check_grid(cfg.numerics.grid)
        with tempfile.TemporaryDirectory(prefix="cmpsim-serve-") as tmp:
            path = Path(tmp) / "upload.csv"
            path.write_text(text, encoding="utf-8")
            try:
                datasets = load_datasets(path)
            except ValueError as exc:
                raise InputError(str(exc).replace(str(path), "upload.csv")) from None
        n = sum(len(d.points) for d in datasets)
        if n > limits.max_sweep_points:
            raise LimitError(f"the CSV has {n} data points, more than this server solves in one request ({limits.max_sweep_points}; --max-sweep-points)")
        with slots:
            report = validate(datasets, config=cfg)
        return validation_payload(report)

    return app
