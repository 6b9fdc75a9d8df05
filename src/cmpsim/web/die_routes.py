"""The die routes of ``cmpsim serve``: a layout uploaded, the die model run on it as ``cmpsim die LAYOUT`` runs it.

``POST /api/die`` takes the layout file (.gds, .gds.gz, .oas or .oas.gz; recognised from its first
bytes) as the request body and the options of ``cmpsim die LAYOUT`` as query parameters. The
upload is written to a temporary directory of its own, which is removed when the answer is
sent; the run ends in the functions the command calls, :func:`cmpsim.die.chip.layout_die` and
:func:`cmpsim.die.simulate`, and answers the object ``cmpsim die LAYOUT --json`` prints
(``?include=maps`` adds the per-window maps). Cheap checks of the query (layers, PDK, window,
limits, inputs) come before the body is read; the run holds a job slot. ``GET /api/layer-maps``
lists the named layers of the open PDKs.
"""

from __future__ import annotations

import json
import math
import os
import re
import shutil
import tempfile
from pathlib import Path
from typing import Literal

from fastapi import APIRouter, Query, Request
from fastapi.responses import JSONResponse
from starlette.concurrency import run_in_threadpool

from .limits import JobSlots, Limits
from .payloads import InputError, config_from_request, maps_payload

__all__ = ["die_routes", "DIE_MAPS", "die_parameter"]

#: The maps ``?include=maps`` answers unless ``maps=`` chooses: what the page draws (the density,
#: the final surface, and the quantities with hotspot limits).
DIE_MAPS = ["density", "thickness", "step_height", "dishing", "erosion"]

_LAYOUT_FORMATS = "GDSII (.gds), gzipped GDSII (.gds.gz) or OASIS (.oas, .oas.gz)"


def die_parameter(message: str) -> str | None:
    """The query parameter a message of cmpsim's layout and die code is about."""
    m = message.lstrip()
    if m.startswith("layout path") or m.startswith("the layout") or (m.startswith("layout ") and "has no cells" in m):
        return "layout"
    if m.startswith("top cell") or m.startswith("--top") or "top-level cells" in m:
        return "top"
    if m.startswith("layer") or m.startswith("--layer"):  # a layer the file lacks, an empty layer, an unknown name
        return "layer"
    if m.startswith("pdk"):
        return "pdk"
    if m.startswith("window") or m.startswith("--window"):
        return "window"
    if m.startswith("--spec"):
        return "spec"
    for name in ("time", "blanket_rate", "process"):
        if m.startswith(name):
            return name
    return None


def _safe_name(filename: str | None) -> str:
    """The upload's file name as the messages show it: its last part, only [A-Za-z0-9._-]."""
    name = re.sub(r"[^A-Za-z0-9._-]", "_", Path(str(filename or "")).name)[:120].lstrip(".")
    return name or "upload"


def _layers(layer: list[str] | None) -> list[str]:
    out = [s.strip() for item in (layer or []) for s in str(item).split(",") if s.strip()]
    if not out:
        raise InputError('a layout needs at least one layer: layer=L/D (e.g. 68/20), or a name with pdk (e.g. pdk=sky130&layer=met1)', "layer")
    return out


