"""Files of a polished recipe (``cmpsim polish --out DIR``): JSON, CSV and plots, each written atomically.

- ``polish.json``: :meth:`cmpsim.polisher.engine.PolishResult.to_dict` (SI, units inside);
- ``thickness.csv``: the thickness per radius after each step, one column per step and film
  (``radius_m``, ``<step>.<film>_m``);
- ``die.csv`` and ``die_<k>_r<mm>mm/`` (``cmpsim polish --die``): the die per step and site, and the
  files of ``cmpsim die`` for each site's die after the last step;
- ``thickness.png`` (thickness per radius after each step), ``pad_temperature.png`` (the pad's
  surface temperature against time) and ``endpoint.png`` (the reflectance signal and the platen
  torque against time).

Everything is computed before the first file is written, and each file goes through
:func:`cmpsim.io.atomic_path`: an error leaves no partial file.
"""

from __future__ import annotations

import io as _io
import json
from pathlib import Path

from ..io import atomic_path, atomic_write_text

__all__ = ["thickness_csv", "write_outputs", "FILES"]

#: The files ``write_outputs`` writes.
FILES = ("polish.json", "thickness.csv", "thickness.png", "pad_temperature.png", "endpoint.png")


def thickness_csv(result) -> str:
    """The thickness per radius after each step as CSV text (m)."""
    first = result.steps[0].thickness
    header = ["radius_m"]
    columns = [first["radius"]]
    for s in result.steps:
        for name in result.final.names:
            header.append(f"{s.name}.{name}_m")
            columns.append(s.thickness[name])
    out = _io.StringIO()
    out.write(",".join(header) + "\n")
    for row in zip(*columns):
        out.write(",".join(f"{v:.9e}" for v in row) + "\n")
    return out.getvalue()


def _figures(result) -> dict:
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    figs = {}
    fig, ax = plt.subplots(figsize=(7, 4.2))
    for s in result.steps:
        r = [1e3 * x for x in s.thickness["radius"]]
        total = [sum(s.thickness[n][i] for n in result.final.names) for i in range(len(r))]
        ax.plot(r, [1e9 * t for t in total], label=f"{s.name}: stack")
        top = result.final.names[0]
        ax.plot(r, [1e9 * t for t in s.thickness[top]], ls="--", label=f"{s.name}: {top}")
    ax.set_xlabel("radius (mm)")
    ax.set_ylabel("thickness (nm)")
    ax.set_title("Thickness per radius after each step")
    ax.legend(fontsize=8)
    figs["thickness.png"] = fig
    fig, ax = plt.subplots(figsize=(7, 4.2))
    for s in result.steps:
        ax.plot(s.pad_temperature["time"], [v - 273.15 for v in s.pad_temperature["value"]], label=s.name)
    ax.set_xlabel("time (s)")
    ax.set_ylabel("pad surface temperature (°C)")
    ax.set_title("Pad temperature")
    ax.legend(fontsize=8)
    figs["pad_temperature.png"] = fig
    fig, ax = plt.subplots(figsize=(7, 4.2))
    ax2 = ax.twinx()
    for s in result.steps:
        line, = ax.plot(s.signals.time, s.signals.reflectance, label=f"{s.name}: reflectance")
        ax2.plot(s.signals.time, s.signals.torque, ls=":", color=line.get_color())
        if s.endpoint and s.endpoint["detected"]:
            ax.axvline(s.signals.time[-1], color=line.get_color(), ls="--", lw=0.8)
    ax.set_xlabel("time (s)")
    ax.set_ylabel("reflectance at 650 nm (area mean)")
    ax2.set_ylabel("platen torque (N m), dotted")
    ax.set_title("End-point signals")
    ax.legend(fontsize=8)
    figs["endpoint.png"] = fig
    return figs


def write_files(out_dir, texts: dict, figures: dict) -> list:
    """Write ``texts`` ({name: str}) and ``figures`` ({name: matplotlib figure}, as PNG) into
    ``out_dir``, each file atomically and every figure rendered before the first write (an error
    while rendering leaves nothing); closes the figures. Returns the paths."""
    import matplotlib.pyplot as plt

    out_dir = Path(out_dir)
    images = {}
    try:
        for name, fig in figures.items():
            buf = _io.BytesIO()
            fig.savefig(buf, format="png", dpi=110, bbox_inches="tight")
            images[name] = buf.getvalue()
    finally:
        for fig in figures.values():
            plt.close(fig)
    written = []
    for name, text in texts.items():
        atomic_write_text(out_dir / name, text)
        written.append(out_dir / name)
    for name, data in images.items():
        with atomic_path(out_dir / name) as tmp:
            tmp.write_bytes(data)
        written.append(out_dir / name)
    return written


def die_csv(result) -> str:
    """With a layout riding along: one row per step and site, the die's metrics (SI units in the header)."""
    from .ride import SITE_KEYS

    units = {"time": "s", "blanket_rate": "m_per_s", "hotspot_count": "1", "time_to_planarize": "s", "time_to_clear": "s"}
    keys = ("radius", "duration") + SITE_KEYS
    out = _io.StringIO()
    out.write(",".join(["step"] + [f"{k}_{units.get(k, 's' if k == 'duration' else 'm')}" for k in keys]) + "\n")
    for s in result.steps:
        for d in s.die:
            out.write(",".join([s.name] + ["" if d[k] is None else f"{d[k]:.9e}" if isinstance(d[k], float) else str(d[k]) for k in keys]) + "\n")
    return out.getvalue()


def site_folder(radius: float, k: int) -> str:
    """The folder of site ``k`` (from 1) at ``radius`` (m) under ``--out``: ``die_<k>_r<mm>mm``."""
    return f"die_{k}_r{radius * 1e3:.0f}mm"


def write_outputs(result, out_dir) -> list:
    """Write the files of :data:`FILES` into ``out_dir``; returns their paths. With a layout riding along also
    ``die.csv`` (the die per step and site) and per site the files of ``cmpsim die`` after the last step
    (``cmpsim.die.report.write_die_outputs``) in ``die_<k>_r<mm>mm/``."""
    texts = {"polish.json": json.dumps(result.to_dict(), indent=1), "thickness.csv": thickness_csv(result)}
    ride = result.ride
    if ride is not None:
        texts["die.csv"] = die_csv(result)
    written = write_files(out_dir, texts, _figures(result))
    if ride is not None:
        from ..die.report import write_die_outputs

        original = str(ride.riding.layout) if ride.layout.windowed else ""
        for k, (r, die) in enumerate(zip(ride.radii, ride.dies), start=1):
            written += write_die_outputs(die, Path(out_dir) / site_folder(r, k), original_file=original)
    return written
