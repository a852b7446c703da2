// Khronos glTF-Validator on each file given; prints one summary line per file (and the
// messages of errors and warnings), writes the full reports as JSON with --json FILE, and
// exits 1 if any file has an error.
import fs from "node:fs";
import path from "node:path";
import validator from "gltf-validator";

const args = process.argv.slice(2);
let jsonOut = null;
const files = [];
for (let i = 0; i < args.length; i++) {
  if (args[i] === "--json") jsonOut = args[++i];
  else files.push(args[i]);
}
if (!files.length) {
  console.error("usage: node validate.mjs [--json report.json] FILE.glb ...");
  process.exit(2);
}
let failed = false;
const reports = {};
for (const file of files) {
  const bytes = new Uint8Array(fs.readFileSync(file));
  const report = await validator.validateBytes(bytes, {
    uri: path.basename(file),
    maxIssues: 0,
    externalResourceFunction: (uri) =>
      Promise.resolve(new Uint8Array(fs.readFileSync(path.resolve(path.dirname(file), decodeURIComponent(uri))))),
  });
  reports[file] = report;
  const s = report.issues;
  const info = report.info || {};
  console.log(
    `${file}: ${s.numErrors} errors, ${s.numWarnings} warnings, ${s.numInfos} infos, ` +
      `${s.numHints} hints; ${info.drawCallCount} draw calls, ${info.totalTriangleCount} triangles, ` +
      `${info.totalVertexCount} vertices, ${info.materialCount} materials, ` +
      `extensions: ${(info.extensionsUsed || []).join(", ") || "none"}`
  );
  const shown = s.messages.filter((m) => m.severity <= 1);
  for (const m of shown.slice(0, 12)) {
    console.log(`  [${m.severity === 0 ? "error" : "warning"}] ${m.code} ${m.pointer || ""}: ${m.message}`);
  }
  if (shown.length > 12) console.log(`  … ${shown.length - 12} more errors and warnings (--json for all)`);
  if (s.numErrors > 0) failed = true;
}
if (jsonOut) fs.writeFileSync(jsonOut, JSON.stringify(reports, null, 1));
process.exit(failed ? 1 : 0);
