"""The pad's temperature during a polishing step and between wafers (issue 32): pure kernels, SI units.

The frictional power per unit wafer area, q = tau |u_pad - u_wafer| (W/m^2, computed by the caller
from the solved shear field), is released at the pad-wafer interface. A point of the pad's wafer
track is under the wafer only a share f of each platen turn (the *duty*, :func:`wafer_duty`), and a
platen turn (about 0.6 s) is short against the pad's diffusion time, so
the pad (diffusion time L^2/alpha about 9 s for the 1.27 mm top pad, 37 s with its subpad) is
described by its track-averaged temperature, a 1-D column across its thickness:

    rho c dT/dt = d/dz (k dT/dz)                                   in the pad (and subpad) layers,
    f q = h_s (T(0) - T_slurry) - k dT/dz|0 + f C_w dT(0)/dt (+ f x carrier flux)   at the surface,
    -k dT/dz = h_b (T - T_platen)  (or T = T_platen)               at the platen,

per unit area of the wafer track. The wafer is a lumped heat capacity C_w = rho_Si c_Si t_w in
perfect thermal contact with the pad surface (its own diffusion time t_w^2/alpha_Si is 7 ms), on an
adiabatic carrier by default, or on carrier layers of its own (scaled by f, like the wafer). The
slurry carries heat away with a film coefficient h_s; the flow of slurry that leaves the pad at the
pad's temperature gives h_s = rho_w c_w Q / A_track (:func:`slurry_heat_transfer_coefficient`).

Between two semi-infinite bodies heated at their interface, the share of the heat that enters the
pad is the effusivity partition (Blok 1937; Jaeger 1942) e_p / (e_p + f e_c) with e = sqrt(k rho c)
(:func:`partition_coefficient`; f weights the counter-body, which is heated all the time while a
pad point is heated a share f of it). The column reproduces it (``tests/test_thermal.py``).

Closed forms (Carslaw & Jaeger, Conduction of Heat in Solids, 2nd ed., 1959):

* semi-infinite body, constant surface flux (section 2.9):  T - T0 = 2 q sqrt(t / (pi k rho c));
* the same with surface loss h (section 2.7):  T - T0 = (q/h) [1 - exp(b^2) erfc(b)], b = h sqrt(alpha t)/k,
  which saturates at q/h;
* slab 0 < x < L, flux at one face, the other adiabatic (section 3.3, eq. (3)):
  T(face) - T0 = q t/(rho c L) + q L/(3k) - (2 q L/(k pi^2)) sum_n exp(-alpha n^2 pi^2 t / L^2) / n^2.

Numerics: vertex-centred finite volumes across the layers give M dT/dt = -K T + b with a diagonal
capacity matrix M and a symmetric conductance matrix K; the generalised eigenproblem K V = M V Lambda
(once per column) makes :meth:`ThermalColumn.advance` exact in time for a heat flux constant over
the step (no time-step error), with the energy that entered, was stored and left through slurry
and platen integrated exactly too. The spatial error is second order in the cell size. A recipe
that recomputes q from the temperature at the start of each step couples the two explicitly (first
order in the step; second order with the mid-step flux). See ``docs/polisher.md``.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np
from scipy.linalg import eigh
from .heatflow import (
    diffusivity,
    effusivity,
    lumped_rise,
    maxwell_eucken,
    partition_coefficient,
    semi_infinite_rise,
    semi_infinite_rise_convective,
    slab_rise,
)

__all__ = [
    "ThermalConstants",
    "THERMAL",
    "Layer",
    "effusivity",
    "diffusivity",
    "maxwell_eucken",
    "partition_coefficient",
    "wafer_duty",
    "mean_wafer_duty",
    "slurry_heat_transfer_coefficient",
    "semi_infinite_rise",
    "semi_infinite_rise_convective",
    "slab_rise",
    "lumped_rise",
    "PadThermalState",
    "StepEnergy",
    "ThermalColumn",
    "pad_column",
    "ic1000_layers",
    "polisher_column",
    "advance_pad_temperature",
]


@dataclass(frozen=True)
class ThermalConstants:
    """Thermal constants of the pad, the wafer and the slurry (SI), each with its source.

    IC1000 is polyurethane filled with hollow polymer microelements (closed, gas-filled pores;
    Reinhardt et al., US 5,578,362 (1996), the patent of the IC1000 pad family): the pore share is
    ``1 - pad_density / polyurethane_density`` and the pad's conductivity the Maxwell–Eucken
    mixture of matrix and gas (:func:`maxwell_eucken`), its heat capacity the matrix's share
    (:attr:`pad_conductivity`, :attr:`pad_volumetric_heat_capacity`, the defaults). Water-filled
    pores (:attr:`pad_wet_conductivity`) bound it from above: only the surface pores opened by
    conditioning hold slurry.
    """

    # Solid polyurethane, Hot Disk transient plane source at 24 C on a 1261 kg/m^3 polyurethane
    # board: k = 0.2685 W/(m K), rho c = 1.580 MJ/(m^3 K) (Thermtest application note "Testing.2:
    # thermal conductivity testing of varying density polyurethane boards", 2015). The specific heat
    # is rho c / rho = 1253 J/(kg K).
    polyurethane_conductivity: float = 0.2685
    polyurethane_heat_capacity: float = 1.580e6 / 1261.0
    # Solid (unfilled) polyurethane of the IC10x0 family, 1.145 g/cm^3 (pad density literature,
    # read in a transcription: /work/shared/LITERATURE.md, "The polisher over time"; verify).
    polyurethane_density: float = 1145.0
    # IC1010 bulk density 0.72 g/cm^3 (same transcription). IC1000 is the same filled polyurethane
    # in another thickness; its own density was not found: 720 kg/m^3 stands for it.
    pad_density: float = 720.0
    # Water at 300 K: k = 0.613 W/(m K), rho = 1/v_f = 997 kg/m^3, c_p = 4179 J/(kg K)
    # (Incropera & DeWitt, Fundamentals of Heat and Mass Transfer, Table A.6, saturated water).
    water_conductivity: float = 0.613
    water_density: float = 997.0
    water_heat_capacity: float = 4179.0
    # Silicon at 300 K: k = 148 W/(m K), rho = 2330 kg/m^3, c_p = 712 J/(kg K) (Incropera &
    # DeWitt, Table A.1).
    silicon_conductivity: float = 148.0
    silicon_density: float = 2330.0
    silicon_heat_capacity: float = 712.0
    # 300 mm wafer thickness, 775 um (SEMI M1; the 300mm preset's wafer_thickness).
    wafer_thickness: float = 775e-6
    # Air in dry pores, 0.026 W/(m K) at 300 K (Incropera & DeWitt, Table A.4): the dry pad only.
    air_conductivity: float = 0.0263

    @property
    def pad_porosity(self) -> float:
        """Pore volume fraction of the pad, 1 - rho_pad / rho_PU (0.371 for IC10x0), dimensionless."""
        return 1.0 - self.pad_density / self.polyurethane_density

    @property
    def pad_conductivity(self) -> float:
        """Conductivity of the pad with gas-filled (closed) pores, Maxwell–Eucken, W/(m K): 0.158."""
        return float(maxwell_eucken(self.polyurethane_conductivity, self.air_conductivity, self.pad_porosity))

    @property
    def pad_volumetric_heat_capacity(self) -> float:
        """rho c of the pad with gas-filled pores, (1 - phi) rho_PU c_PU, J/(m^3 K): 9.02e5 (the gas in the pores, 0.05 % of it, left out)."""
        return (1 - self.pad_porosity) * self.polyurethane_density * self.polyurethane_heat_capacity

    @property
    def pad_wet_conductivity(self) -> float:
        """Conductivity of the pad with water-filled pores (Maxwell–Eucken), W/(m K): 0.369 (upper bound)."""
        return float(maxwell_eucken(self.polyurethane_conductivity, self.water_conductivity, self.pad_porosity))

    @property
    def pad_wet_volumetric_heat_capacity(self) -> float:
        """rho c of the pad with water-filled pores, (1 - phi) rho_PU c_PU + phi rho_w c_w, J/(m^3 K): 2.45e6."""
        phi = self.pad_porosity
        return self.pad_volumetric_heat_capacity + phi * self.water_density * self.water_heat_capacity

    @property
    def water_volumetric_heat_capacity(self) -> float:
        """rho c of water, J/(m^3 K)."""
        return self.water_density * self.water_heat_capacity

    @property
    def wafer_heat_capacity(self) -> float:
        """Heat capacity of the wafer per unit area, rho c t_w, J/(m^2 K): 1286 for 775 um silicon."""
        return self.silicon_density * self.silicon_heat_capacity * self.wafer_thickness


#: The default constants.
THERMAL = ThermalConstants()


@dataclass(frozen=True)
class Layer:
    """One homogeneous layer of a thermal column: thickness (m), conductivity k (W/(m K)),
    volumetric heat capacity rho c (J/(m^3 K)), number of cells, and the geometric grading of the
    cells from the layer's top (``grading`` > 1: cells grow away from the top)."""

    thickness: float
    conductivity: float
    volumetric_heat_capacity: float
    cells: int = 20
    grading: float = 1.0

    def __post_init__(self) -> None:
        for name in ("thickness", "conductivity", "volumetric_heat_capacity", "grading"):
            v = getattr(self, name)
            if not (np.isfinite(v) and v > 0):
                raise ValueError(f"Layer.{name} must be finite and > 0; got {v!r}")
        if int(self.cells) < 1:
            raise ValueError(f"Layer.cells must be >= 1; got {self.cells!r}")

    def edges(self) -> np.ndarray:
        """Cell boundaries from 0 (top) to the thickness, m."""
        n = int(self.cells)
        w = self.grading ** np.arange(n)
        return np.concatenate(([0.0], np.cumsum(w))) / w.sum() * self.thickness


