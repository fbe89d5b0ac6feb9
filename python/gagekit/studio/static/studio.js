// gagekit studio client: the gage document, the panel, and the calls that keep the
// view in step with the server (counts, alignment, the check, saving).
import { View } from "./view.js";
import * as api from "./api.js";

const MOTIONS = ["alpha", "beta", "gamma", "dx", "dy", "dz"];
const MOTION_HELP = { alpha: "about z", beta: "about y", gamma: "about x", dx: "along x", dy: "along y", dz: "along z" };
const ROLES = ["primary", "secondary", "tertiary"];
const NORMALS = { "+x": [1, 0, 0], "-x": [-1, 0, 0], "+y": [0, 1, 0], "-y": [0, -1, 0], "+z": [0, 0, 1], "-z": [0, 0, -1] };
const $ = (id) => document.getElementById(id);

const studio = window.__studio = { ready: false, errors: [], firstRenderMs: null, selectMs: [] };
const state = { scan: null, spec: null, doc: null, kind: "gage", selected: null, counts: [], align: null, run: null, applyT: false, inspection: null, cadKey: null };
let view;

// ------------------------------------------------------------------ helpers

const round = (v, d) => { const f = 10 ** d; return Math.round(v * f) / f; };
const fmt = (v, d = 4) => (v == null || Number.isNaN(v) ? "–" : Number(v).toFixed(d));
const angleFactor = () => (state.doc && state.doc.angle_unit === "deg" ? Math.PI / 180 : 1);
const isPart = () => state.kind === "part";
const features = () => (state.doc.feature = state.doc.feature || []);
const tolerances = () => (state.doc.tolerance = state.doc.tolerance || []);
// the boxes: a gage file's [[region]] tables, or a drawing's feature regions (inline
// tables of [[feature]], in the scan's frame) carrying their feature's name unseen by JSON
const FACE_BOXES = new WeakMap();
function regions() {
  if (!isPart()) return (state.doc.region = state.doc.region || []);
  return features().map((f) => {
    // a feature located by CAD faces has no box: a detached empty one keeps the indices in step
    const byFaces = Array.isArray(f.faces) && !f.region;
    if (byFaces && !FACE_BOXES.has(f)) FACE_BOXES.set(f, { center: [0, 0, 0], size: [0, 0, 0] });
    if (!byFaces && (!f.region || typeof f.region !== "object" || Array.isArray(f.region))) f.region = { center: [0, 0, 0], size: [1, 1, 1] };
    const box = byFaces ? FACE_BOXES.get(f) : f.region;
    Object.defineProperty(box, "name", { value: f.name, enumerable: false, configurable: true, writable: true });
    Object.defineProperty(box, "frame", { value: "scanner", enumerable: false, configurable: true, writable: true });
    return box;
  });
}
const gages = () => (state.doc.gage = state.doc.gage || []);
const VEC_KEYS = { outward: "fe-o", direction: "fe-d" };

function datumLetterOf(name) {
  const d = state.doc.datums || {};
  return Object.keys(d).find((k) => d[k] === name || (d[k] && d[k].feature === name)) || "";
}
const identity = () => [[1, 0, 0, 0], [0, 1, 0, 0], [0, 0, 1, 0], [0, 0, 0, 1]];
const mulPoint = (M, p) => [0, 1, 2].map((i) => M[i][0] * p[0] + M[i][1] * p[1] + M[i][2] * p[2] + M[i][3]);

function roleOf(name) {
  const al = state.doc.alignment || {};
  return ROLES.find((k) => Array.isArray(al[k]) && al[k].includes(name)) || "";
}

function regionInRad(r) {
  const f = angleFactor();
  return { center: r.center || [0, 0, 0], size: r.size || [1, 1, 1], rotation: (r.rotation || [0, 0, 0]).map((v) => v * f), frame: r.frame || "part" };
}

function nextFrame() { return new Promise((res) => requestAnimationFrame(() => requestAnimationFrame(res))); }

// ------------------------------------------------------------------ errors next to their tables

function showValidation(v) {
  document.querySelectorAll(".errors").forEach((el) => { el.textContent = ""; });
  const bad = new Set();
  const put = (e, warn) => {
    const el = document.querySelector(`.errors[data-table="${e.table}"]`) || document.querySelector('.errors[data-table="top"]');
    const line = document.createElement("div");
    if (warn) line.className = "warn";
    line.textContent = (warn ? "warning: " : "") + e.message;
    el.appendChild(line);
    if (e.table === "region" && e.name) bad.add(e.name);
    if (e.table === "region" && e.index) bad.add(regions()[e.index - 1] && regions()[e.index - 1].name);
  };
  (v && v.errors || []).forEach((e) => put(e, false));
  (v && v.warnings || []).forEach((e) => put(e, true));
  (v && v.errors || []).forEach((e) => { if (e.table === "feature" && e.index) bad.add(features()[e.index - 1] && features()[e.index - 1].name); });
  (v && v.errors || []).forEach((e) => { if (e.table === "tolerance" && e.index) { const t = tolerances()[e.index - 1]; if (t) bad.add(t.feature); } });
  state.counts.forEach((c) => { if (c && c.error) bad.add(c.name); });
  document.querySelectorAll("#regions tbody tr").forEach((tr) => tr.classList.toggle("bad", bad.has(tr.dataset.name)));
}

