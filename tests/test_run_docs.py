"""tools/run_docs.py: which blocks of a page run, what is refused, how outputs are checked."""

from __future__ import annotations

import json
import struct
import sys
import zlib
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT / "tools"))
try:
    import run_docs as rd
finally:
    sys.path.pop(0)

PAGE = """# A page

Text with `ionic-usd inline --not-run`.

```bash
ionic-usd column -o c.usda --lod low
ionic-usd fit volute --reference examples/v.csv \\
    --json fit.json  # a comment
```

<!-- docs-run: skip installs packages -->
```bash
pip install .
```

```python
print("hello")
```

```toml
[not] = "run"
```

- a list item

    indented prose is fine
"""


def test_blocks_languages_lines_and_skip_markers():
    blocks, problems = rd.extract_blocks(PAGE, "p.md")
    assert problems == []
    assert [(b.lang, b.line, b.skip) for b in blocks] == [
        ("bash", 5, None),
        ("bash", 12, "installs packages"),
        ("python", 16, None),
    ]
    assert blocks[0].code.startswith("ionic-usd column -o c.usda --lod low\n")
    assert blocks[2].code == 'print("hello")\n'


@pytest.mark.parametrize(
    ("text", "needle"),
    [
        ("Run:\n\n    ionic-usd fit volute --reference x.csv\n", "indented command"),
        ("```bash\n$ ionic-usd temple\n```\n", "shell prompt"),
        ("```console\nionic-usd temple\n```\n", "```console"),
        ("<!-- docs-run: skip -->\n```bash\nls\n```\n", "needs a reason"),
        ("<!-- docs-run: later x -->\n```bash\nls\n```\n", "unknown marker"),
        ("```bash\nls\n", "never closed"),
    ],
)
def test_commands_that_would_not_run_are_refused(text, needle):
    _, problems = rd.extract_blocks(text, "p.md")
    assert len(problems) == 1 and needle in problems[0], problems


def test_named_outputs_follow_continuations_and_chains():
    code = (
        "ionic-usd fit volute --reference a.csv \\\n    --json fit.json --plot f.png\n"
        "ionic-usd city Forum --plan p.geojson && ionic-usd export Forum/City.usda -o f.glb\n"
        "# ionic-usd column -o commented.usda\n"
        "python -c 'print(1)' -o not-ours\n"
    )
    assert rd.named_outputs(code) == ["fit.json", "f.png", "Forum", "f.glb"]


def _png(width: int, height: int) -> bytes:
    def chunk(kind: bytes, data: bytes) -> bytes:
        return (
            struct.pack(">I", len(data)) + kind + data + struct.pack(">I", zlib.crc32(kind + data))
        )

    raw = b"".join(b"\0" + b"\0\0\0" * width for _ in range(height))
    ihdr = struct.pack(">IIBBBBB", width, height, 8, 2, 0, 0, 0)
    return (
        b"\x89PNG\r\n\x1a\n"
        + chunk(b"IHDR", ihdr)
        + chunk(b"IDAT", zlib.compress(raw))
        + chunk(b"IEND", b"")
    )


def test_check_file_opens_what_it_claims(tmp_path):
    good = {"a.json": json.dumps({"x": 1}), "a.toml": "x = 1\n"}
    for name, text in good.items():
        (tmp_path / name).write_text(text)
        assert rd.check_file(tmp_path / name) is None
    (tmp_path / "a.png").write_bytes(_png(3, 2))
    assert rd.check_file(tmp_path / "a.png") is None
    (tmp_path / "cut.png").write_bytes(_png(3, 2)[:40])
    (tmp_path / "bad.json").write_text('{"x": ')
    (tmp_path / "bad.toml").write_text("x = \n")
    (tmp_path / "bad.glb").write_bytes(b"glTF" + struct.pack("<II", 2, 999))
    (tmp_path / "bad.stl").write_bytes(b"\0" * 80 + struct.pack("<I", 3) + b"\0" * 10)
    (tmp_path / "bad.usda").write_text('#usda 1.0\ndef Xform "A" {\n')
    for name in ("cut.png", "bad.json", "bad.toml", "bad.glb", "bad.stl", "bad.usda"):
        assert rd.check_file(tmp_path / name), name


def test_every_page_of_the_repository_parses():
    pages = rd.doc_pages()
    assert ROOT / "README.md" in pages and ROOT / "docs" / "getting-started.md" in pages
    run = 0
    for page in pages:
        blocks, problems = rd.extract_blocks(page.read_text("utf-8"), page.name)
        assert problems == [], problems
        run += sum(1 for b in blocks if not b.skip)
    assert run >= 20
