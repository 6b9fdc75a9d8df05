// The sweep panel: one or two inputs over a range, run on the server (POST /api/sweeps),
// followed by its server-sent events, plotted as the points arrive, cancelled on request.

import { state, $, fmt, clearErrors, showMessage, showFieldError } from "./page.js";
import { api, errorText } from "./http.js";
import { requestValue, collectInputs, numericParams } from "./form.js";
import { ensurePlotly, PLOT_CONFIG } from "./plots.js";

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

export function buildSweepPanel() {
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

export async function runSweep() {
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
  if (st.error) showMessage("sweep-message", st.error);
  $("sweep-downloads").hidden = false;
  const file = $("download-sweep-file");
  file.href = `/api/sweeps/${sweep.id}/file`;
  file.download = `cmpsim-sweep-${sweep.id}.toml`;
  const nc = $("download-sweep-netcdf");
  nc.hidden = st.status !== "done";
  nc.href = `/api/sweeps/${sweep.id}/result`;
  nc.download = `cmpsim-sweep-${sweep.id}.nc`;
  // the state is marked once the final curve is drawn (or Plotly failed to load), so whoever
  // waits on data-state sees the plot of every point, not the one before the last event
  ensurePlotly()
    .then(drawSweep, (err) => showMessage("sweep-message", err.message))
    .finally(() => { $("sweep-status").dataset.state = st.status; });
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

export function drawSweep() {
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
  return Plotly.react(div, traces, layout, PLOT_CONFIG);
}

export async function cancelSweep() {
  if (!state.sweep) return;
  $("cancel-sweep").disabled = true;
  $("sweep-status").textContent = "cancelling\u2026";
  await api("DELETE", `/api/sweeps/${state.sweep.id}`);
}
