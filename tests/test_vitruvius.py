"""Temple types after Vitruvius (ionic_usd.temple.vitruvius, typed_layout, presets)."""

from __future__ import annotations

import itertools
import subprocess
import sys

import numpy as np
import pytest

from ionic_usd.errors import ParameterError
from ionic_usd.temple.description import ColumnKind, Layer
from ionic_usd.temple.presets import PRESETS, preset_layout
from ionic_usd.temple.typed_layout import type_layout
from ionic_usd.temple.vitruvius import (
    CLEAR_BAY,
    FRONTS,
    HEIGHT_IN_D,
    Arrangement,
    Intercolumniation,
    TempleType,
    front_parts,
    resolve,
)

EPS = 1e-9


def test_front_division_iii_3_7():
    # tetrastyle eustyle 11½ parts, hexastyle 18, octastyle 24½ (Vitruvius III.3.7)
    for front, parts in ((4, 11.5), (6, 18.0), (8, 24.5)):
        assert front_parts(front, 2.25, 3.0) == pytest.approx(parts)
    # the module from a stylobate width: width = (parts − 1 + 2·0.75)·D
    t = TempleType(arrangement="peripteral", front=6, stylobate_width=18.5)
    assert resolve(t).lower_diameter == pytest.approx(18.5 / 18.5)


@pytest.mark.parametrize("ic", list(Intercolumniation))
def test_rule_bays_and_heights(ic):
    t = TempleType(
        arrangement="peripteral", front=6, intercolumniation=ic.value, lower_diameter=2.0
    )
    pl = resolve(t)
    bays = np.array(pl.intercolumniations()) / 2.0
    want = [CLEAR_BAY[ic]] * 5
    if ic is Intercolumniation.EUSTYLE:
        want[2] = 3.0
    assert bays == pytest.approx(want)
    assert pl.column_height == pytest.approx(HEIGHT_IN_D[ic] * 2.0)
    assert pl.side == 11  # III.2.5: six in front, eleven on the flanks
    assert pl.flank_spacing == pytest.approx(2.0 * (1 + CLEAR_BAY[ic]))


def _check_plan(layout):
    """No part floats or interpenetrates (on the plan's boxes)."""
    p = layout.params
    pl = resolve(p.vitruvian)
    y0, y1 = p.podium_height, p.podium_height + p.columns_height
    arch = layout.cuboid("architrave")
    assert arch.min[1] == pytest.approx(y1)
    w2, l2 = p.stylobate_width / 2, p.stylobate_length / 2
    r = p.columns_lower_diameter / 2
    for c in layout.columns:
        x, y, z = c.position
        assert y == pytest.approx(y0), c.name  # on the stylobate
        assert abs(x) + r <= w2 + EPS and abs(z) + r <= l2 + EPS, c.name
        # under the architrave (its top radius within the architrave's plan)
        assert (
            arch.min[0] - EPS <= x <= arch.max[0] + EPS
            and arch.min[2] - EPS <= z <= arch.max[2] + EPS
        )
    for a, b in itertools.combinations(layout.columns, 2):
        d = np.hypot(a.position[0] - b.position[0], a.position[2] - b.position[2])
        assert d >= 2 * r, (a.name, b.name)
    for w in layout.cuboids[Layer.CELLA]:
        assert w.max[1] == pytest.approx(y1), w.name
        if w.name != "door_lintel":  # the lintel spans the doorway
            assert w.min[1] == pytest.approx(y0), w.name
        assert -w2 - EPS <= w.min[0] and w.max[0] <= w2 + EPS, w.name
        assert -l2 - EPS <= w.min[2] and w.max[2] <= l2 + EPS, w.name
        assert arch.min[0] - EPS <= w.min[0] and w.max[0] <= arch.max[0] + EPS, w.name
        for c in layout.columns_of(ColumnKind.FREE):  # free shafts clear the walls
            x, _, z = c.position
            dx = max(w.min[0] - x, 0.0, x - w.max[0])
            dz = max(w.min[2] - z, 0.0, z - w.max[2])
            assert np.hypot(dx, dz) >= r - EPS, (w.name, c.name)
    # the stack: podium/steps up to the stylobate, entablature members, roof on the cornice
    tops = [c.max[1] for c in layout.cuboids[Layer.PODIUM]]
    assert max(tops) == pytest.approx(y0)
    ent = sorted(layout.cuboids[Layer.ENTABLATURE], key=lambda c: c.min[1])
    for lower, upper in zip(ent, ent[1:], strict=False):
        assert upper.min[1] == pytest.approx(lower.max[1]), upper.name
    roof_bottom = min(c.min[1] for c in layout.cuboids[Layer.ROOF])
    assert roof_bottom == pytest.approx(ent[-1].max[1])
    # the frieze follows the order
    assert ("frieze" in {c.name for c in ent}) == (pl.frieze_ratio > 0)
    # corner columns of every colonnade that turns a corner carry angle capitals
    if pl.arrangement is not Arrangement.IN_ANTIS:
        xs = [c.position[0] for c in layout.columns]
        zs = [c.position[2] for c in layout.columns]
        for sx, sz in itertools.product((min(xs), max(xs)), (max(zs),)):
            (corner,) = [
                c
                for c in layout.columns
                if abs(c.position[0] - sx) < EPS and abs(c.position[2] - sz) < EPS
            ]
            assert corner.angle_rotation_deg is not None
            assert corner.rotation_deg == corner.angle_rotation_deg


