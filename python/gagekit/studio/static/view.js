// The 3-D view: the scan's displayed points, the region boxes, orbit and box handles.
// Display only: every count and every check is computed on the server.
import * as THREE from "./vendor/three/build/three.module.js";
import { OrbitControls } from "./vendor/three/examples/jsm/controls/OrbitControls.js";
import { TransformControls } from "./vendor/three/examples/jsm/controls/TransformControls.js";

const BOX_COLOURS = { part: 0x4aa3ff, scanner: 0xffb347 };

export class View {
  constructor(container, events) {
    this.container = container;
    this.events = events; // {boxChanged(idx, final), boxPicked(idx), pointPicked(scannerPoint)}
    this.renderer = new THREE.WebGLRenderer({ antialias: false, preserveDrawingBuffer: true });
    this.renderer.setPixelRatio(window.devicePixelRatio || 1);
    container.prepend(this.renderer.domElement);
    this.scene = new THREE.Scene();
    this.scene.background = new THREE.Color(0x20262e);
    this.camera = new THREE.PerspectiveCamera(40, 1, 0.1, 1e6);
    this.camera.up.set(0, 0, 1);
    // scanner frame: the points and the scanner-frame boxes; its matrix is H or T* H
    this.scanGroup = new THREE.Group();
    this.scanGroup.matrixAutoUpdate = false;
    this.partGroup = new THREE.Group();
    this.scene.add(this.scanGroup, this.partGroup);
    this.scene.add(new THREE.AmbientLight(0xffffff, 1));
    // the CAD model (in part mode the scan's frame is the CAD's): lit from the camera
    this.cadGroup = new THREE.Group();
    this.scanGroup.add(this.cadGroup);
    this.cadLight = new THREE.DirectionalLight(0xffffff, 0.55);
    this.camera.add(this.cadLight);
    this.scene.add(this.camera);
    this.cad = null;
    this.orbit = new OrbitControls(this.camera, this.renderer.domElement);
    this.orbit.screenSpacePanning = true;
    this.orbit.addEventListener("change", () => this.requestRender());
    this.handles = new TransformControls(this.camera, this.renderer.domElement);
    this.handles.setSpace("local");
    this.handles.addEventListener("change", () => this.requestRender());
    this.handles.addEventListener("dragging-changed", (e) => {
      this.orbit.enabled = !e.value;
      if (!e.value && this.handles.object) this.events.boxChanged(this.handles.object.userData.index, true);
    });
    this.handles.addEventListener("objectChange", () => {
      const o = this.handles.object;
      if (o) {
        o.scale.set(Math.max(Math.abs(o.scale.x), 1e-3), Math.max(Math.abs(o.scale.y), 1e-3), Math.max(Math.abs(o.scale.z), 1e-3));
        this.events.boxChanged(o.userData.index, false);
      }
    });
    this.scene.add(this.handles);
    this.boxes = [];
    this.points = null;
    this.baseColours = null;
    this.adding = false;
    this.raycaster = new THREE.Raycaster();
    this._bindPointer();
    new ResizeObserver(() => this.resize()).observe(container);
    this.resize();
  }

  resize() {
    const w = this.container.clientWidth, h = this.container.clientHeight;
    if (!w || !h) return;
    this.renderer.setSize(w, h, false);
    this.camera.aspect = w / h;
    this.camera.updateProjectionMatrix();
    this.requestRender();
  }

  requestRender() {
    if (this._pending) return;
    this._pending = true;
    requestAnimationFrame(() => { this._pending = false; this.render(); });
  }

  render() { this.renderer.render(this.scene, this.camera); }

  // ------------------------------------------------------------------ points

