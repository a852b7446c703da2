"""OpenUSD's ``Warning:`` lines, folded into the command's one-line error (issue 31).

OpenUSD prints its warnings (a sublayer that cannot be loaded, a reference that does not
resolve, a sublayer cycle) from C++ straight to file descriptor 2, ahead of the command's own
``ionic-usd: error: …`` line. :class:`UsdWarnings` points descriptor 2 at a pipe for the
duration of a command: a reader thread passes every other line through at once and keeps
OpenUSD's warnings; the command then either folds them into its one error line
(:meth:`fold`) or, when it succeeds, prints them as they were (:meth:`stop`).

Python's own ``sys.stderr`` is pointed back at the real stderr, so progress bars and log
messages are not delayed. Nothing is captured when ``sys.stderr`` is not descriptor 2 (a test
harness capturing it).
"""

from __future__ import annotations

import os
import re
import sys
import threading
from typing import Any

__all__ = ["UsdWarnings"]

_PREFIX = b"Warning: in "
_LOCATION = re.compile(r"^Warning: in .*? at line \d+ of \S+ -- ")
_CONTEXT = re.compile(r"\s*\((?:instantiating stage|in _|when).*\)\s*$")


def _summary(line: str) -> str:
    text = _LOCATION.sub("", line.strip())
    return _CONTEXT.sub("", text)


class UsdWarnings:
    """Capture OpenUSD's warnings on descriptor 2 between :meth:`start` and :meth:`stop`."""

    def __init__(self) -> None:
        self.lines: list[str] = []
        self._saved: int | None = None
        self._thread: threading.Thread | None = None
        self._stderr: Any = None
        self._own: Any = None

    def start(self) -> UsdWarnings:
        try:
            if sys.stderr is None or sys.stderr.fileno() != 2:
                return self
        except (AttributeError, OSError, ValueError):
            return self
        sys.stderr.flush()
        self._saved = os.dup(2)
        r, w = os.pipe()
        os.dup2(w, 2)
        os.close(w)
        self._stderr = sys.stderr
        self._own = open(  # noqa: SIM115 - closed in stop()
            os.dup(self._saved),
            "w",
            buffering=1,
            encoding=sys.stderr.encoding or "utf-8",
            errors="backslashreplace",
        )
        sys.stderr = self._own
        self._thread = threading.Thread(target=self._read, args=(r, self._saved), daemon=True)
        self._thread.start()
        return self

    def _read(self, r: int, out: int) -> None:
        with os.fdopen(r, "rb") as pipe:
            for raw in pipe:
                if raw.startswith(_PREFIX):
                    self.lines.append(raw.decode("utf-8", "replace").rstrip("\n"))
                else:
                    os.write(out, raw)

    def _finish(self) -> None:
        if self._saved is None:
            return
        with_own = self._own
        if with_own is not None:
            with_own.flush()
        os.dup2(self._saved, 2)  # the pipe's write end closes: the reader sees its end
        sys.stderr = self._stderr
        if self._thread is not None:
            self._thread.join(timeout=2.0)
        if with_own is not None:
            with_own.close()
        if self._thread is None or not self._thread.is_alive():
            os.close(self._saved)
        # else a child process still holds the pipe: the reader keeps passing its lines to
        # the saved descriptor, which stays open (closing it could let the number be reused)
        self._saved = None

    def stop(self) -> None:
        """Restore descriptor 2 and print the warnings kept (the command succeeded)."""
        self._finish()
        for line in self.lines:
            print(line, file=sys.stderr)
        self.lines = []

    def fold(self, message: str) -> str:
        """Restore descriptor 2 and return ``message`` with the warnings kept, summarised."""
        self._finish()
        if not self.lines:
            return message
        seen: list[str] = []
        for line in self.lines:
            s = _summary(line)
            if s not in seen:
                seen.append(s)
        more = f" and {len(seen) - 2} more" if len(seen) > 2 else ""
        self.lines = []
        return f"{message} (OpenUSD warned: {'; '.join(seen[:2])}{more})"
