// Talking to the cmpsim server: every call of the JSON API, and the text of its errors.

export async function api(method, url, body) {
  const init = { method, headers: {} };
  if (body !== undefined) {
    init.headers["Content-Type"] = "application/json";
    init.body = JSON.stringify(body);
  }
  return call(url, init);
}

// A file sent as the request body (POST /api/die takes the layout so); answers as api() does.
export async function upload(url, file) {
  return call(url, { method: "POST", headers: { "Content-Type": "application/octet-stream" }, body: file });
}

async function call(url, init) {
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

export function errorText(r) {
  let text = r.data && r.data.detail ? String(r.data.detail) : `error ${r.status}`;
  if (r.status === 429) {
    const wait = r.response && r.response.headers.get("Retry-After");
    text += wait ? ` (retry in ${wait} s)` : "";
  }
  return text;
}