def wafer_duty(pad_radius, wafer_radius, centre_distance):
    """Share of a platen turn that the pad circle of radius rho spends under the wafer, dimensionless.

    The circle meets the wafer (radius R, centre at distance d from the platen axis) over the arc
    2 arccos((rho^2 + d^2 - R^2) / (2 rho d)); f = arccos(...)/pi, 0 off the track, 1 for a
    circle inside the wafer. ``pad_radius`` in m (array), the others in m.
    """
    rho = np.asarray(pad_radius, dtype=float)
    R, d = float(wafer_radius), float(centre_distance)
    with np.errstate(divide="ignore", invalid="ignore"):
        c = (rho**2 + d**2 - R**2) / (2 * rho * d)
    c = np.where(rho > 0, c, np.where(d < R, -np.inf, np.inf))
    return np.arccos(np.clip(c, -1.0, 1.0)) / np.pi


def mean_wafer_duty(wafer_radius, centre_distance):
    """Area-mean duty over the wafer track, R / (4 d) for d >= R (wafer area over track area 4 pi d R)."""
    R, d = float(wafer_radius), float(centre_distance)
    if d < R:
        raise ValueError(f"centre_distance {d!r} m must be >= wafer_radius {R!r} m (the wafer's track is an annulus)")
    return R / (4.0 * d)


