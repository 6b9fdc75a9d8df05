"""Command line: ``cmpsim run | params | sweep | reproduce | validate | calibrate | die``.

A thin layer over the Python API: every command calls the function of the same name.
Bad input exits with status 2 and a message naming the parameter and its valid range;
an operating point without equilibrium exits with status 3 and the diagnosis.

Every command that solves takes its inputs the same way (:func:`config_options`): a preset
(``--preset``), then a TOML file (``--config FILE``), then changes (``--set NAME=VALUE``,
repeatable) and the grid (``--grid``), in that order. ``cmpsim run FILE`` is the same as
``cmpsim run --config FILE``.
"""

from __future__ import annotations

import functools
import os
import sys
import warnings
from pathlib import Path

import click

from ._version import __version__

EXIT_INPUT = 2
#: The names of cmpsim.config.PRESETS (written out so that the command line starts without importing the config; a test keeps them equal).
PRESET_NAMES = ("default", "paper", "300mm")
EXIT_NO_EQUILIBRIUM = 3


def _fail(message: str, code: int = EXIT_INPUT):
    click.echo(f"cmpsim: error: {message}", err=True)
    sys.exit(code)


def _warn(message: str) -> None:
    """A warning of cmpsim as the command line prints every one: ``cmpsim: warning: <message>``, one line on stderr."""
    text = " ".join(str(message).split())
    click.echo(f"cmpsim: warning: {text}", err=True)


def parse_assignments(items) -> dict[str, str]:
    """``["NAME=VALUE", ...]`` -> {NAME: VALUE}; ValueError on a malformed item."""
    out = {}
    for item in items:
        if "=" not in item:
            raise ValueError(f"--set expects NAME=VALUE (e.g. applied_pressure=4psi); got {item!r}")
        name, value = item.split("=", 1)
        name = name.strip().replace("-", "_")
        if not name:
            raise ValueError(f"--set expects NAME=VALUE; got {item!r}")
        out[name] = value.strip()
    return out


def load_config(config_path, assignments, preset: str | None = None, grid: str | None = None):
    """Config from a preset, an optional TOML file, --set overrides and the grid, in that order (raises ValueError)."""
    from .config import Config

    base = Config.preset(preset) if preset else Config.default()
    cfg = Config.from_toml(config_path, base=base) if config_path else base
    cfg = cfg.replace(**parse_assignments(assignments))
    return cfg.replace(grid=grid) if grid else cfg


def config_options(command):
    """The options of the inputs, the same on every command that solves: --config, --preset, --set, --grid."""
    for option in reversed(
        [
            click.option("--config", "config_path", type=click.Path(dir_okay=False), help="TOML file of inputs: sections [wafer] [process] [slurry] [pad] [numerics] or flat keys, values with units or SI (e.g. from `cmpsim calibrate`)."),
            click.option("--preset", type=click.Choice(PRESET_NAMES), default=None, help="Start from a named preset: 'paper' is the paper's model exactly; 'default' the predictive model; '300mm' a 300 mm wafer in a five-zone membrane head with a retaining ring on IC1000/Suba IV, a production oxide recipe (docs/model.md)."),
            click.option("--set", "assignments", multiple=True, metavar="NAME=VALUE", help="Change an input, with units: --set applied_pressure=3psi (repeatable)."),
            click.option("--grid", default=None, metavar="GRID", help="Grid: coarse, default, fine or NRxNT (rings x sectors); default: the configuration's."),
        ]
    ):
        command = option(command)
    return command


def _rich_table(title, header, rows):
    from rich.table import Table

    t = Table(title=title, show_lines=False)
    for i, h in enumerate(header):
        t.add_column(h, justify="right" if i == 1 else "left")
    for r in rows:
        t.add_row(*[str(c) for c in r])
    return t


_PACKAGE = Path(__file__).resolve().parent


def show_warning(message, category, filename, lineno, file=None, line=None, other=warnings.showwarning):
    """``warnings.showwarning`` of the command line: a warning raised in cmpsim's code is one
    line on stderr, ``cmpsim: warning: <message>``, without Python's file, line and source echo;
    other packages' warnings go to ``other`` (Python's format: their source says where they come from)."""
    try:
        ours = Path(filename).resolve().is_relative_to(_PACKAGE)
    except (TypeError, ValueError, OSError):
        ours = False
    if not ours:
        other(message, category, filename, lineno, file, line)
        return
    _warn(str(message))


