// Calls to the studio server. Every answer that is not 2xx becomes an ApiError
// carrying the server's message and, for spec errors, the located errors.
export class ApiError extends Error {
  constructor(status, body) {
    super(body && body.error ? body.error : `HTTP ${status}`);
    this.status = status;
    this.errors = (body && body.errors) || [];
    this.warnings = (body && body.warnings) || [];
  }
}

async function answer(res) {
  let body = null;
  try { body = await res.json(); } catch (e) { body = null; }
  if (!res.ok) throw new ApiError(res.status, body);
  return body;
}

export async function get(path) { return answer(await fetch(path, { credentials: "same-origin" })); }

export async function post(path, data) {
  return answer(await fetch(path, {
    method: "POST", credentials: "same-origin",
    headers: { "Content-Type": "application/json" }, body: JSON.stringify(data),
  }));
}

export async function points() {
  const res = await fetch("/api/scan/points", { credentials: "same-origin" });
  if (!res.ok) throw new ApiError(res.status, null);
  return new Float32Array(await res.arrayBuffer());
}

export function bytes(b64) {
  const s = atob(b64), out = new Uint8Array(s.length);
  for (let i = 0; i < s.length; i++) out[i] = s.charCodeAt(i);
  return out;
}

export function floats(b64) { return new Float32Array(bytes(b64).buffer); }

export function uint32s(b64) { return new Uint32Array(bytes(b64).buffer); }

// the CAD model's shown mesh: {xyz: Float32Array (minus origin), tris: Uint32Array, origin, key}
export async function cadMesh() {
  const res = await fetch("/api/cad/mesh", { credentials: "same-origin" });
  if (!res.ok) { let body = null; try { body = await res.json(); } catch (e) { body = null; } throw new ApiError(res.status, body); }
  const nv = Number(res.headers.get("X-Vertex-Count")), nt = Number(res.headers.get("X-Triangle-Count"));
  const buf = await res.arrayBuffer();
  return { xyz: new Float32Array(buf, 0, 3 * nv), tris: new Uint32Array(buf, 12 * nv, 3 * nt),
    origin: res.headers.get("X-Origin").split(",").map(Number), key: Number(res.headers.get("X-Cad-Key")) };
}
