"""Packaging and the first run: what a user installs is what the code needs.

The import tests run in subprocesses with a meta-path finder that refuses chosen top-level
modules, so a dependency that only the test extras bring (the crash of the first wave:
``shapely`` imported while building the CLI parser) fails here, not on a user's machine.
"""

from __future__ import annotations

import importlib.metadata as md
import importlib.util
import re
import subprocess
import sys
import tomllib
from fnmatch import fnmatch
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parent.parent
PYPROJECT = tomllib.loads((ROOT / "pyproject.toml").read_text(encoding="utf-8"))


def _dist_name(requirement: str) -> str:
    return re.split(r"[<>=!~\[ ;]", requirement, maxsplit=1)[0].strip().lower().replace("_", "-")


def _import_names(dist: str) -> set[str]:
    """Top-level import names that an installed distribution provides."""
    names = {
        top
        for top, dists in md.packages_distributions().items()
        if any(d.lower().replace("_", "-") == dist for d in dists)
    }
    names = {n for n in names if n.isidentifier() and not n.startswith("_")}
    if not names:  # a lone extension module (xatlas, manifold3d) lists no package
        guess = dist.replace("-", "_")
        if importlib.util.find_spec(guess) is not None:
            names = {guess}
    return names


RUNTIME = {_dist_name(r) for r in PYPROJECT["project"]["dependencies"]}
#: the extras that build the docs and run benchmarks: tools around the package, which never
#: imports them (and the test environment does not install them)
TOOLING_EXTRAS = {"docs", "bench"}
OPTIONAL = sorted(
    {
        _dist_name(r)
        for extra, reqs in PYPROJECT["project"]["optional-dependencies"].items()
        if extra not in TOOLING_EXTRAS
        for r in reqs
    }
    - RUNTIME
    - {"pytest", "hypothesis", "ruff", "mypy"}
)

BLOCKER = """
import sys
BLOCKED = set({blocked!r})
class Block:
    def find_spec(self, name, path=None, target=None):
        if name.split('.')[0] in BLOCKED:
            raise ImportError(f'{{name}} is blocked by the test')
sys.meta_path.insert(0, Block())
"""


def _run(blocked: set[str], code: str, cwd: Path | None = None) -> subprocess.CompletedProcess:
    return subprocess.run(
        [sys.executable, "-c", BLOCKER.format(blocked=sorted(blocked)) + code],
        capture_output=True,
        text=True,
        cwd=cwd,
        timeout=300,
    )


#: runtime dependencies the package imports only inside the functions that use them (numpy is
#: the kernel's one import-time dependency)
LAZY_RUNTIME = sorted(RUNTIME - {"numpy"})


def test_optional_dependencies_are_known():
    assert OPTIONAL, "no optional dependencies found in pyproject.toml"
    assert {"usd-core", "numpy", "shapely", "tqdm"} <= RUNTIME
    extras = {
        _dist_name(r)
        for extra, reqs in PYPROJECT["project"]["optional-dependencies"].items()
        if extra not in TOOLING_EXTRAS
        for r in reqs
    }
    # every feature extra is blocked in turn below (or is a runtime dependency, blocked as lazy)
    assert extras - {"pytest", "hypothesis", "mypy", "ruff"} <= set(OPTIONAL) | RUNTIME


@pytest.mark.parametrize("dist", OPTIONAL + LAZY_RUNTIME)
def test_cli_builds_with_each_dependency_blocked(dist):
    """The whole parser and every subcommand's help, with one dependency missing."""
    names = _import_names(dist)
    assert names, f"{dist} is not installed: blocking it would test nothing"
    code = (
        "from ionic_usd.cli import build_parser\n"
        "p = build_parser()\n"
        "for a in p._subparsers._group_actions:\n"
        "    for name, sub in a.choices.items():\n"
        "        sub.format_help()\n"
        "print('ok')\n"
    )
    out = _run(names, code)
    assert out.returncode == 0, out.stderr[-2000:]
    assert out.stdout.strip() == "ok"


def test_column_command_with_every_optional_dependency_blocked(tmp_path):
    names: set[str] = set()
    for dist in OPTIONAL:
        names |= _import_names(dist)
    code = (
        "import sys\n"
        "from ionic_usd.cli import main\n"
        f"sys.exit(main(['column', '-o', {str(tmp_path / 'c.usda')!r}, '--lod', 'low']))\n"
    )
    out = _run(names, code)
    assert out.returncode == 0, out.stderr[-2000:]
    assert (tmp_path / "c.usda").stat().st_size > 0


def test_geometry_kernel_is_numpy_only_at_import():
    """Every kernel module imports with only numpy (and the standard library) available."""
    heavy = {"pxr", "scipy", "shapely", "numba", "xatlas", "OpenImageIO", "manifold3d"}
    for dist in OPTIONAL:
        heavy |= _import_names(dist)
    kernel = [
        ".".join(p.relative_to(ROOT).with_suffix("").parts)
        for sub in ("geometry", "grammar", "column", "temple")
        for p in sorted((ROOT / "ionic_usd" / sub).glob("*.py"))
    ]
    kernel = [m.removesuffix(".__init__") for m in kernel]
    code = (
        "import importlib\n"
        f"for m in {kernel!r}:\n"
        "    importlib.import_module(m)\n"
        f"bad = sorted(m for m in sys.modules if m.split('.')[0] in {sorted(heavy)!r})\n"
        "assert not bad, bad\n"
        "print('ok')\n"
    )
    out = _run(heavy, code)
    assert out.returncode == 0, out.stderr[-2000:]


