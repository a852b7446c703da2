#!/usr/bin/env bash
# Frame times of `ionic-usd web` for the default temple and a 16-temple city (4 x 4 Portunus
# grid), in headless Chromium with SwiftShader software GL (tools/node/web_frames.mjs; needs
# `npm ci` in tools/node and Chromium, as tools/check_web.sh sets up). Prints one line per scene:
# load seconds, the first three frames (geometry upload, shader compile) and then N frames
# (render + gl.finish; again with a one-pixel readPixels): median, p95, max, draw calls,
# triangles; then per view (the default one, and street level: walk mode's eye facing a
# temple) the triangles and draw calls, the units (temples, street columns, stoa bays) drawn in
# full, and the times.
#
#   tools/web_frames.sh [FRAMES]      (default 30; 1024 x 640)
set -euo pipefail
ROOT="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
PY="${PYTHON:-python}"
N="${1:-30}"
WORK="$(mktemp -d)"; trap 'rm -rf "$WORK"' EXIT
cd "$WORK"
"$PY" -m ionic_usd temple -o T --force -q
"$PY" -m ionic_usd city C --rows 4 --cols 4 --temple portunus --force -q
for s in T/Temple.usda C/City.usda; do
  site="site-$(dirname "$s")"
  "$PY" -m ionic_usd web "$s" -o "$site" --force -q >/dev/null
  if ! line="$(timeout "${WEB_FRAMES_TIMEOUT:-300}" node "$ROOT/tools/node/web_frames.mjs" \
    "$site" --frames "$N" | grep '^FRAMES ')"; then
    echo "$s: not measured in ${WEB_FRAMES_TIMEOUT:-300} s (too slow to draw)"; continue
  fi
  "$PY" - "$s" "$(du -sm "$site" | cut -f1)" "$N" "${line#FRAMES }" <<'PYEOF'
import json, sys
scene, mb, n, r = sys.argv[1], sys.argv[2], sys.argv[3], json.loads(sys.argv[4])
print(
    f"{scene}: {r['triangles']:,} triangles, {r['calls']:,} draw calls, site {mb} MB, "
    f"loaded in {r['loadSeconds']:.1f} s; first frames {r['firstFrames']} ms; "
    f"{n} frames: median {r['median']:.1f} ms, p95 {r['p95']:.1f} ms, max {r['max']:.1f} ms"
    + f" (with a pixel read back: median {r['readback']['median']:.1f} ms, "
    f"p95 {r['readback']['p95']:.1f} ms; while the camera moves: median "
    f"{r['moving']['median']:.1f} ms, p95 {r['moving']['p95']:.1f} ms"
    + ("; software GL: no MSAA, half resolution while moving" if r["software"] else "")
    + ")"
    + (f"; {len(r['errors'])} console errors" if r["errors"] else "")
)
for name, v in (("default view", r), ("street level", r.get("street"))):
    if not v:
        continue
    lod = v["lod"]
    full = ", ".join(
        k.rsplit("/", 1)[-1] + (f" x{n}" if n > 1 else "") for k, n in lod["full"].items()
    )
    print(
        f"  {name}: {v['triangles']:,} triangles, {v['calls']:,} draw calls; "
        f"{lod['inView']:,} of {lod['units']:,} units in view, in full (of those with a far "
        f"level): {full or 'none'}; with a pixel read back: median {v['readback']['median']:.1f} ms, "
        f"p95 {v['readback']['p95']:.1f} ms; moving: median {v['moving']['median']:.1f} ms, "
        f"p95 {v['moving']['p95']:.1f} ms; turning: median {v['turning']['median']:.1f} ms, "
        f"p95 {v['turning']['p95']:.1f} ms"
    )
PYEOF
done
