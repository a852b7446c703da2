#!/usr/bin/env bash
# Check the default temple's usdz against Apple's ARKit profile (CI runs this in step 5):
# usd-core 24.11 (the last line with UsdUtils.ComplianceChecker and its arkit rules) in a venv
# of its own, made in a temp folder; the temple built and exported with the project's Python;
# tools/arkit_check.py runs every ARKit rule on the package. Exit 1 on any error or failed check.
#
# Usage (from anywhere; the project's Python environment active):
#   tools/check_arkit.sh                       # builds the default temple in a temp folder
#   tools/check_arkit.sh some.usdz other.usdz  # checks these packages instead
# Environment: PYTHON (default python), ARKIT_PYTHON (a Python that already has usd-core
# 24.11: no venv is made), USD_CORE (default 24.11).
set -euo pipefail

ROOT="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
PY="${PYTHON:-python}"
export PYTHONPATH="$ROOT${PYTHONPATH:+:$PYTHONPATH}"
WORK="$(mktemp -d -t ionic_usd_check_arkit.XXXXXX)"
trap 'rm -rf "$WORK"' EXIT
export IONIC_USD_CACHE="${IONIC_USD_CACHE:-$WORK/cache}"

if [[ -z "${ARKIT_PYTHON:-}" ]]; then
  "$PY" -m venv "$WORK/venv"
  "$WORK/venv/bin/pip" install --quiet --disable-pip-version-check "usd-core==${USD_CORE:-24.11}"
  ARKIT_PYTHON="$WORK/venv/bin/python"
fi
# USD's own definitions of the preview shaders (the 24.x wheels lack the usdShaders plugin)
DEFS="$("$PY" -c 'import pathlib, pxr; print(pathlib.Path(pxr.__file__).parent /
  "pluginfo/usdShaders/resources/shaders/shaderDefs.usda")')"

if [[ $# -eq 0 ]]; then
  "$PY" -m ionic_usd.cli temple -o "$WORK/PortunusTemple" --force >/dev/null
  "$PY" -m ionic_usd.cli export "$WORK/PortunusTemple/Temple.usda" -o "$WORK/temple.usdz" --force
  set -- "$WORK/temple.usdz"
fi
"$ARKIT_PYTHON" "$ROOT/tools/arkit_check.py" --shader-defs "$DEFS" "$@"
