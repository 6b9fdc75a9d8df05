"""Files of a die run: die.json, die.nc, die.png (and wafer.nc, wafer.png for a wafer of dies), each written atomically."""

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


def write_die_outputs(result, out) -> list[Path]:
    """Write the files of a :class:`DieResult` or :class:`WaferDies` into ``out``; return their paths."""
    import matplotlib

    matplotlib.use("Agg", force=False)
    from ..io import atomic_write_text

    out = Path(out)
    out.mkdir(parents=True, exist_ok=True)
    die = getattr(result, "die", result)
    written = [out / "die.nc", out / "die.png", out / "die.json"]
    _netcdf(die.dataset(), written[0])
    _figure(die.plot(), written[1])
    atomic_write_text(written[2], to_json(result, indent=2) + "\n")
    if result is not die:
        written += [out / "wafer.nc", out / "wafer.png"]
        _netcdf(result.dataset(), written[3])
        _figure(result.plot(), written[4])
    return written
