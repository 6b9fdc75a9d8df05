"""Files of a die run, each written atomically: die.json, die.nc, die.png (and wafer.nc, wafer.png for a wafer of dies;
one die_<level>.png per level of a stack); on a real layout or with limits, hotspots.lyrdb and hotspots.csv."""

from __future__ import annotations

import json
from pathlib import Path

__all__ = ["write_die_outputs", "to_json"]


def to_json(obj, indent: int | None = None) -> str:
    """JSON of a result's :meth:`to_dict` (NaN and inf were already turned into null)."""
    return json.dumps(obj.to_dict(), indent=indent, allow_nan=False)


def _figure(fig, path: Path) -> None:
    import matplotlib.pyplot as plt

    from ..io import atomic_path

    with atomic_path(path, suffix=".png") as tmp:
        fig.savefig(tmp, dpi=110, format="png")
    plt.close(fig)


def _netcdf(ds, path: Path) -> None:
    from ..io import atomic_path

    with atomic_path(path, suffix=".nc") as tmp:
        ds.to_netcdf(tmp, engine="scipy")


def _safe(name: str) -> str:
    return "".join(c if c.isalnum() or c in "-_." else "_" for c in str(name))


def write_die_outputs(result, out, original_file: str = "") -> list[Path]:
    """Write the files of a :class:`DieResult`, :class:`WaferDies` or :class:`~cmpsim.die.chip.StackResult` into ``out``; return their paths.

    ``original_file`` (the layout's path) is recorded in the hotspot database.
    """
    import matplotlib

    matplotlib.use("Agg", force=False)
    from ..io import atomic_write_text
    from .hotspots import write_csv, write_lyrdb

    out = Path(out)
    out.mkdir(parents=True, exist_ok=True)
    if hasattr(result, "levels"):  # a stack
        written = [out / "die.nc", out / "die.json"]
        _netcdf(result.dataset(), written[0])
        atomic_write_text(written[1], to_json(result, indent=2) + "\n")
        for lv in result.levels:
            written.append(out / f"die_{_safe(lv.level)}.png")
            _figure(lv.plot(), written[-1])
        hot = result.hotspots()
        written += [write_lyrdb(out / "hotspots.lyrdb", hot, result.top.layout.name, "cmpsim die --stack: CMP hotspots", original_file),
                    write_csv(out / "hotspots.csv", hot)]
        return written
    die = getattr(result, "die", result)
    written = [out / "die.nc", out / "die.png", out / "die.json"]
    _netcdf(die.dataset(), written[0])
    _figure(die.plot(), written[1])
    atomic_write_text(written[2], to_json(result, indent=2) + "\n")
    if result is not die:
        written += [out / "wafer.nc", out / "wafer.png"]
        _netcdf(result.dataset(), written[3])
        _figure(result.plot(), written[4])
    if die.layout.windowed or die.spec:
        hot = die.hotspots()
        written += [write_lyrdb(out / "hotspots.lyrdb", hot, die.layout.name, "cmpsim die: CMP hotspots", original_file),
                    write_csv(out / "hotspots.csv", hot)]
    return written
