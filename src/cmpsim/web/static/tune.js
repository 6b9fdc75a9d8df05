// Zone tuning of a membrane head: POST /api/tune-zones with the form's inputs, then the tuned
// zone pressures (psi and Pa), the non-uniformity before and after, the profile before and after
// (with the zone boundaries), and the tuned pressures written into the zone_pressures input.
// "with the ring" also tunes the retaining ring's pressure (POST /api/tune-zones?ring=true, the call
// of `cmpsim tune-zones --ring`, which keeps the mean removal rate) and writes it into its input.

import { state, $, showMessage, beginAction, showActionError } from "./page.js";
import { api, errorText } from "./http.js";
import { collectInputs } from "./form.js";
import { ensurePlotly, zoneBoundaries, PLOT_CONFIG } from "./plots.js";

const PSI = 6894.757293168361; // Pa per psi (pint's psi)

// The button is usable only when the form's carrier is the membrane head.
export function syncTuneButton() {
  const carrier = document.querySelector('#inputs [name="carrier"]');
  $("tune-zones").disabled = !carrier || carrier.value !== "membrane";
  $("tune-ring").disabled = $("tune-zones").disabled;
}

const psiText = (pa) => String(Number((pa / PSI).toPrecision(6)));
const percent = (f) => `${(100 * f).toPrecision(3)} %`;

function setInput(name, text) {
  const el = document.querySelector(`#inputs [name="${name}"]`);
  el.value = text;
  el.dispatchEvent(new Event("input"));
}

export async function tuneZones() {
  const body = collectInputs();
  const t0 = beginAction("tune-zones", "Tuning zones\u2026");
  const ring = $("tune-ring").checked;
  const r = await api("POST", "/api/tune-zones" + (ring ? "?ring=true" : ""), body);
  syncTuneButton();
  if (!r.ok) {
    showActionError(r, errorText(r), "Tune zones: ");
    return;
  }
  const d = r.data;
  $("status").textContent = `Zones tuned in ${((performance.now() - t0) / 1000).toFixed(1)} s (${d.solves} solves)`;
  // zone_pressures now carry the load: applied_pressure (their area-weighted mean) back to its default,
  // since an input that sets both is refused
  const applied = state.byName.applied_pressure;
  const appliedReset = applied && body.applied_pressure !== undefined;
  if (appliedReset) setInput("applied_pressure", applied.default_display);
  const unit = state.byName.zone_pressures.display_unit;
  setInput("zone_pressures", d.zone_pressures.map(psiText).join(", ") + (unit === "psi" ? "" : " psi"));
  if (d.ring_pressure !== undefined) {
    const ringUnit = state.byName.retaining_ring_pressure.display_unit;
    setInput("retaining_ring_pressure", psiText(d.ring_pressure) + (ringUnit === "psi" ? "" : " psi"));
  }
  renderTune(d, appliedReset);
  try {
    await ensurePlotly();
  } catch (err) {
    showMessage("message", err.message);
    return;
  }
  plotTune(d);
}

function renderTune(d, appliedReset) {
  $("tune").hidden = false;
  const before = d.before.within_wafer_nonuniformity, after = d.within_wafer_nonuniformity;
  const rate = (v) => `${(v * 6e10).toFixed(2)} nm/min`;
  const kept = d.keep === "rate" ? "kept" : "not kept";
  $("tune-summary").textContent = `Within-wafer non-uniformity ${percent(before)} before, ${percent(after)} after tuning;`
    + ` mean removal rate inside the edge exclusion (${kept}) ${rate(d.before.mean_rate)} before, ${rate(d.mean_rate)} after.`
    + " The tuned pressures are in the zone_pressures input" + (d.ring_pressure !== undefined ? " and the ring's in retaining_ring_pressure" : "")
    + (appliedReset ? " (applied_pressure set back to its default: the zones now set the load)." : ".");
  $("tune-summary").dataset.before = before;
  $("tune-summary").dataset.after = after;
  $("tune-summary").dataset.rateBefore = d.before.mean_rate;
  $("tune-summary").dataset.rateAfter = d.mean_rate;
  const tbody = document.querySelector("#tune-table tbody");
  tbody.textContent = "";
  const row = (cells) => {
    const tr = document.createElement("tr");
    for (const c of cells) {
      const td = document.createElement("td");
      td.textContent = c;
      tr.append(td);
    }
    tbody.append(tr);
  };
  d.zone_pressures.forEach((p, k) => {
    row([`${k + 1}`, String(Number((d.zone_radii[k] * 1e3).toPrecision(5))), psiText(d.before.zone_pressures[k]), psiText(p), String(Number(p.toPrecision(6)))]);
  });
  if (d.ring_pressure !== undefined) {
    row(["ring", "beside the wafer", psiText(d.before.ring_pressure), psiText(d.ring_pressure), String(Number(d.ring_pressure.toPrecision(6)))]);
  }
}

function plotTune(d) {
  const mm = (v) => v * 1e3, nm = (v) => (v === null ? null : v * 6e10);
  const line = (prof, name, dash) => ({ x: prof.radius.map(mm), y: prof.rate.map(nm), mode: "lines+markers", name, line: { dash }, hovertemplate: `r %{x:.1f} mm<br>%{y:.4g} nm/min<extra>${name}</extra>` });
  const traces = [line(d.before.profile, "before", "dot"), line(d.profile, "tuned", "solid")];
  const inputs = { carrier: "membrane", zone_radii: d.zone_radii };
  const layout = {
    title: { text: "Removal rate before and after tuning the zones", font: { size: 13 } },
    xaxis: { title: { text: "wafer radius (mm)" } },
    yaxis: { title: { text: "removal rate (nm/min)" } },
    margin: { l: 60, r: 20, t: 40, b: 45 },
    legend: { orientation: "h", y: -0.25 },
    ...zoneBoundaries(inputs),
  };
  Plotly.react($("tune-profile"), traces, layout, PLOT_CONFIG);
}
