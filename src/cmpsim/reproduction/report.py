"""The products of a reproduction run: figure PNGs and CSVs, the trend table, REPORT.md and REPORT.html."""

from __future__ import annotations

import base64
import csv
import html
import io
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np

from ..inputs import units
from .._version import __version__
from ..inputs.config import Config
from ..tables import markdown_table
from .checks import SIMILAR, SLIGHT, StatementResult
from .paper import CURVES, LOADS_PSI, SPEEDS_RPM, FigureSpec, RunData

__all__ = ["ReproductionReport", "FigureResult", "CSV_COLUMNS"]

#: Columns of every figure CSV (SI unless the name says otherwise).
CSV_COLUMNS = (
    "figure",
    "curve",
    "label",
    "model",
    "particle_diameter_nm",
    "pad_roughness_um",
    "applied_pressure_psi",
    "rotation_speed_rpm",
    "film_thickness_center_um",
    "film_thickness_ratio",
    "attack_angle_rad",
    "contact_area_ratio_elastic",
    "contact_area_ratio_elastoplastic",
    "contact_area_ratio_plastic",
    "fluid_load_fraction",
    "removal_rate_nm_per_min",
    "removal_rate_relative",
    "flow_factor_floored_fraction",
    "converged",
    "status",
)


# --------------------------------------------------------------------------- the report object
@dataclass
class FigureResult:
    spec: FigureSpec
    png: Path
    csv: Path
    rows: list[dict[str, Any]]


@dataclass
class ReproductionReport:
    """Everything a ``cmpsim reproduce`` run produced."""

    out: Path
    grid: str
    config: Config
    data: RunData
    figures: list[FigureResult]
    statements: list[StatementResult]
    equilibria: int
    factorizations: int
    failures: list[str]
    elapsed_s: float
    solve_s: float
    report_md: Path
    report_html: Path
    notes: list[str] = field(default_factory=list)

    @property
    def n_reproduced(self) -> int:
        return sum(s.reproduced for s in self.statements)

    def trend_rows(self) -> list[list[str]]:
        return [s.as_row() for s in self.statements]

    def figure(self, number: int) -> FigureResult:
        for f in self.figures:
            if f.spec.number == number:
                return f
        raise KeyError(number)


# --------------------------------------------------------------------------- figures and CSV
def _csv_rows(spec: FigureSpec, data: RunData) -> list[dict[str, Any]]:
    rows = []
    for c in spec.curves:
        for p in data.curve(c, spec.sweep):
            cfg = p.config
            r = {
                "figure": spec.number,
                "curve": c,
                "label": CURVES[c].label,
                "model": cfg.model,
                "particle_diameter_nm": units.convert(cfg.particle_diameter, "m", "nm"),
                "pad_roughness_um": units.convert(cfg.pad_roughness, "m", "um"),
                "applied_pressure_psi": units.convert(cfg.applied_pressure, "Pa", "psi"),
                "rotation_speed_rpm": units.convert(cfg.rotation_speed, "rad/s", "rpm"),
            }
            for col, key, f in (
                ("film_thickness_center_um", "film_thickness_center", 1e6),
                ("film_thickness_ratio", "film_thickness_ratio", 1.0),
                ("attack_angle_rad", "attack_angle", 1.0),
                ("contact_area_ratio_elastic", "contact_area_ratio_elastic", 1.0),
                ("contact_area_ratio_elastoplastic", "contact_area_ratio_elastoplastic", 1.0),
                ("contact_area_ratio_plastic", "contact_area_ratio_plastic", 1.0),
                ("fluid_load_fraction", "fluid_load_fraction", 1.0),
                ("removal_rate_nm_per_min", "removal_rate_mean", 1e9 * 60.0),
                ("removal_rate_relative", "removal_rate_relative", 1.0),
                ("flow_factor_floored_fraction", "flow_factor_floored_fraction", 1.0),
            ):
                r[col] = p.get(key) * f
            r["converged"] = "yes" if p.ok else "no"
            r["status"] = p.status
            rows.append(r)
    return rows


