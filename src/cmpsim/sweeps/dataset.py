"""The result of a sweep: the records of the points as one :class:`xarray.Dataset`, its file, its summary."""

from __future__ import annotations

import os
import shutil
import uuid
from pathlib import Path
from typing import Iterable

import numpy as np

from .._version import __version__
from ..results import outputs
from ..inputs.config import PARAMETERS
from .spec import SweepError, SweepSpec, _is_string_param

__all__ = ["STATUS_MEANINGS", "summary_lines"]

STATUS_MEANINGS = {
    "ok": "equilibrium found",
    "failed": "no equilibrium found (the error says why)",
    "invalid": "bad parameters at this point (the error names the parameter and its range)",
    "not_requested": "grid cell that is neither in the outer product of the axes nor an explicit point",
}


def _dtype(name: str) -> str:
    """Data type of a scalar of the registry (``float`` for a name it does not know)."""
    return outputs.scalar(name).dtype if name in _SCALAR_NAMES else "float"


_SCALAR_NAMES = frozenset(outputs.scalar_names())


def _scalar_keys(records: Iterable[dict]) -> list[str]:
    keys = outputs.scalar_names()
    extra = sorted({k for r in records for k in r.get("scalars", {}) if k not in _SCALAR_NAMES})
    return keys + extra


def _coord_attrs(name: str) -> dict:
    p = PARAMETERS[name]
    attrs = {"long_name": p.description}
    if not _is_string_param(name):
        attrs["units"] = p.unit or "1"
        if p.display and p.display != p.unit:
            attrs["display_units"] = p.display
    return attrs


def _build_dataset(spec: SweepSpec, chains, records: dict[str, dict], identity: str, warm_start: bool, chain_length: int):
    import xarray as xr

    from ..results.result import REFERENCES

    shape = spec.shape
    dims = spec.dims
    recs = list(records.values())
    keys = _scalar_keys(recs)
    arrays: dict[str, np.ndarray] = {}
    for k in keys:
        if _dtype(k) == "int":
            arrays[k] = np.full(shape, -1, dtype=np.int32)
        elif _dtype(k) == "bool":
            arrays[k] = np.zeros(shape, dtype=bool)
        else:
            arrays[k] = np.full(shape, np.nan, dtype=float)
    status = np.full(shape, "not_requested", dtype=object)
    error = np.full(shape, "", dtype=object)
    start = np.full(shape, "", dtype=object)
    counts = {"ok": 0, "failed": 0, "invalid": 0}
    for chain in chains:
        for p in chain:
            rec = records[p.key]
            idx = tuple(p.index)
            status[idx] = rec["status"]
            error[idx] = rec["error"]
            start[idx] = rec.get("start", "")
            counts[rec["status"]] = counts.get(rec["status"], 0) + 1
            for k, v in rec.get("scalars", {}).items():
                if v is None:
                    continue
                arrays[k][idx] = v
    data_vars = {}
    for k in keys:
        # the attributes of the single-result NetCDF (cmpsim.results.outputs): units, long_name, CF flags
        attrs = dict(outputs.scalar(k).cf_attrs) if k in _SCALAR_NAMES else {}
        if _dtype(k) == "bool":
            attrs["flag_values"] = np.array(attrs["flag_values"], dtype=np.int8)
            attrs["comment"] = "0 where status is not 'ok'"
        elif _dtype(k) == "int":
            attrs["comment"] = "-1 where status is not 'ok'"
        elif k in _SCALAR_NAMES:
            attrs["comment"] = "NaN where status is not 'ok'"
        data_vars[k] = (dims, arrays[k], attrs)
    data_vars["status"] = (dims, status, {"long_name": "outcome of the point", "comment": "; ".join(f"{k}: {v}" for k, v in STATUS_MEANINGS.items())})
    data_vars["error"] = (dims, error, {"long_name": "error message ('' when ok)"})
    data_vars["start"] = (
        dims,
        start,
        {"long_name": "Newton start: warm (predicted from converged chain neighbours), cold, or cold-retry (the warm start failed)"},
    )
    coords = {}
    for d in dims:
        vals = spec.coords[d]
        arr = np.array(vals, dtype=object) if _is_string_param(d) else np.array(vals, dtype=float)
        coords[d] = (d, arr, _coord_attrs(d))
    ds = xr.Dataset(data_vars, coords=coords)
    ds.attrs.update(
        {
            "Conventions": "CF-1.11",
            "title": "cmpsim parameter sweep",
            "source": f"cmpsim {__version__}, model {spec.base.model!r}",
            "history": f"created by cmpsim {__version__} (cmpsim sweep; no time stamp, so that a resumed sweep gives the same file)",
            "references": "\n".join(REFERENCES),
            "cmpsim_version": __version__,
            "cmpsim_schema": outputs.SCHEMA_VERSION,
            "config_toml": spec.base.to_toml_text(),
            "sweep_toml": spec.source,
            "sweep_id": identity,
            "points_requested": int(spec.n_points),
            "points_ok": int(counts.get("ok", 0)),
            "points_failed": int(counts.get("failed", 0)),
            "points_invalid": int(counts.get("invalid", 0)),
            "warm_start": int(bool(warm_start)),
            "chain_dimension": (spec.chain_dim or "") if warm_start else "",
            "chain_length": int(chain_length),
            "status_meanings": "; ".join(f"{k}: {v}" for k, v in STATUS_MEANINGS.items()),
        }
    )
    return ds


