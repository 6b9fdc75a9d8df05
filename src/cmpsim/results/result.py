"""The result of one operating point: scalars in SI, wafer maps, radial profiles, export and plots.

Every output is declared in :mod:`cmpsim.results.outputs` (name, SI unit, long name, display unit,
reduction); the JSON (schema 2), the NetCDF (CF-1.11), the tables and the plots below are
generated from that registry.
"""

from __future__ import annotations

import json
import math
import warnings
from pathlib import Path
from typing import Any

import numpy as np

from . import outputs as _reg
from .._version import __version__
from ..inputs.config import PARAMETERS, Config, format_display

__all__ = ["Result", "SCALARS", "FIELDS", "REFERENCES", "JSON_SCHEMA_PATH"]

#: Every scalar output (values, then solver diagnostics): name -> (SI unit, display factor,
#: display unit, long name). Derived from :data:`cmpsim.results.outputs.OUTPUTS`.
SCALARS: dict[str, tuple[str, float, str, str]] = {
    n: (_reg.scalar(n).unit, _reg.scalar(n).display_factor, _reg.scalar(n).display_unit, _reg.scalar(n).long_name) for n in _reg.scalar_names()
}

#: Every wafer map: name -> (SI unit, long name). Derived from :data:`cmpsim.results.outputs.OUTPUTS`.
FIELDS: dict[str, tuple[str, str]] = {n: (_reg.field(n).unit, _reg.field(n).long_name) for n in _reg.field_names()}

#: The JSON Schema of :meth:`Result.to_dict` (schema 2).
JSON_SCHEMA_PATH = Path(__file__).parents[1] / "data" / "result.schema.json"  # src/cmpsim/data

REFERENCES = [
    "The paper: 'An improved model considering elastic-plastic contact and partial hydrodynamic lubrication for chemical mechanical polishing' (shared/paper)",
    "Haff, J. Fluid Mech. 134, 401 (1983): grain flow",
    "Patir & Cheng, J. Lubr. Technol. 100, 12 (1978); Tripp, J. Lubr. Technol. 105, 458 (1983): flow factors",
    "Greenwood & Williamson, Proc. R. Soc. A 295, 300 (1966): elastic asperity contact",
    "Zhao, Maietta & Chang, J. Tribol. 122, 86 (2000): elastoplastic asperity contact",
    "Abbott & Firestone, Mech. Eng. 55, 569 (1933): plastic asperity contact",
    "Runnels & Eyman, J. Electrochem. Soc. 141, 1698 (1994): RR = K sigma_n tau",
    "SEMI M1 and SEMI MF1530: wafer quality area inside a metrology edge exclusion; within-wafer non-uniformity as 1-sigma / mean (docs/model.md, 'Within-wafer uniformity')",
]


def _jsonable(v: Any) -> Any:
    if isinstance(v, (bool, np.bool_)):
        return bool(v)
    if isinstance(v, (int, np.integer)):
        return int(v)
    if isinstance(v, (float, np.floating)):
        return float(v)
    return v


def _finite(v: Any) -> Any:
    """NaN and inf -> None (JSON null)."""
    return None if isinstance(v, float) and not math.isfinite(v) else v


class _Scalars(dict):
    """The scalars of a result, by current name; a 0.1 name still reads (DeprecationWarning)."""

    def __missing__(self, key):
        new, factors = _reg.canonical_name(key)
        if new == key or not dict.__contains__(self, new):
            raise KeyError(key)
        return _reg.legacy_value(dict.__getitem__(self, new), factors)


