// Load a .glb with three.js's GLTFLoader in headless Chromium (driven by playwright-core),
// render it lit by a PBR room environment, save a PNG, and check the picture: the model
// loaded, its textures decoded, and the frame is not empty. Exit 1 on failure.
//
//   node render.mjs MODEL.glb OUT.png [--width 1280 --height 800] [--chromium /usr/bin/chromium]
//                   [--without EXT_mesh_gpu_instancing] [--json OUT.json]
// --without NAME: the loader's plugin for that extension is removed, as a client without it
// loads the file. The report gives the frame's draw calls (renderer.info.render.calls) and
// the triangles three.js drew (renderer.info.render.triangles).
import fs from "node:fs";
import http from "node:http";
import path from "node:path";
import { fileURLToPath } from "node:url";
import { chromium } from "playwright-core";

const here = path.dirname(fileURLToPath(import.meta.url));
const args = process.argv.slice(2);
const opt = (name, dflt) => {
  const i = args.indexOf(name);
  return i >= 0 ? args.splice(i, 2)[1] : dflt;
};
const width = Number(opt("--width", 1280));
const height = Number(opt("--height", 800));
const exe = opt("--chromium", process.env.CHROMIUM || "/usr/bin/chromium");
const without = opt("--without", "");
const jsonOut = opt("--json", "");
const [model, outPng] = args;
if (!model || !outPng) {
  console.error("usage: node render.mjs MODEL.glb OUT.png [--width W --height H]");
  process.exit(2);
}

const page = `<!doctype html><html><head><meta charset="utf-8">
<script type="importmap">{"imports": {"three": "/three/build/three.module.js",
 "three/addons/": "/three/examples/jsm/"}}</script></head>
<body style="margin:0;background:#000"><script type="module">
import * as THREE from "three";
import { GLTFLoader } from "three/addons/loaders/GLTFLoader.js";
import { DRACOLoader } from "three/addons/loaders/DRACOLoader.js";
import { RoomEnvironment } from "three/addons/environments/RoomEnvironment.js";
const W = ${width}, H = ${height};
try {
  const renderer = new THREE.WebGLRenderer({ antialias: true, preserveDrawingBuffer: true });
  renderer.setSize(W, H);
  renderer.toneMapping = THREE.ACESFilmicToneMapping;
  renderer.toneMappingExposure = 0.75;
  document.body.appendChild(renderer.domElement);
  const scene = new THREE.Scene();
  scene.background = new THREE.Color(0.62, 0.70, 0.80);
  scene.environment = new THREE.PMREMGenerator(renderer).fromScene(new RoomEnvironment(), 0.04).texture;
  scene.environmentIntensity = 0.55;
  const sun = new THREE.DirectionalLight(0xfff4e0, 2.2);
  sun.position.set(-30, 50, 40);
  scene.add(sun);
  const loader = new GLTFLoader();
  const WITHOUT = ${JSON.stringify(without)};
  if (WITHOUT) {  // a client that does not know the extension: drop its plugin
    const n = loader.pluginCallbacks.length;
    loader.pluginCallbacks = loader.pluginCallbacks.filter((cb) => cb({}).name !== WITHOUT);
    if (loader.pluginCallbacks.length !== n - 1) throw new Error("no plugin " + WITHOUT);
  }
  loader.setDRACOLoader(new DRACOLoader().setDecoderPath("/three/examples/jsm/libs/draco/gltf/"));
  const gltf = await loader.loadAsync("/model.glb");
  scene.add(gltf.scene);
  const stats = { meshes: 0, instancedMeshes: 0, instances: 0, triangles: 0, textures: 0,
                  texturesDecoded: 0, extras: Object.keys(gltf.scene.userData || {}).length };
  const seen = new Set();
  gltf.scene.traverse((o) => {
    if (!o.isMesh) return;
    stats.meshes++;
    const tris = (o.geometry.index ? o.geometry.index.count : o.geometry.attributes.position.count) / 3;
    if (o.isInstancedMesh) { stats.instancedMeshes++; stats.instances += o.count; stats.triangles += tris * o.count; }
    else stats.triangles += tris;
    for (const key of ["map", "normalMap", "roughnessMap", "metalnessMap"]) {
      const t = o.material[key];
      if (t && !seen.has(t.uuid)) {
        seen.add(t.uuid); stats.textures++;
        if (t.image && t.image.width > 0) stats.texturesDecoded++;
      }
    }
  });
  // frame the model: a three-quarter view from the front-left, above the podium
  const box = new THREE.Box3().setFromObject(gltf.scene);
  const size = box.getSize(new THREE.Vector3()), centre = box.getCenter(new THREE.Vector3());
  const radius = size.length() / 2;
  const camera = new THREE.PerspectiveCamera(35, W / H, radius / 100, radius * 20);
  const dir = new THREE.Vector3(-0.8, 0.62, 1.0).normalize();
  camera.position.copy(centre).addScaledVector(dir, radius / Math.sin(THREE.MathUtils.degToRad(35 / 2)) * 0.7);
  camera.lookAt(centre);
  renderer.render(scene, camera);
  stats.drawCalls = renderer.info.render.calls;
  stats.trianglesDrawn = renderer.info.render.triangles;
  // picture checks on the drawn pixels
  const gl = renderer.getContext();
  const px = new Uint8Array(W * H * 4);
  gl.readPixels(0, 0, W, H, gl.RGBA, gl.UNSIGNED_BYTE, px);
  const bg = [px[(H - 1) * W * 4], px[(H - 1) * W * 4 + 1], px[(H - 1) * W * 4 + 2]];
  let cover = 0, sum = 0, sum2 = 0;
  for (let i = 0; i < W * H; i++) {
    const r = px[4 * i], g = px[4 * i + 1], b = px[4 * i + 2];
    if (Math.abs(r - bg[0]) + Math.abs(g - bg[1]) + Math.abs(b - bg[2]) > 24) {
      cover++; const l = 0.3 * r + 0.59 * g + 0.11 * b; sum += l; sum2 += l * l;
    }
  }
  const mean = cover ? sum / cover : 0;
  stats.coverage = cover / (W * H);
  stats.lumaStd = cover ? Math.sqrt(Math.max(0, sum2 / cover - mean * mean)) : 0;
  stats.bounds = [size.x, size.y, size.z];
  window.__result = stats;
} catch (e) {
  window.__result = { error: String(e && e.stack || e) };
}
</script></body></html>`;