def _write_csv(path: Path, rows: list[dict[str, Any]], header_lines: list[str]) -> None:
    from ..io import atomic_write_text

    buf = io.StringIO()
    for line in header_lines:
        buf.write(f"# {line}\n")
    w = csv.DictWriter(buf, fieldnames=list(CSV_COLUMNS), lineterminator="\n")
    w.writeheader()
    for r in rows:
        w.writerow({k: (f"{v:.10g}" if isinstance(v, float) else v) for k, v in r.items()})
    atomic_write_text(path, buf.getvalue())


_STYLE = {
    "hydro_s20": dict(color="tab:blue", marker="s", linestyle="--"),
    "lep_s15": dict(color="tab:red", marker="o", linestyle="-"),
    "hydro_s10": dict(color="tab:green", marker="^", linestyle=":"),
    "d100": dict(color="tab:blue", marker="o", linestyle="-"),
    "d200": dict(color="tab:orange", marker="s", linestyle="--"),
    "a": dict(color="tab:blue", marker="o", linestyle="-"),
    "b": dict(color="tab:orange", marker="s", linestyle="--"),
    "c": dict(color="tab:green", marker="^", linestyle=":"),
}


def _plot(spec: FigureSpec, data: RunData, path: Path) -> None:
    import matplotlib

    matplotlib.use("Agg", force=False)
    import matplotlib.pyplot as plt

    from ..io import atomic_path

    n = len(spec.panels)
    fig, axes = plt.subplots(1, n, figsize=(max(6.0 * n, 7.5), 5.2), squeeze=False, layout="constrained")
    xlabel = "Applied load (psi)" if spec.sweep == "load" else "Relative rotation speed (rpm)"
    any_floored = False
    for ax, (key, ylabel, factor, log) in zip(axes[0], spec.panels):
        for c in spec.curves:
            x, y = data.xy(c, spec.sweep, key)
            _, fl = data.xy(c, spec.sweep, "flow_factor_floored_fraction")
            st = _STYLE[c]
            label = CURVES[c].label
            floored = np.nan_to_num(fl) > 0
            if floored.any():
                any_floored = True
                label += f" [flow factors regularised on {100 * np.nanmin(fl[floored]):.0f}-{100 * np.nanmax(fl[floored]):.0f} % of faces]"
            ax.plot(x, y * factor, color=st["color"], linestyle=st["linestyle"], marker=st["marker"], mfc="none" if floored.any() else st["color"], label=label)
        ax.set_xlabel(xlabel)
        ax.set_ylabel(ylabel)
        if log:
            ax.set_yscale("log")
        ax.grid(True, alpha=0.3)
        ax.legend(fontsize=8, loc="best")
    import textwrap

    title = textwrap.fill(f"Fig. {spec.number} (cmpsim): {spec.title}", 95 if n > 1 else 80)
    if any_floored:
        title += "\nhollow markers: equilibrium outside the validity of the flow factors (regularised)"
    if spec.number in (3, 4):
        title += "\nexperimental data of Lu et al. (2004): not available to this project, not shown"
    fig.suptitle(title, fontsize=10)
    with atomic_path(path, suffix=".png") as tmp:
        fig.savefig(tmp, dpi=110, format="png")
    plt.close(fig)