// ------------------------------------------------------------------ panel

function renderScan() {
  const s = state.scan;
  $("scan-info").textContent = `${s.name}: ${s.count.toLocaleString()} points (${s.lod_count.toLocaleString()} shown), read in ${s.load_seconds} s`;
}

function renderRegions() {
  const tb = $("regions").tBodies[0];
  tb.textContent = "";
  const heads = isPart() ? ["name", "shape", "datum", "points", "tolerances"] : ["name", "frame", "datum", "points", "gages"];
  $("regions").tHead.rows[0].querySelectorAll("th").forEach((th, k) => { th.textContent = heads[k]; });
  if (isPart()) {
    features().forEach((f, i) => {
      const tr = tb.insertRow();
      tr.dataset.name = f.name;
      tr.dataset.index = i;
      if (i === state.selected) tr.classList.add("sel");
      const c = state.counts[i], n = tolerances().filter((t) => t.feature === f.name).length;
      [f.name, f.shape || "–", datumLetterOf(f.name) || "–", c && c.count != null ? c.count.toLocaleString() : "–", n || "–"]
        .forEach((v, k) => { const td = tr.insertCell(); td.textContent = v; if (k >= 3) td.className = "num"; });
      tr.addEventListener("click", () => selectRegion(i));
    });
    return;
  }
  regions().forEach((r, i) => {
    const tr = tb.insertRow();
    tr.dataset.name = r.name;
    tr.dataset.index = i;
    if (i === state.selected) tr.classList.add("sel");
    const n = gages().filter((g) => g.region === r.name).length;
    const c = state.counts[i];
    [r.name, r.frame || "part", roleOf(r.name) || "–", c && c.count != null ? c.count.toLocaleString() : "–", n || "–"]
      .forEach((v, k) => { const td = tr.insertCell(); td.textContent = v; if (k >= 3) td.className = "num"; });
    tr.addEventListener("click", () => selectRegion(i));
  });
}

function renderEditor() {
  const i = state.selected, r = regions()[i];
  $("region-edit").hidden = r == null;
  if (r == null) return;
  $("re-title").textContent = r.name;
  $("re-name").value = r.name;
  $("re-frame").value = r.frame || "part";
  $("re-role").value = roleOf(r.name);
  $("re-unit").textContent = state.doc.angle_unit === "deg" ? "deg" : "rad";
  const rot = r.rotation || [0, 0, 0];
  ["x", "y", "z"].forEach((a, k) => {
    $(`re-c${a}`).value = r.center[k]; $(`re-s${a}`).value = r.size[k]; $(`re-r${a}`).value = rot[k];
  });
  if (isPart()) { renderFeature(); return; }
  renderGages();
}

// ------------------------------------------------------------------ drawing: feature and its tolerances

function renderFeature() {
  const f = features()[state.selected];
  if (!f) return;
  const shapes = state.inspection.shapes;
  $("fe-shape").innerHTML = shapes.map((s) => `<option>${s}</option>`).join("");
  $("fe-shape").value = f.shape || "plane";
  $("fe-kind").value = f.kind || "";
  Object.entries(VEC_KEYS).forEach(([key, id]) => {
    const v = Array.isArray(f[key]) ? f[key] : ["", "", ""];
    ["x", "y", "z"].forEach((a, k) => { $(`${id}${a}`).value = v[k]; });
  });
  $("fe-datum").value = datumLetterOf(f.name);
  renderTolerances();
}

