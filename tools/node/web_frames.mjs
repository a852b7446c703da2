// Frame times of a site written by `ionic-usd web`, in headless Chromium (playwright-core,
// SwiftShader software GL): load it, wait until it is drawn, then time N frames (render +
// gl.finish) from the site's own camera. Prints one JSON line "FRAMES {...}" (median, p95,
// max ms; draw calls; triangles; load seconds).
//
//   node web_frames.mjs SITE_DIR [--frames 30] [--width 1024 --height 640]
import fs from "node:fs";
import http from "node:http";
import path from "node:path";
import { chromium } from "playwright-core";

const args = process.argv.slice(2);
const opt = (name, dflt) => {
  const i = args.indexOf(name);
  return i >= 0 ? args.splice(i, 2)[1] : dflt;
};
const width = Number(opt("--width", 1024));
const height = Number(opt("--height", 640));
const frames = Number(opt("--frames", 30));
const exe = opt("--chromium", process.env.CHROMIUM || "/usr/bin/chromium");
const [site] = args;
if (!site) {
  console.error("usage: node web_frames.mjs SITE_DIR [--frames N]");
  process.exit(2);
}
const root = path.resolve(site);
const types = { ".html": "text/html", ".js": "text/javascript", ".css": "text/css", ".json": "application/json", ".glb": "model/gltf-binary" };
const server = http.createServer((req, res) => {
  const p = path.resolve(path.join(root, decodeURIComponent(new URL(req.url, "http://x").pathname)));
  if (!p.startsWith(root)) return res.writeHead(403).end();
  const f = fs.existsSync(p) && fs.statSync(p).isDirectory() ? path.join(p, "index.html") : p;
  if (!fs.existsSync(f)) return res.writeHead(404).end();
  res.writeHead(200, { "content-type": types[path.extname(f)] || "application/octet-stream" });
  fs.createReadStream(f).pipe(res);
});
await new Promise((r) => server.listen(0, "127.0.0.1", r));
const origin = `http://127.0.0.1:${server.address().port}`;
const browser = await chromium.launch({ executablePath: exe, args: ["--use-angle=swiftshader", "--enable-unsafe-swiftshader", "--ignore-gpu-blocklist"] });
const out = { errors: [] };
try {
  const page = await browser.newPage({ viewport: { width, height } });
  page.on("console", (m) => m.type() === "error" && out.errors.push(m.text()));
  page.on("pageerror", (e) => out.errors.push(String(e)));
  const t0 = Date.now();
  await page.goto(origin + "/index.html");
  await page.waitForFunction(() => document.body.dataset.ready === "1", null, { timeout: 300000 });
  out.loadSeconds = (Date.now() - t0) / 1000;
  // the first frames upload the geometry and compile the shaders: timed apart, then N frames
  out.firstFrames = await page.evaluate(() => {
    const gl = document.querySelector("canvas").getContext("webgl2");
    const t = [];
    for (let i = 0; i < 3; i++) {
      const t0 = performance.now();
      app.render();
      gl.finish();
      t.push(Math.round(performance.now() - t0));
    }
    return t;
  });
  Object.assign(out, await page.evaluate((n) => app.frameTimes(n), frames));
  // the same with a one-pixel readPixels after each frame: the pixels must exist, whatever
  // gl.finish waits for; at rest, then as while the camera moves (app.interactive), then also
  // turning the camera 0.01 rad about its target before each frame (the level of detail
  // follows; SwiftShader takes about twice as long for a frame whose view changed)
  const timed = (moving, turning = false) =>
    page.evaluate(
      ([n, mv, turn]) => {
        const gl = document.querySelector("canvas").getContext("webgl2");
        app.interactive(mv);
        const px = new Uint8Array(4), t = [];
        for (let i = 0; i < n; i++) {
          const t0 = performance.now();
          if (turn) app.turn(0.01);
          app.render();
          gl.readPixels(0, 0, 1, 1, gl.RGBA, gl.UNSIGNED_BYTE, px);
          t.push(performance.now() - t0);
        }
        app.interactive(false);
        t.sort((a, b) => a - b);
        return { median: t[Math.floor(n / 2)], p95: t[Math.floor(n * 0.95)], max: t[n - 1] };
      },
      [frames, moving, turning],
    );
  out.readback = await timed(false);
  out.moving = await timed(true);
  out.turning = await timed(true, true);
  out.software = await page.evaluate(() => app.software);
  // level of detail: units drawn in full here; then the same at street level (walk mode, eye
  // height, facing the middle unit of data.json's lodGroups: a temple of the city)
  const lodOf = () =>
    page.evaluate(() => {
      const s = app.lod();
      const full = s.groups.filter((g) => g.inView && g.level && g.proxy < g.full); // two levels
      const kinds = {};
      for (const g of full) {
        const k = app.data.lodGroups.includes(g.key) ? g.key : g.key.replace(/\[\d+\]$/, "");
        kinds[k] = (kinds[k] || 0) + 1;
      }
      return { units: s.groups.length, inView: s.groups.filter((g) => g.inView).length, full: kinds, budget: s.budget };
    });
  out.lod = await lodOf();
  if (!process.argv.includes("--no-street")) {
    await page.evaluate(() => app.streetView(app.data.lodGroups[Math.floor(app.data.lodGroups.length / 2)]));
    const street = await page.evaluate((n) => app.frameTimes(n), Math.min(frames, 3));
    street.readback = await timed(false);
    street.moving = await timed(true);
    street.turning = await timed(true, true);
    street.lod = await lodOf();
    out.street = street;
  }
} finally {
  await browser.close();
  server.close();
}
console.log("FRAMES " + JSON.stringify(out));
