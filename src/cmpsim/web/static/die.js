// The die view: a layout uploaded to POST /api/die (the file as the body, the options of
// `cmpsim die LAYOUT` in the query), then the density, the final surface and the hotspots drawn
// on the window grid (the hotspots also as markers on the height map), and the scalars of the answer (`hotspot_count`, `thickness_range`, ...).
// The wafer solve behind the blanket rate takes the form's inputs.

import { state, $, fmt, showMessage, showFieldError, clearErrors } from "./page.js";
import { api, upload, errorText } from "./http.js";
import { collectInputs } from "./form.js";
import { ensurePlotly, PLOT_CONFIG } from "./plots.js";

const SPEC_KINDS = ["thickness", "step_height", "dishing", "erosion"];
// the die controls by the query parameter they set (a 422 names one of these)
const CONTROLS = { layout: "die-file", layer: "die-layers", pdk: "die-pdk", window: "die-window", process: "die-process", top: "die-top", spec: "die-spec-thickness" };
const MARKERS = 5000; // hotspots drawn as markers at most (the count and the JSON have them all)

let layerMaps = {};
let lastJson = null;

export async function buildDiePanel() {
  const r = await api("GET", "/api/layer-maps");
  if (r.ok) layerMaps = r.data;
  const pdk = $("die-pdk");
  for (const name of Object.keys(layerMaps)) pdk.append(new Option(name, name));
  pdk.addEventListener("change", showPdkLayers);
  for (const el of document.querySelectorAll("#die-form input, #die-form select")) {
    el.addEventListener("input", () => { el.removeAttribute("aria-invalid"); });
  }
  $("die-file").addEventListener("change", () => { $("run-die").disabled = !$("die-file").files.length; });
  $("run-die").addEventListener("click", runDie);
  $("download-die-json").addEventListener("click", (e) => {
    if (!lastJson) e.preventDefault();
  });
}

// The named layers of the chosen PDK, as checkboxes (each name stands for its drawn and fill L/D).
function showPdkLayers() {
  const box = $("die-pdk-layers");
  box.textContent = "";
  const names = layerMaps[$("die-pdk").value];
  box.hidden = !names;
  if (!names) return;
  for (const [name, pairs] of Object.entries(names)) {
    const label = document.createElement("label");
    label.className = "chip";
    label.title = `${name}: ${pairs.join(", ")} (drawn and fill, merged)`;
    const cb = document.createElement("input");
    cb.type = "checkbox";
    cb.name = "die-pdk-layer";
    cb.value = name;
    label.append(cb, ` ${name}`);
    box.append(label);
  }
}

function chosenLayers() {
  const typed = $("die-layers").value.split(",").map((s) => s.trim()).filter(Boolean);
  const named = [...document.querySelectorAll('#die-pdk-layers input[name="die-pdk-layer"]:checked')].map((cb) => cb.value);
  return [...typed, ...named];
}

const NUMBER = /^[-+]?(\d+\.?\d*|\.\d+)([eE][-+]?\d+)?$/;
const withUnit = (text, unit) => (NUMBER.test(text) ? `${text} ${unit}` : text); // a bare number is in the unit shown

function query(file) {
  const q = new URLSearchParams();
  for (const l of chosenLayers()) q.append("layer", l);
  if ($("die-pdk").value) q.set("pdk", $("die-pdk").value);
  const w = $("die-window").value.trim();
  if (w) q.set("window", withUnit(w, "um"));
  q.set("process", $("die-process").value);
  const top = $("die-top").value.trim();
  if (top) q.set("top", top);
  for (const kind of SPEC_KINDS) {
    const v = $(`die-spec-${kind}`).value.trim();
    if (v) q.append("spec", `${kind}=${withUnit(v, "nm")}`);
  }
  const inputs = collectInputs();
  if (Object.keys(inputs).length) q.set("inputs", JSON.stringify(inputs));
  q.set("filename", file.name);
  q.set("include", "maps");
  return q;
}

