// ionic-usd web: the temple, its hypotheses and their evidence (three.js, no network).
import * as THREE from "three";
import { GLTFLoader } from "three/addons/loaders/GLTFLoader.js";
import { OrbitControls } from "three/addons/controls/OrbitControls.js";
import { createLod, instanceCopies } from "./lod.js";

const data = await (await fetch("data.json")).json();
const host = document.getElementById("view");
// Software GL (SwiftShader, llvmpipe, WARP: no GPU) spends most of a frame on multisampling
// and fill: there the view draws without MSAA, and at half resolution while the camera moves
const software = (() => {
  const gl = document.createElement("canvas").getContext("webgl2");
  const info = gl && gl.getExtension("WEBGL_debug_renderer_info");
  return /swiftshader|llvmpipe|softpipe|software|warp/i.test(
    info ? String(gl.getParameter(info.UNMASKED_RENDERER_WEBGL)) : "");
})();
const renderer = new THREE.WebGLRenderer({ antialias: !software, preserveDrawingBuffer: true });
renderer.setPixelRatio(1);
function interactive(on) {
  // while the camera moves (software GL only): half the pixels, then the full view at rest
  const ratio = on && software ? 0.5 : 1;
  if (renderer.getPixelRatio() !== ratio) {
    renderer.setPixelRatio(ratio);
    resize();
  }
}
host.appendChild(renderer.domElement);
const scene = new THREE.Scene();
scene.background = new THREE.Color(0.8, 0.84, 0.89);
scene.add(new THREE.HemisphereLight(0xffffff, 0x8a7f70, 1.6));
const sun = new THREE.DirectionalLight(0xfff4e0, 2.0);
sun.position.set(-30, 50, 40);
scene.add(sun);
const camera = new THREE.PerspectiveCamera(40, 1, 0.1, 2000);
const controls = new OrbitControls(camera, renderer.domElement);

const loader = new GLTFLoader();
const base = (await loader.loadAsync(data.scene)).scene;
scene.add(base);
instanceCopies(base, data.lodGroups || []); // a city's merged street copies: GPU instances
const alts = {};
for (const h of data.hypotheses) {
  if (!h.glb) continue;
  alts[h.id] = (await loader.loadAsync(h.glb)).scene;
  alts[h.id].visible = false;
  scene.add(alts[h.id]);
}

// every drawn mesh, with its original material and (instanced) matrices
const meshes = [];
for (const root of [base, ...Object.values(alts)]) {
  root.traverse((o) => {
    if (!o.isMesh) return;
    o.userData.appearance = o.material;
    if (o.isInstancedMesh) {
      o.userData.matrices = Array.from({ length: o.count }, (_, i) => {
        const m = new THREE.Matrix4();
        o.getMatrixAt(i, m);
        return m;
      });
    }
    meshes.push(o);
  });
}
// level of detail by distance (lod.js): units (a city's temples, its street columns) far from
// the camera draw a coarse copy; a triangle budget keeps software GL responsive
const lod = createLod(base, data.lodGroups || [], { budget: software ? 200000 : 3000000 });
scene.add(lod.far);

function extrasOf(obj, instanceId) {
  // the paradata a mesh (or one instance of it) carries: the exporter keeps what copies share
  // on their group node (and on a GPU-instanced node), the rest per copy, so a record is
  // merged from the node up through its ancestors, the nearer taking precedence
  let out = null;
  for (let o = obj; o; o = o.parent) {
    let u = o.userData || {};
    if (instanceId !== undefined && o === obj && Array.isArray(u.instances)) {
      const e = u.instances[instanceId] || {};
      u = { ...u, ...e, paradata: { ...(u.paradata || {}), ...(e.paradata || {}) } };
      delete u.instances;
    }
    if (!u.paradata) continue;
    out = out
      ? { ...u, ...out, paradata: { ...u.paradata, ...out.paradata } }
      : { ...u, path: u.path || (obj.userData || {}).path };
  }
  return out;
}
function pathOf(obj) {
  for (let o = obj; o; o = o.parent) if (o.userData && o.userData.path) return o.userData.path;
  return "";
}
const covers = (list, p) => list.some((c) => p === c || p.startsWith(c + "/") || p.startsWith(c + "["));