  setPoints(xyz, origin, bbox) {
    if (this.points) { this.scanGroup.remove(this.points); this.points.geometry.dispose(); }
    const n = xyz.length / 3;
    const geom = new THREE.BufferGeometry();
    geom.setAttribute("position", new THREE.BufferAttribute(xyz, 3));
    const colours = new Uint8Array(3 * n);
    // shade by height (z of the scanner frame) for depth
    const zmin = bbox.min[2] - origin[2], span = Math.max(bbox.max[2] - bbox.min[2], 1e-9);
    for (let i = 0; i < n; i++) {
      const t = (xyz[3 * i + 2] - zmin) / span;
      colours[3 * i] = 85 + 110 * t; colours[3 * i + 1] = 95 + 110 * t; colours[3 * i + 2] = 110 + 110 * t;
    }
    this.baseColours = colours.slice();
    this.lit = null; this.litAll = false;
    geom.setAttribute("color", new THREE.BufferAttribute(colours, 3, true));
    geom.computeBoundingSphere();
    const mat = new THREE.PointsMaterial({ size: 2, sizeAttenuation: false, vertexColors: THREE.VertexColors });
    this.points = new THREE.Points(geom, mat);
    this.points.position.set(origin[0], origin[1], origin[2]);
    this.scanGroup.add(this.points);
    this.bbox = bbox;
    const d = new THREE.Vector3(...bbox.max).sub(new THREE.Vector3(...bbox.min)).length();
    this.diagonal = Math.max(d, 1e-6);
    this.raycaster.params.Points.threshold = this.diagonal * 0.004;
    this.camera.near = this.diagonal / 1000; this.camera.far = this.diagonal * 100;
    this.viewAlong("iso");
  }

  // sel: {indices: Uint32Array of displayed points} (the work grows with the box, not the
  // scan: only the points lit before and now are touched), {mask: Uint8Array of packed
  // bits, little-endian, one per displayed point}, or null (none)
  highlight(sel) {
    if (!this.points) return;
    const attr = this.points.geometry.getAttribute("color");
    const c = attr.array, base = this.valueColours || this.baseColours, n = c.length / 3;
    const lit = (i) => { c[3 * i] = 255; c[3 * i + 1] = 120; c[3 * i + 2] = 20; };
    if (this.lit && !this.litAll) {
      for (const i of this.lit) { c[3 * i] = base[3 * i]; c[3 * i + 1] = base[3 * i + 1]; c[3 * i + 2] = base[3 * i + 2]; }
    } else {
      c.set(base);
    }
    this.lit = null; this.litAll = false;
    if (sel && sel.indices) {
      for (const i of sel.indices) lit(i);
      this.lit = sel.indices;
    } else if (sel && sel.mask) {
      const mask = sel.mask;
      for (let i = 0; i < n; i++) if (mask[i >> 3] & (1 << (i & 7))) lit(i);
      this.lit = []; this.litAll = true;
    }
    attr.needsUpdate = true;
    this.requestRender();
  }

  // values: Float32Array per displayed point (NaN: in no gage region); null clears
  colourBy(values, lo, hi) {
    this.lit = null; this.litAll = false; // the base colours change: the next highlight redraws all
    if (!values) { this.valueColours = null; this.highlight(null); return; }
    const n = values.length, c = this.baseColours.slice();
    const neg = Math.min(lo, -1e-9), pos = Math.max(hi, 1e-9);
    for (let i = 0; i < n; i++) {
      const v = values[i];
      if (Number.isNaN(v)) continue;
      let r, g, b;
      if (v < 0) { const t = Math.min(v / neg, 1); r = 242 - 50 * t; g = 211 - 171 * t; b = 107 - 62 * t; }
      else {
        const t = Math.min(v / pos, 1);
        if (t < 0.5) { const s = t / 0.5; r = 242 - 195 * s; g = 211 - 68 * s; b = 107 - 29 * s; }
        else { const s = (t - 0.5) / 0.5; r = 47; g = 143 - 32 * s; b = 78 + 101 * s; }
      }
      c[3 * i] = r; c[3 * i + 1] = g; c[3 * i + 2] = b;
    }
    this.valueColours = c;
    this.highlight(null);
  }

  // ------------------------------------------------------------------ CAD model

