// A plain reference of the HTTP API, drawn from /api/openapi.json (served by cmpsim itself, no CDN).
"use strict";

function el(tag, text, cls) {
  const e = document.createElement(tag);
  if (text !== undefined) e.textContent = text;
  if (cls) e.className = cls;
  return e;
}

async function main() {
  const routes = document.getElementById("routes");
  const r = await fetch("/api/openapi.json");
  if (!r.ok) { routes.textContent = `cannot load /api/openapi.json (${r.status})`; return; }
  const spec = await r.json();
  document.getElementById("version").textContent = `version ${spec.info.version}`;
  document.getElementById("description").append(el("p", spec.info.description || ""));
  routes.textContent = "";
  for (const [path, ops] of Object.entries(spec.paths)) {
    for (const [method, op] of Object.entries(ops)) {
      const box = el("section", undefined, "route");
      box.append(el("h2", `${method.toUpperCase()} ${path}`));
      if (op.summary) box.append(el("p", op.summary));
      if (op.description) box.append(el("p", op.description, "muted"));
      const params = (op.parameters || []).map((p) => `${p.name} (${p.in})${p.description ? ": " + p.description : ""}`);
      if (params.length) {
        const ul = el("ul");
        for (const p of params) ul.append(el("li", p));
        box.append(el("h3", "parameters"), ul);
      }
      const body = op.requestBody && op.requestBody.content;
      if (body) {
        for (const [type, media] of Object.entries(body)) {
          const examples = media.examples ? Object.values(media.examples).map((x) => x.value) : [];
          box.append(el("h3", `body (${type})`));
          if (examples.length) box.append(el("pre", JSON.stringify(examples[0], null, 2)));
        }
      }
      routes.append(box);
    }
  }
}

document.addEventListener("DOMContentLoaded", main);
