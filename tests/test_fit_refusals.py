"""Fit inputs that are not what the fit expects (issue 31): each refused with exit status 2,
one line naming the problem and its measure, nothing written."""

from __future__ import annotations

import os
import sys
from pathlib import Path

import pytest

from ionic_usd.cli import main

sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "tools"))


def _cases():
    from hostile_sweep import fit_scan_cases

    return [
        pytest.param(c, marks=pytest.mark.slow) if {"sphere.xyz", "spheres.xyz"} & set(c[1]) else c
        for c in fit_scan_cases()
    ]


#: what each refusal must say (the measure that says the input is wrong)
EXPECT = {
    "garbage.ply": "malformed input",
    "truncated.ply": "early end-of-file",
    "same.xyz": "span 0 mm",
    "huge.xyz": "coordinates up to 2e+300 m",
    "plane.xyz": "lie on a plane",
    "line.xyz": "lie on a line",
    "sphere.xyz": "% of D",
    "spheres.xyz": "column 1 of 3: scan: not a column",
    "eight.csv": "must not cross itself",
    "triangle.csv": "not a fluted shaft section",
}


@pytest.mark.parametrize("case", _cases(), ids=lambda c: next(iter(c[1])))
def test_fit_refuses_what_is_not_a_column(case, tmp_path, capsys):
    argv, files = case
    name, data = next(iter(files.items()))
    (tmp_path / name).write_bytes(data)
    old = Path.cwd()
    os.chdir(tmp_path)
    try:
        code = main(argv)
    finally:
        os.chdir(old)
    err = capsys.readouterr().err.strip().splitlines()
    assert code == 2
    assert len(err) == 1 and EXPECT[name] in err[0], err
    assert sorted(p.name for p in tmp_path.iterdir()) == [name]  # nothing written
