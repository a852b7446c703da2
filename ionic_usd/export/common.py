"""Output paths and atomic writes shared by the exporters."""

from __future__ import annotations

import os
from collections.abc import Callable
from pathlib import Path

from ionic_usd.errors import IonicError, ParameterError
from ionic_usd.io import atomic_path, check_output_file

__all__ = [
    "EXPORT_FORMATS",
    "MissingDependencyError",
    "check_export_path",
    "atomic_write",
    "require",
]


class MissingDependencyError(IonicError, RuntimeError):
    """An optional library an export needs is not installed (names what to install)."""


def require(module: str, what: str):
    """Import ``module`` or raise MissingDependencyError naming the ``export`` extra."""
    import importlib  # noqa: PLC0415

    try:
        return importlib.import_module(module)
    except ImportError:
        raise MissingDependencyError(
            f"{what} needs the Python package {module!r}: pip install 'ionic_usd[export]'"
        ) from None


EXPORT_FORMATS = (".glb", ".gltf", ".usdz", ".stl", ".3mf")


def check_export_path(path: str | os.PathLike, *, force: bool = False) -> Path:
    """An export path: a known extension, a file in an existing folder, no file unless
    ``force`` (and the refusals of :func:`ionic_usd.io.check_output_file`)."""
    p = check_output_file(path, force=force, what="--output", suffixes=EXPORT_FORMATS)
    if not p.parent.is_dir():
        raise ParameterError(
            "--output", str(p), f"a file in an existing folder ({p.parent} does not exist)"
        )
    return p


def atomic_write(path: Path, write: Callable[[Path], None]) -> Path:
    """Call ``write(tmp)`` on a temporary sibling of ``path``, then rename it into place: the
    package's one atomic writer (:func:`ionic_usd.io.atomic_path`; synced, stale temporaries
    of killed runs removed). A failure leaves no partial file and ``path`` untouched."""
    with atomic_path(path) as tmp:
        write(tmp)
    return Path(path)