def slurry_heat_transfer_coefficient(flow_rate, track_area, volumetric_heat_capacity=THERMAL.water_volumetric_heat_capacity):
    """Heat taken by the slurry flow per unit track area and kelvin, h_s = rho c Q / A, W/(m^2 K).

    The upper bound of a slurry that arrives at T_slurry and leaves the pad at the pad's
    temperature. ``flow_rate`` Q in m^3/s (150 mL/min = 2.5e-6 m^3/s), ``track_area`` in m^2.
    """
    return volumetric_heat_capacity * np.asarray(flow_rate, dtype=float) / np.asarray(track_area, dtype=float)


# --------------------------------------------------------------------------- the column


@dataclass(frozen=True)
class PadThermalState:
    """Temperatures of a thermal column's nodes, K (``temperature[..., 0]`` is the pad surface, the
    wafer's temperature; then down through the pad and subpad; the carrier nodes, if any, follow the
    pad's), and the time since the state was made, s. Carried between steps and wafers."""

    temperature: np.ndarray
    time: float = 0.0

    @property
    def surface(self) -> np.ndarray:
        """Pad surface (and wafer) temperature, K."""
        return self.temperature[..., 0]


@dataclass(frozen=True)
class StepEnergy:
    """Energy balance of one advance per unit track area, J/m^2 (arrays over the batch):
    ``supplied`` = f q dt, ``stored`` = sum M dT, ``to_slurry``, ``to_platen``, ``to_carrier``
    (heat leaving through the surface film, the platen and the carrier's back). ``residual`` =
    supplied - stored - losses, zero to round-off."""

    supplied: np.ndarray
    stored: np.ndarray
    to_slurry: np.ndarray
    to_platen: np.ndarray
    to_carrier: np.ndarray

    @property
    def residual(self) -> np.ndarray:
        """Energy balance residual, J/m^2."""
        return self.supplied - self.stored - self.to_slurry - self.to_platen - self.to_carrier