ALL = [(a, f, ic) for a in Arrangement for f in FRONTS[a] for ic in Intercolumniation]


@pytest.mark.parametrize("arrangement,front,ic", ALL)
def test_every_type_lays_out(arrangement, front, ic):
    t = TempleType(
        arrangement=arrangement.value, front=front, intercolumniation=ic.value, lower_diameter=1.0
    )
    layout = type_layout(t, name=f"{arrangement}-{front}-{ic}")
    _check_plan(layout)
    pl = resolve(t)
    n_front = sum(1 for c in layout.columns if abs(c.position[2] - pl.z_front) < EPS)
    assert n_front == (front - 2 if arrangement is Arrangement.IN_ANTIS else front)
    if pl.side:
        n_flank = sum(1 for c in layout.columns if abs(c.position[0] - pl.x_outer) < EPS)
        assert n_flank == 2 * front - 1


# cited values (the preset files' comments give the source of each)
CITED = {
    "priene": dict(width=19.53, length=37.17, side=11, front=6, d=1.29, h=10.10, axial=3.533),
    "nike": dict(width=5.38, length=8.16, front=4, d=0.52, h=4.06),
    "ilissos": dict(width=5.85, length=12.68, front=4, d=0.55, h=4.47),
    "magnesia": dict(width=31.60, length=57.90, side=15, front=8, d=1.40, h=12.19, axial=3.94),
    "ephesus": dict(width=49.92, length=104.41, side=20, front=8, d=1.83, h=17.74),
    "saturn": dict(front=6, d=1.43, h=11.0, columns=8),
}


@pytest.mark.parametrize("name", sorted(CITED))
def test_presets_match_their_sources(name):
    layout = preset_layout(name)
    p, want = layout.params, CITED[name]
    pl = resolve(p.vitruvian)
    rel = pytest.approx
    if "width" in want:
        assert p.stylobate_width == rel(want["width"], rel=0.01)
        assert p.stylobate_length == rel(want["length"], rel=0.01)
    assert p.columns_lower_diameter == rel(want["d"], rel=0.01)
    assert p.columns_height == rel(want["h"], rel=0.01)
    n_front = sum(1 for c in layout.columns if abs(c.position[2] - pl.z_front) < EPS)
    assert n_front == want["front"]
    if "columns" in want:
        assert len(layout.columns) == want["columns"]
    if "side" in want:
        n_flank = sum(1 for c in layout.columns if abs(c.position[0] - pl.x_outer) < EPS)
        assert n_flank == want["side"]
    if "axial" in want:
        assert pl.flank_spacing == rel(want["axial"], rel=0.01)
        normal = [b + pl.lower_diameter for b in pl.intercolumniations()]
        assert normal[0] == rel(want["axial"], rel=0.01)
    _check_plan(layout)
    for h in layout.hypotheses:  # every alternative lays out, and fits
        _check_plan(preset_layout(name, apply=[h.id]))


def test_portunus_preset_is_the_reference():
    from ionic_usd.temple.layout import portunus_layout

    a, b = preset_layout("portunus"), portunus_layout()
    assert a.params == b.params and a.columns == b.columns


def test_bad_types_refused():
    with pytest.raises(ParameterError, match="front"):
        TempleType(arrangement="dipteral", front=4, lower_diameter=1.0)
    with pytest.raises(ParameterError, match="lower_diameter"):
        TempleType(arrangement="peripteral", front=6)
    with pytest.raises(ParameterError, match="arrangement"):
        TempleType(arrangement="tholos", front=6, lower_diameter=1.0)
    with pytest.raises(ParameterError, match="stylobate"):
        resolve(TempleType(front=6, lower_diameter=1.0, stylobate_width=5.0, clear_bay=2.0))


