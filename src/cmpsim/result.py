"""The result of one operating point: scalars in SI, wafer maps, provenance, export and plots."""

from __future__ import annotations

import json
import math
from pathlib import Path
from typing import Any

import numpy as np

from ._version import __version__
from .config import PARAMETERS, Config, format_display

__all__ = ["Result", "SCALARS", "REFERENCES"]

#: Every scalar output: name -> (SI unit, display factor, display unit, description).
SCALARS: dict[str, tuple[str, float, str, str]] = {
    "film_thickness_center_m": ("m", 1e6, "um", "Film thickness at the wafer centre"),
    "film_thickness_min_m": ("m", 1e6, "um", "Minimum film thickness over the wafer"),
    "h0_m": ("m", 1e6, "um", "Height of the rim-chord centre (pivot) above the pad mean plane"),
    "attack_angle_rad": ("rad", 1.0, "rad", "Attack angle (tilt about y; > 0 converging along the sliding direction)"),
    "cross_tilt_rad": ("rad", 1.0, "rad", "Cross tilt (about x)"),
    "fluid_load_fraction": ("1", 1.0, "-", "Share of the load carried by the slurry"),
    "contact_load_fraction": ("1", 1.0, "-", "Share of the load carried by pad asperities"),
    "contact_area_ratio_elastic": ("1", 1.0, "-", "Elastic real contact area / wafer area"),
    "contact_area_ratio_elastoplastic": ("1", 1.0, "-", "Elastoplastic real contact area / wafer area"),
    "contact_area_ratio_plastic": ("1", 1.0, "-", "Plastic real contact area / wafer area"),
    "mean_normal_stress_pa": ("Pa", 1e-3, "kPa", "Mean normal stress sigma_n of the removal law"),
    "mean_shear_stress_pa": ("Pa", 1e-3, "kPa", "Mean shear stress tau on the wafer"),
    "removal_rate": ("m/s", 1e9 * 60.0, "nm/min", "Wafer-mean removal rate K sigma_n tau"),
    "removal_rate_nm_per_min": ("nm/min", 1.0, "nm/min", "The same in nm/min"),
    "removal_rate_relative": ("1", 1.0, "-", "Removal rate / reference case (LEP, 100 nm, 15 um, 4 psi, 60 rpm)"),
    "ambient_pressure_pa": ("Pa", 1e-3, "kPa", "Granular pressure p0 at the wafer edge"),
    "sliding_speed_m_s": ("m/s", 1.0, "m/s", "Relative sliding speed at the wafer centre"),
    "load_residual": ("1", 1.0, "-", "Relative load residual"),
    "moment_residual": ("1", 1.0, "-", "Relative moment residual (max of the two axes)"),
    "flow_factor_floored_fraction": ("1", 1.0, "-", "Share of faces where the flow-factor tensor was regularised"),
    "iterations": ("1", 1.0, "-", "Newton iterations"),
    "factorizations": ("1", 1.0, "-", "Sparse LU factorisations (pressure solves)"),
    "converged": ("1", 1.0, "-", "Equilibrium converged"),
    "moment_roots_found": ("1", 1.0, "-", "Moment roots found by the attack-angle scan (--check-roots)"),
}

#: Field name -> (SI unit, description).
FIELDS: dict[str, tuple[str, str]] = {
    "film_thickness": ("m", "Film thickness h (eq. 30)"),
    "slurry_pressure": ("Pa", "Slurry (granular) gauge pressure on the wafer, (1 - A_r/A_n)(p - p0)"),
    "granular_pressure": ("Pa", "Absolute granular pressure p (eq. 5 solved in ln p)"),
    "contact_pressure": ("Pa", "Pad asperity contact pressure (eq. 28)"),
    "total_pressure": ("Pa", "Slurry gauge plus contact pressure"),
    "area_ratio_elastic": ("1", "Elastic real contact area fraction"),
    "area_ratio_elastoplastic": ("1", "Elastoplastic real contact area fraction"),
    "area_ratio_plastic": ("1", "Plastic real contact area fraction"),
    "normal_stress": ("Pa", "Normal stress sigma_n of the removal law"),
    "shear_stress": ("Pa", "Shear stress magnitude tau"),
    "removal_rate": ("m/s", "Local removal rate K sigma_n tau"),
}