@click.group(context_settings={"help_option_names": ["-h", "--help"]})
@click.version_option(version=__version__, prog_name="cmpsim")  # the source's version, not an install's metadata
@click.pass_context
def main(ctx):
    """cmpsim: wafer-scale CMP simulator (grain-flow lubrication + pad asperity contact)."""
    # for this command only (restored when it ends): importing cmpsim changes no warning display
    ctx.with_resource(warnings.catch_warnings())
    warnings.showwarning = functools.partial(show_warning, other=warnings.showwarning)


@main.command()
@click.argument("config", required=False, type=click.Path(dir_okay=False))
@config_options
@click.option("--json", "as_json", is_flag=True, help="Print exactly one JSON object (SI units) on stdout: schema 2, see cmpsim/data/result.schema.json.")
@click.option("--schema", "schema", type=click.Choice(["1", "2"]), default="2", show_default=True, help="JSON layout of --json and result.json: 2, or the flat object of cmpsim 0.1 (deprecated).")
@click.option("--out", "out_dir", type=click.Path(file_okay=False), help="Also write fields.nc, maps.png, profile.png, result.json and config.toml to DIR.")
@click.option("--check-roots", is_flag=True, help="Scan the attack angle for other equilibria (adds moment_roots_found).")
@click.option(
    "--relative/--no-relative",
    default=None,
    help="Give removal_rate_relative (solves the reference case too); default: only with the paper's removal law (the paper preset).",
)
def run(config, config_path, preset, assignments, grid, as_json, schema, out_dir, check_roots, relative):
    """Solve one operating point (the paper's base case by default).

    CONFIG is an optional TOML file, the same as --config (sections `[wafer]` `[process]`
    `[slurry]` `[pad]` `[numerics]` or flat keys; values with units such as "4 psi" or SI
    numbers). See `cmpsim params`.
    """
    from .equilibrium import EquilibriumError
    from .model import solve

    if config and config_path:
        _fail(f"give the configuration once: CONFIG ({config}) or --config ({config_path})")
    try:
        cfg = load_config(config or config_path, assignments, preset, grid)
    except ValueError as exc:
        _fail(str(exc))
    try:
        result = solve(cfg, check_roots=check_roots, relative=relative)
    except EquilibriumError as exc:
        _fail(f"no equilibrium: {exc}", EXIT_NO_EQUILIBRIUM)
    except ValueError as exc:
        _fail(str(exc))
    schema = int(schema)
    if schema == 1:
        _warn("--schema 1 (the flat JSON of cmpsim 0.1) is deprecated and will be removed; use schema 2 (cmpsim/data/result.schema.json)")
    if out_dir:
        write_outputs(result, Path(out_dir), schema=schema)
    if as_json:
        click.echo(result.to_json(schema=schema))
        return
    from rich.console import Console

    console = Console()
    console.print(result.summary_table(console.width))
    if result.flow_factor_floored_fraction > 0:
        _warn(
            f"the flow-factor tensor was regularised on {100 * result.flow_factor_floored_fraction:.1f} % "
            "of the faces: the film is outside the validity of the perturbation flow factors (docs/model.md)"
        )
    if result.root_scan is not None and len(result.root_scan.roots) != 1:
        roots = ", ".join(f"{r:.3g}" for r in result.root_scan.roots) or "none"
        _warn(
            f"the attack-angle scan found {len(result.root_scan.roots)} moment roots "
            f"(at {roots} rad); the equilibrium above is the one Newton reached from the default start"
        )
    if out_dir:
        console.print(f"wrote {out_dir}/fields.nc, maps.png, profile.png, result.json, config.toml")


def write_outputs(result, out: Path, schema: int = 2) -> None:
    """fields.nc, maps.png, profile.png, result.json, config.toml into ``out`` (each written atomically)."""
    import matplotlib.pyplot as plt

    from .io import atomic_path, atomic_write_text

    out.mkdir(parents=True, exist_ok=True)
    result.to_netcdf(out / "fields.nc")
    for name, fig in (("maps.png", result.plot()), ("profile.png", result.plot_profiles())):
        with atomic_path(out / name, suffix=".png") as tmp:
            fig.savefig(tmp, dpi=110, format="png")
        plt.close(fig)
    atomic_write_text(out / "result.json", result.to_json(indent=2, schema=schema) + "\n")
    result.config.to_toml(out / "config.toml")


