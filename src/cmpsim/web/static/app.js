// The page of `cmpsim serve`: a thin client of the JSON API (/api/params, /api/solve, /api/sweeps).
// It knows no physics: it builds the form from /api/params, sends what the user typed (a plain
// number gets the display unit appended), and draws what the API answers.
"use strict";

const state = { params: [], byName: {}, result: null, body: null, sweep: null, source: null };
const NUMBER = /^[-+]?(\d+\.?\d*|\.\d+)([eE][-+]?\d+)?$/;
const $ = (id) => document.getElementById(id);

// ------------------------------------------------------------------ HTTP
async function api(method, url, body) {
  const init = { method, headers: {} };
  if (body !== undefined) {
    init.headers["Content-Type"] = "application/json";
    init.body = JSON.stringify(body);
  }
  let response;
  try {
    response = await fetch(url, init);
  } catch (err) {
    return { ok: false, status: 0, data: { detail: `cannot reach the cmpsim server (${err.message})`, parameter: null } };
  }
  const type = response.headers.get("content-type") || "";
  let data = null;
  if (type.includes("json")) {
    try { data = await response.json(); } catch (err) { data = null; }
  }
  if (!response.ok && !(data && data.detail)) {
    data = { detail: `the server answered ${response.status} ${response.statusText}`, parameter: null };
  }
  return { ok: response.ok, status: response.status, data, response };
}

function errorText(r) {
  let text = r.data && r.data.detail ? String(r.data.detail) : `error ${r.status}`;
  if (r.status === 429) {
    const wait = r.response && r.response.headers.get("Retry-After");
    text += wait ? ` (retry in ${wait} s)` : "";
  }
  return text;
}