  // xyz: Float32Array of vertices minus origin, tris: Uint32Array of corners (mm, CAD frame)
  setCad(xyz, tris, origin) {
    this.clearCad();
    const geom = new THREE.BufferGeometry();
    geom.setAttribute("position", new THREE.BufferAttribute(xyz, 3));
    geom.setIndex(new THREE.BufferAttribute(tris, 1));
    const n = xyz.length / 3, grey = new Uint8Array(3 * n).fill(185);
    geom.setAttribute("color", new THREE.BufferAttribute(grey, 3, true));
    geom.computeVertexNormals();
    geom.computeBoundingSphere();
    // behind the points lying on it (polygon offset), both sides lit, ambient + camera light
    const mat = new THREE.MeshPhongMaterial({ vertexColors: THREE.VertexColors, color: 0xa0a0a0, side: THREE.DoubleSide, shininess: 10,
      polygonOffset: true, polygonOffsetFactor: 1, polygonOffsetUnits: 1, transparent: true, opacity: 0.9 });
    this.cad = new THREE.Mesh(geom, mat);
    this.cad.position.set(origin[0], origin[1], origin[2]);
    this.cad.name = "cad";
    this.cadGroup.add(this.cad);
    if (!this.points) { // no scan drawn yet: frame the model
      const b = new THREE.Box3().setFromObject(this.cad);
      this.bbox = { min: b.min.toArray(), max: b.max.toArray() };
      this.diagonal = Math.max(b.max.clone().sub(b.min).length(), 1e-6);
    }
    this.requestRender();
  }

  clearCad() {
    if (!this.cad) return;
    this.cadGroup.remove(this.cad);
    this.cad.geometry.dispose();
    this.cad.material.dispose();
    this.cad = null;
    this.requestRender();
  }

  // rgb: Uint8Array, 3 per vertex (null: plain grey)
  colourCad(rgb) {
    if (!this.cad) return;
    const attr = this.cad.geometry.getAttribute("color");
    if (rgb && rgb.length === attr.array.length) attr.array.set(rgb); else attr.array.fill(185);
    attr.needsUpdate = true;
    this.requestRender();
  }

  showCad(on) { this.cadGroup.visible = on; this.requestRender(); }

  setFrame(matrix) { // 4x4 row-major, scanner -> view (H, or T* H)
    const m = new THREE.Matrix4();
    m.set(...matrix.flat());
    this.scanGroup.matrix.copy(m);
    this.scanGroup.matrixWorldNeedsUpdate = true;
    this.requestRender();
  }

  // ------------------------------------------------------------------ boxes

  // regions: [{center, size, rotation (rad), frame}] in their own frames
  setBoxes(regions, selected) {
    for (const b of this.boxes) { b.parent.remove(b); b.geometry.dispose(); }
    this.boxes = regions.map((r, i) => {
      const colour = BOX_COLOURS[r.frame] || BOX_COLOURS.part;
      const mesh = new THREE.Mesh(new THREE.BoxBufferGeometry(1, 1, 1),
        new THREE.MeshBasicMaterial({ color: colour, transparent: true, opacity: i === selected ? 0.22 : 0.1, depthWrite: false }));
      const edges = new THREE.LineSegments(new THREE.EdgesGeometry(mesh.geometry), new THREE.LineBasicMaterial({ color: colour }));
      mesh.add(edges);
      mesh.userData.index = i;
      this.placeBox(mesh, r);
      (r.frame === "scanner" ? this.scanGroup : this.partGroup).add(mesh);
      return mesh;
    });
    this.select(selected);
  }

  placeBox(mesh, r) {
    mesh.position.set(...r.center);
    mesh.scale.set(...r.size.map((s) => Math.max(s, 1e-6)));
    const v = new THREE.Vector3(...r.rotation), angle = v.length();
    if (angle > 0) mesh.quaternion.setFromAxisAngle(v.normalize(), angle);
    else mesh.quaternion.set(0, 0, 0, 1);
    this.requestRender();
  }