def _phi1(x):
    """(1 - exp(-x)) / x, 1 at x = 0 (stable)."""
    x = np.asarray(x, dtype=float)
    small = np.abs(x) < 1e-8
    xs = np.where(small, 1.0, x)
    return np.where(small, 1.0 - x / 2.0, -np.expm1(-xs) / xs)


def _phi2(x):
    """(x - 1 + exp(-x)) / x^2, 1/2 at x = 0 (stable: series below 1e-3)."""
    x = np.asarray(x, dtype=float)
    small = np.abs(x) < 1e-3
    xs = np.where(small, 1.0, x)
    series = 0.5 - x / 6.0 + x**2 / 24.0 - x**3 / 120.0
    return np.where(small, series, (xs + np.expm1(-xs)) / xs**2)


@dataclass(frozen=True, eq=False)
class ThermalColumn:
    """A 1-D thermal column of the pad under the wafer track (built by :func:`pad_column`).

    Nodes at depths ``depth`` (m) below the pad surface; the node 0 carries the wafer. Linear system
    M dT/dt = -K T + s + g q with M = diag(``capacity``), K symmetric, s the sink terms and
    g = ``duty`` e_0 the heat input of a frictional power q per unit wafer area.
    """

    depth: np.ndarray
    capacity: np.ndarray
    stiffness: np.ndarray
    duty: float
    surface_coefficient: float
    slurry_temperature: float
    platen_coefficient: float
    platen_temperature: float
    carrier_coefficient: float
    carrier_temperature: float
    carrier_node: int
    platen_node: int
    eigenvalues: np.ndarray = field(repr=False)
    eigenvectors: np.ndarray = field(repr=False)

    @property
    def size(self) -> int:
        """Number of nodes."""
        return self.capacity.size

    @property
    def time_constant(self) -> float:
        """Slowest thermal time constant 1 / lambda_min, s (inf for a column without any loss)."""
        lam = float(self.eigenvalues[0])
        return math.inf if lam <= 1e-300 else 1.0 / lam

    @property
    def time_constants(self) -> np.ndarray:
        """All modal time constants 1/lambda_k, s, slowest first."""
        with np.errstate(divide="ignore"):
            return 1.0 / self.eigenvalues

    def sinks(self) -> np.ndarray:
        """Constant part s of the right-hand side for the temperature above the slurry's,
        theta = T - T_slurry (losses to the platen and carrier reference temperatures), W/m^2."""
        s = np.zeros(self.size)
        s[self.platen_node] += self.platen_coefficient * (self.platen_temperature - self.slurry_temperature)
        if self.carrier_node >= 0:
            s[self.carrier_node] += self.carrier_coefficient * (self.carrier_temperature - self.slurry_temperature)
        return s

    def initial_state(self, temperature=None) -> PadThermalState:
        """Uniform state at ``temperature`` (K; default the slurry temperature), shape (..., nodes)."""
        t = self.slurry_temperature if temperature is None else temperature
        t = np.asarray(t, dtype=float)
        return PadThermalState(np.broadcast_to(t[..., None], t.shape + (self.size,)).copy(), 0.0)

    def steady_state(self, heat_flux) -> PadThermalState:
        """Steady temperatures under a constant frictional power q (W/m^2 of wafer), K.

        Needs some loss (surface, platen or carrier coefficient > 0)."""
        if self.eigenvalues[0] <= 1e-300:
            raise ValueError("a column without any heat loss has no steady state")
        q = np.asarray(heat_flux, dtype=float)
        rhs = self.sinks() + q[..., None] * self._unit_source()
        flat = rhs.reshape(-1, self.size)
        T = np.linalg.solve(self.stiffness, flat.T).T.reshape(rhs.shape)
        return PadThermalState(T + self.slurry_temperature, 0.0)

    def _unit_source(self) -> np.ndarray:
        g = np.zeros(self.size)
        g[0] = self.duty
        return g

    def advance(self, state: PadThermalState, heat_flux, dt: float, with_energy: bool = False):
        """Advance ``state`` by ``dt`` seconds under a frictional power ``heat_flux`` q (W/m^2 of
        wafer area, constant over the step; 0 between wafers); exact in time.

        Modal solution of M dT/dt = -K T + b (eq. P5 of ``docs/polisher.md``): with K V = M V Lambda,
        V^T M V = I and y = V^T M T, y(dt) = exp(-Lambda dt) y0 + dt phi1(Lambda dt) V^T b. Returns
        the new :class:`PadThermalState` (and a :class:`StepEnergy` if ``with_energy``).
        """
        if not (np.isfinite(dt) and dt >= 0):
            raise ValueError(f"time step must be finite and >= 0 s; got {dt!r}")
        q = np.asarray(heat_flux, dtype=float)
        Ts = self.slurry_temperature
        T0 = np.asarray(state.temperature, dtype=float) - Ts  # theta: exact zeros stay zero
        b = self.sinks() + q[..., None] * self._unit_source()
        V, lam = self.eigenvectors, self.eigenvalues
        y0 = (T0 * self.capacity) @ V
        bb = b @ V
        x = lam * dt
        decay = np.exp(-x)
        y1 = decay * y0 + dt * _phi1(x) * bb
        T1 = y1 @ V.T
        new = PadThermalState(T1 + Ts, state.time + dt)
        if not with_energy:
            return new
        # exact time integral of T over the step: int y = dt phi1 y0 + dt^2 phi2 bb
        yint = dt * _phi1(x) * y0 + dt**2 * _phi2(x) * bb
        Tint = yint @ V.T
        supplied = self.duty * q * dt * np.ones(T0.shape[:-1])
        stored = np.sum(self.capacity * (T1 - T0), axis=-1)
        to_slurry = self.surface_coefficient * Tint[..., 0]
        to_platen = self.platen_coefficient * (Tint[..., self.platen_node] - (self.platen_temperature - Ts) * dt)
        to_carrier = (self.carrier_coefficient * (Tint[..., self.carrier_node] - (self.carrier_temperature - Ts) * dt)
                      if self.carrier_node >= 0 else np.zeros_like(stored))
        return new, StepEnergy(supplied, stored, to_slurry, to_platen, to_carrier)