function renderTolerances() {
  const box = $("tolerances");
  box.textContent = "";
  const f = features()[state.selected];
  if (!f) return;
  const applies = state.inspection.applies_to;
  const chars = Object.keys(applies).filter((c) => applies[c].includes(f.shape || "plane"));
  tolerances().forEach((t, ti) => {
    if (t.feature !== f.name) return;
    const card = document.createElement("div");
    card.className = "tol";
    card.dataset.characteristic = t.characteristic || "";
    const opts = [...new Set([t.characteristic, ...chars].filter(Boolean))];
    card.innerHTML = `
      <div class="head"><select class="t-char">${opts.map((c) => `<option>${c}</option>`).join("")}</select><button class="t-del danger" title="remove this tolerance">×</button></div>
      <div class="grid">
        <label>tolerance (mm)</label><input class="t-tol" type="number" step="any" min="0">
        <label title="datum letters of the feature control frame, in order of precedence">datums</label><input class="t-datums" type="text" placeholder="e.g. A, B, C">
        <label title="in the datum frame (position, profile)">nominal point</label><span class="xyz"><input class="t-px" type="number" step="any"><input class="t-py" type="number" step="any"><input class="t-pz" type="number" step="any"></span>
        <label title="in the datum frame (position, profile)">nominal direction</label><span class="xyz"><input class="t-dx" type="number" step="any"><input class="t-dy" type="number" step="any"><input class="t-dz" type="number" step="any"></span>
        <label title="angularity: basic angle to the datum (deg)">angle (deg)</label><input class="t-angle" type="number" step="any">
      </div>`;
    const q = (c) => card.querySelector(c);
    q(".t-char").value = t.characteristic || chars[0];
    if (!t.characteristic) t.characteristic = chars[0];
    q(".t-tol").value = t.tolerance != null ? t.tolerance : "";
    q(".t-datums").value = (t.datums || []).join(", ");
    const nom = t.nominal || {};
    ["x", "y", "z"].forEach((a, k) => {
      q(`.t-p${a}`).value = Array.isArray(nom.point) ? nom.point[k] : "";
      q(`.t-d${a}`).value = Array.isArray(nom.direction) ? nom.direction[k] : "";
    });
    q(".t-angle").value = t.angle != null ? t.angle : "";
    q(".t-char").addEventListener("change", () => { t.characteristic = q(".t-char").value; card.dataset.characteristic = t.characteristic; changed(false); });
    q(".t-tol").addEventListener("input", () => { const v = parseFloat(q(".t-tol").value); if (!Number.isNaN(v)) { t.tolerance = v; changed(false); } });
    q(".t-datums").addEventListener("change", () => {
      const d = q(".t-datums").value.split(/[\s,|]+/).map((x) => x.trim()).filter(Boolean);
      if (d.length) t.datums = d; else delete t.datums;
      changed(false);
    });
    const readNominal = () => {
      const get = (p) => ["x", "y", "z"].map((a) => parseFloat(q(`.t-${p}${a}`).value));
      const p = get("p"), d = get("d"), n = {};
      if (p.every((v) => !Number.isNaN(v))) n.point = p;
      if (d.every((v) => !Number.isNaN(v))) n.direction = d;
      if (Object.keys(n).length) t.nominal = n; else delete t.nominal;
      changed(false);
    };
    ["x", "y", "z"].forEach((a) => { q(`.t-p${a}`).addEventListener("change", readNominal); q(`.t-d${a}`).addEventListener("change", readNominal); });
    q(".t-angle").addEventListener("change", () => { const v = parseFloat(q(".t-angle").value); if (Number.isNaN(v)) delete t.angle; else t.angle = v; changed(false); });
    q(".t-del").addEventListener("click", () => { tolerances().splice(ti, 1); if (!tolerances().length) delete state.doc.tolerance; renderTolerances(); changed(true); });
    box.appendChild(card);
  });
}

function bindFeature() {
  const f = () => features()[state.selected];
  $("fe-shape").addEventListener("change", () => {
    const x = f(); if (!x) return;
    x.shape = $("fe-shape").value;
    if (!["plane", "line"].includes(x.shape)) delete x.outward;
    else if (!x.outward) x.outward = [0, 0, 1];
    if (!["cylinder", "circle", "sphere", "cone"].includes(x.shape)) delete x.kind;
    if (!["cylinder", "cone", "circle", "line"].includes(x.shape)) delete x.direction;
    renderFeature(); changed(true);
  });
  $("fe-kind").addEventListener("change", () => { const x = f(); if (!x) return; if ($("fe-kind").value) x.kind = $("fe-kind").value; else delete x.kind; changed(true); });
  Object.entries(VEC_KEYS).forEach(([key, id]) => ["x", "y", "z"].forEach((a) => $(`${id}${a}`).addEventListener("change", () => {
    const x = f(); if (!x) return;
    const v = ["x", "y", "z"].map((b) => parseFloat($(`${id}${b}`).value));
    if (v.every((c) => !Number.isNaN(c))) x[key] = v; else if (v.every(Number.isNaN)) delete x[key];
    changed(false);
  })));
  $("fe-datum").addEventListener("change", () => {
    const x = f(); if (!x) return;
    const letter = $("fe-datum").value.trim();
    const d = state.doc.datums = state.doc.datums || {};
    const old = datumLetterOf(x.name);
    let entry = x.name;
    if (old) { entry = d[old]; delete d[old]; }
    if (letter) d[letter] = entry;
    if (!Object.keys(d).length) delete state.doc.datums;
    changed(true);
  });
  $("tol-add").addEventListener("click", () => {
    const x = f(); if (!x) return;
    const applies = state.inspection.applies_to;
    const c = Object.keys(applies).find((k) => applies[k].includes(x.shape || "plane"));
    tolerances().push({ feature: x.name, characteristic: c, tolerance: 0.1 });
    renderTolerances(); changed(true);
  });
}

