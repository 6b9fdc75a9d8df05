"""``cmpsim serve``: a browser UI and a JSON HTTP API over :func:`cmpsim.solve` and :func:`cmpsim.sweep`.

The page and the API are a thin client of the Python API: every solve goes through
:meth:`cmpsim.inputs.config.Config.from_mapping`, :func:`cmpsim.solve` and the JSON serialisation
that ``cmpsim run --json`` prints; every sweep through :func:`cmpsim.sweeps.sweep` on a Dask
cluster, as ``cmpsim sweep`` does. Nothing in this package knows physics.

Modules: :mod:`~cmpsim.web.app` (the FastAPI application, :func:`~cmpsim.web.app.create_app`,
put together from the others), :mod:`~cmpsim.web.payloads` (request bodies to a Config,
answers to JSON, the 422 of bad input), :mod:`~cmpsim.web.page` (the page's files),
:mod:`~cmpsim.web.sweep_routes` (the sweep routes), :mod:`~cmpsim.web.die_routes` (the die model
on an uploaded layout, as ``cmpsim die LAYOUT``), :mod:`~cmpsim.web.jobs` (background
sweeps), :mod:`~cmpsim.web.guard` (the token), :mod:`~cmpsim.web.limits` (what one client may
ask of the machine), :mod:`~cmpsim.web.server` (running it with uvicorn). The page itself is
``static/``: HTML, CSS and ES modules by job (``app.js`` starts the page and imports
``page.js``, ``http.js``, ``form.js``, ``results.js``, ``plots.js``, ``sweep.js``, ``tune.js``,
``die.js``); its
plotting library is the plotly.js bundled in the installed ``plotly`` wheel, so no request
leaves the machine.

The dependencies are an extra: ``pip install "cmpsim[web]"``. Importing this package (not its
modules) needs none of them.
"""

#: What to run when the web extra is missing.
INSTALL_HINT = 'pip install "cmpsim[web]"'

__all__ = ["INSTALL_HINT"]