def test_type_toml_few_lines(tmp_path):
    from ionic_usd.temple.layout import layout_from_toml

    f = tmp_path / "t.toml"
    f.write_text(
        '[temple]\nname = "Mine"\n[type]\narrangement = "peripteral"\nfront = 6\n'
        'intercolumniation = "eustyle"\nlower_diameter = 1.2\n'
        '[[hypothesis]]\nid = "sys"\ndescription = "systyle"\nsources = ["V III.3.2"]\n'
        'certainty = "low"\nchanges = { "type.intercolumniation" = "systyle" }\n'
    )
    lay = layout_from_toml(f)
    assert lay.name == "Mine" and len(lay.columns) == 6 * 2 + 9 * 2 + 4
    assert lay.params.columns_height == pytest.approx(8.5 * 1.2)
    alt = layout_from_toml(f, apply=["sys"])
    assert alt.params.columns_height == pytest.approx(9.5 * 1.2)
    f.write_text('[type]\narrangement = "peripteral"\nfront = 6\nlower_diameter = "big"\n')
    with pytest.raises(ParameterError, match="lower_diameter"):
        layout_from_toml(f)
    f.write_text(
        '[type]\narrangement = "peripteral"\nfront = 6\nlower_diameter = 1.0\n'
        '[[cuboid]]\nname = "wall_left"\nlayer = "cella"\nmin = [0, 0, 0]\nmax = [1, 1, 1]\n'
    )
    with pytest.raises(ParameterError, match="wall_left"):
        layout_from_toml(f)


def test_cli_presets_and_bad_preset(tmp_path):
    out = subprocess.run(
        [sys.executable, "-m", "ionic_usd", "presets"], capture_output=True, text=True, check=True
    ).stdout.splitlines()
    assert [line.split("\t")[0] for line in out] == list(PRESETS)
    r = subprocess.run(
        [
            sys.executable,
            "-m",
            "ionic_usd",
            "temple",
            "--preset",
            "nosuch",
            "-o",
            str(tmp_path / "o"),
        ],
        capture_output=True,
        text=True,
    )
    assert r.returncode == 2 and len(r.stderr.strip().splitlines()) == 1
    assert not (tmp_path / "o").exists()


def _compose(tmp_path, layout):
    from pxr import Usd

    from ionic_usd.api import Temple

    rep = Temple(layout).save(tmp_path / layout.name.replace(" ", "_"), texture_size=16)
    stage = Usd.Stage.Open(str(rep.root))
    caps = [
        p
        for p in stage.Traverse()
        if p.GetVariantSets().HasVariantSet("capital")
        and p.GetVariantSets().GetVariantSelection("capital") == "angle"
    ]
    return rep, caps


@pytest.mark.slow
@pytest.mark.parametrize("name", [n for n in PRESETS if n != "portunus"])
def test_presets_compose(tmp_path, name):
    layout = preset_layout(name)
    rep, caps = _compose(tmp_path, layout)
    assert rep.instances == len(layout.columns)
    assert len(caps) == sum(1 for c in layout.columns if c.angle_rotation_deg is not None) > 0


@pytest.mark.slow
@pytest.mark.parametrize("arrangement,front,ic", ALL)
def test_every_type_composes(tmp_path, arrangement, front, ic):
    t = TempleType(
        arrangement=arrangement.value, front=front, intercolumniation=ic.value, lower_diameter=1.0
    )
    layout = type_layout(t, name=f"{arrangement}_{front}_{ic}")
    rep, _ = _compose(tmp_path, layout)
    assert rep.instances == len(layout.columns)


def test_porch_returns_and_rear_count():
    t = TempleType(arrangement="amphiprostyle", front=4, lower_diameter=1.0, porch=2, rear=5)
    lay = type_layout(t)
    _check_plan(lay)
    pl = resolve(t)
    rear = [c for c in lay.columns if abs(c.position[2] + pl.z_front) < EPS]
    nine = preset_layout("ephesus", apply=["rear-nine"])  # the Artemision's modern plan
    pl9 = resolve(nine.params.vitruvian)
    assert sum(1 for c in nine.columns if abs(c.position[2] + pl9.z_front) < EPS) == 9
    assert len(rear) == 5 and len(lay.columns) == 4 + 5 + 2 * 2
    xs = sorted(c.position[0] for c in rear)
    assert np.diff(xs) == pytest.approx([np.diff(xs)[0]] * 4)  # evenly between the corners
    with pytest.raises(ParameterError, match="rear"):
        TempleType(arrangement="prostyle", front=4, lower_diameter=1.0, rear=6)
