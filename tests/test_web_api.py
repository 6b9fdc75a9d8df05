"""The HTTP API of `cmpsim serve`: same answers as the CLI and the Python API, clean errors, limits.

FastAPI's TestClient drives the application in-process; one test talks to a real uvicorn
server through a raw socket (path traversal is checked on the bytes a client can send).
The sweeps run on a one-worker local Dask cluster that the application starts at its first sweep.
"""

from __future__ import annotations

import json
import re
import socket
import sys
import time
import tomllib
from pathlib import Path

import numpy as np
import pytest

pytest.importorskip("fastapi", reason='the web extra is not installed: pip install "cmpsim[web]"')
pytest.importorskip("httpx", reason="FastAPI's TestClient needs httpx")

from click.testing import CliRunner  # noqa: E402
from fastapi.testclient import TestClient  # noqa: E402

import cmpsim  # noqa: E402
from cmpsim.cli import main  # noqa: E402
from cmpsim.inputs.config import PARAMETERS, Config  # noqa: E402
from cmpsim.web.app import create_app  # noqa: E402
from cmpsim.web.limits import Limits  # noqa: E402

pytestmark = pytest.mark.filterwarnings("ignore::DeprecationWarning")

DATA = Path(cmpsim.__file__).parent / "data"
LIMITS = Limits(max_grid="default", max_sweep_points=20, max_jobs=2, max_body_bytes=64 * 1024)


@pytest.fixture(scope="module")
def client():
    app = create_app(LIMITS, workers=1)
    with TestClient(app) as c:
        yield c


def _run_json(*sets: str) -> dict:
    args = ["run", "--json"]
    for s in sets:
        args += ["--set", s]
    res = CliRunner().invoke(main, args)
    assert res.exit_code == 0, res.output
    return json.loads(res.stdout)


# ---------------------------------------------------------------------------- inputs


def test_params_lists_every_input_with_its_unit_range_source_and_choices(client):
    r = client.get("/api/params")
    assert r.status_code == 200
    body = r.json()
    by_name = {p["name"]: p for p in body["parameters"]}
    assert list(by_name) == list(PARAMETERS)
    assert body["sections"] == ["wafer", "process", "slurry", "pad", "numerics"]
    p = by_name["applied_pressure"]
    assert (p["section"], p["unit"], p["display_unit"], p["default_display"]) == ("process", "Pa", "psi", "4")
    assert p["range"] == PARAMETERS["applied_pressure"].range_text() and p["source"]
    assert by_name["model"]["choices"] == ["lep", "elastic", "hydrodynamic"] and by_name["model"]["kind"] == "choice"
    assert by_name["grid"]["kind"] == "grid"


# ---------------------------------------------------------------------------- solve


def test_outputs_lists_every_scalar_of_a_solve_with_its_display_unit(client):
    from cmpsim.results import outputs

    r = client.get("/api/outputs")
    assert r.status_code == 200
    listed = {o["name"]: o for o in r.json()}
    body = client.post("/api/solve", json={"grid": "coarse"}).json()
    assert set(body["values"]) | set(body["solver"]) <= set(listed)
    for name, o in listed.items():
        entry = outputs.scalar(name)
        assert (o["unit"], o["display_unit"], o["display_factor"], o["long_name"]) == (entry.unit, entry.display_unit, entry.display_factor, entry.long_name)
        assert o["unit"] == body["units"].get(name, o["unit"])  # the same SI unit the solve answers with
    assert (listed["film_thickness_center"]["display_unit"], listed["film_thickness_center"]["display_factor"]) == ("um", 1e6)


def test_solve_answers_exactly_the_object_cmpsim_run_json_prints(client):
    r = client.post("/api/solve", json={"applied_pressure": "3 psi", "grid": "coarse"})
    assert r.status_code == 200 and r.headers["content-type"] == "application/json"
    assert r.json() == _run_json("applied_pressure=3psi", "grid=coarse")
    assert r.json() == json.loads(cmpsim.solve(applied_pressure="3 psi", grid="coarse").to_json())


def test_solve_takes_si_numbers_and_config_sections_as_the_cli_does(client):
    by_unit = client.post("/api/solve", json={"applied_pressure": "20.7 kPa", "grid": "coarse"}).json()
    by_si = client.post("/api/solve", json={"process": {"applied_pressure": 20700.0}, "numerics": {"grid": "coarse"}}).json()
    assert by_si == by_unit == _run_json("applied_pressure=20.7kPa", "grid=coarse")


def test_solve_as_netcdf_is_the_file_result_to_netcdf_writes(client, tmp_path):
    import xarray as xr

    r = client.post("/api/solve?format=netcdf", json={"applied_pressure": "3 psi", "grid": "coarse"})
    assert r.status_code == 200 and r.headers["content-type"] == "application/x-netcdf"
    assert r.content[:3] == b"CDF"
    (tmp_path / "r.nc").write_bytes(r.content)
    ds = xr.open_dataset(tmp_path / "r.nc", engine="scipy")
    expected = cmpsim.solve(applied_pressure="3 psi", grid="coarse")
    assert ds["film_thickness_center"].item() == expected.film_thickness_center
    np.testing.assert_array_equal(ds["removal_rate"].values, expected.fields["removal_rate"].values)