#: what parsing a command line must not load (each costs 0.1-1 s of every run)
HEAVY_AT_STARTUP = (
    "scipy",
    "numba",
    "pxr",
    "matplotlib",
    "xatlas",
    "OpenImageIO",
    "manifold3d",
    "shapely",
)


def _modules_after(code: str) -> set[str]:
    probe = (
        code + "\nimport sys, json\n"
        "sys.__stdout__.write('\\n' + json.dumps(sorted({m.split('.')[0] "
        "for m in sys.modules})))\n"
    )
    out = subprocess.run([sys.executable, "-c", probe], capture_output=True, text=True, timeout=300)
    assert out.returncode == 0, out.stderr[-2000:]
    import json

    return set(json.loads(out.stdout.splitlines()[-1]))


def test_building_the_whole_parser_loads_no_heavy_library():
    """Every subcommand's flags (and their help) come without scipy, numba, pxr, ..."""
    mods = _modules_after("from ionic_usd.cli import build_parser\nbuild_parser()")
    assert not mods & set(HEAVY_AT_STARTUP), sorted(mods & set(HEAVY_AT_STARTUP))


@pytest.mark.parametrize(
    "argv",
    [["--version"], ["--help"], ["temple", "--help"], ["shaft", "--help"], ["evaluate", "--help"]],
)
def test_parsing_loads_no_heavy_library(argv):
    code = (
        "from ionic_usd.cli import main\n"
        "try:\n"
        f"    main({argv!r})\n"
        "except SystemExit as e:\n"
        "    assert e.code == 0, e.code\n"
    )
    mods = _modules_after(code)
    assert not mods & set(HEAVY_AT_STARTUP), sorted(mods & set(HEAVY_AT_STARTUP))
    if argv in (["--version"], ["--help"], ["temple", "--help"]):
        assert "numpy" not in mods  # the floor of `ionic-usd --version` <= 0.2 s


def test_python_dash_m_runs_the_cli():
    from ionic_usd import __version__

    out = subprocess.run(
        [sys.executable, "-m", "ionic_usd", "--version"], capture_output=True, text=True
    )
    assert out.returncode == 0, out.stderr
    assert out.stdout.strip() == f"ionic-usd {__version__}"


def test_version_lives_in_one_place():
    assert "version" in PYPROJECT["project"]["dynamic"]
    assert "version" not in PYPROJECT["project"]
    attr = PYPROJECT["tool"]["setuptools"]["dynamic"]["version"]["attr"]
    assert attr == "ionic_usd.__version__"
    hits = [
        p
        for p in (ROOT / "ionic_usd").rglob("*.py")
        if re.search(r"""__version__\s*=\s*['"]""", p.read_text(encoding="utf-8"))
    ]
    assert hits == [ROOT / "ionic_usd" / "__init__.py"]


def test_license_file_matches_declared_license():
    assert PYPROJECT["project"]["license"] == "MIT"
    text = (ROOT / "LICENSE").read_text(encoding="utf-8")
    assert text.startswith("MIT License")
    assert "LICENSE" in PYPROJECT["project"]["license-files"]


def test_package_data_globs_match_the_data_files():
    """Every non-Python file in the package is covered by a glob, and every glob matches."""
    globs = PYPROJECT["tool"]["setuptools"]["package-data"]["ionic_usd"]
    pkg = ROOT / "ionic_usd"
    data = [
        p.relative_to(pkg).as_posix()
        for p in pkg.rglob("*")
        if p.is_file() and p.suffix not in (".py", ".pyc") and "__pycache__" not in p.parts
    ]
    assert (pkg / "py.typed").is_file()
    for f in data:
        assert any(fnmatch(f, g) for g in globs), f"{f} is not shipped (no package-data glob)"
    for g in globs:
        assert any(fnmatch(f, g) for f in data), f"package-data glob {g!r} matches no file"


MAX_MODULE_LINES = 600


def test_no_module_is_over_600_lines():
    """Every module stays readable: at most 600 lines (DESIGN.md convention 8)."""
    modules = sorted((ROOT / "ionic_usd").rglob("*.py"))
    assert len(modules) > 50  # the glob found the package
    lines = {
        p.relative_to(ROOT).as_posix(): len(p.read_text(encoding="utf-8").splitlines())
        for p in modules
    }
    over = {name: n for name, n in lines.items() if n > MAX_MODULE_LINES}
    listed = ", ".join(f"{name} ({n} lines)" for name, n in sorted(over.items()))
    assert not over, f"modules over {MAX_MODULE_LINES} lines, split them: {listed}"


def test_readme_quick_start_is_what_ci_runs():
    sys.path.insert(0, str(ROOT / "tools"))
    try:
        from quickstart import quickstart_commands
    finally:
        sys.path.pop(0)
    cmds = quickstart_commands((ROOT / "README.md").read_text(encoding="utf-8"))
    assert len(cmds) == 2
    assert cmds[0].startswith("pip install . ") and "ionic-usd temple" in cmds[0]
    assert cmds[1].endswith("python -m pytest")
    ci = (ROOT / ".ci" / "run").read_text(encoding="utf-8")
    assert "tools/quickstart.py 1" in ci and "tools/quickstart.py 2" in ci
