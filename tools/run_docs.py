"""Run every command line of README.md and docs/**/*.md as written, and check what it wrote.

Each page runs in a fresh scratch folder holding a copy of the repository's ``examples/``; its
fenced ``bash`` blocks run with ``bash -euo pipefail`` and its ``python`` blocks as scripts, one
block after another in page order, so a block may read what an earlier block of the same page
wrote. ``ionic-usd`` and ``python`` are this interpreter's (the environment running this script).
After each block every file it created or changed is opened: USD layers and packages with
``Usd.Stage.Open`` and ``pxr.UsdValidation`` (0 errors), JSON, TOML, PNG (header and size),
glTF/GLB, STL and 3MF by their structure; and every output a command names (``-o``, ``--json``,
``--plot``, ``--curves``, a city's folder) must exist.

Markers, an HTML comment on the line before a fence (invisible in the rendered page)::

    <!-- docs-run: skip REASON -->      the block is not run (REASON is required)

Indented command lines (``    ionic-usd ...``) and shell prompts (``$ ionic-usd``) are refused:
write commands in fenced ``bash`` blocks, so that they run.

    python tools/run_docs.py                 # every page
    python tools/run_docs.py docs/fitting.md # some pages
    python tools/run_docs.py --list          # the blocks, not run

Exit status 0 when every block ran and every output opened, 1 otherwise.
"""

from __future__ import annotations

import argparse
import json
import os
import re
import shlex
import shutil
import struct
import subprocess
import sys
import tempfile
import time
import tomllib
import zipfile
from dataclasses import dataclass
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent
LANGS = {"bash": "bash", "sh": "bash", "shell": "bash", "python": "python", "py": "python"}
REFUSED_LANGS = {"console", "shell-session", "sh-session", "pycon"}
FENCE = re.compile(r"^(?P<indent>\s*)(?P<fence>`{3,}|~{3,})\s*(?P<lang>[\w+-]*)")
MARKER = re.compile(r"^\s*<!--\s*docs-run:\s*(?P<word>\w+)\s*(?P<arg>.*?)\s*-->\s*$")
COMMAND = re.compile(r"^\s*(?:\$\s*)?(?:ionic-usd|python3?|pip)\s")
OUTPUT_FLAGS = {"-o", "--output", "--json", "--plot", "--curves", "--markdown"}
USD = {".usd", ".usda", ".usdc", ".usdz"}
BLOCK_TIMEOUT = 600


@dataclass(frozen=True)
class Block:
    """One fenced code block of a page."""

    page: str
    line: int  # 1-based line of the opening fence
    lang: str  # "bash" or "python"
    code: str
    skip: str | None = None  # the reason given by a skip marker


def extract_blocks(text: str, page: str = "") -> tuple[list[Block], list[str]]:
    """The runnable blocks of a Markdown page and the problems found while reading it."""
    blocks: list[Block] = []
    problems: list[str] = []
    lines = text.splitlines()
    i = 0
    while i < len(lines):
        m = FENCE.match(lines[i])
        if not m:
            _check_plain_line(lines, i, page, problems)
            i += 1
            continue
        start, indent, fence, lang = i, m["indent"], m["fence"], m["lang"].lower()
        body: list[str] = []
        i += 1
        while i < len(lines) and not lines[i].strip().startswith(fence):
            body.append(lines[i][len(indent) :] if lines[i].startswith(indent) else lines[i])
            i += 1
        if i == len(lines):
            problems.append(f"{page}:{start + 1}: code block never closed")
        i += 1
        where = f"{page}:{start + 1}"
        if lang in REFUSED_LANGS:
            problems.append(f"{where}: a ```{lang} block: write the commands in a ```bash block")
            continue
        if lang not in LANGS:
            continue
        skip = _marker(lines, start, where, problems)
        code = "\n".join(body) + "\n"
        if LANGS[lang] == "bash":
            problems += [
                f"{where}: a shell prompt in a bash block: {ln.strip()!r}"
                for ln in body
                if ln.lstrip().startswith("$ ")
            ]
        blocks.append(Block(page, start + 1, LANGS[lang], code, skip))
    return blocks, problems


def _check_plain_line(lines: list[str], i: int, page: str, problems: list[str]) -> None:
    """An indented code line holding a command (Markdown's other code block) is refused."""
    line = lines[i]
    if line.startswith(("    ", "\t")) and COMMAND.match(line):
        problems.append(
            f"{page}:{i + 1}: an indented command line: put it in a ```bash block "
            f"so that it runs: {line.strip()!r}"
        )


def _marker(lines: list[str], start: int, where: str, problems: list[str]) -> str | None:
    """The skip reason of the marker on the line before a fence (None: run the block)."""
    prev = lines[start - 1] if start > 0 else ""
    m = MARKER.match(prev)
    if not m:
        if "docs-run" in prev:
            problems.append(f"{where}: unreadable marker {prev.strip()!r}")
        return None
    if m["word"] != "skip":
        problems.append(f"{where}: unknown marker 'docs-run: {m['word']}' (only 'skip REASON')")
        return None
    if not m["arg"]:
        problems.append(f"{where}: 'docs-run: skip' needs a reason")
    return m["arg"] or "no reason"