class Result:
    """Outputs of one operating point.

    * ``result.NAME``: every scalar of :mod:`cmpsim.results.outputs` in SI (``result.attack_angle``,
      ``result.within_wafer_nonuniformity``) and the profiles (``result.removal_rate_profile``,
      ``result.radius``); the 0.1 names (``result.film_thickness_center_m``,
      ``result.removal_rate_nm_per_min``) still read, with a ``DeprecationWarning``.
    * :meth:`to_dict` / :meth:`to_json`: the object of ``cmpsim run --json`` (schema 2);
      :meth:`to_schema1`: the 0.1 object.
    * :attr:`fields`: the wafer maps; :attr:`dataset` / :meth:`to_netcdf`: maps, profiles and
      scalars as a CF-1.11 dataset.
    * :meth:`summary`, :meth:`plot`, :meth:`plot_profiles`, :attr:`provenance`.
    """

    def __init__(self, config: Config, scalars: dict, polar: dict, grid, problem=None, solution=None, profiles: dict | None = None):
        self.config = config
        order = [n for n in _reg.scalar_names() if n in scalars] + [n for n in scalars if n not in _reg.scalar_names()]
        self.scalars = _Scalars({k: _jsonable(scalars[k]) for k in order})
        self.polar = polar
        self.grid = grid
        self.problem = problem
        self.solution = solution
        if profiles is None:
            from .uniformity import ring_mean

            profiles = {"radius": grid.r[:, 0].copy()}
            profiles.update({n: ring_mean(polar[_reg.profile(n).of[0]]) for n in _reg.profile_names()})
        self.profiles = profiles
        self._fields = None
        self.root_scan = None

    def __getattr__(self, name: str):
        d = self.__dict__
        scalars = d.get("scalars", {})
        if dict.__contains__(scalars, name):
            return scalars[name]
        profiles = d.get("profiles") or {}
        if name in profiles:
            return profiles[name]
        new, factors = _reg.canonical_name(name, warn=False)
        if new != name and dict.__contains__(scalars, new):
            warnings.warn(
                f"Result.{name} is deprecated (cmpsim 0.1 name); use Result.{new}, in SI", DeprecationWarning, stacklevel=2
            )
            return _reg.legacy_value(scalars[new], factors)
        raise AttributeError(name)

    def __dir__(self):
        return sorted(set(super().__dir__()) | set(self.scalars) | set(self.profiles))

    def __repr__(self) -> str:
        shown = ("film_thickness_center", "attack_angle", "fluid_load_fraction", "removal_rate_mean", "within_wafer_nonuniformity", "converged")
        parts = [f"model={self.config.model!r}"]
        for name in shown:
            if dict.__contains__(self.scalars, name):
                o, v = _reg.scalar(name), self.scalars[name]
                parts.append(f"{name}={v}" if isinstance(v, bool) else f"{name}={_reg.to_display(o, v):.4g} {o.display_unit}")
        return f"Result({', '.join(parts)})"

    # ------------------------------------------------------------------ export
    def to_dict(self) -> dict[str, Any]:
        """The object of ``cmpsim run --json`` (schema 2), SI throughout.

        ``{"schema": 2, "cmpsim_version", "inputs": {every input}, "values": {result
        scalars}, "units": {name: unit of every value, diagnostic and profile}, "solver":
        {diagnostics}, "profiles": {"radius": [...], "removal_rate": [...],
        "film_thickness": [...]}}``; described by ``cmpsim/data/result.schema.json``.
        """
        s = self.scalars
        values = {n: s[n] for n in _reg.value_names() if dict.__contains__(s, n)}
        solver = {n: s[n] for n in _reg.diagnostic_names() if dict.__contains__(s, n)}
        profiles = {"radius": [float(v) for v in self.profiles["radius"]]}
        units = {n: _reg.scalar(n).unit for n in [*values, *solver]}
        units["radius"] = _reg.profile("radius").unit
        for n in _reg.profile_names():
            key = _reg.profile(n).of[0]
            profiles[key] = [float(v) for v in self.profiles[n]]
            units[key] = _reg.profile(n).unit
        return {
            "schema": _reg.SCHEMA_VERSION,
            "cmpsim_version": __version__,
            "inputs": {k: _jsonable(v) for k, v in self.config.to_dict().items()},
            "values": values,
            "units": units,
            "solver": solver,
            "profiles": profiles,
        }

    def to_schema1(self) -> dict[str, Any]:
        """The flat object of cmpsim 0.1 (``cmpsim run --json --schema 1``), unchanged: deprecated."""
        out = {}
        for old, new, factors in _reg.SCHEMA1_KEYS:
            if dict.__contains__(self.scalars, new):
                out[old] = _reg.legacy_value(self.scalars[new], factors)
        return out

    def to_json(self, indent: int | None = None, schema: int = _reg.SCHEMA_VERSION) -> str:
        """:meth:`to_dict` (or, with ``schema=1``, :meth:`to_schema1`) as JSON; NaN and inf are written as null."""
        if schema == 1:
            data: Any = {k: _finite(v) for k, v in self.to_schema1().items()}
        elif schema == _reg.SCHEMA_VERSION:
            data = self.to_dict()
            for part in ("values", "solver"):
                data[part] = {k: _finite(v) for k, v in data[part].items()}
            data["profiles"] = {k: [_finite(v) for v in vs] for k, vs in data["profiles"].items()}
        else:
            raise ValueError(f"schema must be 1 or {_reg.SCHEMA_VERSION}; got {schema!r}")
        return json.dumps(data, indent=indent, allow_nan=False)

    def summary_rows(self) -> list[tuple[str, str, str, str]]:
        """(name, value in the display unit, display unit, long name) for every scalar: values, then diagnostics."""
        rows = []
        for name in _reg.scalar_names():
            if not dict.__contains__(self.scalars, name):
                continue
            o = _reg.scalar(name)
            v = self.scalars[name]
            if isinstance(v, bool):
                text = "yes" if v else "no"
            elif isinstance(v, int):
                text = str(v)
            else:
                text = f"{_reg.to_display(o, v):.6g}"
            rows.append((name, text, o.display_unit, o.long_name))
        return rows

    def summary_table(self, width: int = 80, plain: bool = False):
        """:meth:`summary_rows` as a ``rich`` table legible at ``width`` columns (names never cut; ``plain``: no box lines)."""
        from ..tables import legible_table

        rows = self.summary_rows()
        n_values = sum(1 for r in rows if _reg.scalar(r[0]).kind == "value")
        g = self.grid
        return legible_table(
            f"cmpsim {__version__}, model {self.config.model!r}, grid {g.n_r}x{g.n_theta}",
            ["output", "value", "unit"],
            [r[:3] for r in rows],
            detail=[r[3] for r in rows],
            detail_header="meaning",
            width=width,
            sections=(n_values - 1,),
            plain=plain,
        )

    def summary(self, width: int = 80) -> str:
        """A plain-text table of every scalar with its unit and meaning, ``width`` columns wide."""
        from ..tables import render_text

        return render_text(self.summary_table(width, plain=True), width)

    @property
    def provenance(self) -> dict[str, Any]:
        """Model variant, package version, references, and every parameter with value, unit and source."""
        params = {}
        for name, value, display, source in self.config.describe():
            p = PARAMETERS[name]
            params[name] = {
                "value_si": getattr(self.config, name),
                "si_unit": p.unit if p.unit not in ("choice", "grid") else "",
                "value_display": value,
                "display_unit": display,
                "source": source,
            }
        return {
            "package": "cmpsim",
            "version": __version__,
            "model": self.config.model,
            "kinematics": self.config.kinematics,
            "grid": f"{self.grid.n_r}x{self.grid.n_theta}",
            "references": list(REFERENCES),
            "parameters": params,
        }

    # ------------------------------------------------------------------ fields
    def _polar_interpolator(self, values: np.ndarray, edge_value: float | None):
        from scipy.interpolate import RegularGridInterpolator

        g = self.grid
        r = np.concatenate([[0.0], g.r[:, 0], [g.radius]])
        t = g.theta[0]
        t = np.concatenate([[t[-1] - 2 * np.pi], t, [t[0] + 2 * np.pi]])
        v = np.concatenate([values[:, -1:], values, values[:, :1]], axis=1)
        centre = np.full((1, v.shape[1]), values[0].mean())
        # the last centres lie dr/2 inside the rim: linear extrapolation over half a ring
        edge = 1.5 * v[-1:] - 0.5 * v[-2:-1] if edge_value is None else np.full((1, v.shape[1]), edge_value)
        v = np.concatenate([centre, v, edge], axis=0)
        return RegularGridInterpolator((r, t), v, bounds_error=False, fill_value=None)

    def _field_names(self) -> list[str]:
        """The fields of this result: every field of the registry, the optional ones if solved."""
        return [n for n in FIELDS if not _reg.field(n).optional or n in self.polar]

    def field_arrays(self, n: int | None = None) -> dict[str, Any]:
        """Wafer maps on an n x n Cartesian grid: {'x', 'y', name: array}, NaN outside the wafer."""
        from ..physics.contact import asperity_contact

        g = self.grid
        n = n or max(65, 4 * g.n_r + 1)
        x = np.linspace(-g.radius, g.radius, n)
        X, Y = np.meshgrid(x, x, indexing="xy")
        inside = X**2 + Y**2 <= g.radius**2 * (1 + 1e-12)
        Rr = np.hypot(X, Y)
        T = np.mod(np.arctan2(Y, X), 2 * np.pi)
        pts = np.stack([Rr[inside], T[inside]], axis=-1)
        out = {"x": x, "y": x}
        u = self.solution.state.u
        h = self.problem.film(u, X[inside], Y[inside])
        exact = {"film_thickness": h}
        if self.config.model != "hydrodynamic":
            c = asperity_contact(h, self.problem.pad, model=self.config.model)
            exact.update(
                contact_pressure=c.pressure,
                contact_area_ratio_elastic=c.area_ratio_elastic,
                contact_area_ratio_elastoplastic=c.area_ratio_elastoplastic,
                contact_area_ratio_plastic=c.area_ratio_plastic,
            )
        # the slurry fields are interpolated (their edge values are known exactly); the fields
        # built from them and from the exact contact are recombined pointwise, so that the
        # maps keep the identities of the solver (total = slurry + contact, ...)
        edges = {"slurry_pressure": 0.0, "granular_pressure": self.scalars["ambient_pressure"]}
        values = dict(exact)
        for name in self._field_names():
            if name not in values and name not in ("total_pressure", "normal_stress"):
                values[name] = self._polar_interpolator(self.polar[name], edges.get(name))(pts)
        if "fill_fraction" in values:
            values["fill_fraction"] = np.clip(values["fill_fraction"], 0.0, 1.0)
        if "contact_pressure" in values:
            a_r = values["contact_area_ratio_elastic"] + values["contact_area_ratio_elastoplastic"] + values["contact_area_ratio_plastic"]
            values["total_pressure"] = values["slurry_pressure"] + values["contact_pressure"]
            values["normal_stress"] = (1.0 - a_r) * values["granular_pressure"] + values["contact_pressure"]
        else:
            values["total_pressure"] = values["slurry_pressure"]
            values["normal_stress"] = values["granular_pressure"]
        for name in self._field_names():
            arr = np.full(X.shape, np.nan)
            arr[inside] = values[name]
            out[name] = arr
        return out

    @property
    def fields(self):
        """Wafer maps as an ``xarray.Dataset`` on x, y (m), CF attributes, NaN outside the wafer."""
        if self._fields is None:
            import xarray as xr

            arrays = self.field_arrays()
            x = arrays.pop("x")
            y = arrays.pop("y")
            ds = xr.Dataset(
                {k: (("y", "x"), v, _reg.field(k).cf_attrs) for k, v in arrays.items()},
                coords={
                    "x": ("x", x, {"units": "m", "long_name": "position along the sliding direction", "axis": "X"}),
                    "y": ("y", y, {"units": "m", "long_name": "position across the sliding direction", "axis": "Y"}),
                },
            )
            ds.attrs["cmpsim_version"] = __version__
            ds.attrs["model"] = self.config.model
            ds.attrs["config_toml"] = self.config.to_toml_text()
            self._fields = ds
        return self._fields

    def profile_dataset(self):
        """The radial profiles on the ``radius`` coordinate (m, with ring bounds), CF attributes."""
        import xarray as xr

        edges = self.grid.ring_faces
        radius_attrs = dict(_reg.profile("radius").cf_attrs, bounds="radius_bounds")
        data = {
            n: ("radius", np.asarray(self.profiles[n], dtype=float), dict(_reg.profile(n).cf_attrs, comment=_reg.REDUCTIONS["ring_mean"]))
            for n in _reg.profile_names()
        }
        data["radius_bounds"] = (("radius", "nv"), np.stack([edges[:-1], edges[1:]], axis=1), {"units": "m", "long_name": "inner and outer radius of each ring"})
        return xr.Dataset(data, coords={"radius": ("radius", np.asarray(self.profiles["radius"], dtype=float), radius_attrs)})

    def scalar_variables(self) -> dict:
        """Every scalar as a 0-d ``xarray.DataArray`` under its NetCDF name, with CF attributes."""
        import xarray as xr

        out = {}
        for name in _reg.scalar_names():
            if not dict.__contains__(self.scalars, name):
                continue
            o = _reg.scalar(name)
            v = self.scalars[name]
            attrs = dict(o.cf_attrs)
            if o.netcdf_name != name:
                attrs["cmpsim_name"] = name
            if o.dtype == "bool":
                attrs["flag_values"] = np.array(attrs["flag_values"], dtype=np.int8)
                arr = np.array(int(bool(v)), dtype=np.int8)
            elif o.dtype == "int":
                arr = np.array(int(v), dtype=np.int32)
            else:
                arr = np.array(float(v), dtype=float)
            out[o.netcdf_name] = xr.DataArray(arr, attrs=attrs)
        return out

    @property
    def dataset(self):
        """Maps, profiles and scalars (0-d variables) in one CF-1.11 ``xarray.Dataset``: what :meth:`to_netcdf` writes."""
        import xarray as xr

        ds = xr.merge([self.fields, self.profile_dataset(), xr.Dataset(self.scalar_variables())], combine_attrs="override")
        ds.attrs = {
            "Conventions": "CF-1.11",
            "title": f"cmpsim result: one operating point of chemical mechanical polishing (model {self.config.model!r})",
            "source": f"cmpsim {__version__}, model {self.config.model!r}, grid {self.grid.n_r}x{self.grid.n_theta}",
            "history": f"created by cmpsim {__version__} (cmpsim.solve / cmpsim run; no time stamp: the same inputs give the same file)",
            "references": "\n".join(REFERENCES),
            "comment": "Scalars are 0-d variables; a wafer mean whose map has the same name is stored as NAME_mean (attribute cmpsim_name). Inputs in SI in config_toml.",
            "cmpsim_version": __version__,
            "cmpsim_schema": _reg.SCHEMA_VERSION,
            "model": self.config.model,
            "config_toml": self.config.to_toml_text(),
        }
        return ds

    def to_netcdf(self, path) -> Path:
        """Write :attr:`dataset` (maps, profiles, scalars, config) to a CF-1.11 NetCDF file, atomically."""
        from ..io import atomic_path

        path = Path(path)
        with atomic_path(path, suffix=".nc") as tmp:
            self.dataset.to_netcdf(tmp, engine="scipy")
        return path

    # ------------------------------------------------------------------ plots
    def plot(self, fields=("film_thickness", "slurry_pressure", "contact_pressure", "removal_rate")):
        """Wafer maps of the chosen fields (display units of the registry); returns a matplotlib Figure."""
        import matplotlib.pyplot as plt

        ds = self.fields
        n = len(fields)
        ncol = 2 if n > 1 else 1
        nrow = math.ceil(n / ncol)
        fig, axes = plt.subplots(nrow, ncol, figsize=(5.2 * ncol, 4.4 * nrow), squeeze=False, layout="constrained")
        xmm = ds.x.values * 1e3
        ymm = ds.y.values * 1e3
        # cells centred on the rim would overhang the wafer by half a pixel: leave them blank
        half = 0.5 * (ds.x.values[1] - ds.x.values[0])
        X, Y = np.meshgrid(ds.x.values, ds.y.values)
        drawn = np.hypot(X, Y) <= 0.5 * self.config.wafer_diameter - half
        for ax, name in zip(axes.flat, fields):
            o = _reg.field(name)
            im = ax.pcolormesh(xmm, ymm, np.where(drawn, _reg.to_display(o, ds[name].values), np.nan), shading="auto", cmap="viridis")
            ax.set_aspect("equal")
            ax.set_xlabel("x, sliding direction (mm)")
            ax.set_ylabel("y (mm)")
            ax.set_title(o.long_name, fontsize=9)
            fig.colorbar(im, ax=ax, label=f"{name.replace('_', ' ')} ({o.display_unit})")
        for ax in list(axes.flat)[n:]:
            ax.set_visible(False)
        fig.suptitle(self._title())
        return fig

    def _title(self) -> str:
        c = self.config
        return (
            f"cmpsim {c.model}: P = {format_display('applied_pressure', c.applied_pressure)} psi, "
            f"{format_display('rotation_speed', c.rotation_speed)} rpm, "
            f"d = {format_display('particle_diameter', c.particle_diameter)} nm, "
            f"sigma = {format_display('pad_roughness', c.pad_roughness)} um"
        )

    def plot_profiles(self):
        """Rotation-averaged removal rate and film thickness versus wafer radius; returns a matplotlib Figure.

        The edge exclusion is shaded; the title gives the within-wafer non-uniformity and
        the removal-rate range over the rest of the wafer.
        """
        import matplotlib.pyplot as plt

        r_o = _reg.profile("radius")
        r = _reg.to_display(r_o, np.asarray(self.profiles["radius"]))
        edge = _reg.to_display(r_o, self.grid.radius)
        inner = _reg.to_display(r_o, self.grid.radius - self.config.edge_exclusion)
        names = _reg.profile_names()
        fig, axes = plt.subplots(len(names), 1, figsize=(6.4, 2.6 * len(names) + 0.6), sharex=True, squeeze=False, layout="constrained")
        for ax, name in zip(axes[:, 0], names):
            o = _reg.profile(name)
            ax.plot(r, _reg.to_display(o, np.asarray(self.profiles[name])), "o-", ms=3)
            ax.axvspan(inner, edge, color="0.85", label=f"edge exclusion ({format_display('edge_exclusion', self.config.edge_exclusion)} mm)")
            ax.set_ylabel(f"{o.of[0].replace('_', ' ')} ({o.display_unit})")
            ax.set_xlim(0.0, edge)
            ax.grid(alpha=0.3)
        axes[0, 0].legend(loc="best", fontsize=8)
        axes[-1, 0].set_xlabel(f"wafer radius ({r_o.display_unit}), rotation average along each ring")
        s = self.scalars
        wiwnu = _reg.scalar("within_wafer_nonuniformity")
        rng = _reg.scalar("removal_rate_range")
        fig.suptitle(
            f"{self._title()}\nWIWNU = {_reg.to_display(wiwnu, s['within_wafer_nonuniformity']):.3g} {wiwnu.display_unit}, "
            f"range = {_reg.to_display(rng, s['removal_rate_range']):.3g} {rng.display_unit}",
            fontsize=9,
        )
        return fig
