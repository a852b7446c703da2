"""The curated top-level API: its doctests and the README's Python example, run as written."""

from __future__ import annotations

import doctest
import re
import subprocess
import sys
from pathlib import Path

import pytest

import ionic_usd
import ionic_usd.api
import ionic_usd.checks
import ionic_usd.lazy

ROOT = Path(__file__).resolve().parent.parent


def _doctests(slow: bool) -> list[doctest.DocTest]:
    """The doctests of the API modules; the temple's (a whole scene build) is the slow one."""
    finder = doctest.DocTestFinder()
    tests = [
        t
        for m in (ionic_usd.api, ionic_usd.checks, ionic_usd.lazy)
        for t in finder.find(m)
        if t.examples
    ]
    return [t for t in tests if (t.name == "ionic_usd.api.Temple") == slow]


def _run(tests: list[doctest.DocTest]) -> doctest.TestResults:
    runner = doctest.DocTestRunner(optionflags=doctest.ELLIPSIS)
    for t in tests:
        runner.run(t)
    return runner.summarize(verbose=False)


def test_api_doctests():
    result = _run(_doctests(slow=False))
    assert result.attempted >= 6 and result.failed == 0


@pytest.mark.slow
def test_temple_in_five_lines_doctest():
    tests = _doctests(slow=True)
    assert len(tests) == 1
    result = _run(tests)
    assert result.attempted >= 5 and result.failed == 0


def test_every_top_level_name_is_documented():
    """``__all__`` is the curated API, and the package docstring names each entry."""
    doc = ionic_usd.__doc__
    for name in ionic_usd.__all__:
        if name != "__version__":
            assert f":func:`{name}`" in doc or f":class:`{name}`" in doc, name


def test_top_level_names_resolve_lazily():
    code = (
        "import sys, ionic_usd\n"
        "assert 'ionic_usd.api' not in sys.modules\n"
        "assert 'numpy' not in sys.modules\n"
        "for n in ionic_usd.__all__: getattr(ionic_usd, n)\n"
        "print('ok')\n"
    )
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True)
    assert out.returncode == 0, out.stderr
    with pytest.raises(AttributeError):
        ionic_usd.no_such_name  # noqa: B018


def test_one_default_column():
    """ColumnParams() and the Portunus preset are the same column (issue: two defaults)."""
    from ionic_usd.column.column import ColumnParams, build_column, portunus_column_params

    assert build_column(ColumnParams()).height == pytest.approx(
        build_column(portunus_column_params()).height, abs=1e-9
    )


def _readme_python() -> str:
    text = (ROOT / "README.md").read_text(encoding="utf-8")
    section = re.search(r"^## Python API\s*$(.*?)(?=^## )", text, re.M | re.S)
    assert section, "README has no Python API section"
    block = re.search(r"^```python\s*$(.*?)^```", section.group(1), re.M | re.S)
    assert block
    return block.group(1)


@pytest.mark.slow
def test_readme_python_example_runs(tmp_path):
    out = subprocess.run(
        [sys.executable, "-c", _readme_python()],
        capture_output=True,
        text=True,
        cwd=tmp_path,
        timeout=600,
    )
    assert out.returncode == 0, out.stderr[-2000:]
    assert (tmp_path / "column.usda").is_file()
    assert (tmp_path / "PortunusTemple" / "Temple.usda").is_file()
    assert "column instances" in out.stdout


def test_column_save_writes_the_parts_asked_for(tmp_path):
    """``Column.save(parts=...)`` (what ``ionic-usd column --part`` calls) writes those parts'
    prims, every point of each as built; an unknown part is refused before a byte is written."""
    from pxr import Usd, UsdGeom

    from ionic_usd.errors import ParameterError

    col = ionic_usd.portunus_column(lod="low")
    out = col.save(tmp_path / "c.usda", parts=("Shaft", "Base"))
    stage = Usd.Stage.Open(str(out))
    meshes = {p.GetName(): p for p in stage.Traverse() if p.IsA(UsdGeom.Mesh)}
    assert sorted(meshes) == ["Base", "Shaft"]
    for name, prim in meshes.items():
        pts = UsdGeom.Mesh(prim).GetPointsAttr().Get()
        assert len(pts) == len(col.parts()[name].points)
    with pytest.raises(ParameterError, match="Abacus"):
        col.save(tmp_path / "d.usda", parts=("Abacus",))
    with pytest.raises(ParameterError):
        col.save(tmp_path / "e.usda", parts=())
    assert sorted(p.name for p in tmp_path.iterdir()) == ["c.usda"]