@main.command()
@click.option("--markdown", is_flag=True, help="Print the parameter table of docs/model.md.")
def params(markdown):
    """List every input: name, default, unit, valid range and source."""
    from .config import PARAMETERS, format_display, parameter_table_markdown

    if markdown:
        click.echo(parameter_table_markdown(), nl=False)
        return
    from rich.console import Console

    from .tables import WIDE, legible_table

    console = Console()
    rows, detail = [], []
    for n, p in PARAMETERS.items():
        unit = p.display if p.unit not in ("choice", "grid") else ""
        default = format_display(n, p.default) + (f" {unit}" if unit else "") if p.default != () else "unset"
        # narrow terminals: the default above its valid range, both in the display unit
        rows.append((n, default, p.display_range_text()) if console.width >= WIDE else (n, f"{default}\n{p.display_range_text()}"))
        detail.append(f"{p.description}. Source: {p.source}")
    header = ["name", "default", "valid range"] if console.width >= WIDE else ["name", "default / valid range"]
    console.print(legible_table("cmpsim inputs (set with --set NAME=VALUE)", header, rows, detail=detail, detail_header="meaning and source", width=console.width))


@main.command(name="sweep")
@click.argument("sweep_file", type=click.Path(dir_okay=False))
@click.option("--out", "out_path", type=click.Path(), help="Result file: NetCDF (default SWEEP_FILE stem + .nc in the current directory), or zarr for a .zarr path.")
@click.option("--workers", type=click.IntRange(min=0), default=None, help="Worker processes of the local Dask cluster (default: the machine's cores); 0 runs in this process without Dask.")
@click.option("--scheduler", metavar="ADDRESS", help="Run on an existing Dask cluster, e.g. tcp://host:8786 (its workers need cmpsim installed).")
@click.option("--resume", is_flag=True, help="Continue an interrupted sweep: reuse the points saved next to --out, compute only the missing ones.")
@click.option("--max-points", type=click.IntRange(min=1), default=None, help="Refuse sweeps with more points than this (default 10000).")
@click.option("--no-warm-start", is_flag=True, help="Start every point from the cold start instead of from its converged neighbours.")
@click.option("--no-progress", is_flag=True, help="No progress bar.")
def sweep_command(sweep_file, out_path, workers, scheduler, resume, max_points, no_warm_start, no_progress):
    """Run a parameter sweep (outer product of [axes] plus [[points]]) on dask.distributed.

    SWEEP_FILE is a TOML file with an optional [base] table of `cmpsim run` settings and an
    [axes] table (setting = list of values or {start, stop, num}); see docs/sweeps.md and
    the example shipped as cmpsim/data/example_sweep.toml. The result is one xarray Dataset
    (one dimension per axis, every `cmpsim run --json` scalar as a variable, status and
    error per point). Every finished point is saved in OUT.parts/ as it completes, so an
    interrupted sweep continues with --resume.
    """
    import time as _time

    from .sweeps import DEFAULT_MAX_POINTS, SweepError, SweepSpec, summary_lines
    from .sweeps import sweep as run_sweep

    try:
        spec = SweepSpec.from_toml(sweep_file)
        spec.check_size(max_points or DEFAULT_MAX_POINTS)
    except ValueError as exc:
        _fail(str(exc))
    out = Path(out_path) if out_path else Path.cwd() / (Path(sweep_file).stem + ".nc")
    where = f"Dask cluster at {scheduler}" if scheduler else ("this process (no Dask)" if workers == 0 else "a local Dask cluster")
    click.echo(f"sweep: {spec.n_points} points ({' x '.join(f'{d} {n}' for d, n in zip(spec.dims, spec.shape))}) on {where} -> {out}")
    for message in spec.invalid_values():
        _warn(f"{message}; the points with this value will be recorded as invalid")
    t0 = _time.perf_counter()
    try:
        ds = run_sweep(
            spec,
            out=out,
            workers=workers,
            scheduler=scheduler,
            resume=resume,
            progress=not no_progress,
            warm_start=not no_warm_start,
            max_points=max_points or DEFAULT_MAX_POINTS,
            log=click.echo,
        )
    except SweepError as exc:
        _fail(str(exc))
    except KeyboardInterrupt:
        # The finished points are saved and the cluster closed (or its workers killed) within a
        # bound by now; exit at once, so that no interpreter-exit hook (Dask closes clusters
        # at exit) can wait on a worker that is still busy.
        sys.stdout.flush()
        sys.stderr.flush()
        os._exit(130)
    elapsed = _time.perf_counter() - t0
    for line in summary_lines(ds):
        click.echo(line)
    click.echo(f"wrote {out} in {elapsed:.1f} s")