const types = { ".wasm": "application/wasm", ".js": "text/javascript", ".mjs": "text/javascript", ".html": "text/html",
                ".glb": "model/gltf-binary", ".json": "application/json" };
const server = http.createServer((req, res) => {
  const url = decodeURIComponent(req.url.split("?")[0]);
  let file = null;
  if (url === "/favicon.ico") { res.writeHead(204); res.end(); return; }
  if (url === "/" || url === "/index.html") { res.writeHead(200, { "content-type": "text/html" }); res.end(page); return; }
  if (url === "/model.glb") file = path.resolve(model);
  else if (url.startsWith("/three/")) {
    const root = path.join(here, "node_modules", "three");
    file = path.resolve(root, "." + url.slice("/three".length));
    if (!file.startsWith(root)) file = null;
  }
  if (!file || !fs.existsSync(file)) { res.writeHead(404); res.end(); return; }
  res.writeHead(200, { "content-type": types[path.extname(file)] || "application/octet-stream" });
  fs.createReadStream(file).pipe(res);
});
await new Promise((r) => server.listen(0, "127.0.0.1", r));
const port = server.address().port;

const browser = await chromium.launch({
  executablePath: exe,
  args: ["--headless", "--no-sandbox", "--disable-gpu", "--disable-background-networking",
         "--no-first-run", "--disable-component-update", "--disable-sync",
         "--use-angle=swiftshader", "--enable-unsafe-swiftshader"],
});
let ok = false;
try {
  const p = await browser.newPage({ viewport: { width, height } });
  const logs = [];
  p.on("console", (m) => logs.push(`${m.type()}: ${m.text()}`));
  p.on("pageerror", (e) => logs.push(`pageerror: ${e}`));
  await p.goto(`http://127.0.0.1:${port}/`);
  await p.waitForFunction(() => window.__result !== undefined, null, { timeout: 240000 });
  const r = await p.evaluate(() => window.__result);
  if (r.error) {
    console.log(`three.js: FAILED to load ${model}: ${r.error}`);
    for (const l of logs) console.log("  " + l);
  } else {
    await p.locator("canvas").screenshot({ path: outPng });
    ok = r.meshes > 0 && r.textures > 0 && r.texturesDecoded === r.textures &&
         r.coverage > 0.02 && r.lumaStd > 2;
    console.log(`three.js r170 GLTFLoader: ${model}: ${r.meshes} meshes (${r.instancedMeshes} ` +
      `InstancedMesh, ${r.instances} instances), ${Math.round(r.triangles)} triangles, ` +
      `${r.texturesDecoded}/${r.textures} textures decoded, picture coverage ` +
      `${(100 * r.coverage).toFixed(1)} %, luma std ${r.lumaStd.toFixed(1)}, bounds ` +
      `${r.bounds.map((x) => x.toFixed(2)).join(" x ")} m, ${r.drawCalls} draw calls, ` +
      `${r.trianglesDrawn} triangles rendered` + (without ? ` (without ${without})` : "") +
      ` -> ${outPng}: ${ok ? "OK" : "FAILED"}`);
    if (jsonOut) fs.writeFileSync(jsonOut, JSON.stringify({ model, without, ...r }, null, 1));
    for (const l of logs.filter((l) => l.startsWith("error") || l.startsWith("pageerror"))) console.log("  " + l);
  }
} finally {
  await browser.close();
  server.close();
}
process.exit(ok ? 0 : 1);