  updateBox(i, r) { if (this.boxes[i]) this.placeBox(this.boxes[i], r); }

  // the box as {center, size, rotation (rad, a rotation vector)} in its own frame
  readBox(i) {
    const m = this.boxes[i];
    const q = m.quaternion.clone().normalize();
    if (q.w < 0) { q.x = -q.x; q.y = -q.y; q.z = -q.z; q.w = -q.w; }
    const s = Math.sqrt(q.x * q.x + q.y * q.y + q.z * q.z);
    const angle = 2 * Math.atan2(s, q.w);
    const rot = s < 1e-12 ? [0, 0, 0] : [q.x / s * angle, q.y / s * angle, q.z / s * angle];
    return { center: m.position.toArray(), size: m.scale.toArray().map(Math.abs), rotation: rot };
  }

  select(i) {
    this.selected = i;
    this.boxes.forEach((b, k) => { b.material.opacity = k === i ? 0.22 : 0.1; });
    if (i != null && this.boxes[i]) this.handles.attach(this.boxes[i]); else this.handles.detach();
    this.requestRender();
  }

  setMode(mode) { this.handles.setMode(mode); }

  // the orbit centre in scanner coordinates
  targetInScanner() {
    const inv = new THREE.Matrix4().getInverse(this.scanGroup.matrix);
    return this.orbit.target.clone().applyMatrix4(inv).toArray();
  }

  // ------------------------------------------------------------------ camera

  viewAlong(which) {
    if (!this.bbox) return;
    const lo = new THREE.Vector3(...this.bbox.min), hi = new THREE.Vector3(...this.bbox.max);
    const centre = lo.clone().add(hi).multiplyScalar(0.5).applyMatrix4(this.scanGroup.matrix);
    const dist = this.diagonal * 1.6;
    const dirs = { "+x": [1, 0, 0], "-x": [-1, 0, 0], "+y": [0, 1, 0], "-y": [0, -1, 0], "+z": [0, 0, 1], "-z": [0, 0, -1], iso: [1, -1, 0.8] };
    if (which === "fit") {
      const dir = this.camera.position.clone().sub(this.orbit.target).normalize();
      this.camera.position.copy(centre.clone().add(dir.multiplyScalar(dist)));
    } else {
      const d = new THREE.Vector3(...dirs[which]).normalize();
      this.camera.up.set(0, 0, 1);
      if (Math.abs(d.z) > 0.99) this.camera.up.set(0, 1, 0);
      this.camera.position.copy(centre.clone().add(d.multiplyScalar(dist)));
    }
    this.orbit.target.copy(centre);
    this.camera.lookAt(centre);
    this.orbit.update();
    this.requestRender();
  }

  // ------------------------------------------------------------------ pointer

  _ray(ev) {
    const r = this.renderer.domElement.getBoundingClientRect();
    const p = new THREE.Vector2(((ev.clientX - r.left) / r.width) * 2 - 1, -((ev.clientY - r.top) / r.height) * 2 + 1);
    this.raycaster.setFromCamera(p, this.camera);
  }

  _bindPointer() {
    const el = this.renderer.domElement;
    let down = null;
    el.addEventListener("pointerdown", (ev) => { down = [ev.clientX, ev.clientY]; });
    el.addEventListener("pointerup", (ev) => {
      if (!down || Math.hypot(ev.clientX - down[0], ev.clientY - down[1]) > 4 || this.handles.dragging) return;
      down = null;
      this._ray(ev);
      if (this.adding) {
        const hits = this.points ? this.raycaster.intersectObject(this.points) : [];
        if (hits.length) {
          // the hit in scanner coordinates (the frame the points are stored in)
          const local = this.scanGroup.worldToLocal(hits[0].point.clone());
          this.events.pointPicked(local.toArray());
        } else if (this.events.missed) this.events.missed();
        return;
      }
      const hit = this.raycaster.intersectObjects(this.boxes, false)[0];
      if (hit) this.events.boxPicked(hit.object.userData.index);
    });
  }
}