function dieError(r) {
  const text = errorText(r);
  $("die-status").textContent = "";
  const name = r.data && r.data.parameter;
  const control = name && $(CONTROLS[name]);
  if (r.status === 422 && control) {
    control.setAttribute("aria-invalid", "true");
    showMessage("die-message", `Check ${name}: ${text}`);
  } else if (r.status === 422 && showFieldError(name, text)) {
    showMessage("die-message", `Check ${name} (in the inputs): ${text}`);
  } else {
    showMessage("die-message", text);
  }
}

export async function runDie() {
  const file = $("die-file").files[0];
  showMessage("die-message", "");
  clearErrors($("inputs"));
  for (const el of document.querySelectorAll("#die-form [aria-invalid]")) el.removeAttribute("aria-invalid");
  if (!file) {
    showMessage("die-message", "Choose a layout file (.gds, .gds.gz or .oas) first.");
    return;
  }
  const max = state.limits && state.limits.max_upload_bytes;
  if (max && file.size > max) { // the server would answer 413 with the same words
    $("die-file").setAttribute("aria-invalid", "true");
    showMessage("die-message", `the uploaded layout is larger than this server accepts (${max} bytes = ${Number((max / 1048576).toPrecision(3))} MiB; --max-upload): ${file.name} has ${file.size} bytes`);
    return;
  }
  $("run-die").disabled = true;
  $("die-status").textContent = `Uploading ${file.name} and polishing the die\u2026`;
  const t0 = performance.now();
  const r = await upload(`/api/die?${query(file)}`, file);
  $("run-die").disabled = false;
  if (!r.ok) {
    dieError(r);
    return;
  }
  const data = r.data;
  const maps = data.maps;
  delete data.maps; // what is left is the object `cmpsim die LAYOUT --json` prints
  $("die-status").textContent = `Done in ${((performance.now() - t0) / 1000).toFixed(1)} s`;
  renderDieSummary(data);
  renderDieTable(data);
  setDieDownload(data);
  try {
    await ensurePlotly();
  } catch (err) {
    showMessage("die-message", err.message);
    return;
  }
  plotDie(data, maps);
}

// ------------------------------------------------------------------ numbers
function shown(value, unit) {
  if (typeof value !== "number") return [fmt(value), unit === "1" ? "" : unit || ""];
  if (unit === "m") return Math.abs(value) < 1e-5 ? [fmt(value * 1e9), "nm"] : [fmt(value * 1e3), "mm"];
  if (unit === "m s-1") return [fmt(value * 6e10), "nm/min"];
  return [fmt(value), unit === "1" ? "" : unit || ""];
}

function renderDieSummary(d) {
  const w = d.windows || {};
  const [range, ru] = shown(d.thickness_range, "m");
  $("die-count").textContent = String(d.hotspot_count);
  $("die-count").dataset.count = d.hotspot_count;
  const limits = Object.entries(d.spec || {}).map(([k, v]) => `${k} ${fmt(v * 1e9)} nm`).join(", ");
  $("die-summary-text").textContent = ` hotspots${limits ? ` (limits: ${limits})` : " (no limits given)"} \u00b7 thickness range ${range} ${ru}`
    + ` \u00b7 ${w.nx} x ${w.ny} windows of ${fmt(w.window * 1e6)} \u00b5m on ${(w.layers || []).join(", ")} of ${w.top}`
    + ` \u00b7 ${d.process}, ${fmt(d.time)} s at ${fmt(d.blanket_rate * 6e10)} nm/min`;
  $("die-summary").hidden = false;
}

function renderDieTable(d) {
  const tbody = document.querySelector("#die-results tbody");
  tbody.textContent = "";
  const units = d.units || {};
  for (const [name, value] of Object.entries(d)) {
    if (value !== null && typeof value === "object") continue; // spec, hotspots, inputs, windows, units
    const tr = document.createElement("tr");
    const n = document.createElement("td");
    n.textContent = name;
    const v = document.createElement("td");
    v.dataset.key = name;
    const [text, unit] = shown(value, units[name]);
    v.textContent = text;
    v.title = String(value); // the SI value, as the API answered it
    const u = document.createElement("td");
    u.textContent = unit;
    if (units[name]) u.title = `SI: ${units[name]}`;
    tr.append(n, v, u);
    tbody.append(tr);
  }
  $("die-results").hidden = false;
}

