"""What one client may ask of the machine: grid and sweep size, running jobs, body and upload size, die windows.

:class:`Limits` holds the numbers (``cmpsim serve`` options). The checks raise
:class:`LimitError` (the request asks for more than the server allows: HTTP 422 naming the
setting, since asking again will not help) or :class:`Busy` (every job slot is taken: HTTP 429
with ``Retry-After``). :class:`BodySizeLimit` answers 413 to a request body over the limit
before the application reads it; the routes that take an uploaded file (``/api/die``, a layout)
have a limit of their own, ``max_upload_bytes``.
"""

from __future__ import annotations

import json
import threading
from dataclasses import dataclass

__all__ = ["Limits", "LimitError", "Busy", "JobSlots", "BodySizeLimit", "UPLOAD_ROUTES", "grid_cells"]


def grid_cells(grid: str) -> tuple[int, int, int]:
    """(rings, sectors, cells) of a grid setting (preset or ``NRxNT``); ValueError if malformed."""
    from ..inputs.config import Config

    n_r, n_t = Config.default().replace(grid=grid).grid_shape
    return n_r, n_t, n_r * n_t


@dataclass(frozen=True)
class Limits:
    """Limits of one ``cmpsim serve`` (defaults: the ``cmpsim serve`` option defaults)."""

    #: Largest grid a request may use: a preset or NRxNT; compared by number of cells.
    max_grid: str = "fine"
    #: Largest sweep (points) and largest validation upload (data rows).
    max_sweep_points: int = 1000
    #: Solves, validations and sweeps running at once; one more gets 429.
    max_jobs: int = 2
    #: Largest request body, bytes; a larger one gets 413.
    max_body_bytes: int = 1_048_576
    #: Largest uploaded layout (the body of /api/die), bytes; a larger one gets 413.
    max_upload_bytes: int = 52_428_800
    #: Most windows of a die on an uploaded layout (its bounding box over the window side, squared).
    max_windows: int = 1_000_000
    #: Seconds a client is told to wait (Retry-After) when every job slot is taken.
    retry_after_s: int = 5

    def __post_init__(self):
        try:
            grid_cells(self.max_grid)
        except ValueError as exc:
            raise ValueError(f"max_grid: {exc}") from None
        for name in ("max_sweep_points", "max_jobs", "max_body_bytes", "max_upload_bytes", "max_windows", "retry_after_s"):
            v = getattr(self, name)
            if isinstance(v, bool) or not isinstance(v, int) or v < 1:
                raise ValueError(f"{name} must be an integer >= 1; got {v!r}")

    @property
    def max_cells(self) -> int:
        return grid_cells(self.max_grid)[2]

    def check_grid(self, grid: str) -> None:
        """Raise :class:`LimitError` (parameter ``grid``) if ``grid`` has more cells than allowed."""
        n_r, n_t, cells = grid_cells(grid)
        if cells > self.max_cells:
            m_r, m_t, m = grid_cells(self.max_grid)
            raise LimitError(
                f"grid {n_r}x{n_t} has {cells} cells, more than this server allows ({self.max_grid!r} = {m_r}x{m_t}, "
                f"{m} cells); choose a smaller grid, or start the server with a larger --max-grid",
                parameter="grid",
            )

    def as_dict(self) -> dict:
        n_r, n_t, cells = grid_cells(self.max_grid)
        return {
            "max_grid": self.max_grid,
            "max_grid_cells": cells,
            "max_sweep_points": self.max_sweep_points,
            "max_jobs": self.max_jobs,
            "max_body_bytes": self.max_body_bytes,
            "max_upload_bytes": self.max_upload_bytes,
            "max_windows": self.max_windows,
        }

    def check_windows(self, nx: int, ny: int, window: float) -> None:
        """Raise :class:`LimitError` (parameter ``window``) if a die of nx x ny windows is more than allowed."""
        if nx * ny > self.max_windows:
            raise LimitError(
                f"window = {window:g} m cuts the die into {nx} x {ny} = {nx * ny} windows, more than this server "
                f"allows ({self.max_windows}; --max-windows); choose a larger window",
                parameter="window",
            )