class _ListOptionsCommand(click.Command):
    """A command whose list options take several values after one flag: ``--free A B C``.

    Before click parses the command line, ``--free A B C`` is rewritten as ``--free A --free B
    --free C``: the values run to the next option, or to a value that looks like a file
    (contains '.' or '/'), so ``--free A data.csv`` still reads data.csv as an argument.
    Values may also be repeated (``--free A --free B``) or comma-separated.
    """

    list_options = ("--free",)

    def parse_args(self, ctx, args):
        out, rest = [], list(args)
        while rest:
            arg = rest.pop(0)
            out.append(arg)
            if arg == "--":
                out += rest
                break
            if arg in self.list_options and rest:
                out.append(rest.pop(0))
                while rest and not rest[0].startswith("-") and "." not in rest[0] and "/" not in rest[0]:
                    out += [arg, rest.pop(0)]
        return super().parse_args(ctx, out)


def _split_names(values) -> list[str]:
    out = []
    for v in values:
        out += [s.strip() for s in str(v).split(",") if s.strip()]
    return out


@main.command(name="reproduce", short_help="Regenerate the paper's Figs. 3-12, their CSVs and a trend-table report.")
@click.option("--out", "out_dir", type=click.Path(file_okay=False), default="reproduction", show_default=True, help="Directory for the ten PNG + CSV figures, trends.csv, REPORT.md and REPORT.html.")
@config_options
def reproduce_command(out_dir, config_path, preset, assignments, grid):
    """Regenerate the paper's Figs. 3-12, their CSVs and a report with the trend table.

    Solves every equilibrium behind the figures (load 2-6 psi, speed 30-90 rpm; the paper's
    curves), writes figNN_*.png and figNN_*.csv, and checks each qualitative statement the
    paper makes about them against the data of the run (REPORT.md / REPORT.html, trends.csv).
    The inputs set the parameters the figures do not vary.
    """
    from .reproduction import reproduce

    try:
        cfg = load_config(config_path, assignments, preset or "paper", grid)  # the paper's figures: the paper's model by default
    except ValueError as exc:
        _fail(str(exc))
    command = " ".join(
        ["cmpsim reproduce"]
        + ([f"--out {out_dir}"] if out_dir != "reproduction" else [])
        + ([f"--preset {preset}"] if preset else [])
        + ([f"--config {config_path}"] if config_path else [])
        + [f"--set {a}" for a in assignments]
        + ([f"--grid {grid}"] if grid else [])
    )
    try:
        rep = reproduce(out=out_dir, progress=True, config=cfg, command=command)
    except (ValueError, OSError) as exc:
        _fail(str(exc))
    from rich.console import Console

    console = Console()
    rows = [[s.id, s.figure, s.text, "[green]yes[/green]" if s.reproduced else "[red]no[/red]"] for s in rep.statements]
    console.print(_rich_table(f"Statements of the paper reproduced: {rep.n_reproduced} of {len(rep.statements)}", ["#", "Fig.", "statement", "reproduced"], rows))
    console.print(
        f"{rep.equilibria} equilibria ({rep.factorizations} factorisations) in {rep.solve_s:.1f} s; total {rep.elapsed_s:.1f} s. "
        f"Wrote {len(rep.figures)} figures (PNG + CSV), {rep.report_md} and {rep.report_html}.",
        highlight=False,
    )
    if rep.failures:
        console.print(f"[yellow]{len(rep.failures)} operating point(s) without equilibrium: see the report[/yellow]")