def test_include_fields_adds_the_wafer_maps_and_changes_nothing_else(client):
    plain = client.post("/api/solve", json={"grid": "coarse"}).json()
    r = client.post("/api/solve?include=fields&fields=removal_rate,film_thickness", json={"grid": "coarse"})
    assert r.status_code == 200
    body = r.json()
    fields = body.pop("fields")
    assert body == plain
    assert set(fields["maps"]) == {"removal_rate", "film_thickness"}
    z = np.array(fields["maps"]["film_thickness"]["z"], dtype=float)  # null (outside the wafer) -> nan
    assert z.shape == (len(fields["y"]), len(fields["x"]))
    assert np.isnan(z[0, 0]) and np.isfinite(z[z.shape[0] // 2, z.shape[1] // 2])
    assert fields["maps"]["film_thickness"]["units"] == "m"
    bad = client.post("/api/solve?include=fields&fields=no_such_field", json={"grid": "coarse"})
    assert bad.status_code == 422 and bad.json()["parameter"] == "fields"


def _cmpsim_message(**inputs) -> str:
    with pytest.raises(ValueError) as info:
        Config.from_mapping(inputs)
    return str(info.value)


@pytest.mark.parametrize(
    "body, parameter",
    [
        ({"applied_pressure": "3 kg"}, "applied_pressure"),  # wrong dimension
        ({"applied_pressure": "-3 psi"}, "applied_pressure"),  # out of range
        ({"pad_poisson": 0.7}, "pad_poisson"),  # out of range, SI number
        ({"no_such_input": "3 psi"}, "no_such_input"),  # unknown parameter
        ({"model": "quantum"}, "model"),  # not one of the choices
        ({"process": {"particle_diameter": "100 nm"}}, "particle_diameter"),  # wrong section
    ],
    ids=["wrong-dimension", "out-of-range", "out-of-range-si", "unknown", "bad-choice", "wrong-section"],
)
def test_bad_input_is_422_with_cmpsims_own_message_naming_the_parameter(client, body, parameter):
    r = client.post("/api/solve", json=body)
    assert r.status_code == 422
    assert r.json() == {"detail": _cmpsim_message(**body), "parameter": parameter}
    assert parameter in r.json()["detail"]


@pytest.mark.parametrize(
    "content, parameter, words",
    [
        (b'{"applied_pressure": "3 psi"', None, "not valid JSON"),
        (b'["applied_pressure", "3 psi"]', None, "JSON object"),
        (b'{"applied_pressure": ["3 psi"]}', "applied_pressure", "got a JSON array"),
        (b'{"applied_pressure": true}', "applied_pressure", "got a JSON bool"),
    ],
    ids=["malformed", "not-an-object", "array-value", "boolean-value"],
)
def test_a_malformed_body_is_422_not_500(client, content, parameter, words):
    r = client.post("/api/solve", content=content, headers={"content-type": "application/json"})
    assert r.status_code == 422
    assert r.json()["parameter"] == parameter and words in r.json()["detail"]


def test_an_unknown_query_value_is_422_naming_it(client):
    r = client.post("/api/solve?format=xml", json={})
    assert r.status_code == 422 and r.json()["parameter"] == "format"


def test_no_equilibrium_is_422_with_the_diagnosis_the_cli_prints(client):
    r = client.post("/api/solve", json={"applied_pressure": "1000 psi", "grid": "coarse"})
    assert r.status_code == 422
    detail = r.json()["detail"]
    assert detail.startswith("no equilibrium: ") and "lower applied_pressure" in detail
    cli = CliRunner().invoke(main, ["run", "--json", "--set", "applied_pressure=1000psi", "--set", "grid=coarse"])
    assert cli.exit_code == 3 and detail in cli.stderr


def test_an_internal_error_is_a_clean_500_without_traceback(monkeypatch):
    import cmpsim.solver.model

    def broken(*args, **kwargs):
        raise RuntimeError("internal detail that must not reach the client")

    monkeypatch.setattr(cmpsim.solver.model, "solve", broken)
    with TestClient(create_app(LIMITS, workers=1), raise_server_exceptions=False) as c:
        r = c.post("/api/solve", json={"grid": "coarse"})
    assert r.status_code == 500 and r.headers["content-type"] == "application/json"
    assert set(r.json()) == {"detail", "parameter"}
    for leak in ("Traceback", 'File "', "internal detail", "RuntimeError"):
        assert leak not in r.text


# ---------------------------------------------------------------------------- limits


def test_a_grid_larger_than_the_servers_limit_is_refused_naming_grid(client):
    r = client.post("/api/solve", json={"grid": "fine"})
    assert r.status_code == 422 and r.json()["parameter"] == "grid"
    assert "--max-grid" in r.json()["detail"]


def test_more_jobs_than_the_limit_get_429_with_retry_after():
    app = create_app(Limits(max_jobs=1, retry_after_s=7), workers=1)
    with TestClient(app) as c:
        app.state.slots.take()  # a job is running
        try:
            r = c.post("/api/solve", json={"grid": "coarse"})
            assert r.status_code == 429 and r.headers["retry-after"] == "7"
            assert "--max-jobs 1" in r.json()["detail"]
            s = c.post("/api/sweeps", json={"base": {"grid": "coarse"}, "axes": {"applied_pressure": ["2 psi"]}})
            assert s.status_code == 429 and s.headers["retry-after"] == "7"
        finally:
            app.state.slots.give_back()
        assert c.post("/api/solve", json={"grid": "coarse"}).status_code == 200


def test_a_body_over_the_size_limit_is_413_declared_or_streamed(client):
    big = json.dumps({"applied_pressure": "3 psi", "pad": {"x" * 70_000: 1}}).encode()
    assert client.post("/api/solve", content=big, headers={"content-type": "application/json"}).status_code == 413

    def chunks():  # no Content-Length: the server counts what arrives
        for _ in range(70):
            yield b" " * 1024

    r = client.post("/api/solve", content=chunks(), headers={"content-type": "application/json"})
    assert r.status_code == 413 and "--max-body" in r.json()["detail"]


def test_a_sweep_larger_than_the_limit_is_refused_before_any_work(client):
    # refused as read (num above 10 million): nothing of size 1e9 is built (no time asserted: building it would exhaust memory)
    r = client.post("/api/sweeps", json={"axes": {"applied_pressure": {"start": "2 psi", "stop": "6 psi", "num": 10**9}}})
    assert r.status_code == 422 and r.json()["parameter"] == "applied_pressure"
    r = client.post("/api/sweeps", json={"axes": {"applied_pressure": ["2 psi", "3 psi", "4 psi", "5 psi", "6 psi"], "rotation_speed": {"start": "30 rpm", "stop": "90 rpm", "num": 5}}})
    assert r.status_code == 422 and "more than the maximum of 20" in r.json()["detail"]
    r = client.post("/api/sweeps", json={"base": {"grid": "fine"}, "axes": {"applied_pressure": ["2 psi"]}})
    assert r.status_code == 422 and r.json()["parameter"] == "grid"


def test_a_bad_sweep_is_422_with_the_message_of_cmpsim_sweep(client):
    from cmpsim.sweeps import SweepError, SweepSpec

    body = {"axes": {"applied_pressure": ["2 psi", "3 kg"]}}
    with pytest.raises(SweepError) as info:
        SweepSpec.from_mapping(body, where="sweep")
    r = client.post("/api/sweeps", json=body)
    assert r.status_code == 422 and r.json() == {"detail": str(info.value), "parameter": "applied_pressure"}


# ---------------------------------------------------------------------------- sweeps


def _events(client, job_id: str) -> list[tuple[str, dict]]:
    events, kind = [], None
    with client.stream("GET", f"/api/sweeps/{job_id}/events") as s:
        assert s.headers["content-type"].startswith("text/event-stream")
        for line in s.iter_lines():
            if line.startswith("event: "):
                kind = line[7:]
            elif line.startswith("data: "):
                events.append((kind, json.loads(line[6:])))
    return events


@pytest.mark.slow
def test_a_three_point_sweep_runs_to_completion_with_one_event_per_point(client, tmp_path):
    import xarray as xr

    from cmpsim.sweeps import sweep

    body = {"base": {"grid": "coarse"}, "axes": {"applied_pressure": ["2 psi", "3 psi", "1000 psi"]}}
    r = client.post("/api/sweeps", json=body)
    assert r.status_code == 202
    job = r.json()
    assert job["total"] == 3 and job["dims"] == ["applied_pressure"]
    assert job["display"]["applied_pressure"] == {"unit": "psi", "values": [2.0, 3.0, 1000.0]}

    events = _events(client, job["id"])
    points = [e for k, e in events if k == "point"]
    assert [k for k, _ in events] == ["point"] * 3 + ["end"]
    assert [p["done"] for p in points] == [1, 2, 3] and {p["total"] for p in points} == {3}
    by_index = {p["index"][0]: p for p in points}
    assert [by_index[i]["status"] for i in range(3)] == ["ok", "ok", "failed"]
    assert by_index[2]["error"].startswith("no equilibrium:")
    assert events[-1][1]["status"] == "done" and events[-1][1]["failed"] == 1

    state = client.get(f"/api/sweeps/{job['id']}").json()
    assert (state["status"], state["done"], state["total"]) == ("done", 3, 3)

    # the file is what `cmpsim sweep` writes for the same sweep
    nc = client.get(f"/api/sweeps/{job['id']}/result")
    assert nc.status_code == 200 and nc.content[:3] == b"CDF"
    (tmp_path / "web.nc").write_bytes(nc.content)
    got = xr.open_dataset(tmp_path / "web.nc", engine="scipy")
    expected = sweep(body, out=tmp_path / "cli.nc", workers=0, progress=False)
    assert got["status"].values.tolist() == expected["status"].values.tolist()
    np.testing.assert_allclose(got["film_thickness_center"].values, expected["film_thickness_center"].values, rtol=1e-12)
    for i in range(2):
        assert by_index[i]["values"]["film_thickness_center"] == pytest.approx(float(expected["film_thickness_center"].values[i]), rel=1e-12)

    toml = client.get(f"/api/sweeps/{job['id']}/file")
    assert toml.status_code == 200 and tomllib.loads(toml.text) == body

    assert client.delete(f"/api/sweeps/{job['id']}").json()["status"] == "deleted"
    assert client.get(f"/api/sweeps/{job['id']}").status_code == 404


@pytest.mark.slow
def test_delete_cancels_a_running_sweep(client):
    body = {"base": {"grid": "default"}, "axes": {"applied_pressure": {"start": "2 psi", "stop": "6 psi", "num": 20}}}
    job = client.post("/api/sweeps", json=body).json()
    deadline = time.monotonic() + 60
    while client.get(f"/api/sweeps/{job['id']}").json()["done"] < 1:
        assert time.monotonic() < deadline
        time.sleep(0.05)
    assert client.delete(f"/api/sweeps/{job['id']}").json()["status"] == "cancelling"
    events = _events(client, job["id"])  # ends once the sweep has stopped
    end = events[-1][1]
    assert events[-1][0] == "end" and end["status"] == "cancelled" and end["done"] < 20
    assert client.get(f"/api/sweeps/{job['id']}/result").status_code == 409
    assert client.get("/api/info").json()["jobs_running"] == 0  # the job slot was given back


def test_an_unknown_sweep_is_404(client):
    for method, path in [("GET", "/api/sweeps/nope"), ("GET", "/api/sweeps/nope/events"), ("GET", "/api/sweeps/nope/result"), ("DELETE", "/api/sweeps/nope")]:
        assert client.request(method, path).status_code == 404


# ---------------------------------------------------------------------------- validate


def test_validate_answers_the_tables_cmpsim_validate_prints(client):
    from cmpsim.validation import validate

    path = DATA / "sun2010_real_contact_area.csv"
    r = client.post("/api/validate?grid=coarse", content=path.read_bytes(), headers={"content-type": "text/csv"})
    assert r.status_code == 200
    body = r.json()
    report = validate([path], config=Config.default().replace(grid="coarse"))
    assert body["points"] == {"header": report.POINT_HEADER, "rows": report.point_rows()}
    assert body["datasets"] == {"header": report.DATASET_HEADER, "rows": report.dataset_rows()}
    as_json = client.post("/api/validate", json={"csv": path.read_text(), "base": {"grid": "coarse"}}).json()
    assert as_json["points"] == body["points"]


def test_validate_a_bad_csv_is_422_naming_the_line(client):
    text = "quantity,value,unit,applied_pressure\nremoval_rate,100,nm/min,3 kg\n"
    r = client.post("/api/validate?grid=coarse", content=text.encode(), headers={"content-type": "text/csv"})
    assert r.status_code == 422
    detail = r.json()["detail"]
    assert detail.startswith("upload.csv:2:") and "applied_pressure" in detail and "/tmp" not in detail


# ---------------------------------------------------------------------------- page, static files, token


def test_the_page_and_its_scripts_are_served_with_their_types(client):
    for path, kind in [("/", "text/html"), ("/static/app.js", "text/javascript"), ("/static/app.css", "text/css"), ("/static/plotly.min.js", "text/javascript"), ("/api/docs", "text/html")]:
        r = client.get(path)
        assert r.status_code == 200 and r.headers["content-type"].startswith(kind), path
        assert r.headers["x-content-type-options"] == "nosniff"
    # the page is ES modules: app.js and every module it imports, directly or not, are served as JavaScript
    assert '<script type="module" src="/static/app.js">' in client.get("/").text
    seen, todo = set(), ["app.js"]
    while todo:
        name = todo.pop()
        r = client.get(f"/static/{name}")
        assert r.status_code == 200 and r.headers["content-type"].startswith("text/javascript"), name
        seen.add(name)
        todo += [m for m in re.findall(r'from "\./([\w.-]+\.js)"', r.text) if m not in seen]
    assert {"form.js", "plots.js", "sweep.js", "results.js", "tune.js"} <= seen, seen
    page = client.get("/").text + "".join(client.get(f"/static/{n}").text for n in sorted(seen))
    assert "/static/plotly.min.js" in page and "http://" not in page and "https://" not in page


def test_every_file_of_the_static_folder_is_on_the_served_list():
    """A new module of the page must be listed in STATIC_FILES, or the page cannot load it."""
    from cmpsim.web.page import STATIC_FILES, static_dir

    files = {p.name for p in static_dir().iterdir() if p.is_file()}
    assert files <= set(STATIC_FILES), files - set(STATIC_FILES)
    assert set(STATIC_FILES) - {"plotly.min.js"} <= files, set(STATIC_FILES) - files


TRAVERSALS = [
    "/static/../../etc/passwd",
    "/static/..%2f..%2fetc%2fpasswd",
    "/static/%2e%2e/%2e%2e/etc/passwd",
    "/static/%2e%2e%2f%2e%2e%2fetc%2fpasswd",
    "/static/..%5c..%5cetc%5cpasswd",
    "/static/%252e%252e%252fetc%252fpasswd",
    "/static/",
    "/static/app.js/../../../etc/passwd",
    "/static/__init__.py",
    "/static/../app.py",
    "/../../etc/passwd",
]


@pytest.mark.parametrize("path", TRAVERSALS)
def test_paths_outside_the_static_folder_are_404(client, path):
    r = client.get(path)
    assert r.status_code == 404 and "root:" not in r.text


def test_paths_outside_the_static_folder_are_404_on_the_socket():
    """The raw request line as a hostile client sends it (an HTTP library would normalise the dots)."""
    from cmpsim.web.server import start_in_background

    with start_in_background(create_app(LIMITS, workers=1)) as srv:
        host, port = srv.url.removeprefix("http://").split(":")
        for path in TRAVERSALS + ["/static/..", "/static/../", "/static/./../app.py"]:  # an HTTP library would rewrite these
            with socket.create_connection((host, int(port)), timeout=10) as s:
                s.sendall(f"GET {path} HTTP/1.1\r\nHost: {host}\r\nConnection: close\r\n\r\n".encode())
                reply = b""
                while chunk := s.recv(65536):
                    reply += chunk
            status = reply.split(b"\r\n", 1)[0]
            assert status in (b"HTTP/1.1 404 Not Found", b"HTTP/1.1 400 Bad Request"), (path, status)
            assert b"root:" not in reply


def test_a_token_guards_every_route():
    app = create_app(LIMITS, token="s3cret", workers=1)
    with TestClient(app) as c:
        for path in ["/", "/static/app.js", "/api/params", "/api/openapi.json", "/api/sweeps"]:
            r = c.get(path)
            assert r.status_code == 401 and r.headers["www-authenticate"] == "Bearer", path
        assert c.post("/api/solve", json={"grid": "coarse"}).status_code == 401
        assert c.get("/api/params", headers={"Authorization": "Bearer wrong"}).status_code == 401
        assert c.get("/api/params", headers={"Authorization": "Bearer s3cret"}).status_code == 200
        page = c.get("/?token=s3cret")  # the link `cmpsim serve` prints: sets the cookie the page then sends
        assert page.status_code == 200 and "HttpOnly" in page.headers["set-cookie"]
        assert c.get("/api/params").status_code == 200


# ---------------------------------------------------------------------------- the command


def test_serve_without_the_web_extra_says_which_pip_line_to_run(monkeypatch):
    monkeypatch.setitem(sys.modules, "fastapi", None)  # `import fastapi` now raises ImportError
    res = CliRunner().invoke(main, ["serve"])
    assert res.exit_code == 2
    assert 'pip install "cmpsim[web]"' in res.output and "fastapi" in res.output


def test_serve_says_where_to_point_the_browser_and_warns_off_loopback(monkeypatch):
    import uvicorn

    calls = []
    monkeypatch.setattr(uvicorn, "run", lambda app, **kw: calls.append((app, kw)))
    res = CliRunner().invoke(main, ["serve", "--port", "8123"])
    assert res.exit_code == 0, res.output
    assert "open http://127.0.0.1:8123/ in a browser" in res.stdout and "warning" not in res.output
    assert calls[-1][1]["host"] == "127.0.0.1" and calls[-1][1]["port"] == 8123

    monkeypatch.setenv("CMPSIM_TOKEN", "t0k")
    res = CliRunner().invoke(main, ["serve", "--host", "0.0.0.0", "--max-jobs", "3"])
    assert res.exit_code == 0, res.output
    assert "cmpsim: warning: --host 0.0.0.0 makes the server reachable" in res.stderr and "?token=t0k" in res.stdout
    app = calls[-1][0]
    assert app.state.limits.max_jobs == 3
    with TestClient(app) as c:
        assert c.get("/api/params").status_code == 401
        assert c.get("/api/params", headers={"Authorization": "Bearer t0k"}).status_code == 200

    res = CliRunner().invoke(main, ["serve", "--max-grid", "huge"])
    assert res.exit_code == 2 and "--max-grid" in res.stderr


# ---------------------------------------------------------------------------- the documentation


def test_the_docs_page_states_the_limits_and_messages_the_code_has():
    from cmpsim.cli import serve_command
    from cmpsim.web.limits import grid_cells

    text = (Path(__file__).resolve().parents[1] / "docs" / "web.md").read_text(encoding="utf-8")
    defaults = {p.opts[0]: p.default for p in serve_command.params if p.opts[0].startswith("--max-")}
    lim = Limits()
    assert defaults == {"--max-grid": lim.max_grid, "--max-sweep-points": lim.max_sweep_points, "--max-jobs": lim.max_jobs, "--max-body": lim.max_body_bytes,
                        "--max-upload": lim.max_upload_bytes, "--max-windows": lim.max_windows}
    for option, default in defaults.items():
        assert f"| `{option}` | `{default}` |" in text, option
    n_r, n_t, cells = grid_cells(lim.max_grid)
    assert f"`{lim.max_grid}` = {n_r}x{n_t} = {cells} cells" in text
    for value in ("-3 psi", "3 kg"):
        with pytest.raises(ValueError) as info:
            Config.default().replace(applied_pressure=value)
        assert f"*{info.value}*" in text, value


def test_the_web_form_offers_the_abrasive_inputs_with_units_and_choices(client):
    """Issue 24: the form is built from /api/params, so the new inputs appear with their units and choices."""
    by_name = {p["name"]: p for p in client.get("/api/params").json()["parameters"]}
    assert by_name["solids_loading"]["display_unit"] == "%" and by_name["solids_loading"]["default_display"] == "12.5"
    assert by_name["particle_size_std"]["display_unit"] == "nm"
    assert by_name["abrasive"]["choices"] == ["silica", "ceria", "alumina"]
    assert by_name["film"]["choices"] == ["oxide", "copper", "tungsten", "barrier"]  # the Ta barrier joined the film table in issue 32
    assert by_name["removal_kinetics"]["choices"] == ["mechanical", "two_step"]
    assert "abrasive" in by_name["removal_law"]["choices"] and by_name["removal_law"]["default_display"] == "abrasive"


def test_tune_zones_answers_the_object_of_the_command(client):
    body = {"carrier": "membrane", "zone_radii": "20,38.1 mm", "grid": "8x24"}
    r = client.post("/api/tune-zones", json=body)
    assert r.status_code == 200, r.text
    data = r.json()
    cli = json.loads(CliRunner().invoke(main, ["tune-zones", "--json", "--grid", "8x24", "--set", "carrier=membrane", "--set", "zone_radii=20,38.1 mm"]).output)
    assert data["zone_pressures"] == pytest.approx(cli["zone_pressures"], rel=1e-9)
    assert data["within_wafer_nonuniformity"] == pytest.approx(cli["within_wafer_nonuniformity"], rel=1e-6)
    bad = client.post("/api/tune-zones", json={"grid": "8x24"})
    assert bad.status_code == 422 and "tune_zones needs carrier = 'membrane'" in bad.text



def test_tune_zones_with_the_ring_answers_the_object_of_tune_zones_ring(client, monkeypatch):
    """``?ring=true`` is ``cmpsim tune-zones --ring`` (one step each, to stay quick): the same call, the ring
    pressure and the kept mean rate in the answer; ``ring_bounds`` without ``ring`` is refused like the option."""
    import functools

    import cmpsim.head.tuning

    monkeypatch.setattr(cmpsim.head.tuning, "tune_zones", functools.partial(cmpsim.head.tuning.tune_zones, max_steps=1))
    body = {"carrier": "membrane", "zone_radii": "20,38.1 mm", "grid": "8x24", "pad_compliance": "layer", "retaining_ring_pressure": "4 psi"}
    r = client.post("/api/tune-zones?ring=true", json=body)
    assert r.status_code == 200, r.text
    data = r.json()
    args = ["tune-zones", "--json", "--ring"] + [a for k, v in body.items() for a in (("--grid", v) if k == "grid" else ("--set", f"{k}={v}"))]
    cli = json.loads(CliRunner().invoke(main, args).output)
    assert data["ring_pressure"] == pytest.approx(cli["ring_pressure"], rel=1e-9)
    assert data["zone_pressures"] == pytest.approx(cli["zone_pressures"], rel=1e-9)
    assert data["keep"] == "rate" and data["mean_rate"] == pytest.approx(data["before"]["mean_rate"], rel=1e-3)
    bad = client.post("/api/tune-zones?ring_bounds=1,5%20psi", json=body)
    assert bad.status_code == 422 and "ring_bounds needs ring" in bad.text


# ---------------------------------------------------------------------------- the die on an uploaded layout


def _chip(path: Path, steps: int = 2, fmt: str = "gds") -> Path:
    """A 200 um tile of 8 um lines at 10 um pitch (80 %) beside one of 2 um lines (20 %), stepped
    steps x steps (hierarchical); layer 1/0, plus an outline on 100/0 and a cell of 5/0 nobody uses."""
    import gdstk

    lib = gdstk.Library(unit=1e-6, precision=1e-9)

    def lines(name, width):
        cell = gdstk.Cell(name)
        for i in range(10):
            cell.add(gdstk.rectangle((i * 10.0, 0), (i * 10.0 + width, 100.0), layer=1))
        return cell

    dense, sparse = lines("DENSE", 8.0), lines("SPARSE", 2.0)
    tile = gdstk.Cell("TILE")
    tile.add(gdstk.Reference(dense, (0, 0)), gdstk.Reference(sparse, (100, 0)), gdstk.Reference(sparse, (0, 100)), gdstk.Reference(dense, (100, 100)))
    top = gdstk.Cell("CHIP")
    top.add(gdstk.Reference(tile, (0, 0), columns=steps, rows=steps, spacing=(200.0, 200.0)))
    top.add(gdstk.rectangle((0, 0), (200.0 * steps, 200.0 * steps), layer=100))
    lib.add(dense, sparse, tile, top)
    if fmt == "oas":
        lib.write_oas(str(path))
    else:
        lib.write_gds(str(path))
    return path


DIE_QUERY = {"layer": "1/0", "process": "copper", "spec": ["thickness=30nm", "dishing=50nm"], "inputs": json.dumps({"grid": "coarse"})}


def _post_die(client, path: Path, **query):
    params = {**DIE_QUERY, "filename": path.name, **query}
    return client.post("/api/die", params=params, content=path.read_bytes(), headers={"content-type": "application/octet-stream"})


def test_die_answers_the_object_cmpsim_die_layout_json_prints(client, tmp_path):
    path = _chip(tmp_path / "chip.gds")
    r = _post_die(client, path)
    assert r.status_code == 200, r.text
    args = ["die", str(path), "--layer", "1/0", "--process", "copper", "--spec", "thickness=30nm", "--spec", "dishing=50nm", "--grid", "coarse", "--json"]
    res = CliRunner().invoke(main, args)
    assert res.exit_code == 0, res.output
    cli = json.loads(res.stdout)
    assert r.json() == cli  # the same functions, the same object
    assert cli["hotspot_count"] > 0 and cli["thickness_range"] > 0 and "maps" not in r.json()
    # include=maps adds the per-window maps on the window centres, and changes nothing else
    m = _post_die(client, path, include="maps").json()
    maps = m.pop("maps")
    assert m == cli
    assert list(maps["maps"]) == ["density", "thickness", "step_height", "dishing", "erosion"]
    assert maps["x"] == pytest.approx([(i + 0.5) * 20e-6 for i in range(20)]) and len(maps["y"]) == 20
    density = np.array(maps["maps"]["density"]["z"])
    assert density.shape == (20, 20)
    assert density[0, 0] == pytest.approx(0.8, abs=1e-6) and density[0, 5] == pytest.approx(0.2, abs=1e-6)
    chosen = _post_die(client, path, include="maps", maps="erosion").json()["maps"]["maps"]
    assert list(chosen) == ["erosion"]
    bad = _post_die(client, path, include="maps", maps="nope")
    assert bad.status_code == 422 and bad.json()["parameter"] == "maps"


@pytest.mark.parametrize("fmt", ["gds.gz", "oas"])
def test_die_reads_gzipped_gds_and_oasis_as_the_gds(client, tmp_path, fmt):
    import gzip

    gds = _chip(tmp_path / "chip.gds")
    if fmt == "oas":
        path = _chip(tmp_path / "chip.oas", fmt="oas")
    else:
        path = tmp_path / "chip.gds.gz"
        path.write_bytes(gzip.compress(gds.read_bytes()))
    a = _post_die(client, gds, include="maps", maps="density").json()
    b = _post_die(client, path, include="maps", maps="density").json()
    assert np.array(b["maps"]["maps"]["density"]["z"]) == pytest.approx(np.array(a["maps"]["maps"]["density"]["z"]), abs=1e-9)
    assert b["hotspot_count"] == a["hotspot_count"]


def _empty_layer_chip(path: Path) -> Path:
    """Layer 5/0 only in a cell outside the top cell CHIP: an empty layer under CHIP."""
    import gdstk

    lib = gdstk.Library(unit=1e-6, precision=1e-9)
    top, spare = gdstk.Cell("CHIP"), gdstk.Cell("SPARE")
    top.add(gdstk.rectangle((0, 0), (100, 100), layer=1))
    spare.add(gdstk.rectangle((0, 0), (10, 10), layer=5))
    lib.add(top, spare)
    lib.write_gds(str(path))
    return path


@pytest.mark.parametrize(
    "case, query, parameter",
    [
        ("not a layout", {}, "layout"),
        ("missing layer", {"layer": "2/0"}, "layer"),
        ("unknown PDK layer", {"layer": "met9", "pdk": "sky130"}, "layer"),
        ("PDK layer the file lacks", {"layer": "met1", "pdk": "sky130"}, "layer"),
        ("window larger than the die", {"window": "1 mm"}, "window"),
        ("empty layer", {"layer": "5/0", "top": "CHIP"}, "layer"),
        ("several top cells", {"layer": "1/0"}, "top"),
    ],
)
def test_bad_die_input_is_422_with_cmpsims_own_message_naming_the_parameter(client, tmp_path, case, query, parameter):
    from cmpsim.die.chip import layout_die

    if case == "not a layout":
        path = tmp_path / "notes.gds"
        path.write_text("these are notes, not a layout\n")
    elif case in ("empty layer", "several top cells"):
        path = _empty_layer_chip(tmp_path / "chip.gds")
    else:
        path = _chip(tmp_path / "chip.gds")
    q = {"layer": "1/0", "window": "20 um", **query}
    with pytest.raises(ValueError) as info:  # what `cmpsim die LAYOUT` says, on the same file
        layout_die(path, [q["layer"]], to_si_m(q["window"]), top=q.get("top"), pdk=q.get("pdk"))
    r = _post_die(client, path, **query)
    assert r.status_code == 422, r.text
    body = r.json()
    assert body["parameter"] == parameter
    assert body["detail"] == str(info.value).replace(str(path), path.name)
    assert str(tmp_path) not in body["detail"]  # never the server's folders
    if case == "missing layer":
        assert "'2/0'" in body["detail"] and "1/0, 100/0" in body["detail"]  # the layer named, the file's layers listed
    if case == "unknown PDK layer":
        assert "'met9'" in body["detail"] and "met1" in body["detail"]


def to_si_m(text: str) -> float:
    from cmpsim.inputs.units import to_si

    return to_si(text, "m", "window", "20 um")


@pytest.mark.parametrize(
    "query, parameter, words",
    [
        ({"layer": ""}, "layer", "at least one layer"),
        ({"pdk": "tsmc"}, "pdk", "pdk 'tsmc' is unknown"),
        ({"window": "3 kg"}, "window", "wrong dimension"),
        ({"spec": "flatness=3nm"}, "spec", "not a quantity with a limit"),
        ({"process": "tin"}, "process", "process"),
        ({"inputs": '{"applied_pressure": "-3 psi"}'}, "applied_pressure", "out of range"),
        ({"inputs": "{oops"}, "inputs", "not valid JSON"),
    ],
)
def test_a_bad_die_query_is_422_before_the_upload_is_read(client, tmp_path, query, parameter, words):
    r = _post_die(client, _chip(tmp_path / "chip.gds"), **query)
    assert r.status_code == 422 and r.json()["parameter"] == parameter and words in r.json()["detail"], r.text


def test_an_empty_upload_is_422_naming_the_layout(client):
    r = client.post("/api/die", params={"layer": "1/0"}, content=b"")
    assert r.status_code == 422 and r.json()["parameter"] == "layout" and "empty" in r.json()["detail"]


def test_the_layout_upload_has_its_own_size_limit(tmp_path):
    """/api/die takes a layout over --max-body (the JSON routes' limit) up to --max-upload; beyond, 413 naming --max-upload."""
    path = _chip(tmp_path / "chip.gds")
    size = path.stat().st_size
    app = create_app(Limits(max_grid="default", max_body_bytes=1024, max_upload_bytes=size + 10), workers=1)
    with TestClient(app) as c:
        assert size > 1024 and _post_die(c, path).status_code == 200
        big = tmp_path / "big.gds"
        big.write_bytes(path.read_bytes() + b"\0" * 20)
        r = _post_die(c, big)
        assert r.status_code == 413 and "--max-upload" in r.json()["detail"] and "uploaded layout" in r.json()["detail"]

        def chunks():  # no Content-Length: the server counts what arrives
            for _ in range(4):
                yield b"\0" * (size // 2)

        r = c.post("/api/die", params=DIE_QUERY, content=chunks())
        assert r.status_code == 413 and "--max-upload" in r.json()["detail"]
        assert c.post("/api/solve", content=b" " * 2048, headers={"content-type": "application/json"}).status_code == 413  # others keep --max-body


def test_a_die_of_more_windows_than_the_limit_is_refused_naming_window(tmp_path):
    app = create_app(Limits(max_grid="default", max_windows=100), workers=1)
    with TestClient(app) as c:
        r = _post_die(c, _chip(tmp_path / "chip.gds"))  # 400 um at 20 um: 400 windows
        assert r.status_code == 422 and r.json()["parameter"] == "window" and "--max-windows" in r.json()["detail"]
        assert _post_die(c, _chip(tmp_path / "chip.gds"), window="40 um").status_code == 200


def test_the_upload_is_removed_and_the_run_holds_a_job_slot(tmp_path, monkeypatch):
    import tempfile

    import cmpsim.die

    scratch = tmp_path / "scratch"
    scratch.mkdir()
    monkeypatch.setattr(tempfile, "tempdir", str(scratch))
    app = create_app(Limits(max_grid="default", max_jobs=1, retry_after_s=3), workers=1)
    seen = []
    simulate = cmpsim.die.simulate

    def watched(*args, **kwargs):
        seen.append((app.state.slots.used, sorted(p.name for p in scratch.rglob("*"))))
        return simulate(*args, **kwargs)

    monkeypatch.setattr(cmpsim.die, "simulate", watched)
    path = _chip(tmp_path / "chip.gds")
    with TestClient(app) as c:
        assert _post_die(c, path).status_code == 200
        assert seen[0][0] == 1 and "chip.gds" in seen[0][1]  # the run held the slot; the upload was on disk
        assert list(scratch.iterdir()) == []  # and is gone
        assert _post_die(c, path, layer="2/0").status_code == 422
        assert list(scratch.iterdir()) == []  # also after a refusal
        app.state.slots.take()
        try:
            r = _post_die(c, path)
            assert r.status_code == 429 and r.headers["retry-after"] == "3"
        finally:
            app.state.slots.give_back()
        assert list(scratch.iterdir()) == [] and app.state.slots.used == 0


def test_layer_maps_lists_the_named_layers_of_the_open_pdks(client):
    from cmpsim.layout import PDK_LAYER_MAPS

    maps = client.get("/api/layer-maps").json()
    assert sorted(maps) == ["gf180mcu", "sg13g2", "sky130"]
    assert maps["sky130"]["met1"] == ["68/20", "36/28"]
    assert {p: {n: [tuple(map(int, s.split("/"))) for s in v] for n, v in m.items()} for p, m in maps.items()} == {
        p: {n: list(v) for n, v in m.items()} for p, m in PDK_LAYER_MAPS.items()
    }
