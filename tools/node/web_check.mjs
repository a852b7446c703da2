// Check a site written by `ionic-usd web` in headless Chromium (playwright-core): it loads
// with no console error and no request leaving the site; every hypothesis toggle changes the
// drawn image inside the screen box of what it draws or hides and nowhere else, and toggling it
// off restores the image exactly; the reliability view recolours the temple; a click on a part
// shows its paradata; the permalink restores view, hypotheses and selection; frame times.
// Prints one JSON line "RESULT {...}"; writes screenshots when --shots DIR is given.
//
//   node web_check.mjs SITE_DIR [--shots DIR] [--width 1280 --height 800]
import fs from "node:fs";
import http from "node:http";
import path from "node:path";
import { chromium } from "playwright-core";

const args = process.argv.slice(2);
const opt = (name, dflt) => {
  const i = args.indexOf(name);
  return i >= 0 ? args.splice(i, 2)[1] : dflt;
};
const width = Number(opt("--width", 1280));
const height = Number(opt("--height", 800));
const shots = opt("--shots", "");
const exe = opt("--chromium", process.env.CHROMIUM || "/usr/bin/chromium");
const [site] = args;
if (!site) {
  console.error("usage: node web_check.mjs SITE_DIR [--shots DIR]");
  process.exit(2);
}
const types = { ".html": "text/html", ".js": "text/javascript", ".css": "text/css", ".json": "application/json", ".glb": "model/gltf-binary" };
const server = http.createServer((req, res) => {
  const p = path.join(site, decodeURIComponent(new URL(req.url, "http://x").pathname));
  if (!p.startsWith(path.resolve(site)) && !path.resolve(p).startsWith(path.resolve(site))) return res.writeHead(403).end();
  const f = fs.existsSync(p) && fs.statSync(p).isDirectory() ? path.join(p, "index.html") : p;
  if (!fs.existsSync(f)) return res.writeHead(404).end();
  res.writeHead(200, { "content-type": types[path.extname(f)] || "application/octet-stream" });
  fs.createReadStream(f).pipe(res);
});
await new Promise((r) => server.listen(0, "127.0.0.1", r));
const origin = `http://127.0.0.1:${server.address().port}`;
const browser = await chromium.launch({ executablePath: exe, args: ["--use-angle=swiftshader", "--enable-unsafe-swiftshader", "--ignore-gpu-blocklist"] });
const out = { errors: [], outside: [], hypotheses: {} };
try {
  const page = await browser.newPage({ viewport: { width, height } });
  page.on("console", (m) => m.type() === "error" && out.errors.push(m.text()));
  page.on("pageerror", (e) => out.errors.push(String(e)));
  page.on("request", (r) => !r.url().startsWith(origin) && !r.url().startsWith("data:") && !r.url().startsWith("blob:") && out.outside.push(r.url()));
  const t0 = Date.now();
  await page.goto(origin + "/index.html");
  await page.waitForFunction(() => document.body.dataset.ready === "1", null, { timeout: 240000 });
  out.loadSeconds = (Date.now() - t0) / 1000;
  const ids = await page.evaluate(() => app.data.hypotheses.filter((h) => h.glb).map((h) => h.id));
  await page.evaluate(() => app.snapshot("base"));
  for (const id of ids) {
    out.hypotheses[id] = await page.evaluate((id) => {
      app.setHypothesis(id, true);
      app.snapshot("on");
      const box = app.screenBox(id);
      const d = app.diff("base", "on", box);
      app.setHypothesis(id, false);
      app.snapshot("off");
      const back = app.diff("base", "off", null);
      return { box, inside: d.inside, outside: d.outside, restored: back.outside + back.inside === 0 };
    }, id);
  }
  console.error("toggles", JSON.stringify(out.hypotheses), (Date.now() - t0) / 1000);
  out.reliability = await page.evaluate(() => {
    app.setView("reliability");
    app.snapshot("rel");
    const d = app.diff("base", "rel", null);
    app.setView("appearance");
    app.snapshot("app");
    const back = app.diff("base", "app", null);
    return { changed: d.outside, restored: back.outside === 0 };
  });
  out.frameTimes = await page.evaluate(() => app.frameTimes(30));
  console.error("frames", JSON.stringify(out.frameTimes), (Date.now() - t0) / 1000);
  // clicks on parts: the panel shows the record of what was hit
  const targets = await page.evaluate(() => {
    const pts = [];
    const want = ["/Temple/Podium/step_05", "/Temple/Podium/die", "/Temple/Colonnade/Free/front_2", "/Temple/Roof/roof_right", "/Temple/Entablature/frieze"];
    for (const p of want) {
      const c = app.data.centres && app.data.centres[p];
      if (c) pts.push([p, app.project(c)]);
    }
    return pts;
  });
  out.clicks = [];
  for (const [want, [x, y]] of targets) {
    await page.mouse.click(x, y);
    const shown = await page.evaluate(() => {
      const f = {};
      for (const el of document.querySelectorAll("#part [data-field]")) f[el.dataset.field] = el.innerText;
      return f;
    });
    out.clicks.push({ want, shown });
  }
  // permalink: reliability, one hypothesis, a selection; reopened in a new page
  const hash = await page.evaluate((id) => {
    app.setView("reliability");
    if (id) app.setHypothesis(id, true);
    app.select("/Temple/Podium/die");
    return { hash: location.hash, state: app.state() };
  }, ids[ids.length - 1]);
  if (shots) {
    fs.mkdirSync(shots, { recursive: true });
    await page.screenshot({ path: path.join(shots, "web_reliability.png"), timeout: 300000 });
  }
  const page2 = await browser.newPage({ viewport: { width, height } });
  page2.on("pageerror", (e) => out.errors.push(String(e)));
  await page2.goto(origin + "/index.html" + hash.hash);
  await page2.waitForFunction(() => document.body.dataset.ready === "1", null, { timeout: 240000 });
  out.permalink = { hash: hash.hash, state: hash.state, reopened: await page2.evaluate(() => app.state()) };
  // the reopened page draws the same image as the page that made the permalink (its camera
  // as the link rounds it)
  await page.evaluate((h) => {
    const c = new URLSearchParams(h.slice(1)).get("c").split(",").map(Number);
    app.setCamera(c);
  }, hash.hash);
  const h1 = await page.evaluate(() => { app.snapshot("p"); return app.hash("p"); });
  const h2 = await page2.evaluate(() => { app.snapshot("p"); return app.hash("p"); });
  out.permalink.same = h1 === h2;
  if (shots) {
    await page2.evaluate(() => {
      app.setView("appearance");
      for (const h of app.state().hyps) app.setHypothesis(h, false);
      app.select("/Temple/Colonnade/Free/front_2");
    });
    await page2.screenshot({ path: path.join(shots, "web_appearance.png"), timeout: 300000 });
  }
} finally {
  await browser.close();
  server.close();
}
console.log("RESULT " + JSON.stringify(out));
