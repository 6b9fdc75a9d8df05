// The plots of one solve: wafer maps and the rotation-averaged removal profile, drawn with the
// plotly.js of the installed plotly wheel (served by cmpsim, loaded at the first plot).

import { $ } from "./page.js";
import { valuesOf } from "./results.js";

// plotly.js (from the installed plotly wheel, served by cmpsim) is loaded at the first plot:
// the form is usable before its 4.8 MB are parsed.
let plotlyLoading = null;

export function ensurePlotly() {
  if (window.Plotly) return Promise.resolve(window.Plotly);
  if (!plotlyLoading) {
    plotlyLoading = new Promise((resolve, reject) => {
      const s = document.createElement("script");
      s.src = "/static/plotly.min.js";
      s.onload = () => resolve(window.Plotly);
      s.onerror = () => { plotlyLoading = null; reject(new Error("cannot load /static/plotly.min.js")); };
      document.head.append(s);
    });
  }
  return plotlyLoading;
}

// SI unit -> (factor, unit shown) for plots; anything else is shown as it is.
const SHOWN = { m: [1e6, "\u00b5m"], Pa: [1e-3, "kPa"], "m/s": [6e10, "nm/min"], "m s-1": [6e10, "nm/min"] };

function shownUnit(unit) { return SHOWN[unit] || [1, unit || ""]; }

export const PLOT_CONFIG = { responsive: true, displaylogo: false };

function mapPlot(div, x, y, map) {
  const [f, unit] = shownUnit(map.units);
  const z = map.z.map((row) => row.map((v) => (v === null ? null : v * f)));
  const trace = {
    type: "heatmap", x, y, z, colorscale: "Viridis", hoverongaps: false,
    colorbar: { title: { text: unit } },
    hovertemplate: `x %{x:.1f} mm<br>y %{y:.1f} mm<br>%{z:.4g} ${unit}<extra></extra>`,
  };
  const layout = {
    title: { text: map.long_name, font: { size: 13 } },
    xaxis: { title: { text: "x, sliding direction (mm)" }, constrain: "domain" },
    yaxis: { title: { text: "y (mm)" }, scaleanchor: "x", constrain: "domain" },
    margin: { l: 55, r: 10, t: 40, b: 45 },
  };
  Plotly.react(div, [trace], layout, PLOT_CONFIG);
}

export function renderPlots(data, fields) {
  $("plots").hidden = false;
  const maps = (fields && fields.maps) || {};
  const mm = (v) => v * 1e3;
  const x = fields ? fields.x.map(mm) : [];
  const y = fields ? fields.y.map(mm) : [];
  const pressure = maps.total_pressure || maps.slurry_pressure || maps.contact_pressure;
  const chosen = { "map-removal_rate": maps.removal_rate, "map-film_thickness": maps.film_thickness, "map-pressure": pressure };
  for (const [id, map] of Object.entries(chosen)) {
    const div = $(id);
    if (map) {
      div.classList.remove("note");
      mapPlot(div, x, y, map);
    } else {
      if (window.Plotly) Plotly.purge(div);
      div.classList.add("note");
      div.textContent = "This field is not in the answer.";
    }
  }
  renderProfile(data);
}

// Dashed vertical lines at the outer radius of each zone of a membrane head (inputs in SI, as the
// solve echoes them; zone_radii unset = one zone over the wafer), labelled; none on a rigid head.
export function zoneBoundaries(inputs) {
  if (!inputs || inputs.carrier !== "membrane") return { shapes: [], annotations: [] };
  let radii = Array.isArray(inputs.zone_radii) ? inputs.zone_radii : [];
  if (radii.length === 0 && typeof inputs.wafer_diameter === "number") radii = [inputs.wafer_diameter / 2];
  const shapes = radii.map((r) => ({ type: "line", xref: "x", yref: "paper", x0: r * 1e3, x1: r * 1e3, y0: 0, y1: 1, line: { dash: "dash", width: 1, color: "#888" }, name: "zone boundary" }));
  const annotations = radii.map((r, k) => ({ x: r * 1e3, xref: "x", y: 1, yref: "paper", yanchor: "top", xanchor: "right", showarrow: false, font: { size: 10, color: "#666" }, text: `zone ${k + 1} | ${Number((r * 1e3).toPrecision(4))} mm` }));
  return { shapes, annotations };
}

function renderProfile(data) {
  const div = $("profile");
  const prof = data.profiles;
  if (!prof || !Array.isArray(prof.radius) || !Array.isArray(prof.removal_rate)) {
    if (window.Plotly) Plotly.purge(div);
    div.classList.add("note");
    div.textContent = "The rotation-averaged removal profile appears here when the results carry profiles (the JSON schema 2 of cmpsim run --json).";
    return;
  }
  div.classList.remove("note");
  div.textContent = "";
  const values = valuesOf(data);
  const units = data.units || {};
  const [f, unit] = shownUnit(units.removal_rate_profile || units.removal_rate_mean || "m/s");
  const r = prof.radius.map((v) => v * 1e3);
  const traces = [{ x: r, y: prof.removal_rate.map((v) => (v === null ? null : v * f)), mode: "lines+markers", name: "removal rate", hovertemplate: `r %{x:.1f} mm<br>%{y:.4g} ${unit}<extra></extra>` }];
  const layout = {
    title: { text: "Rotation-averaged removal rate", font: { size: 13 } },
    xaxis: { title: { text: "wafer radius (mm)" } },
    yaxis: { title: { text: `removal rate (${unit})` } },
    margin: { l: 60, r: 60, t: 40, b: 45 },
    legend: { orientation: "h", y: -0.25 },
    ...zoneBoundaries(data.inputs),
  };
  if (Array.isArray(prof.film_thickness)) {
    const [g, fu] = shownUnit("m");
    traces.push({ x: r, y: prof.film_thickness.map((v) => (v === null ? null : v * g)), mode: "lines", name: "film thickness", yaxis: "y2", line: { dash: "dot" }, hovertemplate: `r %{x:.1f} mm<br>%{y:.4g} ${fu}<extra></extra>` });
    layout.yaxis2 = { title: { text: `film thickness (${fu})` }, overlaying: "y", side: "right" };
  }
  const wiwnu = values.within_wafer_nonuniformity;
  if (typeof wiwnu === "number") layout.title.text += ` \u2014 non-uniformity ${(100 * wiwnu).toPrecision(3)} %`;
  Plotly.react(div, traces, layout, PLOT_CONFIG);
}