@main.command(name="validate")
@click.argument("data", nargs=-1, type=click.Path(dir_okay=False))
@config_options
@click.option("--out", "out_dir", type=click.Path(file_okay=False), default="validation", show_default=True, help="Directory for parity.png, points.csv and datasets.csv.")
@click.option("--markdown", is_flag=True, help="Print the tables as Markdown instead of rich tables.")
def validate_command(data, config_path, preset, assignments, grid, out_dir, markdown):
    """Compare the model with measured data; with no DATA, every data set shipped with cmpsim.

    DATA are CSV files in the format of cmpsim/data/README.md (operating conditions with
    units, the measured quantity, its uncertainty and source). For each point the model is
    solved and compared; the tables give model vs measurement, error, RMS error and, for
    shape comparisons, the leave-one-out error beside that of predicting the mean.
    """
    from .validation import validate

    try:
        cfg = load_config(config_path, assignments, preset, grid)
        report = validate(list(data) or None, config=cfg, progress=not markdown)
    except ValueError as exc:
        _fail(str(exc))
    out = Path(out_dir)
    try:
        out.mkdir(parents=True, exist_ok=True)
        report.to_csv(out / "points.csv")
        report.summary_csv(out / "datasets.csv")
        report.parity_plot(out / "parity.png")
    except OSError as exc:
        _fail(f"cannot write to {out}: {exc}")
    if markdown:
        click.echo(report.to_markdown(), nl=False)
        return
    from rich.console import Console

    console = Console()
    console.print(_rich_table("Model vs data, per point (shape data sets: model times the fitted scale)", report.POINT_HEADER, report.point_rows()))
    console.print(_rich_table("Per data set", report.DATASET_HEADER, report.dataset_rows()))
    console.print(
        f"{report.equilibria} equilibria in {report.elapsed_s:.1f} s (grid {cfg.numerics.grid}); wrote {out}/points.csv, datasets.csv, parity.png",
        highlight=False,
    )


@main.command(name="calibrate", cls=_ListOptionsCommand)
@click.argument("data", nargs=-1, required=True, type=click.Path(dir_okay=False))
@click.option("--free", "free", multiple=True, required=True, metavar="NAME [NAME ...]", help="Inputs to fit, e.g. --free asperity_density asperity_radius (or repeated, or comma-separated).")
@click.option("--bounds", "bounds", multiple=True, metavar="NAME=LOW:HIGH", help="Bounds with units, e.g. --bounds pad_modulus=20MPa:500MPa (repeatable; default a factor 10 either side).")
@config_options
@click.option("--out", "out_path", type=click.Path(dir_okay=False), default="calibrated.toml", show_default=True, help="Fitted configuration, accepted by every command's --config (and `cmpsim run FILE`).")
@click.option("--max-evaluations", type=click.IntRange(min=1), default=None, help="Model evaluations allowed to the optimiser.")
@click.option("--quiet", is_flag=True, help="Do not print the evaluations while fitting.")
def calibrate_command(data, free, bounds, config_path, preset, assignments, grid, out_path, max_evaluations, quiet):
    """Fit uncertain inputs to measurements (scipy least_squares, bounded).

    Reports fitted values with standard errors and 95 % intervals, their correlations and
    the residuals before and after, and writes the fitted configuration to --out.
    """
    from .calibration import calibrate

    names = _split_names(free)
    bnds = {}
    try:
        for item in bounds:
            if "=" not in item or ":" not in item.split("=", 1)[1]:
                raise ValueError(f"--bounds expects NAME=LOW:HIGH (e.g. pad_modulus=20MPa:500MPa); got {item!r}")
            name, rng = item.split("=", 1)
            lo, hi = rng.split(":", 1)
            bnds[name.strip().replace("-", "_")] = (lo.strip(), hi.strip())
        cfg = load_config(config_path, assignments, preset, grid)
        result = calibrate(list(data), names, config=cfg, bounds=bnds or None, max_nfev=max_evaluations, progress=not quiet)
    except ValueError as exc:
        _fail(str(exc))
    try:
        result.to_toml(out_path)
    except OSError as exc:
        _fail(f"cannot write {out_path}: {exc}")
    click.echo(result.summary())
    click.echo(f"wrote {out_path}")