const state = { view: "appearance", hyps: new Set(), sel: "" };
const emMaterials = {};
function emMaterial(ev) {
  if (!emMaterials[ev]) {
    const colour = new THREE.Color((data.chart[ev] || { colour: "#888888" }).colour);
    emMaterials[ev] = new THREE.MeshStandardMaterial({ color: colour, roughness: 0.8 });
  }
  return emMaterials[ev];
}
const white = new THREE.MeshStandardMaterial({ color: 0xffffff, roughness: 0.8 });
const zero = new THREE.Matrix4().makeScale(0, 0, 0);

function apply() {
  const hidden = data.hypotheses.filter((h) => state.hyps.has(h.id)).flatMap((h) => h.changes);
  for (const [id, root] of Object.entries(alts)) root.visible = state.hyps.has(id);
  for (const m of meshes) {
    const inBase = isIn(m, base);
    const d = lod.of(m); // the scene's meshes: drawn through lod.js; a hypothesis' own: as they are
    if (m.isInstancedMesh) {
      const inst = m.userData.instances || extrasOf(m)?.instances || [];
      for (let i = 0; i < m.userData.matrices.length; i++) {
        const p = (inst[i] || {}).path || "";
        const hide = inBase && covers(hidden, p);
        if (d) lod.setHidden(m, i, hide);
        else m.setMatrixAt(i, hide ? zero : m.userData.matrices[i]);
        const colour = state.view === "reliability"
          ? emMaterial(((extrasOf(m, i) || {}).paradata || {}).evidence).color
          : (d ? d.colours : m.instanceColor) && new THREE.Color(1, 1, 1);
        if (colour && d) lod.setColour(m, i, colour);
        else if (colour) m.setColorAt(i, colour);
      }
      if (!d) {
        m.instanceMatrix.needsUpdate = true;
        if (m.instanceColor) m.instanceColor.needsUpdate = true;
        m.computeBoundingSphere();
      }
      m.material = state.view === "reliability" ? white : m.userData.appearance;
    } else {
      const hide = inBase && covers(hidden, pathOf(m));
      if (d) for (let i = 0; i < d.n; i++) lod.setHidden(m, i, hide);
      else m.visible = !hide;
      const ev = ((extrasOf(m) || {}).paradata || {}).evidence;
      m.material = state.view === "reliability" ? emMaterial(ev) : m.userData.appearance;
    }
  }
  lod.invalidate();
  writeHash();
  render();
}
function isIn(o, root) {
  for (; o; o = o.parent) if (o === root) return true;
  return false;
}

function render() {
  lod.update(camera, host.clientHeight, walk.checked ? camera.position : controls.target);
  renderer.render(scene, camera);
}
function resize() {
  const w = host.clientWidth, h = host.clientHeight;
  renderer.setSize(w, h, false);
  renderer.domElement.style.width = w + "px";
  renderer.domElement.style.height = h + "px";
  camera.aspect = w / h;
  camera.updateProjectionMatrix();
  render();
}

// camera: fit the temple, three-quarter view from the front
const box = new THREE.Box3().setFromObject(base);
const centre = box.getCenter(new THREE.Vector3());
const size = box.getSize(new THREE.Vector3()).length();
function home() {
  camera.position.copy(centre).add(new THREE.Vector3(0.75, 0.5, 1.0).normalize().multiplyScalar(size * 1.45));
  controls.target.copy(centre);
  controls.update();
}
home();

// walk: eye height above the ground, W A S D to move, arrows to turn
const walk = document.getElementById("walk");
walk.addEventListener("change", () => {
  if (walk.checked) {
    const eye = box.min.y + 1.7;
    camera.position.set(centre.x, eye, box.max.z + 6);
    controls.target.set(centre.x, eye, centre.z);
    controls.update();
    render();
  } else home();
  writeHash();
});
window.addEventListener("keydown", (e) => {
  if (!walk.checked) return;
  const dir = controls.target.clone().sub(camera.position).setY(0).normalize();
  const side = new THREE.Vector3(-dir.z, 0, dir.x);
  const step = { w: dir, s: dir.clone().negate(), d: side, a: side.clone().negate() }[e.key];
  if (step) {
    camera.position.addScaledVector(step, 0.5);
    controls.target.addScaledVector(step, 0.5);
  } else if (e.key === "ArrowLeft" || e.key === "ArrowRight") {
    const a = e.key === "ArrowLeft" ? 0.08 : -0.08;
    const v = controls.target.clone().sub(camera.position).applyAxisAngle(new THREE.Vector3(0, 1, 0), a);
    controls.target.copy(camera.position).add(v);
  } else return;
  controls.update();
  render();
  writeHash();
});