class FigureWriter:
    """Draws the figures of a run, on a second core while this process goes on solving.

    On a machine with two or more cores where ``fork`` is available (Linux) and this process
    runs no other thread (forking those is unsafe; the progress bar's thread starts later), a
    child process is forked at construction: it imports matplotlib and then draws every
    figure :meth:`submit` sends it (pickled over a pipe), while the curves of the next figures
    are being solved (the figures of the last curve too: drawing them here would first import
    matplotlib here, which took longer than the child needs for them); :meth:`finish` waits
    for the child. Otherwise every figure is drawn here, one after the other, by
    :meth:`finish`. matplotlib draws one figure on one core, and the ten figures
    of ``cmpsim reproduce`` took about as long as its 102 equilibria.

    Each PNG is written atomically (:func:`cmpsim.io.atomic_path`), so a failure leaves no
    partial file; a failure in the child is raised by :meth:`finish` as a RuntimeError.
    """

    def __init__(self, processes: int | None = None):
        import multiprocessing
        import os
        import threading

        if processes is None:
            try:
                processes = len(os.sched_getaffinity(0))
            except AttributeError:  # pragma: no cover - macOS / Windows
                processes = os.cpu_count() or 1
        self._late: list = []  # without a child: the figures finish() draws here
        self._child = self._conn = None
        forkable = "fork" in multiprocessing.get_all_start_methods()
        if processes >= 2 and forkable and threading.active_count() == 1:
            ctx = multiprocessing.get_context("fork")
            self._conn, child_end = ctx.Pipe()
            self._child = ctx.Process(target=_figure_worker, args=(child_end,), name="cmpsim-figures", daemon=True)
            self._child.start()
            child_end.close()
            # a sender thread (started after the fork) writes the jobs to the pipe: a pipe
            # write blocks while the child is busy, and the solve must not wait for it
            import queue

            self._jobs: queue.SimpleQueue = queue.SimpleQueue()
            self._sender = threading.Thread(target=self._send_all, name="cmpsim-figures-sender", daemon=True)
            self._sender.start()

    def _send_all(self) -> None:
        while True:
            job = self._jobs.get()
            try:
                self._conn.send(job)
            except (OSError, ValueError):  # the child is gone (or was stopped): finish() reports it
                return
            if job is None:
                return

    def submit(self, spec: FigureSpec, data: RunData, path: Path) -> None:
        """Draw ``spec`` from ``data`` (its curves complete) into ``path``: now, on the child, if there is one."""
        if self._child is not None:
            self._jobs.put((spec, data.subset(spec), path))
        else:
            self._late.append((spec, data, path))

    def finish(self) -> None:
        """Draw what is left and wait for the child; raises RuntimeError if a figure failed."""
        if self._child is None:
            for job in self._late:
                _plot(*job)
            return
        self._jobs.put(None)
        self._sender.join()
        try:
            error = self._conn.recv()
        except (EOFError, OSError):  # the child died without a word
            error = None
        self._child.join()
        self._conn.close()
        if error:
            raise RuntimeError(f"drawing the figures failed in the figure process:\n{error}")
        if self._child.exitcode != 0:
            raise RuntimeError(f"drawing the figures failed: the figure process ended with exit code {self._child.exitcode}")

    def close(self) -> None:
        """Stop the child if :meth:`finish` was not reached (the solve failed or was interrupted)."""
        if self._child is not None and self._child.is_alive():
            self._jobs.put(None)  # the sender thread ends too
            self._child.terminate()
            self._child.join()
            self._sender.join(timeout=5.0)
            self._conn.close()


def _figure_worker(conn) -> None:
    """The child of :class:`FigureWriter`: draw each job received until None; send back "" or the error."""
    import signal
    import traceback

    import matplotlib

    signal.signal(signal.SIGINT, signal.SIG_IGN)  # a Ctrl-C is the parent's to handle (it stops this child)

    matplotlib.use("Agg", force=False)
    import matplotlib.pyplot  # noqa: F401  (while the parent solves)

    error = ""
    while True:
        job = conn.recv()
        if job is None:
            break
        if not error:
            try:
                _plot(*job)
            except Exception:
                error = traceback.format_exc()
    conn.send(error)
    conn.close()