function renderGages() {
  const box = $("gages");
  box.textContent = "";
  const r = regions()[state.selected];
  if (!r) return;
  gages().forEach((g, gi) => {
    if (g.region !== r.name) return;
    const card = document.createElement("div");
    card.className = "gage";
    card.dataset.gage = g.name;
    const plane = Array.isArray(g.plane) && g.plane.length === 4 ? g.plane : [0, 0, 1, 0];
    const preset = Object.keys(NORMALS).find((k) => NORMALS[k].every((v, j) => v === plane[j])) || "";
    card.innerHTML = `
      <div class="head"><input class="g-name" type="text"><button class="g-del danger" title="remove this gage">×</button></div>
      <div class="grid">
        <label>normal (material side)</label>
        <span class="xyz"><select class="g-preset"><option value="">custom</option>${Object.keys(NORMALS).map((k) => `<option>${k}</option>`).join("")}</select>
          <input class="g-a" type="number" step="any"><input class="g-b" type="number" step="any"><input class="g-c" type="number" step="any"></span>
        <label>face position (mm)</label><input class="g-pos" type="number" step="any" title="n·x of the gage plane">
        <label>allowance ε (mm)</label><input class="g-eps" type="number" step="any" value="0" title="stock required beyond the face (Eq. 5.3); the gage is n·x ≥ position + ε">
        <label>weights f, g</label><span class="xyz"><input class="g-w" type="number" step="any" min="0"><input class="g-sw" type="number" step="any" min="0"></span>
      </div>`;
    const q = (c) => card.querySelector(c);
    q(".g-name").value = g.name;
    q(".g-preset").value = preset;
    q(".g-a").value = plane[0]; q(".g-b").value = plane[1]; q(".g-c").value = plane[2];
    q(".g-pos").value = -plane[3];
    q(".g-w").value = g.weight != null ? g.weight : 1;
    q(".g-sw").value = g.slack_weight != null ? g.slack_weight : 10;
    const writePlane = () => {
      const a = parseFloat(q(".g-a").value), b = parseFloat(q(".g-b").value), c = parseFloat(q(".g-c").value);
      const pos = parseFloat(q(".g-pos").value), eps = parseFloat(q(".g-eps").value) || 0;
      if ([a, b, c, pos].some(Number.isNaN)) return;
      g.plane = [a, b, c, round(-(pos + eps), 9)];
      changed(false);
    };
    q(".g-preset").addEventListener("change", () => {
      const n = NORMALS[q(".g-preset").value];
      if (!n) return;
      q(".g-a").value = n[0]; q(".g-b").value = n[1]; q(".g-c").value = n[2];
      writePlane();
    });
    ["g-a", "g-b", "g-c", "g-pos", "g-eps"].forEach((c) => q("." + c).addEventListener("input", writePlane));
    q(".g-name").addEventListener("input", () => { if (q(".g-name").value) { g.name = q(".g-name").value; changed(false); } });
    q(".g-w").addEventListener("input", () => { const v = parseFloat(q(".g-w").value); if (!Number.isNaN(v)) { g.weight = v; changed(false); } });
    q(".g-sw").addEventListener("input", () => { const v = parseFloat(q(".g-sw").value); if (!Number.isNaN(v)) { g.slack_weight = v; changed(false); } });
    q(".g-del").addEventListener("click", () => { gages().splice(gi, 1); changed(true); renderGages(); });
    box.appendChild(card);
  });
}

function renderMotion() {
  const m = state.doc.motion || {};
  const free = Array.isArray(m.free) ? m.free : MOTIONS;
  const box = $("free");
  box.textContent = "";
  MOTIONS.forEach((k) => {
    const l = document.createElement("label");
    l.title = MOTION_HELP[k];
    l.innerHTML = `<input type="checkbox" value="${k}"> ${k}`;
    l.firstChild.checked = free.includes(k);
    l.firstChild.addEventListener("change", () => {
      const mo = state.doc.motion = state.doc.motion || {};
      mo.free = MOTIONS.filter((x) => box.querySelector(`input[value="${x}"]`).checked);
      changed(false);
    });
    box.appendChild(l);
  });
  $("mo-unit").textContent = state.doc.angle_unit === "deg" ? "deg" : "rad";
  $("mo-angle").value = m.max_angle != null ? m.max_angle : round(0.05 / angleFactor(), 9);
  $("mo-shift").value = m.max_shift != null ? m.max_shift : 20;
}

function renderAll() { renderRegions(); renderEditor(); renderMotion(); }

// ------------------------------------------------------------------ document changes

let regionsTimer = null, regionsSeq = 0;

function changed(structural) {
  state.run = null;
  $("run-status").textContent = "";
  if (structural) { renderRegions(); view.setBoxes(regions().map(regionInRad), state.selected); }
  clearTimeout(regionsTimer);
  regionsTimer = setTimeout(refreshRegions, 150);
}

