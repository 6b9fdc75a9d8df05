// The page of `cmpsim serve`: a thin client of the JSON API (/api/params, /api/solve, /api/sweeps).
// It knows no physics: it builds the form from /api/params, sends what the user typed (a plain
// number gets the display unit appended), and draws what the API answers. This module starts
// the page and solves one point; the others each do one job: page.js (state, messages),
// http.js (the API), form.js (the inputs), results.js (the table, downloads), plots.js (maps,
// profile), sweep.js (the sweep panel), tune.js (zone tuning of a membrane head), die.js (the
// die model on an uploaded layout).

import { state, $, showMessage, beginAction, showActionError } from "./page.js";
import { api, errorText } from "./http.js";
import { buildForm, collectInputs, resetForm } from "./form.js";
import { OUTPUTS, renderResults, setDownloads, downloadNetcdf } from "./results.js";
import { ensurePlotly, renderPlots } from "./plots.js";
import { syncTuneButton, tuneZones } from "./tune.js";
import { buildSweepPanel, runSweep, cancelSweep, drawSweep } from "./sweep.js";
import { buildDiePanel } from "./die.js";

async function solve() {
  const body = collectInputs();
  const t0 = beginAction("solve", "Solving\u2026");
  const r = await api("POST", "/api/solve?include=fields", body);
  $("solve").disabled = false;
  if (!r.ok) {
    showActionError(r, errorText(r));
    return;
  }
  const data = r.data;
  const fields = data.fields;
  delete data.fields; // what is left is the object `cmpsim run --json` prints
  state.result = data;
  state.body = body;
  $("status").textContent = `Solved in ${((performance.now() - t0) / 1000).toFixed(1)} s`;
  renderResults(data);
  setDownloads(data);
  try {
    await ensurePlotly();
  } catch (err) {
    showMessage("message", err.message);
    return;
  }
  renderPlots(data, fields);
}

// ------------------------------------------------------------------ start
async function main() {
  const [params, info, outputs] = await Promise.all([api("GET", "/api/params"), api("GET", "/api/info"), api("GET", "/api/outputs")]);
  if (outputs.ok) for (const o of outputs.data) OUTPUTS[o.name] = o;
  if (!params.ok) {
    $("loading").textContent = `Cannot load the inputs: ${errorText(params)}`;
    return;
  }
  buildForm(params.data, solve);
  buildSweepPanel();
  $("version").textContent = `version ${params.data.cmpsim_version}`;
  if (info.ok) {
    const l = info.data.limits;
    state.limits = l;
    $("version").textContent += ` \u00b7 limits: grid up to ${l.max_grid} (${l.max_grid_cells} cells), sweeps up to ${l.max_sweep_points} points, ${l.max_jobs} jobs at once`;
    if (l.max_upload_bytes) $("die-limit").textContent = `at most ${Number((l.max_upload_bytes / 1048576).toPrecision(3))} MiB and ${l.max_windows} windows`;
  }
  await buildDiePanel();
  $("solve").addEventListener("click", solve);
  $("reset").addEventListener("click", () => { resetForm(); syncTuneButton(); });
  $("tune-zones").addEventListener("click", tuneZones);
  $("inputs").addEventListener("change", syncTuneButton);
  $("run-sweep").addEventListener("click", runSweep);
  $("cancel-sweep").addEventListener("click", cancelSweep);
  $("sweep-output").addEventListener("change", () => ensurePlotly().then(drawSweep));
  $("download-netcdf").addEventListener("click", downloadNetcdf);
  for (const id of ["solve", "reset", "run-sweep"]) $(id).disabled = false;
  syncTuneButton();
  document.body.dataset.ready = "true";
}

document.addEventListener("DOMContentLoaded", main);