def die_routes(limits: Limits, slots: JobSlots) -> APIRouter:
    """``POST /api/die`` and ``GET /api/layer-maps``; a die run takes one of the ``slots``."""
    router = APIRouter()

    @router.get("/api/layer-maps", summary="The named layers of the open PDKs: pdk -> name -> [\"L/D\", ...] (drawn and fill)")
    def layer_maps():
        from ..layout import PDK_LAYER_MAPS

        return {pdk: {name: [f"{a}/{b}" for a, b in pairs] for name, pairs in names.items()} for pdk, names in PDK_LAYER_MAPS.items()}

    @router.post(
        "/api/die",
        summary="The die model on an uploaded layout (GDSII/OASIS), as `cmpsim die LAYOUT --json`",
        description=(
            "The body is the layout file itself (`Content-Type: application/octet-stream`; .gds, .gds.gz, .oas or .oas.gz, "
            "recognised from its first bytes), at most the server's upload limit (413 beyond it). The query holds the "
            "options of `cmpsim die LAYOUT`: `layer` (repeatable or comma-separated, `L/D` or a name with `pdk`), "
            "`window`, `process`, `spec` (repeatable `KIND=LIMIT`), `top`, `time`, `blanket_rate`, `weighting`, and "
            "`inputs`, the inputs of the wafer solve as a JSON object (as the body of /api/solve). The answer is the "
            "object `cmpsim die LAYOUT --json` prints; `include=maps` adds `maps` (the per-window maps on the window "
            "centres x, y, m; `maps=a,b` chooses them). 422: not a layout, a layer it lacks or without shapes, a window "
            "larger than the die, an unknown PDK layer (each naming the parameter). 429: every job slot taken."
        ),
        openapi_extra={"requestBody": {"required": True, "content": {"application/octet-stream": {"schema": {"type": "string", "format": "binary"}}}}},
    )
    async def die_route(
        request: Request,
        layer: list[str] | None = Query(None, description="a layer/datatype (68/20) or a name with pdk (met1); repeatable, all merged"),
        pdk: str | None = Query(None, description="the open PDK whose layer map names the layers: sky130, gf180mcu or sg13g2"),
        window: str = Query("20 um", description="the window side with units: every window a cell of the die model"),
        process: Literal["oxide", "copper"] = Query("oxide", description="oxide ILD planarization or copper damascene"),
        spec: list[str] | None = Query(None, description="a hotspot limit KIND=LIMIT: thickness=5nm, step_height=20nm, dishing=30nm, erosion=20nm"),
        top: str | None = Query(None, description="the top cell, where the file has several"),
        time: str | None = Query(None, description="polishing time with units (default: the end point times 1 + over_polish)"),
        blanket_rate: str | None = Query(None, description="blanket rate with units (default: the wafer-mean rate of the wafer solve)"),
        weighting: Literal["gaussian", "pad", "elliptic"] = Query("gaussian", description="weighting function of the effective density"),
        inputs: str | None = Query(None, description="the inputs of the wafer solve, a JSON object as the body of /api/solve"),
        filename: str | None = Query(None, description="the file's name, as the messages show it"),
        include: Literal["maps"] | None = Query(None, description="maps: add the per-window maps"),
        maps: str | None = Query(None, description=f"comma-separated maps for include=maps (default {','.join(DIE_MAPS)})"),
    ):
        from ..die.hotspots import parse_spec
        from ..inputs.units import to_si
        from ..layout import PDK_LAYER_MAPS, resolve_layers

        # ---- the query, checked before the body is read
        layers = _layers(layer)
        if pdk is not None and pdk not in PDK_LAYER_MAPS:
            raise InputError(f"pdk {pdk!r} is unknown; valid: {sorted(PDK_LAYER_MAPS)}", "pdk")
        try:
            resolve_layers(layers, pdk=pdk)
            window_m = to_si(window, "m", "window", "20 um")
            if not (math.isfinite(window_m) and window_m > 0):
                raise ValueError(f"window = {window!r} must be a positive length, e.g. 20 um")
            limits_m = parse_spec(list(spec or []))
            t = to_si(time, "s", "time", "90 s") if time else None
            rate = to_si(blanket_rate, "m/s", "blanket_rate", "200 nm/min") if blanket_rate else None
        except ValueError as exc:
            raise InputError(str(exc), die_parameter(str(exc))) from None
        try:
            base = json.loads(inputs) if inputs else {}
        except ValueError as exc:
            raise InputError(f"inputs is not valid JSON ({exc}); give the inputs of the wafer solve as a JSON object", "inputs") from None
        cfg = config_from_request(base)
        limits.check_grid(cfg.numerics.grid)
        calibrated = _calibrated(base, process, weighting)
        names = [n.strip() for n in maps.split(",") if n.strip()] if maps else None

        # ---- the upload, into a directory of its own, removed with everything in it
        name = _safe_name(filename)
        folder = Path(tempfile.mkdtemp(prefix="cmpsim-serve-die-"))
        try:
            path = folder / name
            size = 0
            with open(path, "wb") as fh:
                async for chunk in request.stream():
                    fh.write(chunk)
                    size += len(chunk)
            if size == 0:
                raise InputError(f"the request body is empty: send the layout file ({_LAYOUT_FORMATS}) as the body", "layout")
            run = dict(path=path, name=name, layers=layers, pdk=pdk, window=window_m, process=process, spec=limits_m, top=top,
                       time=t, blanket_rate=rate, weighting=weighting, config=cfg, include=include, names=names, calibrated=calibrated)
            return await run_in_threadpool(_run, **run)
        finally:
            shutil.rmtree(folder, ignore_errors=True)

    def _run(path: Path, name: str, layers, pdk, window, process, spec, top, time, blanket_rate, weighting, config, include, names, calibrated):
        from ..die import simulate
        from ..die.chip import layout_die
        from ..layout import read_layout, top_cell
        from ..solver.equilibrium import EquilibriumError

        def clean(message: str) -> str:  # the messages name the upload, never the server's folders
            return message.replace(str(path), name).replace(str(path.parent) + os.sep, "")

        with slots:
            try:
                layout = read_layout(path)
                cell = top_cell(layout, top)
                box = cell.bbox()
                w = round(window / layout.dbu)  # in database units, as the extraction counts
                if not box.empty() and w > 0:
                    nx = max(-(-box.width() // w), 1)
                    ny = max(-(-box.height() // w), 1)
                    limits.check_windows(nx, ny, window)
                die = layout_die(layout, layers, window, top=top, pdk=pdk)  # as `cmpsim die LAYOUT --layer ...`
                result = simulate(die, time, config=config, blanket_rate=blanket_rate, weighting=weighting, spec=spec, **calibrated)
            except EquilibriumError as exc:
                raise InputError(f"no equilibrium of the wafer solve: {exc}") from None
            except ValueError as exc:
                if hasattr(exc, "parameter"):  # a LimitError
                    raise
                text = clean(str(exc))
                raise InputError(text, die_parameter(text)) from None
            obj = json.loads(json.dumps(result.to_dict(), allow_nan=False))  # the object `cmpsim die LAYOUT --json` prints
            if include == "maps":
                obj["maps"] = maps_payload(result.dataset(), names, "maps", default=DIE_MAPS)
            return JSONResponse(obj)

    return router


def _calibrated(base, process: str, weighting: str) -> dict:
    """The die keywords of a run whose inputs are a process file of `cmpsim calibrate` (its JSON): the calibrated die
    constants of ``calibration.die`` and their covariance (hotspots with interval and probability); else the process."""
    from ..calibration.processfile import apply_die_constants, die_constants

    try:
        dc = die_constants(base) if isinstance(base, dict) else None
        out = apply_die_constants({"process": process, "weighting": weighting}, dc,
                                  option={"process": "process", "weighting": "weighting", "planarization_length": "planarization_length", "param": "inputs"})
    except ValueError as exc:
        raise InputError(str(exc), "process" if str(exc).startswith("process") else "weighting" if str(exc).startswith("weighting") else "inputs") from None
    out.pop("weighting", None)
    return out