REFERENCES = [
    "The paper: 'An improved model considering elastic-plastic contact and partial hydrodynamic lubrication for chemical mechanical polishing' (shared/paper)",
    "Haff, J. Fluid Mech. 134, 401 (1983): grain flow",
    "Patir & Cheng, J. Lubr. Technol. 100, 12 (1978); Tripp, J. Lubr. Technol. 105, 458 (1983): flow factors",
    "Greenwood & Williamson, Proc. R. Soc. A 295, 300 (1966): elastic asperity contact",
    "Zhao, Maietta & Chang, J. Tribol. 122, 86 (2000): elastoplastic asperity contact",
    "Abbott & Firestone, Mech. Eng. 55, 569 (1933): plastic asperity contact",
    "Runnels & Eyman, J. Electrochem. Soc. 141, 1698 (1994): RR = K sigma_n tau",
]


def _jsonable(v: Any) -> Any:
    if isinstance(v, (bool, np.bool_)):
        return bool(v)
    if isinstance(v, (int, np.integer)):
        return int(v)
    if isinstance(v, (float, np.floating)):
        return float(v)
    return v


class Result:
    """Outputs of one operating point.

    Every scalar of ``cmpsim run --json`` is an attribute in SI (``result.attack_angle_rad``).
    ``fields`` gives the wafer maps as an ``xarray.Dataset``; ``summary()`` a table with
    units; ``plot()`` a matplotlib Figure; ``provenance`` the model variant, package version
    and every parameter with its value and source.
    """

    def __init__(self, config: Config, scalars: dict, polar: dict, grid, problem=None, solution=None):
        self.config = config
        self.scalars = {k: _jsonable(v) for k, v in scalars.items()}
        self.polar = polar
        self.grid = grid
        self.problem = problem
        self.solution = solution
        self._fields = None
        self.root_scan = None

    def __getattr__(self, name: str):
        scalars = self.__dict__.get("scalars", {})
        if name in scalars:
            return scalars[name]
        raise AttributeError(name)

    def __dir__(self):
        return sorted(set(super().__dir__()) | set(self.scalars))

    def __repr__(self) -> str:
        return (
            f"Result(model={self.config.model!r}, film_thickness_center={self.film_thickness_center_m * 1e6:.4g} um, "
            f"attack_angle={self.attack_angle_rad:.4g} rad, fluid_load_fraction={self.fluid_load_fraction:.4g}, "
            f"removal_rate={self.removal_rate_nm_per_min:.4g} nm/min, converged={self.converged})"
        )

    # ------------------------------------------------------------------ export
    def to_dict(self) -> dict[str, Any]:
        """Every scalar output, SI (the object ``cmpsim run --json`` prints)."""
        return dict(self.scalars)

    def to_json(self, indent: int | None = None) -> str:
        """:meth:`to_dict` as JSON (NaN and inf are written as null)."""
        clean = {k: (None if isinstance(v, float) and not math.isfinite(v) else v) for k, v in self.scalars.items()}
        return json.dumps(clean, indent=indent, allow_nan=False)

    def summary_rows(self) -> list[tuple[str, str, str, str]]:
        """(name, value, display unit, description) for every scalar."""
        rows = []
        for name, (_, factor, unit, desc) in SCALARS.items():
            if name not in self.scalars:
                continue
            v = self.scalars[name]
            if isinstance(v, bool):
                text = "yes" if v else "no"
            elif isinstance(v, int):
                text = str(v)
            else:
                text = f"{v * factor:.6g}"
            rows.append((name, text, unit, desc))
        return rows

    def summary(self) -> str:
        """A plain-text table of every scalar with its unit."""
        rows = self.summary_rows()
        w0 = max(len(r[0]) for r in rows)
        w1 = max(len(r[1]) for r in rows)
        w2 = max(len(r[2]) for r in rows)
        head = f"cmpsim {__version__}, model {self.config.model!r}, grid {self.grid.n_r}x{self.grid.n_theta}"
        lines = [head, "-" * len(head)]
        lines += [f"{n:<{w0}}  {v:>{w1}}  {u:<{w2}}  {d}" for n, v, u, d in rows]
        return "\n".join(lines)

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

    def field_arrays(self, n: int | None = None) -> dict[str, Any]:
        """Wafer maps on an n x n Cartesian grid: {'x', 'y', name: array}, NaN outside the wafer."""
        from .contact import asperity_contact

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
                area_ratio_elastic=c.area_ratio_elastic,
                area_ratio_elastoplastic=c.area_ratio_elastoplastic,
                area_ratio_plastic=c.area_ratio_plastic,
            )
        # the slurry fields are interpolated (their edge values are known exactly); the fields
        # built from them and from the exact contact are recombined pointwise, so that the
        # maps keep the identities of the solver (total = slurry + contact, ...)
        edges = {"slurry_pressure": 0.0, "granular_pressure": self.scalars["ambient_pressure_pa"]}
        values = dict(exact)
        for name in FIELDS:
            if name not in values and name not in ("total_pressure", "normal_stress"):
                values[name] = self._polar_interpolator(self.polar[name], edges.get(name))(pts)
        if "contact_pressure" in values:
            a_r = values["area_ratio_elastic"] + values["area_ratio_elastoplastic"] + values["area_ratio_plastic"]
            values["total_pressure"] = values["slurry_pressure"] + values["contact_pressure"]
            values["normal_stress"] = (1.0 - a_r) * values["granular_pressure"] + values["contact_pressure"]
        else:
            values["total_pressure"] = values["slurry_pressure"]
            values["normal_stress"] = values["granular_pressure"]
        for name in FIELDS:
            arr = np.full(X.shape, np.nan)
            arr[inside] = values[name]
            out[name] = arr
        return out

    @property
    def fields(self):
        """Wafer maps as an ``xarray.Dataset`` on x, y (m), units in attrs, NaN outside the wafer."""
        if self._fields is None:
            import xarray as xr

            arrays = self.field_arrays()
            x = arrays.pop("x")
            y = arrays.pop("y")
            ds = xr.Dataset(
                {k: (("y", "x"), v, {"units": FIELDS[k][0], "long_name": FIELDS[k][1]}) for k, v in arrays.items()},
                coords={
                    "x": ("x", x, {"units": "m", "long_name": "position along the sliding direction"}),
                    "y": ("y", y, {"units": "m", "long_name": "position across the sliding direction"}),
                },
            )
            for k, v in self.scalars.items():
                ds.attrs[k] = int(v) if isinstance(v, bool) else v
            ds.attrs["cmpsim_version"] = __version__
            ds.attrs["model"] = self.config.model
            ds.attrs["config_toml"] = self.config.to_toml_text()
            self._fields = ds
        return self._fields

    def to_netcdf(self, path) -> Path:
        """Write :attr:`fields` (with the scalars and config as attributes) to NetCDF, atomically."""
        from .io import atomic_path

        path = Path(path)
        with atomic_path(path, suffix=".nc") as tmp:
            self.fields.to_netcdf(tmp, engine="scipy")
        return path

    # ------------------------------------------------------------------ plots
    def plot(self, fields=("film_thickness", "slurry_pressure", "contact_pressure", "removal_rate")):
        """Wafer maps of the chosen fields; returns a matplotlib Figure."""
        import matplotlib.pyplot as plt

        scale = {
            "film_thickness": (1e6, "um"),
            "slurry_pressure": (1e-3, "kPa"),
            "granular_pressure": (1e-3, "kPa"),
            "contact_pressure": (1e-3, "kPa"),
            "total_pressure": (1e-3, "kPa"),
            "normal_stress": (1e-3, "kPa"),
            "shear_stress": (1e-3, "kPa"),
            "removal_rate": (1e9 * 60, "nm/min"),
        }
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
            f, unit = scale.get(name, (1.0, FIELDS[name][0]))
            im = ax.pcolormesh(xmm, ymm, np.where(drawn, ds[name].values * f, np.nan), shading="auto", cmap="viridis")
            ax.set_aspect("equal")
            ax.set_xlabel("x, sliding direction (mm)")
            ax.set_ylabel("y (mm)")
            ax.set_title(FIELDS[name][1], fontsize=9)
            fig.colorbar(im, ax=ax, label=f"{name.replace('_', ' ')} ({unit})")
        for ax in list(axes.flat)[n:]:
            ax.set_visible(False)
        fig.suptitle(
            f"cmpsim {self.config.model}: P = {format_display('applied_pressure', self.config.applied_pressure)} psi, "
            f"{format_display('rotation_speed', self.config.rotation_speed)} rpm, "
            f"d = {format_display('particle_diameter', self.config.particle_diameter)} nm, "
            f"sigma = {format_display('pad_roughness', self.config.pad_roughness)} um"
        )
        return fig