def logical_lines(code: str) -> list[str]:
    """A shell block's commands: continuation lines joined, comments and blank lines dropped."""
    out: list[str] = []
    cur = ""
    for raw in code.splitlines():
        line = raw.rstrip()
        if line.endswith("\\"):
            cur += line[:-1] + " "
            continue
        cur += line
        if cur.strip() and not cur.lstrip().startswith("#"):
            out.append(cur.strip())
        cur = ""
    if cur.strip():
        out.append(cur.strip())
    return out


def named_outputs(code: str) -> list[str]:
    """Paths a block's ``ionic-usd`` commands name as outputs (they must exist afterwards)."""
    outs: list[str] = []
    for line in logical_lines(code):
        for command in re.split(r"\s*(?:&&|\|\||;)\s*", line):
            try:
                words = shlex.split(command, comments=True)
            except ValueError:
                continue
            if not words or words[0] != "ionic-usd":
                continue
            outs += [b for a, b in zip(words, words[1:], strict=False) if a in OUTPUT_FLAGS]
            if len(words) > 2 and words[1] == "city" and not words[2].startswith("-"):
                outs.append(words[2])
    return outs


def check_file(path: Path) -> str | None:
    """None when the file opens as what its extension says, else what is wrong."""
    suffix = path.suffix.lower()
    try:
        if suffix in USD:
            return _check_usd(path)
        if suffix in (".json", ".gltf"):
            doc = json.loads(path.read_text("utf-8"))
            if suffix == ".gltf" and "asset" not in doc:
                return "a .gltf without an asset object"
            return None
        if suffix == ".toml":
            tomllib.loads(path.read_text("utf-8"))
            return None
        if suffix == ".png":
            return _check_png(path.read_bytes())
        if suffix == ".glb":
            data = path.read_bytes()
            magic, version, length = (
                struct.unpack_from("<4sII", data) if len(data) >= 12 else (b"", 0, 0)
            )
            if magic != b"glTF" or version != 2 or length != len(data):
                return "not a glTF 2.0 binary of its own length"
            return None
        if suffix == ".stl":
            return _check_stl(path.read_bytes())
        if suffix == ".3mf":
            with zipfile.ZipFile(path) as z:
                bad = z.testzip()
                if bad or "3D/3dmodel.model" not in z.namelist():
                    return f"a 3MF without a readable 3D/3dmodel.model ({bad})"
            return None
    except (OSError, ValueError, UnicodeDecodeError, zipfile.BadZipFile) as exc:
        return f"does not open: {exc}"
    return None


def _check_png(data: bytes) -> str | None:
    if len(data) < 33 or data[:8] != b"\x89PNG\r\n\x1a\n" or data[12:16] != b"IHDR":
        return "not a PNG"
    width, height = struct.unpack(">II", data[16:24])
    if width == 0 or height == 0 or not data.rstrip(b"\0").endswith(b"IEND\xaeB`\x82"):
        return f"a PNG of {width} x {height} px without its end"
    return None


def _check_stl(data: bytes) -> str | None:
    if data[:5] == b"solid" and b"endsolid" in data[-300:]:
        return None
    if len(data) < 84:
        return "an STL shorter than its header"
    (count,) = struct.unpack_from("<I", data, 80)
    if count == 0 or len(data) != 84 + 50 * count:
        return f"a binary STL of {count} triangles in {len(data)} bytes"
    return None


def _check_usd(path: Path) -> str | None:
    from pxr import Usd  # noqa: PLC0415 - pxr only when a block wrote USD

    from ionic_usd.usd.stage import validate_stage  # noqa: PLC0415

    try:
        stage = Usd.Stage.Open(str(path))
    except Exception as exc:  # noqa: BLE001 - pxr raises Tf.ErrorException for a bad layer
        return f"USD cannot open it: {str(exc).strip().splitlines()[-1]}"
    if stage is None:
        return "USD cannot open it"
    errors = validate_stage(stage)
    return f"{len(errors)} validation errors: {errors[:3]}" if errors else None


def snapshot(folder: Path) -> dict[Path, tuple[int, int]]:
    """Every file under a folder with its (mtime_ns, size)."""
    out = {}
    for p in folder.rglob("*"):
        if p.is_file() and not p.is_symlink():
            st = p.stat()
            out[p] = (st.st_mtime_ns, st.st_size)
    return out


def shims(folder: Path) -> Path:
    """A bin folder whose ``ionic-usd`` and ``python`` are this interpreter's."""
    bin_dir = folder / "bin"
    bin_dir.mkdir()
    py = shlex.quote(sys.executable)
    for name, line in (
        ("ionic-usd", f'exec {py} -m ionic_usd "$@"'),
        ("python", f'exec {py} "$@"'),
        ("python3", f'exec {py} "$@"'),
    ):
        script = bin_dir / name
        script.write_text(f"#!/bin/sh\n{line}\n")
        script.chmod(0o755)
    return bin_dir


