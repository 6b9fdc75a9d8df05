// The results table (each output in its registry display unit, the SI value on hover) and the
// downloads of one solve.

import { state, $, fmt, showMessage, saveBlob } from "./page.js";

export function valuesOf(data) {
  if (data && typeof data.values === "object" && data.values !== null) return data.values;
  const flat = {};
  for (const [k, v] of Object.entries(data || {})) if (v === null || typeof v !== "object") flat[k] = v;
  return flat;
}

// Output name -> {display_unit, display_factor, unit, long_name} (GET /api/outputs): the table
// shows each value in its display unit, the SI value in the tooltip.
export const OUTPUTS = {};

const UNIT_TEXT = { um: "\u00b5m", urad: "\u00b5rad", "-": "" };

function unitText(u) { return u in UNIT_TEXT ? UNIT_TEXT[u] : u || ""; }

export function renderResults(data) {
  const units = data.units || {};
  const rows = Object.entries(valuesOf(data));
  if (data.solver && typeof data.solver === "object") rows.push(...Object.entries(data.solver));
  const tbody = document.querySelector("#results tbody");
  tbody.textContent = "";
  for (const [name, value] of rows) {
    const tr = document.createElement("tr");
    const n = document.createElement("td");
    n.textContent = name;
    const v = document.createElement("td");
    v.dataset.key = name;
    const out = OUTPUTS[name];
    const shown = out && typeof value === "number" && out.display_unit !== out.unit && out.display_unit !== "-";
    v.textContent = shown ? fmt(value * out.display_factor) : fmt(value);
    v.title = String(value); // the SI value, as the API answered it
    const u = document.createElement("td");
    u.textContent = shown ? unitText(out.display_unit) : unitText(units[name] || "");
    u.title = units[name] ? `SI: ${units[name]}` : "";
    if (out) n.title = out.long_name;
    tr.append(n, v, u);
    tbody.append(tr);
  }
}

export function setDownloads(data) {
  $("downloads").hidden = false;
  const json = $("download-json");
  if (json.href.startsWith("blob:")) URL.revokeObjectURL(json.href);
  json.href = URL.createObjectURL(new Blob([JSON.stringify(data, null, 2) + "\n"], { type: "application/json" }));
}

export async function downloadNetcdf(e) {
  e.preventDefault();
  const r = await fetch("/api/solve?format=netcdf", { method: "POST", headers: { "Content-Type": "application/json" }, body: JSON.stringify(state.body || {}) });
  if (!r.ok) { showMessage("message", `NetCDF: the server answered ${r.status}`); return; }
  saveBlob(await r.blob(), "cmpsim-result.nc");
}
