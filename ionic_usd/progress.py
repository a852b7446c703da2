"""Progress bars and log messages on stderr for the commands that take more than a second.

Library code calls :func:`progress` (a `tqdm`_ bar) or logs through :mod:`logging`
(``logging.getLogger(__name__)``); the command line sets the verbosity once with
:func:`configure`. Bars draw only when stderr is a terminal and the user did not ask for
``--quiet``, so pipelines, CI logs and redirected output stay clean.

.. _tqdm: https://tqdm.github.io/

Examples
--------
>>> from ionic_usd.progress import progress
>>> with progress(3, "unwrapping UVs", unit="mesh") as bar:
...     for _ in range(3):
...         bar.update(1)
"""

from __future__ import annotations

import logging
import sys
from collections.abc import Iterator
from contextlib import contextmanager
from typing import Any

__all__ = ["configure", "progress", "bars_enabled"]

_LOG_FORMAT = "ionic-usd: %(message)s"
_state: dict[str, Any] = {"verbosity": 0}


def configure(verbosity: int = 0) -> None:
    """Set the command line's verbosity: −1 quiet, 0 default, 1 ``-v``, 2 ``-vv`` or more.

    Quiet shows errors only and no bars; the default shows warnings and bars on a terminal;
    ``-v`` adds what each step does (info), ``-vv`` debugging detail.
    """
    _state["verbosity"] = int(verbosity)
    level = {-1: logging.ERROR, 0: logging.WARNING, 1: logging.INFO}.get(
        max(-1, min(int(verbosity), 2)), logging.DEBUG
    )
    root = logging.getLogger("ionic_usd")
    root.setLevel(level)
    if not any(getattr(h, "_ionic_usd", False) for h in root.handlers):
        handler = logging.StreamHandler(sys.stderr)
        handler.setFormatter(logging.Formatter(_LOG_FORMAT))
        handler._ionic_usd = True  # type: ignore[attr-defined]
        root.addHandler(handler)
        root.propagate = False


def bars_enabled() -> bool:
    """True when progress bars should draw: not quiet, and stderr is a terminal."""
    stream = sys.stderr
    return _state["verbosity"] >= 0 and bool(getattr(stream, "isatty", lambda: False)())


def _plural(noun: str) -> str:
    """English plural of a unit's name: mesh → meshes, material → materials."""
    return noun + ("es" if noun.endswith(("s", "sh", "ch", "x")) else "s")


@contextmanager
def progress(total: int | None, desc: str, *, unit: str = "step") -> Iterator[Any]:
    """A progress bar on stderr over ``total`` steps; call ``.update(n)`` on what it yields.

    Parameters
    ----------
    total : int or None
        Number of steps (None: unknown, the bar counts up).
    desc : str
        What is being done, e.g. ``"unwrapping UVs"``.
    unit : str
        Name of one step, e.g. ``"mesh"``.
    """
    logging.getLogger("ionic_usd").info(
        "%s (%s %s)", desc, "?" if total is None else total, unit if total == 1 else _plural(unit)
    )
    from tqdm import tqdm

    bar = tqdm(
        total=total,
        desc=desc,
        unit=unit,
        disable=not bars_enabled(),
        leave=False,
        file=sys.stderr,
        dynamic_ncols=True,
    )
    try:
        yield bar
    finally:
        bar.close()
