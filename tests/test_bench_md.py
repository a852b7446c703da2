"""tools/bench_md.py: a benchmark's printed output becomes the Markdown page the docs include."""

from __future__ import annotations

import sys
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT / "tools"))
try:
    import bench_md
finally:
    sys.path.pop(0)


def test_markdown_flag_is_taken_off_the_command_line():
    assert bench_md.split_markdown_flag(["--repeat", "3", "--markdown", "o.md"]) == (
        ["--repeat", "3"],
        Path("o.md"),
    )
    assert bench_md.split_markdown_flag(["--markdown=x/o.md"]) == ([], Path("x/o.md"))
    assert bench_md.split_markdown_flag(["--repeat", "3"]) == (["--repeat", "3"], None)
    with pytest.raises(SystemExit):
        bench_md.split_markdown_flag(["--markdown"])


def test_run_writes_what_main_printed_only_on_success(tmp_path, monkeypatch, capsys):
    out = tmp_path / "bench" / "x.md"
    script = str(ROOT / "tools" / "bench_x.py")
    seen = []

    def main() -> int:
        seen.append(list(sys.argv[1:]))
        print("case  ms\nfast  1.5")
        return 0

    monkeypatch.setattr(sys, "argv", [script, "--repeat", "2", "--markdown", str(out)])
    assert bench_md.run(main) == 0
    assert seen == [["--repeat", "2"]]  # the script never sees --markdown
    text = out.read_text("utf-8")
    assert "`python tools/bench_x.py --repeat 2`" in text
    assert "```text\ncase  ms\nfast  1.5\n```" in text
    assert "case  ms" in capsys.readouterr().out  # the terminal still gets it

    def failing() -> int:
        print("half a table")
        return 3

    out.unlink()
    monkeypatch.setattr(sys, "argv", [script, "--markdown", str(out)])
    assert bench_md.run(failing) == 3
    assert not out.exists()
