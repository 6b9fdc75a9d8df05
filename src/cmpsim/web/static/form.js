// The inputs form, built from GET /api/params: what the user typed becomes a request body
// (a plain number gets the display unit appended; cmpsim reads a value with its own unit).

import { state, $, clearErrors, showMessage } from "./page.js";

const NUMBER = /^[-+]?(\d+\.?\d*|\.\d+)([eE][-+]?\d+)?$/;

export function requestValue(p, text) {
  const t = String(text).trim();
  if (p.kind === "list") return /[a-z]/i.test(t.replace(/e[-+]?\d/gi, "")) ? t : `${t} ${p.display_unit}`; // "3, 3.5, 4" in the display unit
  if (p.kind !== "number") return t;
  if (NUMBER.test(t)) return p.display_unit ? `${t} ${p.display_unit}` : Number(t);
  return t; // a value with its own unit: cmpsim reads it
}

export function collectInputs() {
  const out = {};
  for (const p of state.params) {
    const el = document.querySelector(`#inputs [name="${p.name}"]`);
    const text = el.value.trim();
    if (text === "" || text === p.default_display) continue;
    out[p.name] = requestValue(p, text);
  }
  return out;
}

// submit: what Enter and the form's submit do (the page's solve)
export function buildForm(payload, submit) {
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
    for (const p of payload.parameters.filter((q) => q.section === section)) fs.append(field(p, submit));
    form.append(fs);
  }
  form.addEventListener("submit", (e) => { e.preventDefault(); submit(); });
}

function field(p, submit) {
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
  input.addEventListener("keydown", (e) => { if (e.key === "Enter") { e.preventDefault(); submit(); } });
  const unit = document.createElement("span");
  unit.className = "unit";
  unit.textContent = p.display_unit || "";
  const error = document.createElement("span");
  error.className = "error";
  error.dataset.errorFor = p.name;
  row.append(label, input, unit, error);
  return row;
}

export function resetForm() {
  for (const p of state.params) {
    const el = document.querySelector(`#inputs [name="${p.name}"]`);
    el.value = p.default_display;
    el.classList.remove("changed");
  }
  clearErrors($("inputs"));
}

export function numericParams() { return state.params.filter((p) => p.kind === "number"); }