# --------------------------------------------------------------------------- report
def _blocks(rep: ReproductionReport, command: str) -> list[tuple]:
    """The report as blocks: ("h", level, text) ("p", text) ("table", header, rows) ("img", png, caption, csv) ("ul", items)."""
    b: list[tuple] = []
    n, m = rep.n_reproduced, len(rep.statements)
    b.append(("h", 1, "cmpsim: reproduction of the paper's parameter study (Figs. 3-12)"))
    b.append(
        (
            "p",
            f"Generated by `{command}` with cmpsim {__version__} on the {rep.grid!r} grid "
            f"({rep.config.grid_shape[0]} rings x {rep.config.grid_shape[1]} sectors): {rep.equilibria} equilibria solved "
            f"({rep.factorizations} sparse LU factorisations) in {rep.solve_s:.1f} s; whole run {rep.elapsed_s:.1f} s. "
            "Every verdict below is computed from the data of this run by the checks in `cmpsim/reproduction/checks.py` (`STATEMENTS`); none is written by hand.",
        )
    )
    b.append(("h", 2, f"Trend table: {n} of {m} statements of the paper reproduced"))
    b.append(
        (
            "p",
            f"Criteria. 'Increases' / 'decreases': strictly monotone over the sampled points ({len(LOADS_PSI)} loads, 2-6 psi; "
            f"{len(SPEEDS_RPM)} speeds, 30-90 rpm). 'Slightly' / 'lightly': monotone and the change across the whole range is "
            f"less than {SLIGHT:g} times the base-case value (4 psi, 60 rpm). 'Approximately the same': largest/smallest ≤ {SIMILAR:g}. "
            "'Higher at any load/speed': above at every sampled point. 'Larger influence': larger max/min ratio over the load range "
            "(×3) than over the speed range (×3).",
        )
    )
    b.append(("table", ["#", "Fig.", "statement of the paper", "criterion", "reproduced", "evidence (this run)", "why not"], rep.trend_rows()))
    b.append(("h", 2, "Notes"))
    b.append(("ul", rep.notes))
    b.append(("h", 2, "Figures"))
    for f in rep.figures:
        b.append(("img", f.png, f"Fig. {f.spec.number}: {f.spec.title}", f.csv))
    if rep.failures:
        b.append(("h", 2, "Operating points without equilibrium"))
        b.append(("ul", rep.failures))
    b.append(("h", 2, "Parameter set"))
    b.append(
        (
            "p",
            "Every input of the run (display units); the curves change only model, particle_diameter, pad_roughness, "
            "applied_pressure and rotation_speed as listed in each CSV.",
        )
    )
    rows = [[name, value, disp or "-", src] for name, value, disp, src in rep.config.describe()]
    b.append(("table", ["parameter", "value", "unit", "source"], rows))
    return b


def _render_md(blocks: list[tuple], out: Path) -> str:
    lines: list[str] = []
    for blk in blocks:
        kind = blk[0]
        if kind == "h":
            lines += ["#" * blk[1] + " " + blk[2], ""]
        elif kind == "p":
            lines += [blk[1], ""]
        elif kind == "ul":
            lines += [f"- {item}" for item in blk[1]] + [""]
        elif kind == "table":
            lines += [markdown_table(blk[1], blk[2])]
        elif kind == "img":
            png, caption, csvp = blk[1], blk[2], blk[3]
            lines += [f"![{caption}]({png.relative_to(out).as_posix()})", "", f"*{caption}* Data: [`{csvp.relative_to(out).as_posix()}`]({csvp.relative_to(out).as_posix()})", ""]
    return "\n".join(lines)