// the panel
document.getElementById("title").textContent = data.title || "Temple";
const legend = document.getElementById("legend");
for (const [ev, c] of Object.entries(data.chart)) {
  const li = document.createElement("li");
  li.innerHTML = `<span class="swatch" style="background:${c.colour}"></span>${ev}: ${c.label}`;
  legend.appendChild(li);
}
const esc = (s) => String(s).replace(/[&<>"]/g, (c) => ({ "&": "&amp;", "<": "&lt;", ">": "&gt;", '"': "&quot;" })[c]);
const groups = {};
for (const h of data.hypotheses) (groups[h.question] ||= []).push(h);
const hypHost = document.getElementById("hypotheses");
for (const [q, hs] of Object.entries(groups)) {
  const g = document.createElement("div");
  g.className = "group";
  g.innerHTML = `<h3>${esc(q)}${hs.length > 1 ? " (alternatives: one at a time)" : ""}</h3>`;
  for (const h of hs) {
    const d = document.createElement("div");
    d.className = "hyp";
    const dis = h.glb ? "" : " disabled";
    d.innerHTML =
      `<label><input type="checkbox" data-hyp="${esc(h.id)}"${dis}> <b>${esc(h.id)}</b></label>` +
      `<p>${esc(h.description)}</p><p>certainty: <b>${esc(h.certainty)}</b>; evidence: ${esc(h.evidence)}</p>` +
      `<p class="sources">${h.sources.map(esc).join("<br>")}</p>`;
    g.appendChild(d);
  }
  hypHost.appendChild(g);
}
hypHost.addEventListener("change", (e) => {
  const id = e.target.dataset.hyp;
  if (id) setHypothesis(id, e.target.checked);
});
for (const r of document.querySelectorAll('input[name="view"]')) r.addEventListener("change", () => setView(r.value));

function showPart(rec) {
  const el = document.getElementById("part");
  if (!rec) {
    el.textContent = "Click a part of the temple.";
    return;
  }
  const c = (data.chart[rec.evidence] || {}).colour || "#888";
  el.innerHTML =
    `<p><b data-field="unit">${esc(rec.unit)}</b> <span class="sources" data-field="path">${esc(rec.path || "")}</span></p>` +
    `<p><span class="swatch" style="background:${c}"></span><span data-field="evidence">${esc(rec.evidence)}</span>: ${esc(rec.evidenceLabel || "")}</p>` +
    `<p>certainty: <b data-field="certainty">${esc(rec.certainty)}</b>; hypothesis: <span data-field="hypothesis">${esc(rec.hypothesis || "baseline")}</span></p>` +
    `<p data-field="description">${esc(rec.description)}</p>` +
    `<p class="sources" data-field="sources">${(rec.sources || []).map(esc).join("<br>")}</p>`;
}

// picking: a click (no drag) selects the part under the pointer
const ray = new THREE.Raycaster();
let down = null;
renderer.domElement.addEventListener("pointerdown", (e) => (down = [e.clientX, e.clientY]));
renderer.domElement.addEventListener("pointerup", (e) => {
  if (!down || Math.hypot(e.clientX - down[0], e.clientY - down[1]) > 4) return;
  const r = renderer.domElement.getBoundingClientRect();
  pick(((e.clientX - r.left) / r.width) * 2 - 1, -((e.clientY - r.top) / r.height) * 2 + 1);
});
function pick(x, y) {
  ray.setFromCamera(new THREE.Vector2(x, y), camera);
  const hits = ray.intersectObjects([base, lod.far, ...Object.values(alts)].filter((o) => o.visible), true);
  const hit = hits.find((h) => h.object.visible && isVisible(h.object, h.instanceId));
  const at = hit ? lod.resolve(hit) : null; // a far copy, a packed instance: the item it draws
  const ex = at ? extrasOf(at.object, at.id) : null;
  const rec = ex && ex.paradata ? { ...ex.paradata, path: ex.path || pathOf(at.object) } : null;
  state.sel = rec ? rec.path : "";
  showPart(rec);
  writeHash();
  return rec;
}
function isVisible(o, i) {
  for (let p = o; p; p = p.parent) if (!p.visible) return false;
  if (o.isInstancedMesh && i !== undefined) {
    const m = new THREE.Matrix4();
    o.getMatrixAt(i, m);
    return m.determinant() !== 0;
  }
  return true;
}
function select(path) {
  const unit = data.prims[path];
  const rec = unit ? { ...data.parts[unit], unit, path } : null;
  if (rec) rec.evidenceLabel = (data.chart[rec.evidence] || {}).label || "";
  state.sel = rec ? path : "";
  showPart(rec);
  writeHash();
  return rec;
}

// state ⇄ URL hash (the permalink)
function writeHash() {
  const f = (v) => [v.x, v.y, v.z].map((n) => n.toFixed(2)).join(",");
  const parts = [`v=${state.view}`, `h=${[...state.hyps].sort().join(",")}`, `c=${f(camera.position)},${f(controls.target)}`];
  if (state.sel) parts.push(`s=${encodeURIComponent(state.sel)}`);
  const hash = "#" + parts.join("&");
  history.replaceState(null, "", hash);
  document.getElementById("permalink").href = hash;
}
function readHash() {
  const q = new URLSearchParams(location.hash.slice(1));
  if (q.get("v") === "reliability") state.view = "reliability";
  for (const id of (q.get("h") || "").split(",")) {
    const me = data.hypotheses.find((x) => x.id === id);
    const taken = me && me.set && data.hypotheses.some((o) => o.set === me.set && state.hyps.has(o.id));
    if (alts[id] && !taken) state.hyps.add(id); // one alternative per question
  }
  const c = (q.get("c") || "").split(",").map(Number);
  if (c.length === 6 && c.every(Number.isFinite)) {
    camera.position.set(c[0], c[1], c[2]);
    controls.target.set(c[3], c[4], c[5]);
    controls.update();
  }
  for (const r of document.querySelectorAll('input[name="view"]')) r.checked = r.value === state.view;
  for (const b of document.querySelectorAll("input[data-hyp]")) b.checked = state.hyps.has(b.dataset.hyp);
  if (q.get("s")) select(decodeURIComponent(q.get("s")));
}

function setView(v) {
  state.view = v;
  for (const r of document.querySelectorAll('input[name="view"]')) r.checked = r.value === v;
  apply();
}
function setHypothesis(id, on) {
  // the alternatives of one question share a variant set: one of them at a time
  const me = data.hypotheses.find((x) => x.id === id);
  if (on && me && me.set) {
    for (const o of data.hypotheses) {
      if (o.id !== id && o.set === me.set && state.hyps.has(o.id)) {
        state.hyps.delete(o.id);
        for (const b of document.querySelectorAll(`input[data-hyp="${o.id}"]`)) b.checked = false;
      }
    }
  }
  if (on) state.hyps.add(id);
  else state.hyps.delete(id);
  for (const b of document.querySelectorAll(`input[data-hyp="${id}"]`)) b.checked = on;
  apply();
}

// the screen box of what a hypothesis draws or hides (for tests)
function screenBox(id) {
  const h = data.hypotheses.find((x) => x.id === id);
  const b = new THREE.Box3();
  const add = (m, i) => {
    if (!m.geometry.boundingBox) m.geometry.computeBoundingBox();
    const bb = m.geometry.boundingBox.clone();
    if (i !== undefined) {
      const im = new THREE.Matrix4();
      m.userData.matrices && im.copy(m.userData.matrices[i]);
      bb.applyMatrix4(im);
    }
    b.union(bb.applyMatrix4(m.matrixWorld));
  };
  scene.updateMatrixWorld(true);
  for (const m of meshes) {
    const inAlt = alts[id] && isIn(m, alts[id]);
    if (m.isInstancedMesh) {
      const inst = m.userData.instances || [];
      for (let i = 0; i < m.userData.matrices.length; i++)
        if (inAlt || (isIn(m, base) && covers(h.changes, (inst[i] || {}).path || ""))) add(m, i);
    } else if (inAlt || (isIn(m, base) && covers(h.changes, pathOf(m)))) add(m);
  }
  const pts = [];
  for (const x of [b.min.x, b.max.x]) for (const y of [b.min.y, b.max.y]) for (const z of [b.min.z, b.max.z]) {
    const p = new THREE.Vector3(x, y, z).project(camera);
    pts.push([((p.x + 1) / 2) * host.clientWidth, ((1 - p.y) / 2) * host.clientHeight]);
  }
  return [Math.min(...pts.map((p) => p[0])), Math.min(...pts.map((p) => p[1])),
          Math.max(...pts.map((p) => p[0])), Math.max(...pts.map((p) => p[1]))];
}
function frameTimes(n = 60) {
  const gl = renderer.getContext();
  const t = [];
  for (let i = 0; i < n; i++) {
    const t0 = performance.now();
    render();
    gl.finish();
    t.push(performance.now() - t0);
  }
  t.sort((a, b) => a - b);
  return { median: t[Math.floor(n / 2)], p95: t[Math.floor(n * 0.95)], max: t[n - 1], calls: renderer.info.render.calls, triangles: renderer.info.render.triangles };
}

// pixels of the drawn image, kept by name, and their difference (for tests)
const shots = {};
function snapshot(name) {
  render();
  const gl = renderer.getContext();
  const w = gl.drawingBufferWidth, h = gl.drawingBufferHeight;
  const px = new Uint8Array(w * h * 4);
  gl.readPixels(0, 0, w, h, gl.RGBA, gl.UNSIGNED_BYTE, px);
  shots[name] = { w, h, px };
  return [w, h];
}
function hash(name) {
  let h = 2166136261;
  for (const v of shots[name].px) h = Math.imul(h ^ v, 16777619) >>> 0;
  return h;
}
function diff(a, b, rect, margin = 2) {
  // changed pixels (any channel > 8 levels) inside and outside rect = [x0, y0, x1, y1] (CSS px)
  const A = shots[a], B = shots[b];
  let inside = 0, outside = 0;
  for (let y = 0; y < A.h; y++) {
    const yy = A.h - 1 - y; // readPixels rows run bottom-up
    for (let x = 0; x < A.w; x++) {
      const i = (y * A.w + x) * 4;
      const d = Math.max(Math.abs(A.px[i] - B.px[i]), Math.abs(A.px[i + 1] - B.px[i + 1]), Math.abs(A.px[i + 2] - B.px[i + 2]));
      if (d <= 8) continue;
      const inRect = rect && x >= rect[0] - margin && x <= rect[2] + margin && yy >= rect[1] - margin && yy <= rect[3] + margin;
      if (inRect) inside++;
      else outside++;
    }
  }
  return { inside, outside };
}

controls.addEventListener("start", () => interactive(true));
controls.addEventListener("end", () => interactive(false));
controls.addEventListener("change", () => {
  render();
  writeHash();
});
window.addEventListener("resize", resize);
resize();
readHash();
apply();
window.app = {
  data, setView, setHypothesis, select, pick, screenBox, frameTimes, render, snapshot, diff, hash,
  interactive, software,
  lod: () => ({ ...lod.stats(), triangles: renderer.info.render.triangles, calls: renderer.info.render.calls }),
  focus: (key) => {
    // the camera on one unit, framed as the temple site frames its temple
    const g = lod.groups.find((x) => x.key === key);
    walk.checked = false;
    camera.position.copy(g.sphere.center).add(new THREE.Vector3(0.75, 0.5, 1.0).normalize().multiplyScalar(g.sphere.radius * 2 * 1.45));
    controls.target.copy(g.sphere.center);
    controls.update();
    render();
  },
  streetView: (key) => {
    // walk mode, at eye height 0.7 of one unit's radius to the +x and the +z of its centre (a
    // city temple's lot corner), facing the unit
    const g = lod.groups.find((x) => x.key === key);
    walk.checked = true;
    const c = g.sphere.center, r = 0.7 * g.sphere.radius;
    camera.position.set(c.x + r, box.min.y + 1.7, c.z + r);
    controls.target.copy(c);
    controls.update();
    render();
  },
  turn: (a) => {
    // the camera a little around the orbit target (no render)
    const v = camera.position.clone().sub(controls.target).applyAxisAngle(new THREE.Vector3(0, 1, 0), a);
    camera.position.copy(controls.target).add(v);
    controls.update();
  },
  state: () => ({ view: state.view, hyps: [...state.hyps].sort(), sel: state.sel }),
  setCamera: (c) => {
    camera.position.set(c[0], c[1], c[2]);
    controls.target.set(c[3], c[4], c[5]);
    controls.update();
    render();
  },
  project: (p) => {
    const v = new THREE.Vector3(...p).project(camera);
    return [((v.x + 1) / 2) * host.clientWidth, ((1 - v.y) / 2) * host.clientHeight];
  },
};
document.body.dataset.ready = "1";