async function refreshRegions() {
  const seq = ++regionsSeq;
  try {
    const res = await api.post("/api/regions", { doc: state.doc });
    if (seq !== regionsSeq) return;
    state.counts = res.regions;
    state.align = res.alignment;
    if (!state.applyT) view.setFrame(state.align ? state.align.H : identity());
    renderRegions();
    showValidation(res.validation);
    if (res.alignment_error) {
      const el = document.querySelector('.errors[data-table="alignment"]');
      if (!el.textContent) el.textContent = "alignment: " + res.alignment_error;
    }
  } catch (e) { report(e); }
}

function report(e) {
  if (e instanceof api.ApiError && e.errors.length) showValidation({ errors: e.errors, warnings: e.warnings });
  else { document.querySelector('.errors[data-table="top"]').textContent = e.message; }
}

// ------------------------------------------------------------------ selection and live recount

let selecting = false, selectAgain = false, selectWaiters = [];

async function recount() {
  if (state.selected == null) { view.highlight(null); return; }
  if (selecting) { selectAgain = true; return; }
  selecting = true;
  const r = regions()[state.selected];
  const t0 = performance.now();
  try {
    const res = await api.post("/api/select", { region: regionInRad(r) });
    studio.selectMs.push(performance.now() - t0);
    $("re-count").textContent = res.count.toLocaleString();
    $("status").textContent = `${r.name}: ${res.count.toLocaleString()} points inside (${res.lod_count.toLocaleString()} shown)`;
    view.highlight(res.indices ? { indices: api.uint32s(res.indices) } : { mask: api.bytes(res.mask) });
    studio.lastCount = res.count;
  } catch (e) {
    $("re-count").textContent = "–";
    $("status").textContent = e.message;
  } finally {
    selecting = false;
    if (selectAgain) { selectAgain = false; recount(); } else { selectWaiters.splice(0).forEach((f) => f()); }
  }
}

function selectRegion(i) {
  state.selected = i;
  view.select(i);
  renderRegions();
  renderEditor();
  recount();
}

function onBoxChanged(i, final) {
  const r = regions()[i], b = view.readBox(i), f = angleFactor();
  r.center = b.center.map((v) => round(v, 4));
  r.size = b.size.map((v) => round(v, 4));
  const rot = b.rotation.map((v) => round(v / f, 6));
  if (r.rotation || rot.some((v) => v !== 0)) r.rotation = rot;
  if (i === state.selected) renderEditor();
  recount();
  if (final) changed(false);
}

function uniqueName(base) {
  const names = new Set(regions().map((r) => r.name));
  let k = 1;
  while (names.has(`${base}${k}`)) k++;
  return `${base}${k}`;
}

function addBoxAt(scannerPoint) {
  const H = state.align ? state.align.H : identity();
  const centre = mulPoint(H, scannerPoint).map((v) => round(v, 3));
  const s = round(Math.max(view.diagonal * 0.05, 1e-3), 1) || 1;
  if (isPart()) { // a new feature: a plane until told otherwise, its region in the scan's frame
    features().push({ name: uniqueName("F"), shape: "plane", outward: [0, 0, 1], region: { center: scannerPoint.map((v) => round(v, 3)), size: [s, s, s] } });
  } else {
    regions().push({ name: uniqueName("box"), frame: "part", center: centre, size: [s, s, s] });
  }
  state.selected = regions().length - 1;
  changed(true);
  renderEditor();
  recount();
  setAdding(false);
}

function setAdding(on) {
  view.adding = on;
  $("add-box").classList.toggle("on", on);
  $("view").classList.toggle("adding", on);
  if (on) $("status").textContent = "click on the scan where the box goes (Esc to cancel)";
}

// ------------------------------------------------------------------ editor inputs