class LimitError(ValueError):
    """The request asks for more than this server allows (HTTP 422, naming the setting)."""

    def __init__(self, message: str, parameter: str | None = None):
        super().__init__(message)
        self.parameter = parameter


class Busy(RuntimeError):
    """Every job slot is taken (HTTP 429 with Retry-After)."""


class JobSlots:
    """A counter of running jobs that refuses, rather than waits, when full."""

    def __init__(self, size: int):
        self.size = size
        self._used = 0
        self._lock = threading.Lock()

    @property
    def used(self) -> int:
        return self._used

    def take(self) -> None:
        """Take a slot or raise :class:`Busy`."""
        with self._lock:
            if self._used >= self.size:
                raise Busy(
                    f"the server is running {self._used} jobs, its limit (--max-jobs {self.size}); try again shortly"
                )
            self._used += 1

    def give_back(self) -> None:
        with self._lock:
            self._used = max(0, self._used - 1)

    def __enter__(self):
        self.take()
        return self

    def __exit__(self, *exc):
        self.give_back()
        return False


class BodyTooLarge(BaseException):
    """Raised from ``receive`` when a streamed body passes the limit; :class:`BodySizeLimit`
    answers 413. A BaseException, so that no ``except Exception`` on the way (FastAPI turns
    errors while reading a body into 400) swallows it."""


def too_large_message(limit: int, option: str = "--max-body", what: str = "the request body") -> str:
    return f"{what} is larger than this server accepts ({limit} bytes = {limit / 1048576:.3g} MiB; {option})"


#: Routes whose body is an uploaded file: path -> (what the body is, the option of its limit).
UPLOAD_ROUTES = {"/api/die": ("the uploaded layout", "--max-upload")}


class BodySizeLimit:
    """ASGI middleware: 413 for a declared ``Content-Length`` over the limit, and for a body
    that streams past it (the application then sees :class:`BodyTooLarge` from ``receive``).
    The routes of :data:`UPLOAD_ROUTES` have the limit ``max_upload`` instead (default ``max_bytes``)."""

    def __init__(self, app, max_bytes: int, max_upload: int | None = None):
        self.app = app
        self.max_bytes = max_bytes
        self.max_upload = max_upload or max_bytes

    def _limit(self, scope) -> tuple[int, str]:
        """(the limit of this request's body, its message)."""
        upload = UPLOAD_ROUTES.get(scope.get("path", ""))
        if upload is not None and scope.get("method") == "POST":
            return self.max_upload, too_large_message(self.max_upload, upload[1], upload[0])
        return self.max_bytes, too_large_message(self.max_bytes)

    async def __call__(self, scope, receive, send):
        if scope["type"] != "http":
            await self.app(scope, receive, send)
            return
        limit, message = self._limit(scope)
        for key, value in scope.get("headers", []):
            if key == b"content-length":
                try:
                    declared = int(value)
                except ValueError:
                    declared = 0
                if declared > limit:
                    await self._reject(send, message)
                    return
        seen = 0

        async def limited():
            nonlocal seen
            msg = await receive()
            if msg["type"] == "http.request":
                seen += len(msg.get("body", b""))
                if seen > limit:
                    raise BodyTooLarge(message)
            return msg

        started = False

        async def watched_send(msg):
            nonlocal started
            if msg["type"] == "http.response.start":
                started = True
            await send(msg)

        try:
            await self.app(scope, limited, watched_send)
        except BodyTooLarge:
            if not started:
                await self._reject(send, message)

    async def _reject(self, send, message: str):
        body = json.dumps({"detail": message, "parameter": None}).encode()
        await send(
            {
                "type": "http.response.start",
                "status": 413,
                "headers": [(b"content-type", b"application/json"), (b"content-length", str(len(body)).encode()), (b"connection", b"close")],
            }
        )
        await send({"type": "http.response.body", "body": body})
