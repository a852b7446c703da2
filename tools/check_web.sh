#!/usr/bin/env bash
# The browser checks of `ionic-usd web` (CI runs this): npm ci in tools/node (three.js,
# playwright-core), Chromium from apt where missing, then the slow tests of tests/test_web.py.
# With DOCS=1 it also builds the default temple, writes its site and saves the screenshots
# docs/web_appearance.png and docs/web_reliability.png, printing the check's JSON (frame times).
set -euo pipefail
ROOT="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
PY="${PYTHON:-python}"
CHROMIUM="${CHROMIUM:-/usr/bin/chromium}"
(cd "$ROOT/tools/node" && npm ci --no-audit --no-fund --loglevel=error)
if [[ ! -x "$CHROMIUM" ]]; then
  if [[ $(id -u) -eq 0 ]]; then
    apt-get update -qq && apt-get install -y -qq chromium >/dev/null
  else
    echo "no Chromium at $CHROMIUM (apt-get install chromium, or set CHROMIUM=)"; exit 1
  fi
fi
export CHROMIUM
cd "$ROOT"
"$PY" -m pytest -q -p no:cacheprovider -m slow tests/test_web.py -rs
if [[ "${DOCS:-0}" == 1 ]]; then
  WORK="$(mktemp -d)"; trap 'rm -rf "$WORK"' EXIT
  "$PY" -m ionic_usd temple -o "$WORK/PortunusTemple" --force -q
  "$PY" -m ionic_usd web "$WORK/PortunusTemple/Temple.usda" -o "$WORK/site" --force
  node tools/node/web_check.mjs "$WORK/site" --shots docs --width 1024 --height 640 | grep RESULT
fi
