"""The package's layering, read from the code's own imports (ast, nothing imported).

- the library never imports the command line: only ``ionic_usd/cli/`` (and ``__main__.py``)
  import ``ionic_usd.cli``;
- ``pxr`` is imported only under ``ionic_usd/usd/``.
"""

from __future__ import annotations

import ast
from pathlib import Path

PACKAGE = Path(__file__).resolve().parents[1] / "ionic_usd"


def _module_name(path: Path) -> str:
    rel = path.relative_to(PACKAGE.parent).with_suffix("")
    parts = list(rel.parts)
    if parts[-1] == "__init__":
        parts.pop()
    return ".".join(parts)


def _imports(path: Path) -> set[str]:
    """Every module ``path`` imports, at any depth (inside functions and ``TYPE_CHECKING`` too):
    ``from a.b import c`` counts as ``a.b`` and ``a.b.c`` (``c`` may be a submodule)."""
    tree = ast.parse(path.read_text(encoding="utf-8"), filename=str(path))
    package = _module_name(path).split(".")
    if path.name != "__init__.py":
        package = package[:-1]
    out: set[str] = set()
    for node in ast.walk(tree):
        if isinstance(node, ast.Import):
            out.update(alias.name for alias in node.names)
        elif isinstance(node, ast.ImportFrom):
            base = node.module or ""
            if node.level:
                stem = package[: len(package) - node.level + 1]
                base = ".".join([*stem, base] if base else stem)
            out.add(base)
            out.update(f"{base}.{alias.name}" for alias in node.names)
    return out


def _library_files() -> list[Path]:
    return sorted(PACKAGE.rglob("*.py"))


def _is_cli(path: Path) -> bool:
    rel = path.relative_to(PACKAGE)
    return rel.parts[0] == "cli" or rel == Path("__main__.py")


def _names(module: str, root: str) -> bool:
    return module == root or module.startswith(root + ".")


def test_the_walk_sees_the_cli_and_its_imports():
    """The reader of imports is itself checked: the CLI package imports its flags, the
    command modules lazily import the library (inside functions), ``__main__`` the CLI."""
    cli = PACKAGE / "cli" / "__init__.py"
    assert "ionic_usd.cli.flags" in _imports(cli)
    assert "ionic_usd.cli.city" in _imports(cli)  # imported inside _add_city
    assert "ionic_usd.cli" in _imports(PACKAGE / "__main__.py")
    assert _is_cli(cli) and not _is_cli(PACKAGE / "api.py")
    assert _module_name(PACKAGE / "usd" / "stage.py") == "ionic_usd.usd.stage"


def test_the_library_never_imports_the_cli():
    offenders = [
        f"{path.relative_to(PACKAGE.parent)} imports {module}"
        for path in _library_files()
        if not _is_cli(path)
        for module in sorted(_imports(path))
        if _names(module, "ionic_usd.cli")
    ]
    assert offenders == []


def test_pxr_is_imported_only_under_usd():
    offenders = [
        f"{path.relative_to(PACKAGE.parent)} imports {module}"
        for path in _library_files()
        if path.relative_to(PACKAGE).parts[0] != "usd"
        for module in sorted(_imports(path))
        if _names(module, "pxr")
    ]
    assert offenders == []
