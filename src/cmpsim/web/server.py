"""Running the application with uvicorn: in the foreground (``cmpsim serve``) or in a thread.

:func:`serve` is what the command line calls. :func:`start_in_background` runs a server on a
free port of 127.0.0.1 in a thread and returns its address and a stop function: the tests and
the documentation's screenshot script use it.
"""

from __future__ import annotations

import socket
import threading
import time
from dataclasses import dataclass
from typing import Callable

from .limits import Limits

__all__ = ["serve", "start_in_background", "BackgroundServer", "LOOPBACK"]

#: Hosts that only this machine can reach.
LOOPBACK = ("127.0.0.1", "localhost", "::1")


def serve(
    host: str = "127.0.0.1",
    port: int = 8000,
    limits: Limits | None = None,
    token: str | None = None,
    workers: int | None = None,
    scheduler: str | None = None,
    echo: Callable[[str], None] = print,
    warn: Callable[[str], None] = lambda message: print(f"warning: {message}"),
) -> None:
    """Serve until interrupted; says in one line where to point the browser (``echo``), and
    gives ``warn`` the text of a warning (the command line prints it as ``cmpsim: warning: ...``)."""
    import uvicorn

    from .app import create_app

    if host not in LOOPBACK:
        warn(
            f"--host {host} makes the server reachable from other machines"
            + (
                "; every request needs the token"
                if token
                else ": anyone who reaches it can run solves and sweeps here. Set --token (or CMPSIM_TOKEN) to require a token"
            )
        )
    app = create_app(limits=limits, token=token, workers=workers, scheduler=scheduler)
    shown = "127.0.0.1" if host in ("0.0.0.0", "::") else host
    shown = f"[{shown}]" if ":" in shown else shown
    url = f"http://{shown}:{port}/" + (f"?token={token}" if token else "")
    echo(f"cmpsim serve: open {url} in a browser (API reference at /api/docs; Ctrl-C stops)")
    uvicorn.run(app, host=host, port=port, log_level="warning", access_log=False)


@dataclass
class BackgroundServer:
    """A server running in a thread: its base URL (``http://127.0.0.1:PORT``) and how to stop it."""

    url: str
    app: object
    _server: object
    _thread: threading.Thread

    def stop(self, timeout: float = 30.0) -> None:
        self._server.should_exit = True
        self._thread.join(timeout)

    def __enter__(self):
        return self

    def __exit__(self, *exc):
        self.stop()
        return False


def start_in_background(app, host: str = "127.0.0.1", timeout: float = 30.0) -> BackgroundServer:
    """Run ``app`` with uvicorn on a free port of ``host`` in a daemon thread; wait until it listens."""
    import uvicorn

    sock = socket.socket(socket.AF_INET, socket.SOCK_STREAM)
    sock.setsockopt(socket.SOL_SOCKET, socket.SO_REUSEADDR, 1)
    sock.bind((host, 0))
    port = sock.getsockname()[1]
    config = uvicorn.Config(app, log_level="warning", access_log=False, lifespan="on")
    server = uvicorn.Server(config)
    thread = threading.Thread(target=server.run, kwargs={"sockets": [sock]}, name="cmpsim-serve", daemon=True)
    thread.start()
    t0 = time.monotonic()
    while not server.started:
        if not thread.is_alive() or time.monotonic() - t0 > timeout:
            raise RuntimeError("the cmpsim server did not start")
        time.sleep(0.02)
    return BackgroundServer(f"http://{host}:{port}", app, server, thread)