def _chain(layers):
    """Node depths, capacities (J/(m^2 K)) and cell conductances (W/(m^2 K)) of stacked layers."""
    edges = [np.zeros(1)]
    cap_cells, cond_cells = [], []
    top = 0.0
    for layer in layers:
        e = layer.edges()
        dz = np.diff(e)
        edges.append(top + e[1:])
        cap_cells.append(layer.volumetric_heat_capacity * dz)
        cond_cells.append(layer.conductivity / dz)
        top += layer.thickness
    depth = np.concatenate(edges)
    cap_cells = np.concatenate(cap_cells)
    cond_cells = np.concatenate(cond_cells)
    cap = np.zeros(depth.size)
    cap[:-1] += cap_cells / 2
    cap[1:] += cap_cells / 2
    return depth, cap, cond_cells


def _stiffness(n, cond, offset, K):
    for i, g in enumerate(cond):
        a, b = offset + i, offset + i + 1
        K[a, a] += g
        K[b, b] += g
        K[a, b] -= g
        K[b, a] -= g


def pad_column(
    pad_layers,
    *,
    duty: float,
    surface_coefficient: float,
    platen_coefficient: float = math.inf,
    wafer_heat_capacity: float = THERMAL.wafer_heat_capacity,
    carrier_layers=(),
    carrier_coefficient: float = 0.0,
    slurry_temperature: float = 293.15,
    platen_temperature: float | None = None,
    carrier_temperature: float | None = None,
) -> ThermalColumn:
    """Build the thermal column of a pad track under a wafer (eq. P4 of ``docs/polisher.md``).

    Parameters
    ----------
    pad_layers : sequence of Layer
        The pad stack from the polishing surface down (top pad, subpad).
    duty : float
        Share f of a platen turn that a track point spends under the wafer (:func:`mean_wafer_duty`), in (0, 1].
    surface_coefficient : float
        Heat-transfer coefficient h_s from the pad surface to the slurry at ``slurry_temperature``,
        W/(m^2 K) per unit track area (:func:`slurry_heat_transfer_coefficient`).
    platen_coefficient : float
        Conductance h_b from the bottom of the stack to the platen at ``platen_temperature``,
        W/(m^2 K); ``inf`` holds the bottom at the platen temperature, 0 makes it adiabatic.
    wafer_heat_capacity : float
        Lumped heat capacity of the wafer per unit wafer area, J/(m^2 K) (weighted by f).
    carrier_layers : sequence of Layer
        Layers behind the wafer (membrane, carrier), from the wafer outwards; their capacity and
        conductance are weighted by f. Empty: an adiabatic carrier.
    carrier_coefficient : float
        Conductance from the outermost carrier node to ``carrier_temperature``, W/(m^2 K) (per wafer area).
    slurry_temperature, platen_temperature, carrier_temperature : float
        Reference temperatures, K (the last two default to the slurry's).
    """
    if not (0.0 < duty <= 1.0):
        raise ValueError(f"duty must be in (0, 1]; got {duty!r}")
    for name, v in (("surface_coefficient", surface_coefficient), ("platen_coefficient", platen_coefficient),
                    ("wafer_heat_capacity", wafer_heat_capacity), ("carrier_coefficient", carrier_coefficient)):
        if not (v >= 0):
            raise ValueError(f"{name} must be >= 0; got {v!r}")
    pad_layers = list(pad_layers)
    if not pad_layers:
        raise ValueError("at least one pad layer is needed")
    Tp = slurry_temperature if platen_temperature is None else platen_temperature
    Tc = slurry_temperature if carrier_temperature is None else carrier_temperature
    depth, cap, cond = _chain(pad_layers)
    dirichlet = math.isinf(platen_coefficient)
    if dirichlet:
        # the bottom node is held at the platen temperature: fold its last cell into a conductance
        g_last = cond[-1]
        depth, cap, cond = depth[:-1], cap[:-1], cond[:-1]
        cap = cap.copy()
        h_base = g_last
    else:
        h_base = platen_coefficient
    n_pad = depth.size
    carrier_layers = list(carrier_layers)
    if carrier_layers:
        c_depth, c_cap, c_cond = _chain(carrier_layers)
        n = n_pad + c_depth.size - 1
    else:
        n = n_pad
    C = np.zeros(n)
    K = np.zeros((n, n))
    C[:n_pad] = cap
    _stiffness(n_pad, cond, 0, K)
    C[0] += duty * wafer_heat_capacity
    K[0, 0] += surface_coefficient
    platen_node = n_pad - 1
    K[platen_node, platen_node] += h_base
    carrier_node = -1
    depths = depth
    if carrier_layers:
        # carrier nodes: wafer (node 0) then n_pad, n_pad+1, ... outwards; weighted by the duty
        idx = [0] + list(range(n_pad, n))
        for i, g in enumerate(c_cond):
            a, b = idx[i], idx[i + 1]
            gg = duty * g
            K[a, a] += gg
            K[b, b] += gg
            K[a, b] -= gg
            K[b, a] -= gg
        for i, c in enumerate(c_cap):
            C[idx[i]] += duty * c
        carrier_node = n - 1
        K[carrier_node, carrier_node] += duty * carrier_coefficient
        depths = np.concatenate((depth, -c_depth[1:]))
    elif carrier_coefficient > 0:
        carrier_node = 0
        K[0, 0] += duty * carrier_coefficient
    lam, V = eigh(K, np.diag(C))
    lam = np.clip(lam, 0.0, None)
    return ThermalColumn(depth=depths, capacity=C, stiffness=K, duty=float(duty), surface_coefficient=float(surface_coefficient),
                         slurry_temperature=float(slurry_temperature), platen_coefficient=float(h_base), platen_temperature=float(Tp),
                         carrier_coefficient=float(duty * carrier_coefficient), carrier_temperature=float(Tc), carrier_node=carrier_node,
                         platen_node=platen_node, eigenvalues=lam, eigenvectors=V)