// plotly.js (from the installed plotly wheel, served by cmpsim) is loaded at the first plot:
// the form is usable before its 4.8 MB are parsed.
let plotlyLoading = null;
function ensurePlotly() {
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

// ------------------------------------------------------------------ values
function requestValue(p, text) {
  const t = String(text).trim();
  if (p.kind === "list") return /[a-z]/i.test(t.replace(/e[-+]?\d/gi, "")) ? t : `${t} ${p.display_unit}`; // "3, 3.5, 4" in the display unit
  if (p.kind !== "number") return t;
  if (NUMBER.test(t)) return p.display_unit ? `${t} ${p.display_unit}` : Number(t);
  return t; // a value with its own unit: cmpsim reads it
}

function collectInputs() {
  const out = {};
  for (const p of state.params) {
    const el = document.querySelector(`#inputs [name="${p.name}"]`);
    const text = el.value.trim();
    if (text === "" || text === p.default_display) continue;
    out[p.name] = requestValue(p, text);
  }
  return out;
}

function fmt(v) {
  if (v === null || v === undefined) return "\u2013";
  if (typeof v === "boolean") return v ? "yes" : "no";
  if (typeof v !== "number") return String(v);
  if (Number.isInteger(v) && Math.abs(v) < 1e9) return String(v);
  const a = Math.abs(v);
  if (a === 0) return "0";
  if (a >= 1e-3 && a < 1e5) return String(Number(v.toPrecision(5)));
  return v.toExponential(4);
}

// SI unit -> (factor, unit shown) for plots; anything else is shown as it is.
const SHOWN = { m: [1e6, "\u00b5m"], Pa: [1e-3, "kPa"], "m/s": [6e10, "nm/min"], "m s-1": [6e10, "nm/min"] };
function shownUnit(unit) { return SHOWN[unit] || [1, unit || ""]; }

// ------------------------------------------------------------------ errors
function clearErrors(scope) {
  for (const el of (scope || document).querySelectorAll(".error")) el.textContent = "";
  for (const el of (scope || document).querySelectorAll("[aria-invalid]")) el.removeAttribute("aria-invalid");
}

function showMessage(id, text) {
  const box = $(id);
  box.textContent = text || "";
  box.hidden = !text;
}

// Puts the message beside the input it names; returns false if no such input is on the page.
function showFieldError(name, text) {
  if (!name) return false;
  const slot = document.querySelector(`[data-error-for="${CSS.escape(name)}"]`);
  if (!slot) return false;
  slot.textContent = text;
  const input = document.querySelector(`#inputs [name="${CSS.escape(name)}"]`);
  if (input) {
    input.setAttribute("aria-invalid", "true");
    input.scrollIntoView({ block: "nearest" });
  }
  return true;
}

// ------------------------------------------------------------------ form
function buildForm(payload) {
  const form = $("inputs");
  form.textContent = "";
  state.params = payload.parameters;
  state.byName = Object.fromEntries(payload.parameters.map((p) => [p.name, p]));
  const grids = document.createElement("datalist");
  grids.id = "grid-presets";
  for (const g of ["coarse", "default", "fine"]) grids.append(new Option(g, g));
  form.append(grids);
  for (const section of payload.sections) {
    const fs = document.createElement("fieldset");
    fs.dataset.section = section;
    const legend = document.createElement("legend");
    legend.textContent = section;
    fs.append(legend);
    for (const p of payload.parameters.filter((q) => q.section === section)) fs.append(field(p));
    form.append(fs);
  }
  form.addEventListener("submit", (e) => { e.preventDefault(); solve(); });
}

function field(p) {
  const row = document.createElement("div");
  row.className = "field";
  const label = document.createElement("label");
  label.htmlFor = `in-${p.name}`;
  label.textContent = p.name;
  label.title = `${p.description}\nvalid range: ${p.range}\nsource: ${p.source}`;
  let input;
  if (p.kind === "choice") {
    input = document.createElement("select");
    for (const c of p.choices) input.append(new Option(c, c));
  } else {
    input = document.createElement("input");
    input.type = "text";
    input.spellcheck = false;
    if (p.kind === "grid") input.setAttribute("list", "grid-presets");
  }
  input.id = `in-${p.name}`;
  input.name = p.name;
  input.value = p.default_display;
  input.title = label.title;
  input.addEventListener("input", () => {
    input.classList.toggle("changed", input.value.trim() !== p.default_display);
    if (input.getAttribute("aria-invalid")) showMessage("message", "");
    input.removeAttribute("aria-invalid");
    row.querySelector(".error").textContent = "";
  });
  input.addEventListener("keydown", (e) => { if (e.key === "Enter") { e.preventDefault(); solve(); } });
  const unit = document.createElement("span");
  unit.className = "unit";
  unit.textContent = p.display_unit || "";
  const error = document.createElement("span");
  error.className = "error";
  error.dataset.errorFor = p.name;
  row.append(label, input, unit, error);
  return row;
}

function resetForm() {
  for (const p of state.params) {
    const el = document.querySelector(`#inputs [name="${p.name}"]`);
    el.value = p.default_display;
    el.classList.remove("changed");
  }
  clearErrors($("inputs"));
}

// ------------------------------------------------------------------ solve
async function solve() {
  clearErrors($("inputs"));
  showMessage("message", "");
  const body = collectInputs();
  $("solve").disabled = true;
  $("status").textContent = "Solving\u2026";
  const t0 = performance.now();
  const r = await api("POST", "/api/solve?include=fields", body);
  $("solve").disabled = false;
  if (!r.ok) {
    $("status").textContent = "";
    const text = errorText(r);
    if (r.status === 422 && showFieldError(r.data.parameter, text)) {
      showMessage("message", `Check ${r.data.parameter}: ${text}`);
    } else {
      showMessage("message", text);
    }
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

function valuesOf(data) {
  if (data && typeof data.values === "object" && data.values !== null) return data.values;
  const flat = {};
  for (const [k, v] of Object.entries(data || {})) if (v === null || typeof v !== "object") flat[k] = v;
  return flat;
}

// Output name -> {display_unit, display_factor, unit, long_name} (GET /api/outputs): the table
// shows each value in its display unit, the SI value in the tooltip.
const OUTPUTS = {};
const UNIT_TEXT = { um: "\u00b5m", urad: "\u00b5rad", "-": "" };
function unitText(u) { return u in UNIT_TEXT ? UNIT_TEXT[u] : u || ""; }

function renderResults(data) {
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

const PLOT_CONFIG = { responsive: true, displaylogo: false };

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

function renderPlots(data, fields) {
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

function setDownloads(data) {
  $("downloads").hidden = false;
  const json = $("download-json");
  if (json.href.startsWith("blob:")) URL.revokeObjectURL(json.href);
  json.href = URL.createObjectURL(new Blob([JSON.stringify(data, null, 2) + "\n"], { type: "application/json" }));
}

async function downloadNetcdf(e) {
  e.preventDefault();
  const r = await fetch("/api/solve?format=netcdf", { method: "POST", headers: { "Content-Type": "application/json" }, body: JSON.stringify(state.body || {}) });
  if (!r.ok) { showMessage("message", `NetCDF: the server answered ${r.status}`); return; }
  saveBlob(await r.blob(), "cmpsim-result.nc");
}

function saveBlob(blob, name) {
  const a = document.createElement("a");
  a.href = URL.createObjectURL(blob);
  a.download = name;
  document.body.append(a);
  a.click();
  setTimeout(() => { URL.revokeObjectURL(a.href); a.remove(); }, 1000);
}

// ------------------------------------------------------------------ sweeps
function numericParams() { return state.params.filter((p) => p.kind === "number"); }

// One row per swept input: #sweep-param-N, #sweep-start-N, #sweep-stop-N, #sweep-num-N.
function axisRow(n, title, points) {
  const row = document.createElement("div");
  row.className = "axis";
  row.dataset.axis = String(n);
  const labelled = (text, el) => {
    const label = document.createElement("label");
    label.append(`${text} `, el);
    return label;
  };
  const control = (tag, id, attrs) => {
    const el = document.createElement(tag);
    el.id = id;
    el.name = id.replaceAll("-", "_");
    Object.assign(el, attrs || {});
    return el;
  };
  const unit = control("span", `sweep-unit-${n}`, { className: "unit" });
  const error = document.createElement("span");
  error.className = "error";
  error.dataset.errorFor = `sweep-${n}`;
  row.append(
    labelled(title, control("select", `sweep-param-${n}`)),
    labelled("from", control("input", `sweep-start-${n}`, { size: 9 })),
    labelled("to", control("input", `sweep-stop-${n}`, { size: 9 })),
    unit,
    labelled("points", control("input", `sweep-num-${n}`, { type: "number", min: 1, value: String(points) })),
    error,
  );
  return row;
}

function buildSweepPanel() {
  $("sweep-axes").append(axisRow(1, "Input", 5), axisRow(2, "Second input", 4));
  const s1 = $("sweep-param-1");
  const s2 = $("sweep-param-2");
  s2.append(new Option("(none)", ""));
  for (const p of numericParams()) {
    s1.append(new Option(p.name, p.name));
    s2.append(new Option(p.name, p.name));
  }
  s1.value = state.byName.applied_pressure ? "applied_pressure" : numericParams()[0].name;
  s2.value = "";
  const fill = (n) => {
    const p = state.byName[$(`sweep-param-${n}`).value];
    $(`sweep-unit-${n}`).textContent = p ? p.display_unit || "" : "";
    const d = p ? Number(p.default_display) : NaN;
    $(`sweep-start-${n}`).value = p && Number.isFinite(d) && d !== 0 ? String(Number((d * 0.5).toPrecision(4))) : "";
    $(`sweep-stop-${n}`).value = p && Number.isFinite(d) && d !== 0 ? String(Number((d * 1.5).toPrecision(4))) : "";
    for (const id of [`sweep-start-${n}`, `sweep-stop-${n}`, `sweep-num-${n}`]) $(id).disabled = !p;
  };
  s1.addEventListener("change", () => fill(1));
  s2.addEventListener("change", () => fill(2));
  fill(1);
  fill(2);
}

function axisOf(n) {
  const name = $(`sweep-param-${n}`).value;
  if (!name) return null;
  const p = state.byName[name];
  const numText = $(`sweep-num-${n}`).value.trim();
  const num = /^\d+$/.test(numText) ? Number(numText) : numText;
  return [name, { start: requestValue(p, $(`sweep-start-${n}`).value), stop: requestValue(p, $(`sweep-stop-${n}`).value), num }];
}

async function runSweep() {
  clearErrors(document);
  showMessage("sweep-message", "");
  const a1 = axisOf(1);
  const a2 = axisOf(2);
  if (a2 && a2[0] === a1[0]) {
    document.querySelector('[data-error-for="sweep-2"]').textContent = "choose a second input different from the first";
    return;
  }
  const body = { base: collectInputs(), axes: Object.fromEntries([a1, a2].filter(Boolean)) };
  $("run-sweep").disabled = true;
  const r = await api("POST", "/api/sweeps", body);
  if (!r.ok) {
    $("run-sweep").disabled = false;
    const text = errorText(r);
    const name = r.data && r.data.parameter;
    const slot = name === a1[0] ? "sweep-1" : a2 && name === a2[0] ? "sweep-2" : null;
    if (slot) document.querySelector(`[data-error-for="${slot}"]`).textContent = text;
    else if (!(r.status === 422 && showFieldError(name, text))) showMessage("sweep-message", text);
    else showMessage("sweep-message", `Check ${name}: ${text}`);
    return;
  }
  startSweep(r.data);
}

function startSweep(job) {
  state.sweep = { ...job, points: [] };
  const bar = $("sweep-progress");
  bar.max = job.total;
  bar.value = 0;
  bar.hidden = false;
  $("cancel-sweep").hidden = false;
  $("cancel-sweep").disabled = false;
  $("sweep-downloads").hidden = true;
  $("sweep-failures").textContent = "";
  $("sweep-status").textContent = `0 of ${job.total} points`;
  delete $("sweep-status").dataset.state;
  for (const w of job.warnings || []) showMessage("sweep-message", `warning: ${w}; those points will be recorded as invalid`);
  if (state.source) state.source.close();
  const source = new EventSource(`/api/sweeps/${job.id}/events`);
  state.source = source;
  source.addEventListener("point", (e) => {
    const point = JSON.parse(e.data);
    state.sweep.points.push(point);
    bar.value = point.done;
    $("sweep-status").textContent = `${point.done} of ${point.total} points`;
    if (point.status !== "ok") addFailure(point);
    ensurePlotly().then(drawSweep, (err) => showMessage("sweep-message", err.message));
  });
  source.addEventListener("end", (e) => {
    source.close();
    state.source = null;
    endSweep(JSON.parse(e.data));
  });
  source.onerror = async () => {
    if (source.readyState !== EventSource.CLOSED) return; // the browser reconnects by itself
    state.source = null;
    const r = await api("GET", `/api/sweeps/${job.id}`);
    if (r.ok && r.data.status !== "running" && r.data.status !== "queued") endSweep(r.data);
    else showMessage("sweep-message", "lost the connection to the sweep's events; its state is at " + `/api/sweeps/${job.id}`);
  };
}

function endSweep(st) {
  $("run-sweep").disabled = false;
  $("cancel-sweep").hidden = true;
  const sweep = state.sweep;
  const failed = st.failed ? `, ${st.failed} failed` : "";
  $("sweep-status").textContent = `${st.status}: ${st.done} of ${st.total} points${failed}`;
  $("sweep-status").dataset.state = st.status;
  if (st.error) showMessage("sweep-message", st.error);
  $("sweep-downloads").hidden = false;
  const file = $("download-sweep-file");
  file.href = `/api/sweeps/${sweep.id}/file`;
  file.download = `cmpsim-sweep-${sweep.id}.toml`;
  const nc = $("download-sweep-netcdf");
  nc.hidden = st.status !== "done";
  nc.href = `/api/sweeps/${sweep.id}/result`;
  nc.download = `cmpsim-sweep-${sweep.id}.nc`;
  ensurePlotly().then(drawSweep, (err) => showMessage("sweep-message", err.message));
}

function addFailure(point) {
  const li = document.createElement("li");
  const where = Object.entries(point.settings).map(([k, v]) => `${k} = ${settingText(k, point.index)}`).join(", ");
  li.textContent = `${where}: ${point.status}: ${point.error}`;
  $("sweep-failures").append(li);
}

function settingText(name, index) {
  const sweep = state.sweep;
  const d = sweep.dims.indexOf(name);
  const shown = sweep.display && sweep.display[name];
  if (d < 0 || !shown) return "";
  return `${fmt(shown.values[index[d]])}${shown.unit ? " " + shown.unit : ""}`;
}

function sweepOutputs() {
  const ok = state.sweep.points.find((p) => p.status === "ok");
  if (!ok) return [];
  return Object.entries(ok.values).filter(([, v]) => typeof v === "number").map(([k]) => k);
}

const PREFERRED = ["removal_rate_mean", "removal_rate_nm_per_min", "removal_rate", "film_thickness_center", "film_thickness_center_m"];

function drawSweep() {
  const sweep = state.sweep;
  if (!sweep || !window.Plotly) return;
  const select = $("sweep-output");
  const names = sweepOutputs();
  if (names.length && select.options.length !== names.length) {
    const keep = select.value;
    select.textContent = "";
    for (const n of names) select.append(new Option(n, n));
    select.value = names.includes(keep) ? keep : PREFERRED.find((n) => names.includes(n)) || names[0];
  }
  $("sweep-output-label").hidden = !names.length;
  const out = select.value;
  const div = $("sweep-plot");
  div.hidden = false;
  const [d0, d1] = sweep.dims;
  const label = (d) => `${d}${sweep.display[d].unit ? ` (${sweep.display[d].unit})` : ""}`;
  const xs = sweep.display[d0].values;
  const unit = state.result && state.result.units ? state.result.units[out] || "" : "";
  const yTitle = out ? `${out}${unit ? ` (${unit})` : ""}` : "";
  const layout = { margin: { l: 70, r: 20, t: 30, b: 50 }, xaxis: { title: { text: label(d0) } }, legend: { orientation: "h", y: -0.2 } };
  let traces;
  if (!d1 || sweep.dims.length < 2) {
    const ok = sweep.points.filter((p) => p.status === "ok").sort((a, b) => a.index[0] - b.index[0]);
    const bad = sweep.points.filter((p) => p.status !== "ok");
    const ys = ok.map((p) => p.values[out]);
    const base = ys.length ? Math.min(...ys.filter((v) => v !== null)) : 0;
    traces = [
      { x: ok.map((p) => xs[p.index[0]]), y: ys, mode: "lines+markers", name: out || "ok", hovertemplate: "%{x:.4g}: %{y:.4g}<extra></extra>" },
      { x: bad.map((p) => xs[p.index[0]]), y: bad.map(() => base), mode: "markers", name: "failed", marker: { symbol: "x", size: 12, color: "#b42318" }, text: bad.map((p) => `${p.status}: ${p.error}`), hovertemplate: "%{x:.4g}: %{text}<extra></extra>" },
    ];
    layout.yaxis = { title: { text: yTitle } };
  } else {
    const ys = sweep.display[d1].values;
    const z = ys.map(() => xs.map(() => null));
    const bad = [];
    for (const p of sweep.points) {
      if (p.status === "ok") z[p.index[1]][p.index[0]] = p.values[out];
      else bad.push(p);
    }
    traces = [
      { type: "heatmap", x: xs, y: ys, z, colorscale: "Viridis", hoverongaps: false, colorbar: { title: { text: out } }, hovertemplate: "%{x:.4g}, %{y:.4g}: %{z:.4g}<extra></extra>" },
      { x: bad.map((p) => xs[p.index[0]]), y: bad.map((p) => ys[p.index[1]]), mode: "markers", name: "failed", marker: { symbol: "x", size: 12, color: "#b42318" }, text: bad.map((p) => `${p.status}: ${p.error}`), hovertemplate: "%{text}<extra></extra>" },
    ];
    layout.yaxis = { title: { text: label(d1) } };
  }
  Plotly.react(div, traces, layout, PLOT_CONFIG);
}

async function cancelSweep() {
  if (!state.sweep) return;
  $("cancel-sweep").disabled = true;
  $("sweep-status").textContent = "cancelling\u2026";
  await api("DELETE", `/api/sweeps/${state.sweep.id}`);
}

// ------------------------------------------------------------------ start
async function main() {
  const [params, info, outputs] = await Promise.all([api("GET", "/api/params"), api("GET", "/api/info"), api("GET", "/api/outputs")]);
  if (outputs.ok) for (const o of outputs.data) OUTPUTS[o.name] = o;
  if (!params.ok) {
    $("loading").textContent = `Cannot load the inputs: ${errorText(params)}`;
    return;
  }
  buildForm(params.data);
  buildSweepPanel();
  $("version").textContent = `version ${params.data.cmpsim_version}`;
  if (info.ok) {
    const l = info.data.limits;
    $("version").textContent += ` \u00b7 limits: grid up to ${l.max_grid} (${l.max_grid_cells} cells), sweeps up to ${l.max_sweep_points} points, ${l.max_jobs} jobs at once`;
  }
  $("solve").addEventListener("click", solve);
  $("reset").addEventListener("click", resetForm);
  $("run-sweep").addEventListener("click", runSweep);
  $("cancel-sweep").addEventListener("click", cancelSweep);
  $("sweep-output").addEventListener("change", () => ensurePlotly().then(drawSweep));
  $("download-netcdf").addEventListener("click", downloadNetcdf);
  for (const id of ["solve", "reset", "run-sweep"]) $(id).disabled = false;
  document.body.dataset.ready = "true";
}

document.addEventListener("DOMContentLoaded", main);