def _render_html(blocks: list[tuple], out: Path) -> str:
    e = html.escape
    parts = [
        "<!DOCTYPE html><html lang='en'><head><meta charset='utf-8'><title>cmpsim reproduction report</title>",
        "<style>body{font-family:sans-serif;max-width:1300px;margin:2em auto;padding:0 1em;line-height:1.4}"
        "table{border-collapse:collapse;font-size:0.85em;margin:1em 0}td,th{border:1px solid #bbb;padding:3px 6px;vertical-align:top}"
        "th{background:#eee}td.yes{background:#e3f6e3;font-weight:bold}td.no{background:#fbe3e3;font-weight:bold}"
        "img{max-width:100%;border:1px solid #ddd}code{background:#f4f4f4}</style></head><body>",
    ]
    for blk in blocks:
        kind = blk[0]
        if kind == "h":
            parts.append(f"<h{blk[1]}>{e(blk[2])}</h{blk[1]}>")
        elif kind == "p":
            text = e(blk[1])
            # `code` spans
            segs = text.split("`")
            text = "".join(f"<code>{s}</code>" if i % 2 else s for i, s in enumerate(segs))
            parts.append(f"<p>{text}</p>")
        elif kind == "ul":
            parts.append("<ul>" + "".join(f"<li>{e(str(i))}</li>" for i in blk[1]) + "</ul>")
        elif kind == "table":
            header, rows = blk[1], blk[2]
            parts.append("<table><tr>" + "".join(f"<th>{e(h)}</th>" for h in header) + "</tr>")
            for r in rows:
                cells = []
                for c in r:
                    cls = f" class='{c}'" if c in ("yes", "no") else ""
                    cells.append(f"<td{cls}>{e(str(c))}</td>")
                parts.append("<tr>" + "".join(cells) + "</tr>")
            parts.append("</table>")
        elif kind == "img":
            png, caption, csvp = blk[1], blk[2], blk[3]
            data = base64.b64encode(png.read_bytes()).decode("ascii")
            rel = csvp.relative_to(out).as_posix()
            parts.append(f"<figure><img alt='{e(caption)}' src='data:image/png;base64,{data}'><figcaption>{e(caption)} Data: <a href='{e(rel)}'>{e(rel)}</a></figcaption></figure>")
    parts.append("</body></html>")
    return "\n".join(parts)


def _notes(data: RunData, failures: list[str]) -> list[str]:
    notes = []
    for c in ("hydro_s20", "hydro_s10"):
        fl = []
        h = []
        for s in ("load", "speed"):
            fl += [p.get("flow_factor_floored_fraction") for p in data.curve(c, s) if p.ok]
            h += [p.get("film_thickness_ratio") for p in data.curve(c, s) if p.ok]
        if fl:
            notes.append(
                f"{CURVES[c].label}: the equilibrium film is h/σ = {min(h):.3g}-{max(h):.3g}; the pressure flow factor of eq. 8 "
                f"was regularised (floored) on {100 * min(fl):.0f}-{100 * max(fl):.0f} % of the cell faces, i.e. these curves lie "
                "outside the validity of the perturbation flow factors (column flow_factor_floored_fraction of the CSVs)."
            )
    lep_fl = [p.get("flow_factor_floored_fraction") for (c, s), pts in data.curves.items() if not c.startswith("hydro") for p in pts if p.ok]
    if lep_fl:
        notes.append(
            "LEP curves: the flow factors were never regularised (valid everywhere)."
            if max(lep_fl) == 0
            else f"LEP curves: flow factors regularised on at most {100 * max(lep_fl):.1f} % of the faces."
        )
    notes.append(
        "Relative removal rate (Figs. 11-12): removal_rate_mean / removal_rate_mean of the LEP case d = 100 nm, σ = 15 μm, 4 psi, 60 rpm "
        "with every other input equal (cmpsim.solver.model.REFERENCE_CASE), as in the paper."
    )
    notes.append(
        "The paper compares Figs. 3-4 with measurements of Lu et al. (J. Electrochem. Soc. 151, G241, 2004); those data were "
        "not available to this project and are neither shown nor estimated. Statement S09 is therefore not reproduced."
    )
    notes.append("Pad roughness is varied with the configured roughness_scaling (see docs/model.md); the curves of a figure differ only in the inputs named in their legend.")
    if failures:
        notes.append(f"{len(failures)} operating point(s) had no equilibrium; they appear as NaN in the CSVs and make the statements that need them fail.")
    return notes


def _write_csv_trends(path: Path, statements: list[StatementResult]) -> None:
    from ..io import atomic_write_text

    buf = io.StringIO()
    w = csv.writer(buf, lineterminator="\n")
    w.writerow(["id", "figure", "statement", "criterion", "reproduced", "evidence", "why_not"])
    for s in statements:
        w.writerow(s.as_row())
    atomic_write_text(path, buf.getvalue())