# ---- serve command (web/) ----
@main.command(name="tune-zones")
@config_options
@click.option("--bounds", default="0.5,8 psi", show_default=True, metavar="LOW,HIGH UNIT", help="Bounds of every zone pressure.")
@click.option("--keep", type=click.Choice(["pressure", "rate"]), default=None, help="Also keep the mean pressure (the load) or the mean removal rate of the start.")
@click.option("--incoming", "incoming", type=click.Path(dir_okay=False), default=None, metavar="FILE.csv", help="Incoming thickness profile to flatten after --polish-time: CSV with header radius_<unit>,thickness_<unit> (e.g. radius_mm,thickness_nm).")
@click.option("--polish-time", "polish_time", default=None, metavar="TIME", help="Polish time with units (e.g. '60 s', '1.5 min'); required with --incoming.")
@click.option("--json", "as_json", is_flag=True, help="Print one JSON object (SI): zone_pressures (Pa), within_wafer_nonuniformity (fraction), profile (radius, rate), before; with --incoming also remaining_thickness (radius, thickness; m) and remaining_nonuniformity (fraction).")
def tune_zones_command(config_path, preset, assignments, grid, bounds, keep, incoming, polish_time, as_json):
    """Find the zone pressures of a membrane head that flatten the removal profile.

    Starts from the configuration's zone_pressures (or applied_pressure in every zone);
    needs --set carrier=membrane and zone_radii. Prints the pressures, the profile before
    and after, and the within-wafer non-uniformity. With --incoming FILE.csv and
    --polish-time, flattens the thickness left after polishing instead.
    """
    import json

    from .equilibrium import EquilibriumError
    from .tuning import tune_zones
    from .units import parse_list

    try:
        cfg = load_config(config_path, assignments, preset, grid)
        limits = parse_list(bounds, "Pa", "--bounds", example="psi")
        if len(limits) != 2:
            raise ValueError(f"--bounds takes two pressures, LOW,HIGH with one unit (e.g. '0.5,8 psi'); got {bounds!r}")
        if incoming is not None and polish_time is None:
            raise ValueError("--incoming needs --polish-time (e.g. --polish-time '60 s')")
        if polish_time is not None and incoming is None:
            raise ValueError("--polish-time needs --incoming FILE.csv (the incoming thickness profile)")
        result = tune_zones(cfg, bounds=limits, keep=keep, incoming=incoming, polish_time=polish_time)
    except EquilibriumError as exc:
        _fail(f"no equilibrium: {exc}", EXIT_NO_EQUILIBRIUM)
    except ValueError as exc:
        _fail(str(exc))
    if as_json:
        click.echo(json.dumps(result.to_dict()))
        return
    psi = 6894.757293168361
    rows = [
        (f"{1e3 * r:.1f}", f"{p0 / psi:.3f}", f"{p1 / psi:.3f}")
        for r, p0, p1 in zip(result.zone_radii, result.before["zone_pressures"], result.zone_pressures)
    ]
    from rich.console import Console

    console = Console()
    console.print(_rich_table("zone pressures", ["zone outer radius (mm)", "before (psi)", "tuned (psi)"], rows))
    nm_min = 1e9 * 60.0
    prof = [
        (f"{1e3 * r:.2f}", f"{nm_min * a:.3f}", f"{nm_min * b:.3f}")
        for r, a, b in zip(result.profile["radius"], result.before["profile"]["rate"], result.profile["rate"])
    ]
    console.print(_rich_table("removal-rate profile", ["radius (mm)", "before (nm/min)", "tuned (nm/min)"], prof))
    if result.remaining_thickness is not None:
        left = [
            (f"{1e3 * r:.2f}", f"{1e9 * a:.3f}", f"{1e9 * b:.3f}")
            for r, a, b in zip(result.remaining_thickness["radius"], result.before["remaining_thickness"]["thickness"], result.remaining_thickness["thickness"])
        ]
        console.print(_rich_table(f"remaining thickness after {result.polish_time:g} s", ["radius (mm)", "before (nm)", "tuned (nm)"], left))
        console.print(
            f"remaining-thickness non-uniformity: {100 * result.before['remaining_nonuniformity']:.3f} % -> "
            f"{100 * result.remaining_nonuniformity:.3f} %"
        )
    console.print(
        f"within-wafer non-uniformity: {100 * result.before['within_wafer_nonuniformity']:.3f} % -> "
        f"{100 * result.within_wafer_nonuniformity:.3f} % ({result.solves} operating points solved)"
    )


