// Level of detail of a site written by `ionic-usd web`, in headless Chromium (playwright-core,
// SwiftShader): the units, their triangles in full and at the far level and the triangles drawn
// from the site's own camera; then, for each unit named with --focus, the same with the camera
// on that unit (app.focus), what a click at the middle of the view picks and whether the
// reliability view changes the picture and switches back exactly, and the same unit at street
// level (app.streetView). Prints one JSON line "LOD {...}".
//
//   node web_lod.mjs SITE_DIR [--focus /City/Temples/Temple_0_0 ...]
import fs from "node:fs";
import http from "node:http";
import path from "node:path";
import { chromium } from "playwright-core";

const args = process.argv.slice(2);
const focus = [];
for (let i = args.indexOf("--focus"); i >= 0; i = args.indexOf("--focus")) focus.push(args.splice(i, 2)[1]);
const exe = process.env.CHROMIUM || "/usr/bin/chromium";
const [site] = args;
if (!site) {
  console.error("usage: node web_lod.mjs SITE_DIR [--focus UNIT ...]");
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
const out = { errors: [], focus: {} };
try {
  const page = await browser.newPage({ viewport: { width: 1024, height: 640 } });
  page.on("console", (m) => m.type() === "error" && out.errors.push(m.text()));
  page.on("pageerror", (e) => out.errors.push(String(e)));
  await page.goto(origin + "/index.html");
  await page.waitForFunction(() => document.body.dataset.ready === "1", null, { timeout: 600000 });
  out.home = await page.evaluate(() => (app.render(), app.lod()));
  for (const key of focus) {
    out.focus[key] = await page.evaluate((k) => {
      app.focus(k);
      const s = app.lod();
      const rec = app.pick(0, 0);
      // the reliability view recolours both levels and switches back exactly
      app.snapshot("a");
      app.setView("reliability");
      app.snapshot("r");
      app.setView("appearance");
      app.snapshot("b");
      const rel = { changed: app.diff("a", "r", null).outside, restored: app.diff("a", "b", null).outside === 0 };
      app.streetView(k);
      const st = app.lod();
      return {
        triangles: s.triangles, unit: s.groups.find((g) => g.key === k), picked: rec ? rec.path : "", reliability: rel,
        street: { triangles: st.triangles, unit: st.groups.find((g) => g.key === k) },
      };
    }, key);
  }
} finally {
  await browser.close();
  server.close();
}
console.log("LOD " + JSON.stringify(out));