def run_block(block: Block, cwd: Path, env: dict[str, str], n: int) -> tuple[bool, str]:
    """Run one block in cwd; (ok, what went wrong or the last lines it printed)."""
    if block.lang == "python":
        script = cwd.parent / f"block_{n}.py"
        script.write_text(block.code, "utf-8")
        args = [sys.executable, str(script)]
    else:
        args = ["bash", "-euo", "pipefail", "-c", block.code]
    try:
        out = subprocess.run(
            args, cwd=cwd, env=env, capture_output=True, text=True, timeout=BLOCK_TIMEOUT
        )
    except subprocess.TimeoutExpired:
        return False, f"still running after {BLOCK_TIMEOUT} s"
    tail = (out.stdout + out.stderr).strip().splitlines()[-12:]
    if out.returncode != 0:
        return False, f"exit status {out.returncode}:\n    " + "\n    ".join(tail)
    return True, ""


def check_outputs(block: Block, cwd: Path, before: dict[Path, tuple[int, int]]) -> list[str]:
    """What is wrong with the files a block wrote (named outputs missing, files not opening)."""
    problems = []
    if block.lang == "bash":
        for name in named_outputs(block.code):
            if not (cwd / name).exists():
                problems.append(f"{name}: named as an output, not written")
    after = snapshot(cwd)
    changed = sorted(p for p, sig in after.items() if before.get(p) != sig)
    for path in changed:
        if any(part.startswith(".") for part in path.relative_to(cwd).parts[:-1]):
            continue  # staging, caches
        bad = check_file(path)
        if bad:
            problems.append(f"{path.relative_to(cwd)}: {bad}")
    return problems


def n_commands(block: Block) -> int:
    """Commands in a block: a bash block's command lines, or 1 for a python script."""
    return len(logical_lines(block.code)) if block.lang == "bash" else 1


def run_page(page: Path, blocks: list[Block], keep: bool) -> tuple[int, list[str]]:
    """Run a page's blocks in a fresh scratch folder; (commands run, failures)."""
    scratch = Path(tempfile.mkdtemp(prefix="ionic-docs-"))
    cwd = scratch / "work"
    shutil.copytree(ROOT / "examples", cwd / "examples")
    env = dict(os.environ, PATH=f"{shims(scratch)}{os.pathsep}{os.environ.get('PATH', '')}")
    env.setdefault("MPLBACKEND", "Agg")
    ran, failures = 0, []
    try:
        for n, block in enumerate(blocks):
            where = f"{block.page}:{block.line} ({block.lang})"
            if block.skip:
                print(f"  skip {where}: {block.skip}")
                continue
            t0 = time.perf_counter()
            before = snapshot(cwd)
            ok, why = run_block(block, cwd, env, n)
            ran += n_commands(block)
            bad = check_outputs(block, cwd, before) if ok else []
            status = "ok" if ok and not bad else "FAIL"
            print(f"  {status} {where} {time.perf_counter() - t0:.1f} s", flush=True)
            if not ok or bad:
                failures.append(f"{where}:\n{_indent(block.code)}\n  {why}{_lines(bad)}")
                break  # later blocks of the page may need this one's outputs
    finally:
        if keep:
            print(f"  kept {cwd}")
        else:
            shutil.rmtree(scratch, ignore_errors=True)
    return ran, failures


def _indent(code: str) -> str:
    return "\n".join("    " + ln for ln in code.rstrip().splitlines())


def _lines(items: list[str]) -> str:
    return "".join(f"\n  {s}" for s in items)


def doc_pages(root: Path = ROOT) -> list[Path]:
    """README.md and every Markdown page under docs/, in a stable order."""
    return [root / "README.md", *sorted((root / "docs").rglob("*.md"))]


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("pages", nargs="*", type=Path, help="pages to run (default: all)")
    ap.add_argument("--list", action="store_true", help="print the blocks, run nothing")
    ap.add_argument("--keep", action="store_true", help="keep the scratch folders")
    args = ap.parse_args(argv)
    pages = [p.resolve() for p in args.pages] or doc_pages()
    t0 = time.perf_counter()
    total, failures = 0, []
    for page in pages:
        rel = page.relative_to(ROOT) if page.is_relative_to(ROOT) else page
        blocks, problems = extract_blocks(page.read_text("utf-8"), str(rel))
        failures += problems
        print(f"{rel}: {len(blocks)} blocks", flush=True)
        if args.list:
            for b in blocks:
                print(f"  {b.line} {b.lang}{' (skip: ' + b.skip + ')' if b.skip else ''}")
                print(_indent(b.code))
            total += sum(n_commands(b) for b in blocks if not b.skip)
            continue
        if problems or not any(not b.skip for b in blocks):
            continue
        ran, bad = run_page(page, blocks, args.keep)
        total += ran
        failures += bad
    verb = "would run" if args.list else "ran"
    print(
        f"{verb} {total} commands (bash command lines and python scripts) of {len(pages)} pages "
        f"in {time.perf_counter() - t0:.0f} s"
    )
    for f in failures:
        print(f"FAILED {f}", file=sys.stderr)
    return 1 if failures else 0


if __name__ == "__main__":
    sys.exit(main())