function setDieDownload(d) {
  lastJson = d;
  const a = $("download-die-json");
  if (a.href.startsWith("blob:")) URL.revokeObjectURL(a.href);
  a.href = URL.createObjectURL(new Blob([JSON.stringify(d, null, 2) + "\n"], { type: "application/json" }));
  $("die-downloads").hidden = false;
}

// ------------------------------------------------------------------ maps
const um = (v) => v * 1e6;

function heatmap(x, y, z, unit, extra = {}) {
  return {
    type: "heatmap", x, y, z, colorscale: "Viridis", hoverongaps: false, colorbar: { title: { text: unit } },
    hovertemplate: `x %{x:.1f} \u00b5m<br>y %{y:.1f} \u00b5m<br>%{z:.4g} ${unit}<extra></extra>`, ...extra,
  };
}

function mapLayout(title) {
  return {
    title: { text: title, font: { size: 13 } },
    xaxis: { title: { text: "x (\u00b5m, layout)" }, constrain: "domain" },
    yaxis: { title: { text: "y (\u00b5m)" }, scaleanchor: "x", constrain: "domain" },
    margin: { l: 60, r: 10, t: 40, b: 45 },
    showlegend: false,
  };
}

function scaled(map, f) {
  return map.z.map((row) => row.map((v) => (v === null ? null : v * f)));
}

function markers(hotspots) {
  const shown = hotspots.slice(0, MARKERS);
  return {
    type: "scatter", mode: "markers", name: "hotspots",
    x: shown.map((h) => um(h.x)), y: shown.map((h) => um(h.y)),
    text: shown.map((h) => `${h.kind} ${fmt(h.value * 1e9)} nm (limit ${fmt(h.limit * 1e9)} nm)`),
    marker: { symbol: "x-thin", size: 7, line: { width: 1.5, color: "#111" }, color: "#111" },
    hovertemplate: "x %{x:.1f} \u00b5m<br>y %{y:.1f} \u00b5m<br>%{text}<extra>hotspot</extra>",
  };
}

function plotDie(d, maps) {
  $("die-plots").hidden = false;
  const x = maps.x.map(um), y = maps.y.map(um), m = maps.maps;
  const hot = d.hotspots || [];
  const density = heatmap(x, y, scaled(m.density, 100), "%", { zmin: 0, zmax: 100 });
  Plotly.react($("die-density"), [density], mapLayout("Pattern density per window"), PLOT_CONFIG);

  const height = heatmap(x, y, scaled(m.thickness, 1e9), "nm", { colorscale: "RdBu", zmid: 0 });
  const hl = mapLayout(`Final surface height off the die mean \u2014 range ${fmt(d.thickness_range * 1e9)} nm`);
  Plotly.react($("die-height"), hot.length ? [height, markers(hot)] : [height], hl, PLOT_CONFIG);

  // per window, the worst |value| / limit over the quantities with a limit: above 1 is a hotspot
  const spec = d.spec || {};
  const kinds = Object.keys(spec).filter((k) => m[k]);
  const div = $("die-hotspots");
  if (!kinds.length) {
    Plotly.purge(div);
    div.classList.add("note");
    div.textContent = "No hotspot limits given: type a limit (nm) for thickness, step_height, dishing or erosion to map the hotspots.";
    return;
  }
  div.classList.remove("note");
  div.textContent = "";
  const ratio = m[kinds[0]].z.map((row, i) => row.map((_, j) => {
    let worst = null;
    for (const k of kinds) {
      const v = m[k].z[i][j];
      if (v !== null && (worst === null || Math.abs(v) / spec[k] > worst)) worst = Math.abs(v) / spec[k];
    }
    return worst;
  }));
  const top = Math.max(2, ...ratio.flat().filter((v) => v !== null));
  const scale = [[0, "#e8f5e9"], [1 / top, "#fdd835"], [Math.min(1, 1.0001 / top), "#fb8c00"], [1, "#b71c1c"]];
  const worst = heatmap(x, y, ratio, "value / limit", { colorscale: scale, zmin: 0, zmax: top });
  const title = `Hotspots: worst value / limit per window (${d.hotspot_count} over: ${kinds.join(", ")})`;
  Plotly.react(div, [worst], mapLayout(title), PLOT_CONFIG);
}
