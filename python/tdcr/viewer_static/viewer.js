// tdcr view, the page: sliders in, one solve request at a time out, the answers drawn with three.js.
// A move while a solve is under way is not queued: the page keeps showing the last answer with a
// busy mark and, when the answer arrives, sends the newest slider values (never blocks, never piles up).
import * as THREE from "three";
import { OrbitControls } from "three/addons/controls/OrbitControls.js";

const COLORS = { cc: 0x1f77b4, ccsub: 0xff7f0e, prb: 0x2ca02c, vc: 0xd62728, vcref: 0x9467bd };
const state = {
  scene: null, values: [], force: [0, 0, 0], moment: [0, 0, 0], models: [],
  inFlight: false, dirty: false, inputTime: 0,
  // For the browser test and the latency benchmark: answers and slider-to-picture times (ms).
  requests: 0, answers: 0, lastResults: [], latencies: [], error: null, ready: false,
};
window.tdcrViewer = state;

const el = (id) => document.getElementById(id);

function showError(msg) {
  state.error = msg;
  el("error").hidden = false;
  el("error").textContent = msg;
}

// --- three.js ---------------------------------------------------------------------------------------
const view = el("view");
const renderer = new THREE.WebGLRenderer({ antialias: true, preserveDrawingBuffer: true });
renderer.setPixelRatio(window.devicePixelRatio);
view.appendChild(renderer.domElement);
const scene3 = new THREE.Scene();
scene3.background = new THREE.Color(0xffffff);
const camera = new THREE.PerspectiveCamera(40, 1, 1e-4, 100);
camera.up.set(0, 0, 1);
const controls = new OrbitControls(camera, renderer.domElement);
scene3.add(new THREE.AmbientLight(0xffffff, 0.6));
const sun = new THREE.DirectionalLight(0xffffff, 0.9);
sun.position.set(1, -1, 2);
scene3.add(sun);
const groups = {};  // per model: a THREE.Group rebuilt on every answer

function resize() {
  const w = view.clientWidth, h = view.clientHeight;
  renderer.setSize(w, h);
  camera.aspect = w / Math.max(h, 1);
  camera.updateProjectionMatrix();
}
window.addEventListener("resize", () => { resize(); render(); });

function render() { renderer.render(scene3, camera); }
controls.addEventListener("change", render);

function frameCamera(L) {
  camera.position.set(1.6 * L, -1.6 * L, 0.9 * L);
  controls.target.set(0, 0, 0.45 * L);
  controls.update();
  const grid = new THREE.GridHelper(2 * L, 10, 0xbbbbbb, 0xdddddd);
  grid.rotation.x = Math.PI / 2;
  scene3.add(grid);
  scene3.add(new THREE.AxesHelper(0.2 * L));
}

function drawModel(result) {
  const old = groups[result.model];
  if (old) { scene3.remove(old); old.traverse((o) => { if (o.geometry) o.geometry.dispose(); }); }
  const g = new THREE.Group();
  groups[result.model] = g;
  scene3.add(g);
  if (!result.disks) return;
  const color = COLORS[result.model] ?? 0x333333;
  const L = state.scene.length, r = state.scene.tendon_radius || 0.01 * L;
  const pts = result.backbone.map((p) => new THREE.Vector3(p[0], p[1], p[2]));
  if (pts.length >= 2) {
    const curve = new THREE.CatmullRomCurve3(pts);
    const tube = new THREE.TubeGeometry(curve, Math.max(8, 2 * pts.length), 0.08 * r, 8, false);
    g.add(new THREE.Mesh(tube, new THREE.MeshStandardMaterial({ color })));
  }
  const diskGeom = new THREE.CylinderGeometry(1.3 * r, 1.3 * r, 0.1 * r, 24);
  diskGeom.rotateX(Math.PI / 2);  // the cylinder's axis along the disk frame's z
  const diskMat = new THREE.MeshStandardMaterial({ color, transparent: true, opacity: 0.55 });
  const frames = result.disks.map((d) => {
    const m = new THREE.Matrix4();
    m.set(d[3], d[4], d[5], d[0], d[6], d[7], d[8], d[1], d[9], d[10], d[11], d[2], 0, 0, 0, 1);
    return m;
  });
  frames.forEach((m, j) => {
    if (j === 0) return;
    const disk = new THREE.Mesh(diskGeom, diskMat);
    disk.matrixAutoUpdate = false;
    disk.matrix.copy(m);
    g.add(disk);
  });
  // Tendons through their holes (straight offsets in each disk frame), up to their segment's end.
  const ends = []; let k = 0;
  state.scene.segments.forEach((s) => { k += s.disks; ends.push(k); });
  for (const t of state.scene.tendons) {
    const holes = [];
    for (let j = 0; j <= ends[t.segment] && j < frames.length; ++j)
      holes.push(new THREE.Vector3(t.x, t.y, 0).applyMatrix4(frames[j]));
    g.add(new THREE.Line(new THREE.BufferGeometry().setFromPoints(holes), new THREE.LineBasicMaterial({ color: 0x444444 })));
  }
  const tip = frames[frames.length - 1];
  const axes = new THREE.AxesHelper(0.12 * L);
  axes.matrixAutoUpdate = false;
  axes.matrix.copy(tip);
  g.add(axes);
  const f = new THREE.Vector3(...state.force);
  if (f.length() > 0) {
    const origin = new THREE.Vector3().setFromMatrixPosition(tip);
    g.add(new THREE.ArrowHelper(f.clone().normalize(), origin, 0.25 * L, 0x000000));
  }
}

