"""The package's layering, read from the code's own imports (ast, nothing imported).

- the library never imports the command line: only ``ionic_usd/cli/`` (and ``__main__.py``)
  import ``ionic_usd.cli``;
- ``pxr`` is imported only under ``ionic_usd/usd/``, and importing ``ionic_usd.blueprint`` (what to
  write) and ``ionic_usd.lod`` loads none (checked in a fresh interpreter);
- the levels of detail have one registry, :mod:`ionic_usd.lod`: no other module spells a
  table keyed by the level names;
- no function of the package is over 80 lines (the kernel's, the fits', the pipeline's, the
  writers' and the command line's alike).
"""

from __future__ import annotations

import ast
import subprocess
import sys
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


def test_blueprint_and_lod_import_without_pxr():
    """What to write, and the LOD registry, load no ``pxr`` (nor the writers): a mesh worker
    or the up-to-date check that needs a name or an option does not pay for USD."""
    modules = [
        "ionic_usd.blueprint",
        *(
            f"ionic_usd.blueprint.{p.stem}"
            for p in sorted((PACKAGE / "blueprint").glob("[!_]*.py"))
        ),
        "ionic_usd.lod",
        "ionic_usd.pipeline.asset",  # the column asset's workers: pxr only to author
        "ionic_usd.pipeline.forms",
        "ionic_usd.pipeline.mesh_cache",
        "ionic_usd.pipeline.temple",
    ]
    assert "ionic_usd.blueprint.column_asset" in modules
    code = (
        "import importlib, sys\n"
        f"for m in {modules!r}:\n"
        "    importlib.import_module(m)\n"
        "print(sorted(m for m in sys.modules if m == 'pxr' or m.startswith(('pxr.', "
        "'ionic_usd.usd'))))\n"
    )
    out = subprocess.run(
        [sys.executable, "-c", code],
        capture_output=True,
        text=True,
        check=True,
        cwd=PACKAGE.parent,
    )
    assert out.stdout.strip() == "[]"


_LEVEL_NAMES = {"high", "medium", "low"}


def _level_tables(source: str, where: str) -> list[str]:
    """The dict literals (and ``dict(...)`` keyword calls) of ``source`` keyed by two level
    names or more: a table of levels of detail."""
    tree = ast.parse(source, filename=where)
    found = []
    for node in ast.walk(tree):
        keys: list[str] = []
        if isinstance(node, ast.Dict):
            keys = [k.value for k in node.keys if isinstance(k, ast.Constant)]
        elif isinstance(node, ast.Call) and getattr(node.func, "id", None) == "dict":
            keys = [k.arg for k in node.keywords if k.arg]
        if len(_LEVEL_NAMES.intersection(k for k in keys if isinstance(k, str))) >= 2:
            found.append(f"{where}:{node.lineno}")
    return found


def test_the_lod_registry_is_the_only_table_of_levels():
    offenders = [
        where
        for path in _library_files()
        if path != PACKAGE / "lod.py"
        for where in _level_tables(
            path.read_text(encoding="utf-8"), str(path.relative_to(PACKAGE.parent))
        )
    ]
    assert offenders == []


def test_the_level_table_check_finds_a_table():
    """The check above can fail: it finds the table shapes it forbids, and not a certainty's
    ``{"certainty": "high"}``."""
    source = (
        'RANK = {"high": 0, "medium": 1, "low": 2}\n'
        "T = dict(high=1.0, low=2.0)\n"
        'P = {"certainty": "high"}\n'
    )
    assert _level_tables(source, "probe.py") == ["probe.py:1", "probe.py:2"]


def _blueprint_names() -> set[str]:
    """The names ``ionic_usd/blueprint/`` defines (each module's ``__all__``)."""
    names: set[str] = set()
    for path in (PACKAGE / "blueprint").glob("[!_]*.py"):
        for node in ast.parse(path.read_text(encoding="utf-8")).body:
            if isinstance(node, ast.Assign) and any(
                isinstance(t, ast.Name) and t.id == "__all__" for t in node.targets
            ):
                names.update(ast.literal_eval(node.value))
    return names


def test_library_code_takes_the_blueprint_from_blueprint():
    """``usd/`` hands the blueprint's names on (old imports keep working), but the library
    outside ``usd/`` imports them from :mod:`ionic_usd.blueprint`, so it loads no ``pxr`` for
    a name or an option."""
    names = _blueprint_names()
    assert {"ColumnAssetOptions", "AssetMesh", "ENGAGED_INSET", "ROOT_LAYER"} <= names
    offenders = []
    for path in _library_files():
        if path.relative_to(PACKAGE).parts[0] == "usd":
            continue
        for node in ast.walk(ast.parse(path.read_text(encoding="utf-8"))):
            if isinstance(node, ast.ImportFrom) and _names(node.module or "", "ionic_usd.usd"):
                offenders += [
                    f"{path.relative_to(PACKAGE.parent)}: {node.module}.{a.name}"
                    for a in node.names
                    if a.name in names
                ]
    assert offenders == []


# a reader holds each function in their head: the kernel (generation and planning) and every
# other part of the package alike (fits, pipeline, USD writers, preview, command line)
MAX_FUNCTION_LINES = 80


def _long_functions(path: Path, limit: int, root: Path = PACKAGE.parent) -> list[str]:
    """``name (lines)`` for each function of ``path`` longer than ``limit`` lines (docstring
    and signature included), at any depth: methods and nested functions count too."""
    tree = ast.parse(path.read_text(encoding="utf-8"), filename=str(path))
    return [
        f"{path.relative_to(root)}:{node.lineno} {node.name} "
        f"({node.end_lineno - node.lineno + 1} lines)"
        for node in ast.walk(tree)
        if isinstance(node, (ast.FunctionDef, ast.AsyncFunctionDef))
        and node.end_lineno is not None
        and node.end_lineno - node.lineno + 1 > limit
    ]


def test_no_function_of_the_package_is_over_80_lines():
    files = sorted(PACKAGE.rglob("*.py"))
    assert len(files) > 150  # the package is found where it lives
    long = [row for p in files for row in _long_functions(p, MAX_FUNCTION_LINES)]
    assert not long, "functions over 80 lines:\n" + "\n".join(long)


def test_the_length_check_finds_a_long_function(tmp_path):
    body = "\n".join(f"    x{i} = {i}" for i in range(81))
    src = tmp_path / "long.py"
    src.write_text(f"def f():\n{body}\n\n\ndef g():\n    return 1\n", encoding="utf-8")
    rows = _long_functions(src, MAX_FUNCTION_LINES, root=tmp_path)
    assert len(rows) == 1 and " f (82 lines)" in rows[0]


def test_a_temple_is_planned_without_pxr():
    """The temple's plan (hypotheses checked, asset options, cuboid meshes, the detail's
    kernel values) is made with no ``pxr`` loaded: only writing it needs USD."""
    code = (
        "import sys\n"
        "from ionic_usd.blueprint.temple_plan import plan_temple\n"
        "from ionic_usd.temple.layout import portunus_layout\n"
        "plan = plan_temple(portunus_layout())\n"
        "assert plan.geometry.mouldings and plan.base_meshes and plan.changes, plan\n"
        "print(len(plan.changes), sorted(m for m in sys.modules if m == 'pxr' or "
        "m.startswith(('pxr.', 'ionic_usd.usd'))))\n"
    )
    out = subprocess.run(
        [sys.executable, "-c", code], capture_output=True, text=True, check=True, cwd=PACKAGE.parent
    )
    assert out.stdout.split(" ", 1) == ["6", "[]\n"]
