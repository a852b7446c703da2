#!/usr/bin/env bash
# Check ionic-usd's exports with real clients (CI runs this as its own step):
#   1. the Khronos glTF-Validator (npm gltf-validator) on every exported .glb/.gltf: 0 errors;
#   2. three.js's GLTFLoader in headless Chromium (playwright-core) loads the temple and renders
#      a non-empty textured picture (saved as docs/export_threejs.png unless PNG= is given);
#      the default temple.glb draws the same triangles with and without three.js's
#      EXT_mesh_gpu_instancing plugin (it needs no extension), and its draw calls are printed;
#   3. Blender (bpy 5.0.1) imports the temple .glb with every triangle and its textures, and
#      the temple .usdz with every mesh, its textures, and no mesh with normals twice;
#   4. the .usdz packages pass pxr.UsdValidation (the exporter refuses to write one that fails);
#      the ARKit profile is tools/check_arkit.sh (CI step 5b).
#
# Usage (from anywhere; the project's Python environment active):
#   tools/check_export.sh                 # builds a temple and a 4 x 4 city in a temp folder
#   KEEP=out/check tools/check_export.sh  # keep the scenes, exports and validator reports there
# Environment: PYTHON (default python), CHROMIUM (default /usr/bin/chromium; installed with
# apt-get if missing and we are root), IONIC_USD_BPY_PYTHON (Python with bpy; default
# /work/venv-bpy/bin/python), PNG (picture path), TEXTURE_SIZE (default 512).
# Exit status: 0 when every check passes, 1 otherwise.
set -euo pipefail

ROOT="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
PY="${PYTHON:-python}"
export PYTHONPATH="$ROOT${PYTHONPATH:+:$PYTHONPATH}"
CHROMIUM="${CHROMIUM:-/usr/bin/chromium}"
PNG="${PNG:-$ROOT/docs/export_threejs.png}"
TEX="${TEXTURE_SIZE:-512}"
if [[ -n "${KEEP:-}" ]]; then
  WORK="$KEEP"; mkdir -p "$WORK"
else
  WORK="$(mktemp -d -t ionic_usd_check_export.XXXXXX)"; trap 'rm -rf "$WORK"' EXIT
fi
export IONIC_USD_CACHE="${IONIC_USD_CACHE:-$WORK/cache}"
t0=$SECONDS
fail=0
step() { echo; echo "== $* ($((SECONDS - t0)) s)"; }

step "tools: npm ci (gltf-validator, three, playwright-core), chromium"
(cd "$ROOT/tools/node" && npm ci --no-audit --no-fund --loglevel=error)
if [[ ! -x "$CHROMIUM" ]]; then
  if [[ $(id -u) -eq 0 ]]; then
    apt-get update -qq && apt-get install -y -qq chromium >/dev/null
  else
    echo "no Chromium at $CHROMIUM (apt-get install chromium, or set CHROMIUM=)"; exit 1
  fi
fi

step "scenes: temple (texture $TEX px), 4 x 4 city, column"
cli() { "$PY" -m ionic_usd.cli "$@"; }
cli temple -o "$WORK/city/PortunusTemple" --texture-size "$TEX" --force
cli city "$WORK/city" --rows 4 --cols 4 --temple portunus --force
cli column -o "$WORK/column.usda" --force
TEMPLE="$WORK/city/PortunusTemple/Temple.usda"
CITY="$WORK/city/City.usda"

step "exports"
E="$WORK/export"; mkdir -p "$E"
cli export "$TEMPLE" -o "$E/temple.glb" --force
cli export "$TEMPLE" -o "$E/temple_gpu.glb" --gpu-instancing --force
cli export "$TEMPLE" -o "$E/temple_unmerged.glb" --no-merge --force
cli export "$TEMPLE" -o "$E/temple.gltf" --force
cli export "$TEMPLE" -o "$E/temple_bare_stone.glb" --variant hyp_finish_bare_stone=alternative --force
cli export "$TEMPLE" -o "$E/temple_low.glb" --lod low --force
cli export "$TEMPLE" -o "$E/temple_reliability.glb" --variant view=reliability --lod low --force
cli export "$TEMPLE" -o "$E/temple_draco.glb" --compress draco --force
cli export "$CITY" -o "$E/city.glb" --force
cli export "$CITY" -o "$E/city_low.glb" --lod low --force
cli export "$WORK/city/PortunusTemple/IonicColumn/IonicColumn.usda" -o "$E/asset.glb" --force
cli export "$WORK/column.usda" -o "$E/column.glb" --force
cli export "$TEMPLE" -o "$E/temple.usdz" --force || fail=1
cli export "$CITY" -o "$E/city.usdz" --lod low --force || fail=1
cli export "$WORK/column.usda" -o "$E/column.stl" --scale 1:20 --force || fail=1

step "Khronos glTF-Validator"
node "$ROOT/tools/node/validate.mjs" --json "$E/validator_reports.json" "$E"/*.glb "$E"/*.gltf \
  || fail=1

step "three.js GLTFLoader in headless Chromium"
mkdir -p "$(dirname "$PNG")"
node "$ROOT/tools/node/render.mjs" "$E/temple_bare_stone.glb" "$PNG" --chromium "$CHROMIUM" \
  || fail=1
node "$ROOT/tools/node/render.mjs" "$E/temple_draco.glb" "$E/temple_draco.png" \
  --chromium "$CHROMIUM" || fail=1  # Draco decoded by three.js's DRACOLoader
for f in temple temple_unmerged; do
  node "$ROOT/tools/node/render.mjs" "$E/$f.glb" "$E/$f.png" --chromium "$CHROMIUM" \
    --json "$E/$f.with.json" || fail=1
done
node "$ROOT/tools/node/render.mjs" "$E/temple.glb" "$E/temple_without.png" --chromium "$CHROMIUM" \
  --without EXT_mesh_gpu_instancing --json "$E/temple.without.json" || fail=1
"$PY" - "$E" <<'EOF2' || fail=1
import json, sys
e = sys.argv[1]
w, wo, un = (json.load(open(f"{e}/{n}.json")) for n in 
    ("temple.with", "temple.without", "temple_unmerged.with"))
print(f"three.js draw calls for the temple: {un['drawCalls']} one node per copy (--no-merge), "
      f"{w['drawCalls']} merged (default)")
print(f"triangles drawn with / without EXT_mesh_gpu_instancing: {w['trianglesDrawn']:,} / "
      f"{wo['trianglesDrawn']:,}")
sys.exit(0 if w["trianglesDrawn"] == wo["trianglesDrawn"] == un["trianglesDrawn"] else 1)
EOF2

step "Blender import"
TRIS=$("$PY" -c "from ionic_usd.usd.reader import read_scene; print(read_scene('$TEMPLE').n_triangles)")
"$PY" "$ROOT/tools/blender_glb_check.py" "$E/temple.glb" --triangles "$TRIS" || fail=1
"$PY" "$ROOT/tools/blender_check.py" "$E/temple.usdz" --no-duplicate-normals --instances 18 \
  | grep -v '^    ' || fail=1

step "done: $([[ $fail -eq 0 ]] && echo 'all checks passed' || echo 'SOME CHECKS FAILED')"
exit $fail