function bindEditor() {
  const num = (id) => parseFloat($(id).value);
  const fromInputs = () => {
    const r = regions()[state.selected];
    if (!r) return;
    const c = ["x", "y", "z"].map((a) => num(`re-c${a}`)), s = ["x", "y", "z"].map((a) => num(`re-s${a}`));
    const rot = ["x", "y", "z"].map((a) => num(`re-r${a}`));
    if (c.some(Number.isNaN) || s.some(Number.isNaN) || rot.some(Number.isNaN)) return;
    r.center = c; r.size = s;
    if (r.rotation || rot.some((v) => v !== 0)) r.rotation = rot;
    changed(false);
    if (s.some((v) => !(v > 0))) { $("re-count").textContent = "–"; return; } // the reader's message shows
    view.updateBox(state.selected, regionInRad(r));
    recount();
  };
  ["c", "s", "r"].forEach((k) => ["x", "y", "z"].forEach((a) => $(`re-${k}${a}`).addEventListener("input", fromInputs)));
  $("re-name").addEventListener("change", () => {
    const r = regions()[state.selected], name = $("re-name").value.trim();
    if (!r || !name || name === r.name) return;
    if (isPart()) {
      const fe = features()[state.selected], d = state.doc.datums || {};
      tolerances().forEach((t) => { if (t.feature === fe.name) t.feature = name; });
      Object.keys(d).forEach((k) => { if (d[k] === fe.name) d[k] = name; else if (d[k] && d[k].feature === fe.name) d[k].feature = name; });
      fe.name = name;
      $("re-title").textContent = name;
      changed(true);
      return;
    }
    gages().forEach((g) => { if (g.region === r.name) g.region = name; });
    const al = state.doc.alignment || {};
    ROLES.forEach((k) => { if (Array.isArray(al[k])) al[k] = al[k].map((n) => (n === r.name ? name : n)); });
    r.name = name;
    $("re-title").textContent = name;
    changed(true);
  });
  $("re-frame").addEventListener("change", () => {
    const r = regions()[state.selected];
    r.frame = $("re-frame").value;
    changed(true);
    recount();
  });
  $("re-role").addEventListener("change", () => {
    const r = regions()[state.selected], role = $("re-role").value;
    const al = state.doc.alignment = state.doc.alignment || {};
    ROLES.forEach((k) => { if (Array.isArray(al[k])) al[k] = al[k].filter((n) => n !== r.name); });
    if (role) { al[role] = [...(al[role] || []), r.name]; r.frame = "scanner"; }
    ROLES.forEach((k) => { if (Array.isArray(al[k]) && !al[k].length) delete al[k]; });
    if (!Object.keys(al).length) delete state.doc.alignment;
    renderEditor();
    changed(true);
  });
  $("re-delete").addEventListener("click", () => {
    const r = regions()[state.selected];
    if (!r) return;
    if (isPart()) {
      const fe = features()[state.selected], d = state.doc.datums || {};
      features().splice(state.selected, 1);
      state.doc.tolerance = tolerances().filter((t) => t.feature !== fe.name);
      if (!state.doc.tolerance.length) delete state.doc.tolerance;
      Object.keys(d).forEach((k) => { if (d[k] === fe.name || (d[k] && d[k].feature === fe.name)) delete d[k]; });
      if (state.doc.datums && !Object.keys(d).length) delete state.doc.datums;
      state.selected = null; view.select(null); renderEditor(); changed(true); view.highlight(null);
      return;
    }
    regions().splice(state.selected, 1);
    state.doc.gage = gages().filter((g) => g.region !== r.name);
    const al = state.doc.alignment;
    if (al) { ROLES.forEach((k) => { if (Array.isArray(al[k])) al[k] = al[k].filter((n) => n !== r.name); if (al[k] && !al[k].length) delete al[k]; }); if (!Object.keys(al).length) delete state.doc.alignment; }
    state.selected = null;
    view.select(null);
    renderEditor();
    changed(true);
    view.highlight(null);
  });
  $("gage-add").addEventListener("click", () => {
    const r = regions()[state.selected];
    if (!r) return;
    const names = new Set(gages().map((g) => g.name));
    let k = 1;
    while (names.has(`${r.name} gage ${k}`)) k++;
    gages().push({ name: `${r.name} gage ${k}`, region: r.name, plane: [0, 0, 1, 0], weight: 1, slack_weight: 10 });
    renderGages();
    changed(true);
  });
  const motion = () => (state.doc.motion = state.doc.motion || {});
  $("mo-angle").addEventListener("input", () => { const v = num("mo-angle"); if (!Number.isNaN(v)) { motion().max_angle = v; changed(false); } });
  $("mo-shift").addEventListener("input", () => { const v = num("mo-shift"); if (!Number.isNaN(v)) { motion().max_shift = v; changed(false); } });
}

// ------------------------------------------------------------------ run and save

async function run() {
  $("run").disabled = true;
  $("run-status").textContent = "running…";
  const t0 = performance.now();
  try {
    const res = await api.post("/api/run", { doc: state.doc });
    state.run = res;
    const r = res.result;
    if (res.kind === "part") { showInspection(res); await showInspectionCad(res); studio.lastRunMs = performance.now() - t0; return; }
    $("run-status").textContent = `${r.status} (${res.seconds} s on ${state.scan.count.toLocaleString()} points)`;
    const tb = $("results").tBodies[0];
    tb.textContent = "";
    r.gages.forEach((g) => {
      const tr = tb.insertRow();
      tr.dataset.gage = g.name;
      const cells = [[g.name, "name"], [g.region, "region"], [g.points, "num points"], [g.filtered_points, "num hull"],
        [fmt(g.allowance_before), "num allow-before"], [fmt(g.allowance_after), "num allow-after"], [fmt(g.q), "num q"], [fmt(g.slack), "num slack"]];
      cells.forEach(([v, cls]) => { const td = tr.insertCell(); td.textContent = v; td.className = cls; });
      if (g.allowance_after < 0) tr.cells[5].classList.add("neg");
    });
    const t = r.transform;
    $("tstar").textContent = `T*: α ${fmt(t.alpha, 6)}  β ${fmt(t.beta, 6)}  γ ${fmt(t.gamma, 6)} rad;  Δx ${fmt(t.dx)}  Δy ${fmt(t.dy)}  Δz ${fmt(t.dz)} mm` +
      (r.infeasible_groups.length ? `\ninfeasible groups: ${r.infeasible_groups.map((g) => g.join(" + ")).join("; ")}` : "") +
      (r.limited_by_motion_bounds ? `\nlimited by the motion bounds: ${r.bound_limits.map((b) => b.motion + " " + b.side).join(", ")}` : "");
    showValidation(res.validation);
    showColours(res);
    $("apply-t").disabled = false;
    setApplyT($("apply-t").checked);
    studio.lastRunMs = performance.now() - t0;
  } catch (e) {
    $("run-status").textContent = "failed";
    report(e);
  } finally {
    $("run").disabled = false;
  }
}

