"""Print the README's quick-start commands, so CI runs exactly what a new user reads.

``python tools/quickstart.py 1`` prints the first command of the fenced ``bash`` block under
"## Quick start" in README.md; ``2`` the second. Exit status 1 when the block is missing or has
another number of commands than two.
"""

from __future__ import annotations

import re
import sys
from pathlib import Path

README = Path(__file__).resolve().parent.parent / "README.md"


def quickstart_commands(text: str) -> list[str]:
    """The non-empty, non-comment lines of the first ```bash block after '## Quick start'."""
    section = re.search(r"^## Quick start\s*$(.*?)(?=^## )", text, re.M | re.S)
    if not section:
        return []
    block = re.search(r"^```bash\s*$(.*?)^```", section.group(1), re.M | re.S)
    if not block:
        return []
    lines = [ln.strip() for ln in block.group(1).splitlines()]
    return [ln for ln in lines if ln and not ln.startswith("#")]


def main(argv: list[str]) -> int:
    cmds = quickstart_commands(README.read_text(encoding="utf-8"))
    if len(cmds) != 2 or len(argv) != 1 or argv[0] not in ("1", "2"):
        print(
            f"quickstart: expected two commands and an argument 1 or 2, found {cmds!r}",
            file=sys.stderr,
        )
        return 1
    print(cmds[int(argv[0]) - 1])
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