// --- the panel ----------------------------------------------------------------------------------------
function slider(parent, label, lo, hi, value, onInput) {
  const wrap = document.createElement("label");
  wrap.className = "slider";
  const text = document.createElement("span");
  const input = document.createElement("input");
  input.type = "range";
  input.min = lo; input.max = hi; input.step = (hi - lo) / 1000; input.value = value;
  // The slider's grid has rounding: a value within a millionth of the range of zero is zero.
  const read = () => { const v = Number(input.value); return Math.abs(v) < 1e-6 * (hi - lo) ? 0 : v; };
  const show = () => { text.textContent = `${label}: ${read().toPrecision(4)}`; };
  input.addEventListener("input", () => { show(); onInput(read()); });
  show();
  wrap.append(text, input);
  parent.appendChild(wrap);
  return input;
}

function changed() {
  state.inputTime = performance.now();
  if (state.inFlight) { state.dirty = true; el("busy").hidden = false; return; }
  send();
}

async function send() {
  state.inFlight = true;
  state.dirty = false;
  el("busy").hidden = false;
  const sentAt = state.inputTime;
  state.requests += 1;
  let reply;
  try {
    const r = await fetch("/api/solve", {
      method: "POST", headers: { "Content-Type": "application/json" },
      body: JSON.stringify({ models: state.models, values: state.values, tip_force: state.force, tip_moment: state.moment }),
    });
    reply = await r.json();
    if (!r.ok) throw new Error(reply.error || r.statusText);
  } catch (e) {
    showError(String(e.message || e));
    state.inFlight = false;
    return;
  }
  el("error").hidden = true;
  state.error = null;
  for (const name of Object.keys(groups)) if (!state.models.includes(name)) { scene3.remove(groups[name]); delete groups[name]; }
  for (const res of reply.results) drawModel(res);
  summaries(reply.results);
  render();
  // The picture is on screen at the next frame: that ends this move's latency.
  requestAnimationFrame(() => {
    if (sentAt > 0) state.latencies.push(performance.now() - sentAt);
    state.lastResults = reply.results;
    state.answers += 1;
    state.inFlight = false;
    if (state.dirty) send(); else el("busy").hidden = true;
  });
}

function summaries(results) {
  const box = el("summaries");
  box.textContent = "";
  for (const r of results) {
    const d = document.createElement("div");
    d.className = "summary" + (r.ok ? "" : " failed");
    d.style.borderColor = "#" + (COLORS[r.model] ?? 0x333333).toString(16).padStart(6, "0");
    const tip = r.tip ? `tip (mm): ${r.tip.map((x) => (1e3 * x).toFixed(3)).join(", ")}` : "";
    const st = r.stability ? `stability: ${r.stability.status}${r.stability.margin != null ? ` (margin ${r.stability.margin.toPrecision(3)})` : ""}` : "";
    d.innerText = `${r.model}: ${r.ok ? r.report : "failed: " + (r.error || r.report)}\n${tip}\n${st}`;
    box.appendChild(d);
  }
}

async function start() {
  let desc;
  try {
    desc = await (await fetch("/api/scene")).json();
  } catch (e) {
    showError("cannot reach the tdcr view server: " + e);
    return;
  }
  el("scene-name").textContent = desc.scene || "";
  if (!desc.ok) { showError(desc.error); state.ready = true; return; }
  state.scene = desc;
  state.values = desc.tendons.map((t) => t.value);
  state.force = desc.tip_force.slice();
  state.moment = desc.tip_moment.slice();
  state.models = desc.selected.slice();
  const models = el("models");
  for (const name of desc.models) {
    const l = document.createElement("label");
    const c = document.createElement("input");
    c.type = "checkbox"; c.value = name; c.checked = state.models.includes(name);
    c.addEventListener("change", () => {
      state.models = [...models.querySelectorAll("input:checked")].map((x) => x.value);
      changed();
    });
    l.append(c, " " + name + " ");
    l.style.color = "#" + (COLORS[name] ?? 0x333333).toString(16).padStart(6, "0");
    models.appendChild(l);
  }
  desc.tendons.forEach((t, i) => {
    const unit = t.kind === "displacements" ? "m" : "N";
    slider(el("tendons"), `${t.label} (${unit})`, t.min, t.max, t.value, (v) => { state.values[i] = v; changed(); }).dataset.tendon = i;
  });
  ["x", "y", "z"].forEach((a, i) => {
    slider(el("loads"), `force ${a} (N)`, -desc.force_max, desc.force_max, state.force[i], (v) => { state.force[i] = v; changed(); }).dataset.force = i;
  });
  ["x", "y", "z"].forEach((a, i) => {
    slider(el("loads"), `moment ${a} (N m)`, -desc.moment_max, desc.moment_max, state.moment[i], (v) => { state.moment[i] = v; changed(); }).dataset.moment = i;
  });
  resize();
  frameCamera(desc.length);
  render();
  await send();
  state.ready = true;
}

start();
