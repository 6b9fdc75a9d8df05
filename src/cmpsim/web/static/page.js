// Shared by the page's modules: its state, element lookup, number format and messages.

export const state = { params: [], byName: {}, result: null, body: null, sweep: null, source: null, limits: null };

export const $ = (id) => document.getElementById(id);

export function fmt(v) {
  if (v === null || v === undefined) return "\u2013";
  if (typeof v === "boolean") return v ? "yes" : "no";
  if (typeof v !== "number") return String(v);
  if (Number.isInteger(v) && Math.abs(v) < 1e9) return String(v);
  const a = Math.abs(v);
  if (a === 0) return "0";
  if (a >= 1e-3 && a < 1e5) return String(Number(v.toPrecision(5)));
  return v.toExponential(4);
}

export function clearErrors(scope) {
  for (const el of (scope || document).querySelectorAll(".error")) el.textContent = "";
  for (const el of (scope || document).querySelectorAll("[aria-invalid]")) el.removeAttribute("aria-invalid");
}

export function showMessage(id, text) {
  const box = $(id);
  box.textContent = text || "";
  box.hidden = !text;
}

// Puts the message beside the input it names; returns false if no such input is on the page.
export function showFieldError(name, text) {
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

// The start of a call from the actions row: old messages cleared, the button off, the status set;
// returns the start time (ms).
export function beginAction(buttonId, status) {
  clearErrors($("inputs"));
  showMessage("message", "");
  $(buttonId).disabled = true;
  $("status").textContent = status;
  return performance.now();
}

// A refused call of the actions row: the API's message beside the input it names (422), else in
// the message box, with `prefix` before it.
export function showActionError(r, text, prefix = "") {
  $("status").textContent = "";
  if (r.status === 422 && showFieldError(r.data.parameter, text)) showMessage("message", `Check ${r.data.parameter}: ${text}`);
  else showMessage("message", prefix + text);
}

export function saveBlob(blob, name) {
  const a = document.createElement("a");
  a.href = URL.createObjectURL(blob);
  a.download = name;
  document.body.append(a);
  a.click();
  setTimeout(() => { URL.revokeObjectURL(a.href); a.remove(); }, 1000);
}