def _write(ds, out: Path) -> None:
    """Write the dataset atomically: NetCDF (scipy engine), or zarr for a ``.zarr`` path."""
    from ..io import atomic_path

    if out.suffix == ".zarr":
        import tempfile

        out.parent.mkdir(parents=True, exist_ok=True)
        tmp = Path(tempfile.mkdtemp(prefix=f".{out.name}.", dir=out.parent))
        try:
            # Zarr format 2 with consolidated metadata: readable by zarr 2 and 3 alike
            ds.to_zarr(tmp / "store.zarr", mode="w", zarr_format=2)
            old = None
            if out.exists():
                old = out.parent / f".{out.name}.old-{uuid.uuid4().hex[:8]}"
                os.replace(out, old)
            os.replace(tmp / "store.zarr", out)
            if old is not None:
                shutil.rmtree(old, ignore_errors=True)
        finally:
            shutil.rmtree(tmp, ignore_errors=True)
        return
    with atomic_path(out, suffix=".nc") as tmp:
        ds.to_netcdf(tmp, engine="scipy")


def _check_out(out: Path) -> None:
    if out.suffix == ".zarr":
        try:
            import zarr  # noqa: F401
        except ImportError:
            raise SweepError(
                f"writing {str(out)!r} needs the zarr package, which is not installed; "
                "install it (pip install zarr) or give a NetCDF path (.nc)"
            ) from None


def summary_lines(ds) -> list[str]:
    """Human summary of a sweep dataset: outcome counts and what the warm start saved."""
    status = ds["status"].values.ravel()
    n = int(ds.attrs.get("points_requested", np.count_nonzero(status != "not_requested")))
    lines = [
        f"{n} points: {np.count_nonzero(status == 'ok')} ok, {np.count_nonzero(status == 'failed')} failed, "
        f"{np.count_nonzero(status == 'invalid')} invalid"
    ]
    start = ds["start"].values.ravel()
    ok = status == "ok"
    warm = ok & (start == "warm")
    cold = ok & (start == "cold")
    if warm.any() and cold.any():
        it = ds["iterations"].values.ravel()
        fa = ds["factorizations"].values.ravel()
        lines.append(
            f"warm start: {np.count_nonzero(warm)} points started from converged neighbours: "
            f"{it[warm].mean():.2f} Newton iterations and {fa[warm].mean():.2f} pressure solves per point, "
            f"against {it[cold].mean():.2f} and {fa[cold].mean():.2f} for the {np.count_nonzero(cold)} cold-started "
            f"points (~{100 * (1 - fa[warm].mean() / fa[cold].mean()):.0f}% fewer pressure solves; an estimate over "
            "different points, --no-warm-start gives the exact cold cost)"
        )
    retry = np.count_nonzero(start == "cold-retry")
    if retry:
        lines.append(f"{retry} warm starts failed and were solved again from the cold start")
    return lines