@main.command(name="serve")
@click.option("--host", default="127.0.0.1", show_default=True, help="Address to listen on; anything but loopback warns (then use --token).")
@click.option("--port", type=click.IntRange(1, 65535), default=8000, show_default=True, help="Port to listen on.")
@click.option("--token", envvar="CMPSIM_TOKEN", default=None, help="Require this token on every route (env: CMPSIM_TOKEN); open the page as /?token=TOKEN.")
@click.option("--max-grid", default="fine", show_default=True, help="Largest grid a request may use (preset or NRxNT; compared by cells).")
@click.option("--max-sweep-points", type=click.IntRange(min=1), default=1000, show_default=True, help="Largest sweep (points) and validation upload (rows).")
@click.option("--max-jobs", type=click.IntRange(min=1), default=2, show_default=True, help="Solves, validations and sweeps running at once; more get HTTP 429 with Retry-After.")
@click.option("--max-body", type=click.IntRange(min=1024), default=1_048_576, show_default=True, help="Largest request body in bytes; larger gets HTTP 413.")
@click.option("--workers", type=click.IntRange(min=1), default=None, help="Worker processes of the local Dask cluster of the sweeps (default: the machine's cores).")
@click.option("--scheduler", metavar="ADDRESS", help="Run the sweeps on an existing Dask cluster, e.g. tcp://host:8786.")
def serve_command(host, port, token, max_grid, max_sweep_points, max_jobs, max_body, workers, scheduler):
    """Start the browser UI and the JSON HTTP API (needs the extra: pip install "cmpsim[web]").

    The page at / solves operating points, draws the wafer maps and runs sweeps; the API
    (/api/solve, /api/sweeps, /api/validate, ...; reference at /api/docs) answers what
    `cmpsim run --json`, `cmpsim sweep` and `cmpsim validate` give. See docs/web.md.
    """
    from .web import INSTALL_HINT

    try:
        from .web.limits import Limits
        from .web.server import serve

        import fastapi, uvicorn  # noqa: E401,F401 - the web extra
    except ImportError as exc:
        _fail(f"`cmpsim serve` needs the web extra ({exc.name or exc} is missing): {INSTALL_HINT}")
    try:
        limits = Limits(max_grid=max_grid, max_sweep_points=max_sweep_points, max_jobs=max_jobs, max_body_bytes=max_body)
    except ValueError as exc:
        _fail(str(exc).replace("max_grid:", "--max-grid:"))
    if workers is not None and scheduler is not None:
        _fail("give either --workers (a local cluster) or --scheduler (an existing cluster), not both")
    serve(host, port, limits=limits, token=token or None, workers=workers, scheduler=scheduler, echo=click.echo, warn=_warn)


# ---- end serve command ----


