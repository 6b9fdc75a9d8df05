"""The page of ``cmpsim serve``: the files of ``static/`` and the plotly.js of the installed
``plotly`` wheel, served by name from a fixed list, so that no other path on the disk is
reachable and no request leaves the machine.

The page is ES modules (``app.js`` imports the others); each module is one entry of
:data:`STATIC_FILES`.
"""

from __future__ import annotations

from importlib import resources
from pathlib import Path

from fastapi import APIRouter
from fastapi.responses import FileResponse

from .payloads import error_response

__all__ = ["STATIC_FILES", "page_routes", "static_dir", "plotly_js"]

_JS = "text/javascript; charset=utf-8"
#: The only files the server sends besides the API: name -> media type.
STATIC_FILES = {
    "index.html": "text/html; charset=utf-8",
    "app.css": "text/css; charset=utf-8",
    # the page's modules: app.js starts it and imports the others
    "app.js": _JS,
    "http.js": _JS,
    "page.js": _JS,
    "form.js": _JS,
    "results.js": _JS,
    "plots.js": _JS,
    "sweep.js": _JS,
    "tune.js": _JS,
    "die.js": _JS,
    # the local page of the HTTP API
    "api.html": "text/html; charset=utf-8",
    "api.js": _JS,
    "plotly.min.js": _JS,  # from the installed plotly wheel
}
_NO_SNIFF = {"X-Content-Type-Options": "nosniff"}


def static_dir() -> Path:
    """The ``static/`` folder of the installed package."""
    return Path(str(resources.files("cmpsim.web") / "static"))


def plotly_js() -> Path | None:
    """plotly.min.js of the installed ``plotly`` wheel (None without it)."""
    try:
        path = Path(str(resources.files("plotly") / "package_data" / "plotly.min.js"))
    except ModuleNotFoundError:  # pragma: no cover - plotly is in the web extra
        return None
    return path if path.is_file() else None


def _file(name: str, static: Path):
    if name not in STATIC_FILES:
        return error_response(404, "Not Found")
    path = plotly_js() if name == "plotly.min.js" else static / name
    if path is None or not path.is_file():
        return error_response(404, "Not Found")
    cache = "public, max-age=86400" if name == "plotly.min.js" else "no-cache"
    return FileResponse(path, media_type=STATIC_FILES[name], headers={**_NO_SNIFF, "Cache-Control": cache})


def page_routes() -> APIRouter:
    """``/`` (the page), ``/api/docs`` (the page of the HTTP API) and ``/static/{name}``."""
    router = APIRouter()
    static = static_dir()

    @router.get("/", include_in_schema=False)
    def index():
        return _file("index.html", static)

    @router.get("/api/docs", include_in_schema=False)
    def api_docs():
        return _file("api.html", static)

    @router.get("/static/{name}", include_in_schema=False)
    def static_file(name: str):
        return _file(name, static)

    return router
