"""Run NVIDIA's USD validator on every layer of a temple or asset folder, one layer at a time.

NVIDIA's ``usd-validation-nvidia`` pins its own ``usd-core``, so it lives in its own virtual
environment::

    python -m venv /path/venv-nv
    /path/venv-nv/bin/pip install "usd-validation-nvidia[usd]"
    python tools/validate_nvidia.py PortunusTemple/ \
        --validator /path/venv-nv/bin/nvidia_usd_validate

Each layer is validated opened alone (``nvidia_usd_validate FILE --no-variants``: the
selected variants only; the project's own tests compose every variant with ``pxr``'s
validators). The report gives, per file, the issues by rule and severity with the first prims
named; the exit status is 1 when any file has a FAILURE or ERROR issue, 0 otherwise
(warnings are reported, not fatal). ``--json`` writes everything.
"""

from __future__ import annotations

import argparse
import json
import os
import shutil
import subprocess
import sys
import tempfile
import time
from collections import Counter, defaultdict
from pathlib import Path

LAYER_SUFFIXES = (".usda", ".usdc", ".usd")


def find_validator(given: str | None) -> str:
    for cand in (
        given,
        os.environ.get("IONIC_USD_NV_VALIDATE"),
        shutil.which("nvidia_usd_validate"),
        "/work/venv-nv/bin/nvidia_usd_validate",
    ):
        if cand and Path(cand).is_file():
            return cand
    sys.exit(
        "validate_nvidia: no nvidia_usd_validate found: pass --validator PATH or set "
        "IONIC_USD_NV_VALIDATE (pip install 'usd-validation-nvidia[usd]' in its own venv)"
    )


def validate(validator: str, path: Path, timeout: float, variants: bool = False) -> dict:
    """The validator's JSON report for one layer (``{"status", "rules": [...]}``); with
    ``variants`` every combination of every prim's variant sets (the validator's default)."""
    with tempfile.TemporaryDirectory() as tmp:
        out = Path(tmp) / "report.json"
        proc = subprocess.run(
            [
                validator,
                str(path),
                "--variants" if variants else "--no-variants",
                "--json-output",
                str(out),
            ],
            capture_output=True,
            text=True,
            timeout=timeout,
        )
        if not out.is_file():
            return {"status": "CRASH", "rules": [], "stderr": proc.stderr[-2000:]}
        return json.loads(out.read_text())


def summarise(report: dict) -> dict[str, dict[str, object]]:
    """rule → {"severity counts": Counter, "at": [first prim paths]}."""
    out: dict[str, dict[str, object]] = defaultdict(lambda: {"counts": Counter(), "at": []})
    for rule in report.get("rules", []):
        name = rule["rule"]["name"]
        for issue in rule.get("issues", []):
            entry = out[name]
            entry["counts"][issue.get("severity", "?")] += 1
            at = (issue.get("at") or {}).get("path")
            if at and len(entry["at"]) < 3:
                entry["at"].append(at)
    return out


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(
        description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter
    )
    ap.add_argument("folder", type=Path, help="a temple or asset folder (or one layer)")
    ap.add_argument("--validator", help="path of nvidia_usd_validate")
    ap.add_argument("--timeout", type=float, default=900.0, help="seconds per layer")
    ap.add_argument("--json", type=Path, help="write every report here")
    ap.add_argument(
        "--variants",
        action="store_true",
        help="validate every combination of every prim's variant sets (the validator's "
        "default; it composes their Cartesian product, instance prims included)",
    )
    args = ap.parse_args(argv)
    validator = find_validator(args.validator)
    root = args.folder
    files = (
        [root]
        if root.is_file()
        else sorted(f for f in root.rglob("*") if f.suffix in LAYER_SUFFIXES and f.is_file())
    )
    if not files:
        print(f"validate_nvidia: no USD layers under {root}", file=sys.stderr)
        return 2
    everything, bad = {}, False
    for f in files:
        name = f.name if root.is_file() else f.relative_to(root).as_posix()
        t0 = time.perf_counter()
        try:
            report = validate(validator, f, args.timeout, args.variants)
        except subprocess.TimeoutExpired:
            report = {"status": "TIMEOUT", "rules": []}
        everything[name] = report
        rules = summarise(report)
        totals = Counter()
        for r in rules.values():
            totals.update(r["counts"])
        fatal = report["status"] in ("CRASH", "TIMEOUT") or totals["FAILURE"] or totals["ERROR"]
        bad = bad or bool(fatal)
        counts = ", ".join(f"{n} {k.lower()}" for k, n in sorted(totals.items())) or "no issues"
        print(f"{name}: {report['status']} — {counts} ({time.perf_counter() - t0:.0f} s)")
        for rule, r in sorted(rules.items()):
            c = ", ".join(f"{n} {k.lower()}" for k, n in sorted(r["counts"].items()))
            more = " …" if sum(r["counts"].values()) > 3 else ""
            print(f"    {rule}: {c}; at {', '.join(r['at'])}{more}")
        if "stderr" in report:
            print("    " + report["stderr"].strip().replace("\n", "\n    "))
    if args.json:
        args.json.write_text(json.dumps(everything, indent=1))
    return 1 if bad else 0


if __name__ == "__main__":
    sys.exit(main())