# ---- die command (cmpsim.die) ----
@main.command(name="die")
@click.argument("layout", required=False)
@click.option("--list", "list_dies", is_flag=True, help="Print the built-in test dies and exit.")
@click.option("--wafer", is_flag=True, help="Polish every die of the wafer, each at the blanket rate of the wafer solve at its site.")
@click.option("--time", "time_text", metavar="T", default=None, help="Polishing time with units (e.g. 90s, 2min; a number is seconds). Default: the end point times 1 + over_polish.")
@click.option("--process", type=click.Choice(["oxide", "copper"]), default="oxide", show_default=True, help="Oxide ILD planarization, or copper damascene (bulk removal, then over-polish: dishing and erosion).")
@click.option("--param", "params", multiple=True, metavar="NAME=VALUE", help="A die-model input with units, e.g. --param step_height=0.8um (repeatable; see docs/model.md section 18).")
@click.option("--planarization-length", "pl_text", metavar="L", default=None, help="Override the planarization length derived from the pad stack (e.g. 3mm).")
@click.option("--weighting", type=click.Choice(["gaussian", "pad"]), default="gaussian", show_default=True, help="Weighting function of the effective density.")
@click.option("--cell-size", "cell_text", metavar="SIZE", default=None, help="Cell size of a built-in die (default 50um).")
@click.option("--blanket-rate", "rate_text", metavar="RATE", default=None, help="Blanket rate of a single die (e.g. 200nm/min); default the wafer-mean rate of the wafer solve.")
@config_options
@click.option("--out", "out_dir", type=click.Path(file_okay=False), help="Write die.nc, die.png, die.json (and wafer.nc, wafer.png with --wafer) to DIR.")
@click.option("--json", "as_json", is_flag=True, help="Print exactly one JSON object (SI units) on stdout.")
def die_command(layout, list_dies, wafer, time_text, process, params, pl_text, weighting, cell_text, rate_text, config_path, preset, assignments, grid, out_dir, as_json):
    """Polish a patterned die: effective density, step heights, copper dishing and erosion.

    LAYOUT is a layout CSV (density grid, cell size, optional line widths; docs/model.md
    section 18) or the name of a built-in test die (`cmpsim die --list`). The blanket rate
    comes from a wafer-scale solve of the inputs (--config/--preset/--set/--grid).
    """
    from .die import BUILTIN_LAYOUTS, simulate, simulate_wafer
    from .die.report import to_json, write_die_outputs
    from .equilibrium import EquilibriumError
    from .units import to_si

    if list_dies:
        for name, (text, _) in BUILTIN_LAYOUTS.items():
            click.echo(f"{name:10s} {text}")
        return
    if not layout:
        _fail("give a LAYOUT (a CSV file or a built-in die: cmpsim die --list)")
    try:
        cfg = load_config(config_path, assignments, preset, grid)
        kwargs = dict(process=process, planarization_length=to_si(pl_text, "m", "--planarization-length", "3 mm") if pl_text else None,
                      weighting=weighting, cell_size=to_si(cell_text, "m", "--cell-size", "50 um") if cell_text else None,
                      **parse_assignments(params))
        t = to_si(time_text, "s", "--time", "90 s") if time_text else None
        if wafer:
            if rate_text:
                raise ValueError("--blanket-rate applies to a single die; with --wafer the rates come from the wafer solve")
            result = simulate_wafer(layout, t, config=cfg, **kwargs)
        else:
            rate = to_si(rate_text, "m/s", "--blanket-rate", "200 nm/min") if rate_text else None
            result = simulate(layout, t, config=cfg, blanket_rate=rate, **kwargs)
    except EquilibriumError as exc:
        _fail(f"no equilibrium of the wafer solve: {exc}", EXIT_NO_EQUILIBRIUM)
    except ValueError as exc:
        _fail(str(exc))
    if out_dir:
        try:
            written = write_die_outputs(result, out_dir)
        except OSError as exc:
            _fail(f"cannot write to {out_dir}: {exc}")
    if as_json:
        click.echo(to_json(result))
        return
    from rich.console import Console

    console = Console()
    die = getattr(result, "die", result)
    d = result.to_dict()

    def um(v, scale=1e9, unit="nm"):
        return "-" if v is None else f"{v * scale:.4g} {unit}"

    rows = [[str(r["index"]), f"{100 * r['density']:.0f} %", um(r["line_width"], 1e6, "um"), f"{r['effective_density']:.3f}", um(r["step_height"]), um(r["dishing"]), um(r["erosion"])]
            for r in d["regions"]]
    console.print(_rich_table(f"die {die.layout.name!r} ({die.process.kind}) after {d['time']:.1f} s", ["region", "density", "line width", "eff. density", "step height", "dishing", "erosion"], rows))
    console.print(f"planarization length {d['planarization_length'] * 1e3:.3g} mm (from the pad stack: {d['planarization_length_from_pad'] * 1e3:.3g} mm); "
                  f"blanket rate {die.blanket_rate * 6e10:.4g} nm/min; time to planarize {um(d['time_to_planarize'], 1, 's')}"
                  + (f"; time to clear {um(d['time_to_clear'], 1, 's')}" if d["time_to_clear"] is not None else ""), highlight=False)
    if wafer:
        import numpy as np

        end = ("clear", result.time_to_clear) if d["time_to_clear"] is not None else ("planarize", result.time_to_planarize)
        console.print(f"{len(result.x)} dies; blanket rate {np.min(result.blanket_rate) * 6e10:.4g}-{np.max(result.blanket_rate) * 6e10:.4g} nm/min; "
                      f"time to {end[0]} {np.nanmin(end[1]):.1f}-{np.nanmax(end[1]):.1f} s", highlight=False)
    if out_dir:
        console.print("wrote " + ", ".join(str(p) for p in written), highlight=False)


# ---- end die command ----


if __name__ == "__main__":  # pragma: no cover
    main()
