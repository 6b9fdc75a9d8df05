"""``cmpsim serve``: the browser UI and the JSON HTTP API (the web extra)."""

from __future__ import annotations

import click

from .group import _fail, _warn, main


@main.command(name="serve")
@click.option("--host", default="127.0.0.1", show_default=True, help="Address to listen on; anything but loopback warns (then use --token).")
@click.option("--port", type=click.IntRange(1, 65535), default=8000, show_default=True, help="Port to listen on.")
@click.option("--token", envvar="CMPSIM_TOKEN", default=None, help="Require this token on every route (env: CMPSIM_TOKEN); open the page as /?token=TOKEN.")
@click.option("--max-grid", default="fine", show_default=True, help="Largest grid a request may use (preset or NRxNT; compared by cells).")
@click.option("--max-sweep-points", type=click.IntRange(min=1), default=1000, show_default=True, help="Largest sweep (points) and validation upload (rows).")
@click.option("--max-jobs", type=click.IntRange(min=1), default=2, show_default=True, help="Solves, validations and sweeps running at once; more get HTTP 429 with Retry-After.")
@click.option("--max-body", type=click.IntRange(min=1024), default=1_048_576, show_default=True, help="Largest request body in bytes; larger gets HTTP 413.")
@click.option("--max-upload", type=click.IntRange(min=1024), default=52_428_800, show_default=True, help="Largest uploaded layout (POST /api/die) in bytes; larger gets HTTP 413.")
@click.option("--max-windows", type=click.IntRange(min=1), default=1_000_000, show_default=True, help="Most windows of a die on an uploaded layout; more gets HTTP 422 naming window.")
@click.option("--workers", type=click.IntRange(min=1), default=None, help="Worker processes of the local Dask cluster of the sweeps (default: the machine's cores).")
@click.option("--scheduler", metavar="ADDRESS", help="Run the sweeps on an existing Dask cluster, e.g. tcp://host:8786.")
def serve_command(host, port, token, max_grid, max_sweep_points, max_jobs, max_body, max_upload, max_windows, workers, scheduler):
    """Start the browser UI and the JSON HTTP API (needs the extra: pip install "cmpsim[web]").

    The page at / solves operating points, draws the wafer maps, runs sweeps and polishes a
    die on an uploaded layout; the API (/api/solve, /api/sweeps, /api/validate, /api/die, ...;
    reference at /api/docs) answers what `cmpsim run --json`, `cmpsim sweep`, `cmpsim validate`
    and `cmpsim die LAYOUT --json` give. See docs/web.md.
    """
    from ..web import INSTALL_HINT

    try:
        from ..web.limits import Limits
        from ..web.server import serve

        import fastapi, uvicorn  # noqa: E401,F401 - the web extra
    except ImportError as exc:
        _fail(f"`cmpsim serve` needs the web extra ({exc.name or exc} is missing): {INSTALL_HINT}")
    try:
        limits = Limits(max_grid=max_grid, max_sweep_points=max_sweep_points, max_jobs=max_jobs, max_body_bytes=max_body,
                        max_upload_bytes=max_upload, max_windows=max_windows)
    except ValueError as exc:
        _fail(str(exc).replace("max_grid:", "--max-grid:"))
    if workers is not None and scheduler is not None:
        _fail("give either --workers (a local cluster) or --scheduler (an existing cluster), not both")
    serve(host, port, limits=limits, token=token or None, workers=workers, scheduler=scheduler, echo=click.echo, warn=_warn)