def ic1000_layers(top_thickness: float = 1.27e-3, subpad_thickness: float = 1.27e-3, constants: ThermalConstants = THERMAL,
                  wet: bool = False, cells: int = 40) -> list:
    """The IC1000 pad stack as thermal layers: the top pad (1.27 mm, the 300mm preset's
    pad_thickness) on a subpad of the same thermal constants (the Suba IV subpad's are not
    published: assumed), m. ``wet``: water-filled pores (upper bound) instead of gas-filled."""
    k = constants.pad_wet_conductivity if wet else constants.pad_conductivity
    rc = constants.pad_wet_volumetric_heat_capacity if wet else constants.pad_volumetric_heat_capacity
    layers = [Layer(top_thickness, k, rc, cells=cells)]
    if subpad_thickness > 0:
        layers.append(Layer(subpad_thickness, k, rc, cells=cells))
    return layers


def polisher_column(wafer_radius: float, centre_distance: float, slurry_flow_rate: float = 2.5e-6, *, platen: str = "sink",
                    slurry_temperature: float = 293.15, constants: ThermalConstants = THERMAL, wet: bool = False,
                    cells: int = 40, surface_coefficient: float | None = None) -> ThermalColumn:
    """The default column of a polisher (eq. P4): IC1000 stack (:func:`ic1000_layers`), the area-mean
    duty R/(4d) of the wafer track, the slurry's flow coefficient rho_w c_w Q / (4 pi d R) and a
    silicon wafer (775 um) on an adiabatic carrier.

    ``wafer_radius`` R and ``centre_distance`` d in m, ``slurry_flow_rate`` Q in m^3/s (150 mL/min,
    US 9,499,721 B2's recipe); ``platen`` "sink" (the platen, a water-cooled aluminium mass, holds
    the subpad's bottom at the slurry temperature) or "adiabatic" (an insulating subpad): the two
    bound the measured thermal time constants (``docs/polisher.md``). ``surface_coefficient`` (W/(m^2 K),
    per unit track area): h_s given (a calibrated heat removal) instead of the slurry flow's.
    """
    if platen not in ("sink", "adiabatic"):
        raise ValueError(f"platen must be 'sink' or 'adiabatic'; got {platen!r}")
    f = mean_wafer_duty(wafer_radius, centre_distance)
    hs = float(slurry_heat_transfer_coefficient(slurry_flow_rate, 4.0 * np.pi * centre_distance * wafer_radius, constants.water_volumetric_heat_capacity))
    if surface_coefficient is not None:
        if not (math.isfinite(surface_coefficient) and surface_coefficient >= 0):
            raise ValueError(f"surface_coefficient must be >= 0 W/(m^2 K); got {surface_coefficient!r}")
        hs = float(surface_coefficient)
    return pad_column(ic1000_layers(constants=constants, wet=wet, cells=cells), duty=f, surface_coefficient=hs,
                      platen_coefficient=math.inf if platen == "sink" else 0.0, wafer_heat_capacity=constants.wafer_heat_capacity,
                      slurry_temperature=slurry_temperature)


def advance_pad_temperature(column: ThermalColumn, state: PadThermalState, heat_flux, dt: float) -> PadThermalState:
    """Advance the pad temperature over ``dt`` s under a frictional power ``heat_flux`` (W/m^2 of
    wafer area; 0 while the pad cools between wafers): :meth:`ThermalColumn.advance`, exact for a
    flux constant over the step. Returns the new state (surface temperature: ``state.surface``, K)."""
    return column.advance(state, heat_flux, dt)