function showColours(res) {
  const values = api.floats(res.values);
  if (res.value_range) {
    view.colourBy(values, res.value_range[0], res.value_range[1]);
    $("legend").hidden = false;
    $("legend-min").textContent = fmt(res.value_range[0], 3);
    $("legend-max").textContent = fmt(res.value_range[1], 3);
  }
}

function showInspection(res) {
  const r = res.result, tols = r.tolerances;
  $("run-status").textContent = `${r.status}: ${tols.filter((t) => t.pass).length}/${tols.length} callouts pass (${res.seconds} s on ${state.scan.count.toLocaleString()} points)`;
  const tb = $("callouts").tBodies[0];
  tb.textContent = "";
  tols.forEach((t) => {
    const tr = tb.insertRow();
    tr.dataset.feature = t.feature;
    tr.dataset.characteristic = t.characteristic;
    const cells = [[t.feature, "feature"], [t.characteristic + (t.zone === "diameter" ? " ⌀" : ""), "characteristic"],
      [(t.datums || []).join("|") || "–", "datums"], [fmt(t.tolerance), "num tolerance"], [fmt(t.measured), "num measured"],
      [fmt(t.margin), "num margin"], [t.pass ? "pass" : "FAIL", t.pass ? "pass" : "fail"]];
    cells.forEach(([v, cls]) => { const td = tr.insertCell(); td.textContent = v; td.className = cls; });
  });
  showValidation(res.validation);
  $("legend-caption").textContent = "deviation from the feature's least-squares fit (mm)";
  showColours(res);
}

async function showInspectionCad(res) {
  if (!res.cad) return;
  if (res.cad.key !== state.cadKey) await drawCad(res.cad.info);
  showCadColours(res.cad);
}

// ------------------------------------------------------------------ the CAD model beside the scan

function cadError(message) {
  const el = document.querySelector('.errors[data-table="cad"]');
  el.textContent = message || "";
}

async function drawCad(info) {
  const mesh = await api.cadMesh();
  view.setCad(mesh.xyz, mesh.tris, mesh.origin);
  view.showCad($("cad-show").checked);
  state.cadKey = mesh.key;
  studio.cad = { key: mesh.key, vertices: mesh.xyz.length / 3, triangles: mesh.tris.length / 3, coloured: false };
  $("cad-legend").hidden = true;
  if (info) {
    $("cad-info").textContent = `${info.name}: ${info.faces} faces, ${info.triangles.toLocaleString()} triangles` +
      (info.decimated ? ` (${info.shown_triangles.toLocaleString()} shown, decimated above ${info.max_triangles.toLocaleString()})` : "") +
      (info.signed ? "" : "; open mesh: unsigned distances") + "; coloured after Run";
    const opt = [...$("cad-file").options].find((o) => o.value === info.name);
    if (!opt) $("cad-file").add(new Option(info.name, info.name));
    $("cad-file").value = info.name;
  }
}

async function openCad(path) {
  cadError("");
  $("cad-info").textContent = "reading the CAD model…";
  try {
    const info = await api.post("/api/cad", path ? { path } : {});
    await drawCad(info);
  } catch (e) {
    $("cad-info").textContent = "";
    cadError(e.message);
    studio.cadError = e.message;
  }
}

function showCadColours(cad) {
  view.colourCad(api.bytes(cad.colours));
  const bar = document.querySelector("#cad-legend .bar");
  bar.style.background = `linear-gradient(to right, ${cad.stops.join(", ")})`;
  $("cad-legend-min").textContent = fmt(-cad.limit, 3);
  $("cad-legend-max").textContent = fmt(cad.limit, 3);
  $("cad-legend").hidden = !$("cad-show").checked;
  studio.cad.coloured = true;
  studio.cad.limit = cad.limit;
}

async function startCad(st) {
  const files = await api.get("/api/files");
  (files.cads || []).forEach((f) => $("cad-file").add(new Option(f, f)));
  $("cad-file").addEventListener("change", async () => {
    const v = $("cad-file").value;
    if (!v) {
      await api.post("/api/cad", { close: true });
      view.clearCad(); state.cadKey = null; studio.cad = null;
      $("cad-info").textContent = ""; $("cad-legend").hidden = true; cadError("");
      return;
    }
    await openCad(v);
  });
  $("cad-show").addEventListener("change", () => {
    view.showCad($("cad-show").checked);
    $("cad-legend").hidden = !$("cad-show").checked || !(studio.cad && studio.cad.coloured);
  });
  const cad = st.cad || {};
  if (cad.drawing_error) cadError(cad.drawing_error);
  if (cad.open) await drawCad(cad.open);
  else if (cad.drawing) await openCad(null);
}

function setApplyT(on) {
  state.applyT = on && !!state.run;
  view.setFrame(state.applyT ? state.run.view_matrix : (state.align ? state.align.H : identity()));
}

async function save() {
  const path = $("save-path").value.trim();
  $("save-status").className = "";
  try {
    const res = await api.post("/api/save", { doc: state.doc, path: path || null });
    const note = res.validation.valid ? "" : " (gage check will reject it until the errors above are fixed)";
    $("save-status").textContent = `saved ${res.name}, ${res.bytes} bytes${res.unchanged ? ", unchanged" : ""}${note}`;
    $("save-status").className = res.validation.valid ? "ok" : "";
    showValidation(res.validation);
    state.spec.path = res.path;
  } catch (e) {
    $("save-status").textContent = "not saved: " + e.message;
  }
}

// ------------------------------------------------------------------ start

function bindToolbar() {
  document.querySelectorAll("[data-view]").forEach((b) => b.addEventListener("click", () => view.viewAlong(b.dataset.view)));
  document.querySelectorAll("[data-mode]").forEach((b) => b.addEventListener("click", () => {
    document.querySelectorAll("[data-mode]").forEach((x) => x.classList.toggle("on", x === b));
    view.setMode(b.dataset.mode);
  }));
  $("add-box").addEventListener("click", () => setAdding(!view.adding));
  $("add-box-2").addEventListener("click", () => {
    addBoxAt(view.targetInScanner());
  });
  $("apply-t").addEventListener("change", () => setApplyT($("apply-t").checked));
  $("run").addEventListener("click", run);
  $("save").addEventListener("click", save);
  window.addEventListener("keydown", (ev) => {
    if (ev.target.tagName === "INPUT" || ev.target.tagName === "SELECT") return;
    const modes = { w: "translate", e: "rotate", r: "scale" };
    if (modes[ev.key]) document.querySelector(`[data-mode="${modes[ev.key]}"]`).click();
    if (ev.key === "Escape") setAdding(false);
  });
}

async function start() {
  window.addEventListener("error", (e) => studio.errors.push(String(e.message)));
  const st = await api.get("/api/state");
  state.scan = st.scan;
  state.spec = st.spec;
  state.kind = st.spec.kind || "gage";
  state.inspection = st.inspection;
  state.doc = st.spec.doc || (isPart() ? { part: { name: "part" } } : { length_unit: "mm" });
  document.body.classList.toggle("part-mode", isPart());
  if (isPart()) {
    $("run-title").textContent = "Inspection";
    $("file-title").textContent = "Drawing (PART.toml)";
    $("add-box").title = "Then click on the scan where the feature's region goes";
  }
  view = new View($("view"), { boxChanged: onBoxChanged, boxPicked: selectRegion, pointPicked: addBoxAt,
    missed: () => { $("status").textContent = "no scan point there: click on the points (Esc to cancel)"; } });
  studio.view = view;
  bindToolbar();
  bindEditor();
  bindFeature();
  renderScan();
  const xyz = await api.points();
  view.setPoints(xyz, state.scan.origin, state.scan.bbox);
  view.render();
  await nextFrame();
  studio.firstRenderMs = performance.now();
  view.setBoxes(regions().map(regionInRad), null);
  renderAll();
  showValidation(st.spec.validation);
  if (st.spec.parse_error) document.querySelector('.errors[data-table="top"]').textContent = st.spec.parse_error;
  $("save-path").placeholder = st.spec.path ? st.spec.name : (isPart() ? "part.toml" : "gages.toml");
  await refreshRegions();
  view.viewAlong("iso");
  studio.ready = true;
  if (isPart()) { // the CAD model may take seconds to read (a STEP model's tessellation): after the scan
    studio.cadStarted = true;
    await startCad(st);
    studio.cadSettled = true;
  }
}

// for tests and benchmarks: move box i to a centre and wait for its recount
studio.moveBox = (i, centre) => new Promise((resolve) => {
  selectWaiters.push(() => resolve(studio.lastCount));
  if (state.selected !== i) selectRegion(i);
  const r = regions()[i];
  r.center = centre;
  view.updateBox(i, regionInRad(r));
  recount();
});
studio.state = state;

start().catch((e) => { studio.errors.push(String(e.message || e)); document.querySelector('.errors[data-table="top"]').textContent = String(e.message || e); });
